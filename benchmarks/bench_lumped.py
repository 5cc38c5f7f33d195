"""Stepped-sine campaign of the paper's 10-DOF model: protocols timed in one run.

Measures, in one process and one run:

1. the default campaign (harmonic balance + continuation) at the paper's resolution:
   12 levels x 0.5 Hz lines over 40-320 Hz (modes 1-9), wall time;
2. the paper's protocol (Newmark, 9 s + 1 s per line from rest) on a few lines; its
   cost is proportional to the number of time steps, so the full campaign is
   extrapolated from the measured time per step (a full run takes hours: said so in
   the output);
3. Newmark until periodic (state carried from line to line) against harmonic balance
   per steady state on the lines of modes 2 and 4 at one level, with the modes
   identified from both FRF sets (LSCF, :func:`ident.identify.identify_modes`):
   frequency and damping must agree within 0.1 %.

Targets: paper / default >= 50x; identified frequency and damping within 0.1 %.

Usage::

    python benchmarks/bench_lumped.py            # about 2-3 minutes
    python benchmarks/bench_lumped.py --quick    # fewer lines, about a minute
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from cases.lumped10.study import MODE_BANDS, LumpedStudy, lumped10_setup
from ident.identify import identify_modes
from runs.campaign import Campaign, HBProtocol, NewmarkProtocol, PaperProtocol
from runs.stepped_sine import run_campaign


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer lines (smoke run)")
    ap.add_argument("--n-sliders", type=int, default=100)
    args = ap.parse_args(argv)

    study = LumpedStudy(n_sliders=args.n_sliders)
    setup = lumped10_setup(study)
    system, bank, model, load, F = (setup.system, setup.bank, setup.model, setup.load,
                                    setup.levels)
    lines = study.lines
    outputs = np.arange(system.n_dof)

    # warm-up: compile the kernels outside the timings
    run_campaign(model, bank, Campaign([61.0, 61.5], [2.0], load, outputs), progress=False)
    run_campaign(model, bank, Campaign([61.0], [2.0], load, outputs,
                                       NewmarkProtocol(max_periods=10_000)), progress=False)

    print(f"10-DOF lumped model, {study.n_sliders} sliders per joint, {lines.size} lines "
          f"({lines[0]:g}-{lines[-1]:g} Hz, {study.df:g} Hz) x {F.size} levels")

    # 1. default campaign, full resolution
    t0 = time.perf_counter()
    full = run_campaign(model, bank, Campaign(lines, F, load, outputs, HBProtocol()),
                        progress=False)
    t_default = time.perf_counter() - t0
    n_ss = lines.size * F.size
    print(f"[1] default (HB) full campaign: {t_default:.2f} s for {n_ss} steady states "
          f"({1e3 * t_default / n_ss:.2f} ms each, mean {full.work.mean():.2f} Newton "
          f"iterations)")

    # 2. paper protocol on a few lines, extrapolated by the number of time steps
    proto = PaperProtocol()
    few = np.array([61.5, 173.5, 246.5]) if not args.quick else np.array([61.5])
    t0 = time.perf_counter()
    run_campaign(model, bank, Campaign(few, [F[3]], load, outputs, proto), progress=False)
    t_few = time.perf_counter() - t0

    def steps(f):
        return np.sum(np.round((proto.settle + proto.window) * f * proto.steps_per_period))

    per_step = t_few / steps(few)
    t_paper = per_step * steps(lines) * F.size
    print(f"[2] paper protocol (9 s + 1 s per line from rest, {proto.steps_per_period} steps "
          f"per period) measured on {few.size} line(s) {[float(x) for x in few]} Hz: "
          f"{t_few:.2f} s, "
          f"{1e6 * per_step:.2f} us per step")
    print(f"    full campaign EXTRAPOLATED from that rate ({steps(lines) * F.size:.3g} steps): "
          f"{t_paper:.0f} s = {t_paper / 3600:.2f} h (not run in full)")
    print(f"    ratio paper / default = {t_paper / t_default:.0f}x   (target >= 50x: "
          f"{'met' if t_paper / t_default >= 50 else 'NOT met'})")

    # 3. Newmark until periodic vs HB per steady state, identified modes compared
    level = 5                                   # 64 N: joints well into micro-slip
    worst_f = worst_z = 0.0
    t_nm_total = t_hb_total = 0.0
    n_total = 0
    for m in ((2,) if args.quick else (2, 4)):
        lo, hi = MODE_BANDS[m]
        band_lines = lines[(lines >= lo) & (lines <= hi)]
        t0 = time.perf_counter()
        hb = run_campaign(model, bank, Campaign(band_lines, [F[level]], load, outputs),
                          progress=False)
        t_hb = time.perf_counter() - t0
        t0 = time.perf_counter()
        nm = run_campaign(model, bank, Campaign(band_lines, [F[level]], load, outputs,
                                                NewmarkProtocol()), progress=False)
        t_nm = time.perf_counter() - t0
        t_nm_total += t_nm
        t_hb_total += t_hb
        n_total += band_lines.size
        target = {2: 61.7, 4: 173.8}[m]
        ids = []
        for res in (hb, nm):
            modes = identify_modes(band_lines, res.receptance[0], band=(lo, hi))
            ids.append(min(modes, key=lambda md: abs(md.frequency_hz - target)))
        df = abs(ids[1].frequency_hz / ids[0].frequency_hz - 1)
        dz = abs(ids[1].zeta / ids[0].zeta - 1)
        worst_f, worst_z = max(worst_f, df), max(worst_z, dz)
        amp = np.max(np.abs(np.abs(nm.receptance) / np.abs(hb.receptance) - 1))
        print(f"[3] mode {m}, {band_lines.size} lines at {F[level]:g} N: HB {t_hb:.2f} s, "
              f"Newmark-until-periodic {t_nm:.2f} s (mean {nm.work.mean():.0f} periods/line); "
              f"max |receptance| difference {100 * amp:.2e} %")
        print(f"    identified f: HB {ids[0].frequency_hz:.5f} Hz, Newmark "
              f"{ids[1].frequency_hz:.5f} Hz (diff {100 * df:.2e} %); zeta: HB "
              f"{ids[0].zeta:.6f}, Newmark {ids[1].zeta:.6f} (diff {100 * dz:.2e} %)")
    print(f"    Newmark / HB per steady state: {t_nm_total / t_hb_total:.0f}x "
          f"({1e3 * t_nm_total / n_total:.1f} ms vs {1e3 * t_hb_total / n_total:.2f} ms per line)")
    ok = worst_f < 1e-3 and worst_z < 1e-3
    print(f"    identified frequency and damping within 0.1 %: {'met' if ok else 'NOT met'} "
          f"(worst {100 * worst_f:.2e} %, {100 * worst_z:.2e} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
