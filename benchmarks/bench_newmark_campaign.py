"""Newmark against harmonic balance over the whole double-beam campaign: cost and
agreement, measured side by side in one run.

The study of ``iwanfe reproduce double-beam`` (FE double beam, 40 modes + 5 static joint
modes, Iwan glue from the estimate of measured levels 1-7, 252 sliders per joint, 10
levels x 65 lines, 236-268 Hz):

1. harmonic balance (the default protocol: odd harmonics to 7, 256 AFT samples,
   continuation over the lines);
2. Newmark (``--protocol newmark``, :mod:`cases.double_beam.protocols`: every line
   started on its harmonic-balance orbit, 256 steps per period, 2048 on levels that
   reach macro-slip, periodic to 1e-5), the orbits it starts from included in its cost;
3. the same Newmark campaign without the period-map Newton step (``period_newton =
   False``, the protocol before issue 21: each line integrated from its orbit until the
   drift bound falls below the tolerance), timed in the same run: before / after;
4. with ``--carried``, on levels 7 and 9, Newmark with the state carried from line to
   line from rest (a stepped-sine test's protocol) against the orbit start: what the
   start saves (minutes).

Both campaigns are identified as the study does (LSCF at the response DOF); the
per-level frequency and damping ratios and their relative differences are printed
with the campaign costs (thread CPU time, wall time in brackets) and their ratio.
One thread (NUMBA/OPENBLAS/OMP/MKL_NUM_THREADS = 1 set before numpy is imported).
Usage::

    python benchmarks/bench_newmark_campaign.py           # about 1 minute
    python benchmarks/bench_newmark_campaign.py --quick   # levels 1, 7, 9 only
    python benchmarks/bench_newmark_campaign.py --carried # + part 4 (minutes)
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from cases.double_beam.joint_setup import (joint_setup, level_campaign, mode_weights,  # noqa: E402
                                           nonlinear_model)
from cases.double_beam.model import build_double_beam  # noqa: E402
from cases.double_beam.pipeline import identify_campaign  # noqa: E402
from cases.double_beam.protocols import comparison_lines, protocol_comparison  # noqa: E402
from cases.double_beam.settings import DoubleBeamStudy, measured_levels  # noqa: E402
from runs.campaign import NewmarkProtocol  # noqa: E402
from runs.stepped_sine import run_campaign, run_level  # noqa: E402


def timed(fn):
    t0, w0 = time.thread_time(), time.perf_counter()
    out = fn()
    return out, time.thread_time() - t0, time.perf_counter() - w0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="levels 1, 7 and 9 only")
    ap.add_argument("--carried", action="store_true",
                    help="also levels 7 and 9 with the state carried from rest (minutes)")
    args = ap.parse_args(argv)

    import numba

    study = DoubleBeamStudy(weak_joint_scales=())
    model = build_double_beam()
    data = measured_levels(study)
    setup = joint_setup(model, data, study)
    red, bank = nonlinear_model(model, setup, study)
    keep = np.array([0, 6, 8]) if args.quick else np.arange(study.n_levels)
    setup.force = setup.force[keep]
    data = data.take(keep)
    camps = {p: level_campaign(model, setup, study, p) for p in ("hb", "newmark")}
    print(f"Double beam, the study of 'iwanfe reproduce double-beam': {red.n_reduced} reduced "
          f"DOFs, {bank.n_joints} joints x {bank.n_sliders} sliders, {keep.size} levels x "
          f"{study.lines.size} lines")
    print(f"Python {platform.python_version()}, numpy {np.__version__}, numba "
          f"{numba.__version__}, {platform.processor() or platform.machine()}, one thread, "
          f"load average {os.getloadavg()[0]:.2f}; thread CPU time [wall]")
    run_campaign(red, bank, dataclasses.replace(camps["newmark"], frequency_hz=[251.0],
                                                force=[setup.force[0]]), progress=False)
    res, cpu, wall = {}, {}, {}
    for p, camp in camps.items():
        res[p], cpu[p], wall[p] = timed(lambda: run_campaign(red, bank, camp, progress=False))
    phi, weights = mode_weights(model, setup)
    ids = {p: identify_campaign(model, setup, study, r, phi, weights) for p, r in res.items()}
    steps = [camps["newmark"].protocol.steps_for(float(a.max()), float(bank.slip_limit.max()))
             for a in res["hb"].slip_amplitude]
    comp = protocol_comparison(data.level, ids["newmark"], ids["hb"], res["newmark"],
                               res["hb"], steps)
    print()
    print("\n".join(comparison_lines(comp)[:-1]))
    print(f" campaign cost: harmonic balance {cpu['hb']:.2f} s [{wall['hb']:.2f}], Newmark "
          f"{cpu['newmark']:.1f} s [{wall['newmark']:.1f}] ({comp['newmark']['steps_total']:.3g} "
          f"steps, {1e6 * cpu['newmark'] / comp['newmark']['steps_total']:.2f} us per step): "
          f"Newmark / HB = {cpu['newmark'] / cpu['hb']:.0f}x")

    # 3. before / after: the same campaign without the period-map Newton step
    before = dataclasses.replace(camps["newmark"], protocol=dataclasses.replace(
        camps["newmark"].protocol, period_newton=False))
    res_b, cpu_b, wall_b = timed(lambda: run_campaign(red, bank, before, progress=False))
    ra, rb = res["newmark"].receptance, res_b.receptance      # (levels, lines, outputs)
    dmax = np.abs(rb - ra).max(axis=1)
    d_out = (dmax / np.abs(ra).max(axis=1)).max()              # of each output's peak
    d_lvl = (dmax.max(axis=1) / np.abs(ra).max(axis=(1, 2))).max()   # of the level's
    print()
    print(f"3. Newmark campaign without / with the period-map Newton step (fe.newmark_period): "
          f"{cpu_b:.1f} s [{wall_b:.1f}] / {cpu['newmark']:.1f} s [{wall['newmark']:.1f}] = "
          f"{cpu_b / cpu['newmark']:.1f}x; periods per line {res_b.work.mean():.1f} / "
          f"{res['newmark'].work.mean():.1f} (largest {res_b.work.max():.0f} / "
          f"{res['newmark'].work.max():.0f}); receptances differ by {d_lvl:.1e} of the level's "
          f"largest, {d_out:.1e} of each output's own peak (relative)")

    # 4. what the orbit start saves: whole levels, state carried from rest instead
    for lv in (6, 8) if args.carried else ():
        if lv not in keep:
            continue
        i = int(np.flatnonzero(keep == lv)[0])
        one = camps["newmark"]
        carried = dataclasses.replace(one, protocol=NewmarkProtocol(
            steps_per_period=one.protocol.steps_per_period, tol=one.protocol.tol))
        (a, ca, wa), (b, cb, wb) = (timed(lambda: run_level(red, bank, c, i))
                                    for c in (one, carried))
        d = np.abs(b.receptance[:, model.response_dof] / a.receptance[:, model.response_dof] - 1)
        print(f"4. level {lv + 1}, all {study.lines.size} lines, tol {one.protocol.tol:g}: "
              f"orbit start {a.work.mean():.0f} periods/line, {ca:.2f} s [{wa:.2f}]; state "
              f"carried from rest {b.work.mean():.0f} periods/line, {cb:.2f} s [{wb:.2f}]: "
              f"{cb / ca:.1f}x; receptances differ by {d.max():.1e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
