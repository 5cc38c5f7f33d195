"""Backbone of the FE double beam: EPMC on the exact-DF path vs the bank path vs the
response-controlled stepped sine that gives the same curve, measured in one run.

Model: the shipped double beam with its simulated glue
(:func:`cases.nonlinear_case.double_beam_case`: 45 reduced DOFs, 5 Iwan glue elements, chi
and R~ from the measured levels 1-7, 252 Jenkins sliders per joint on the bank path).
Target: mode 4 (252 Hz).

1. EPMC (:func:`fe.epmc.epmc_backbone`), 50 points log-spaced from 1e-3 to 3 phi_max
   of the joint that slips most: exact-DF path (first harmonic, continuous Iwan joints)
   and bank path (odd harmonics to 7, 256 AFT samples).
2. The stepped-sine route: response-controlled stepped sine
   (:mod:`runs.response_control`; 65 lines, 236-268 Hz) holding the drive-point
   amplitudes of the 50 EPMC points, each level identified by LSCF
   (:func:`ident.levels.identify_levels`) -- the virtual test that gives the same curve.
   Exact path: all 50 levels; bank path: every 5th level (10), the cost per level
   scaled to 50 (stated in the output).

Accuracy: the largest relative difference between the stepped-sine route and the EPMC
backbone in frequency and damping, over the micro-slip points (largest slip < phi_max)
and over all points. Figures are thread CPU time medians (wall time in brackets); one
thread (NUMBA/OPENBLAS/OMP/MKL_NUM_THREADS = 1 before numpy loads). Usage::

    python benchmarks/bench_backbone.py            # about a minute
    python benchmarks/bench_backbone.py --quick    # fewer repetitions and levels
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from cases.backbone_routes import response_route  # noqa: E402
from cases.nonlinear_case import build_nonlinear_case  # noqa: E402
from fe.epmc import epmc_backbone  # noqa: E402


def timed(func, repeats):
    """(result, median thread CPU time, median wall time) over ``repeats`` calls."""
    cpu, wall, out = [], [], None
    for _ in range(repeats):
        t0, w0 = time.thread_time(), time.perf_counter()
        out = func()
        cpu.append(time.thread_time() - t0)
        wall.append(time.perf_counter() - w0)
    return out, float(np.median(cpu)), float(np.median(wall))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    reps = 2 if args.quick else 5
    case = build_nonlinear_case("double-beam")
    slips = np.geomspace(1e-3, 3.0, 50) * case.phi_max
    paths = {p: case.joint_harmonics(p) for p in ("exact", "bank")}
    epmc_backbone(case.model, paths["bank"], case.mode, slips[:2])     # numba compile
    print(f"double beam, mode {case.mode}: {case.model.n_reduced} reduced DOFs, "
          f"{case.model.n_joints} joints, {case.bank.n_sliders} sliders per joint (bank); "
          f"{platform.processor() or platform.machine()}, one thread")
    res = {}
    for path, J in paths.items():
        bb, cpu, wall = timed(lambda: epmc_backbone(case.model, J, case.mode, slips),
                              reps if path == "exact" else max(1, reps - 2))
        res[path] = (bb, cpu, wall)
        print(f"EPMC {path:5s} 50 points: {cpu:7.3f} s CPU ({wall:.3f} s wall), "
              f"{bb.iterations.sum()} Newton iterations")
    ratio = res["bank"][1] / res["exact"][1]
    print(f"  bank / exact: {ratio:.1f}x;  target exact <= 1 s: "
          f"{'met' if res['exact'][1] <= 1.0 else 'NOT met'}")
    for path in ("exact", "bank"):
        bb = res[path][0]
        held = bb.dof_amplitude(case.drive_dof)
        step = 1 if path == "exact" else 5
        if args.quick:
            step *= 5
        idx = np.arange(0, 50, step)
        (data, slip), cpu, wall = timed(lambda: response_route(case, held[idx], path), 1)
        scale = 50 / idx.size
        f_dev = np.abs(np.sqrt(data.omega2 / bb.omega2[idx]) - 1)
        z_dev = np.abs(data.zeta / bb.zeta[idx] - 1)
        micro = bb.slip_ratio(case.phi_max)[idx] < 1
        print(f"stepped sine ({path}, response control + LSCF), {idx.size} levels x "
              f"{case.lines_hz.size} lines: {cpu:.2f} s CPU ({wall:.2f} s wall)"
              + (f", x{scale:.0f} for 50 levels = {cpu * scale:.1f} s" if scale > 1 else ""))
        print(f"  stepped sine / EPMC ({path}): {cpu * scale / res[path][1]:.0f}x; "
              f"stepped sine ({path}) / EPMC exact: {cpu * scale / res['exact'][1]:.0f}x")
        print(f"  same curve: micro-slip ({micro.sum()} levels) "
              f"|df/f| <= {f_dev[micro].max():.1e}, "
              f"|dzeta/zeta| <= {z_dev[micro].max():.1e}; all levels (to 3 phi_max) "
              f"{f_dev.max():.1e}, {z_dev.max():.1e}")
    e, b = res["exact"][0], res["bank"][0]
    print(f"bank vs exact EPMC at equal slip: |df/f| <= "
          f"{np.abs(b.frequency_hz / e.frequency_hz - 1).max():.1e}, |dzeta/zeta| <= "
          f"{np.abs(b.zeta / e.zeta - 1).max():.1e} (micro-slip: "
          f"{np.abs(b.zeta / e.zeta - 1)[e.slip_ratio(case.phi_max) < 1].max():.1e}; "
          f"discretization + higher harmonics)")


if __name__ == "__main__":
    main()
