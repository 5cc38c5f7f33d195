"""Double beam with Iwan glue joints: reduced-basis vs full-model Newmark, and harmonic
balance vs Newmark, per steady state, measured side by side in one run with the
accuracy each ratio was measured at.

Model: the default double beam (:func:`cases.double_beam.model.build_double_beam`, 402 free
DOFs, calibrated clamp) with a four-parameter Iwan element at each of the 5 glue nodes
(chi = -0.4, beta = 0, K_T = the node's share of the stuck glue stiffness
``model.joint_stiffness``, the same ``phi_max`` = 6 um for all, so ``F_S = K_T phi_max
(chi+1)/(chi+2)``), each discretized into 100 Jenkins sliders
(:func:`joints.jenkins.discretize`). Rayleigh damping ``C = a M + b K_J`` with 0.5 % at
the 3rd and 5th in-phase bending modes (134.4 and 407.9 Hz; 0.43 % at 252 Hz). Drive:
1 N at the exciter (lower strip, 50 mm from the clamp), near the 252 Hz mode, where the
glue slips up to about 0.48 ``phi_max`` (micro-slip). Output: the response DOF (upper
strip at the exciter) and the five joint slips. These are benchmark choices, not the
paper reproduction's (`cases/double_beam/study.py`).

1. Reduced vs full Newmark, one steady state from rest at the line of the resonance
   peak (:class:`runs.stepped_sine.NewmarkProtocol`, 256 steps per period, the line is
   done when the remaining drift of the first harmonic is below ``tol``):

   - reduced: Ritz basis of the 12 lowest stuck-glue modes plus one static mode per
     joint (17 DOFs, :func:`fe.reduction.reduced_basis`);
   - full: every free DOF in physical coordinates (:func:`fe.reduction.full_model`,
     identity basis, dense ``M``, ``K_J``, ``C``), the same integrator
     (:class:`fe.newmark.NewmarkIntegrator`).

   Accuracy: relative difference of the steady-state receptance amplitude at the
   response DOF and of the half peak-to-peak joint slips (largest over the joints).

2. Harmonic balance vs Newmark per steady state on the reduced model: the lines
   249-254 Hz (0.5 Hz) at 1 N, HB with continuation (default
   :class:`runs.stepped_sine.HBProtocol`: odd harmonics to 7, 256 AFT samples) against
   Newmark with the state carried from line to line (NewmarkProtocol, tol 1e-6).
   Accuracy: largest relative difference over the lines of the receptance amplitude
   and of the joint slip amplitudes.

Everything runs on one thread (NUMBA/OPENBLAS/OMP/MKL_NUM_THREADS = 1 set before numpy
is imported); figures are thread CPU time medians, wall time in brackets. Usage::

    python benchmarks/bench_double_beam.py            # about a minute (the full model
                                                      # dominates: ~30 s per run)
    python benchmarks/bench_double_beam.py --quick    # looser tolerance, fewer lines
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from cases.double_beam.model import build_double_beam  # noqa: E402
from fe.newmark import NewmarkIntegrator, NewmarkSettings  # noqa: E402
from fe.reduction import (JointBank, JointedSystem, full_model, rayleigh_damping,  # noqa: E402
                          reduced_basis)
from runs.campaign import Campaign, HBProtocol, NewmarkProtocol  # noqa: E402
from runs.stepped_sine import run_campaign  # noqa: E402
from joints.iwan import IwanParameters  # noqa: E402

CHI = -0.4
PHI_MAX = 6e-6          # m
FORCE = 1.0             # N
N_SLIDERS = 100
N_MODES = 12
DAMPED_AT_HZ = (134.44, 407.92)
ZETA = 0.005
TARGET_REDUCTION = 30.0
TARGET_HB = 50.0
TARGET_ACCURACY = 5e-3


def setup():
    db = build_double_beam()
    w1, w2 = 2 * np.pi * np.asarray(DAMPED_AT_HZ)
    b = 2 * ZETA / (w1 + w2)
    a = 2 * ZETA * w1 * w2 / (w1 + w2)
    system = JointedSystem(M=db.M, K=db.K_without_joints, C=rayleigh_damping(db.M, db.K, a, b),
                           G=db.slip_matrix, K_T=db.joint_stiffness)
    joints = [IwanParameters(chi=CHI, K_T=k, F_S=k * PHI_MAX * (CHI + 1) / (CHI + 2), beta=0.0)
              for k in db.joint_stiffness]
    bank = JointBank.from_iwan(joints, N_SLIDERS)
    load = np.zeros(db.n_free)
    load[db.drive_dof] = 1.0
    return db, system, joints, bank, load, (a, b)


def timed(fn):
    t0, w0 = time.thread_time(), time.perf_counter()
    out = fn()
    return out, time.thread_time() - t0, time.perf_counter() - w0


def amp_diff(a, b):
    """Largest relative difference of |receptance| and of slip amplitudes."""
    rec = float(np.max(np.abs(np.abs(a.receptance) / np.abs(b.receptance) - 1)))
    slip = float(np.max(np.abs(a.slip_amplitude / b.slip_amplitude - 1)))
    return rec, slip


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run (tol 1e-4, 5 lines)")
    ap.add_argument("--repeats", type=int, default=None, help="repetitions of the cheap runs")
    args = ap.parse_args(argv)
    repeats = args.repeats or (2 if args.quick else 5)
    tol_single = 1e-4 if args.quick else 1e-5
    lines = np.arange(250.0, 252.01, 0.5) if args.quick else np.arange(249.0, 254.01, 0.5)

    import numba

    db, system, joints, bank, load, (a, b) = setup()
    red, tc_red, _ = timed(lambda: reduced_basis(system, n_modes=N_MODES, static_joint_modes=True))
    full, tc_full, _ = timed(lambda: full_model(system))
    out = [db.response_dof]
    print(f"Double beam: {db.n_free} free DOFs, {len(joints)} Iwan joints (chi = {CHI:g}, "
          f"beta = 0, phi_max = {PHI_MAX:g} m, F_S = {joints[0].F_S:.4g}..{joints[1].F_S:.4g} N, "
          f"{N_SLIDERS} sliders each); Rayleigh a = {a:.4g} 1/s, b = {b:.4g} s "
          f"({100 * ZETA:g} % at {DAMPED_AT_HZ[0]:g} and {DAMPED_AT_HZ[1]:g} Hz); drive "
          f"{FORCE:g} N")
    print(f"reduced basis: {red.n_reduced} DOFs ({N_MODES} modes + {len(joints)} static joint "
          f"modes, built in {tc_red:.3f} s); full model: {full.n_reduced} DOFs (built in "
          f"{tc_full:.3f} s)")
    print(f"Python {platform.python_version()}, numpy {np.__version__}, numba "
          f"{numba.__version__}, one thread, load average {os.getloadavg()[0]:.2f}; thread "
          f"CPU time [wall]")

    # warm-up (compiled kernels) and the resonance line from a quick HB sweep
    run_campaign(red, bank, Campaign([251.0, 251.5], [FORCE], load, out), progress=False)
    NewmarkIntegrator(red, bank, NewmarkSettings(dt=1e-5)).run(red.load(load),
                                                               np.cos(1e-2 * np.arange(50)))
    sweep = run_campaign(red, bank, Campaign(lines, [FORCE], load, out), progress=False)
    f_peak = float(lines[np.argmax(np.abs(sweep.receptance[0, :, 0]))])
    print()

    # 1. reduced vs full Newmark, one steady state from rest
    proto = NewmarkProtocol(tol=tol_single)
    one = Campaign([f_peak], [FORCE], load, out, proto)
    t_r, w_r = [], []
    for _ in range(repeats):
        res_r, tc, tw = timed(lambda: run_campaign(red, bank, one, progress=False))
        t_r.append(tc)
        w_r.append(tw)
    res_f, tc_f, tw_f = timed(lambda: run_campaign(full, bank, one, progress=False))
    rec_d, slip_d = amp_diff(res_r, res_f)
    ratio1 = tc_f / np.median(t_r)
    periods = int(res_r.work[0, 0])
    steps = periods * proto.steps_per_period
    print(f"1. Newmark per steady state from rest at {f_peak:g} Hz (tol {tol_single:g}; reduced "
          f"{periods} periods, full {int(res_f.work[0, 0])}; slip up to "
          f"{res_f.slip_amplitude.max() / PHI_MAX:.3f} phi_max)")
    print(f"   reduced ({red.n_reduced} DOFs): {np.median(t_r):.3f} s [{np.median(w_r):.3f}] "
          f"= {1e6 * np.median(t_r) / steps:.2f} us/step (median of {repeats})")
    print(f"   full ({full.n_reduced} DOFs):   {tc_f:.3f} s [{tw_f:.3f}] = "
          f"{1e6 * tc_f / (res_f.work[0, 0] * proto.steps_per_period):.1f} us/step (one run)")
    ok1 = ratio1 >= TARGET_REDUCTION and max(rec_d, slip_d) <= TARGET_ACCURACY
    print(f"   full / reduced = {ratio1:.0f}x at steady-state amplitude difference: receptance "
          f"{rec_d:.2e}, joint slips {slip_d:.2e}   (target >= {TARGET_REDUCTION:g}x at <= "
          f"{100 * TARGET_ACCURACY:g} %: {'met' if ok1 else 'NOT met'})")
    print()

    # 2. HB vs Newmark per steady state, reduced model, a sweep of lines
    camp_hb = Campaign(lines, [FORCE], load, out, HBProtocol())
    camp_nm = Campaign(lines, [FORCE], load, out, NewmarkProtocol())
    t_hb, w_hb = [], []
    for _ in range(repeats):
        hb, tc, tw = timed(lambda: run_campaign(red, bank, camp_hb, progress=False))
        t_hb.append(tc)
        w_hb.append(tw)
    nm, tc_nm, tw_nm = timed(lambda: run_campaign(red, bank, camp_nm, progress=False))
    rec_d2, slip_d2 = amp_diff(nm, hb)
    per_hb = np.median(t_hb) / lines.size
    per_nm = tc_nm / lines.size
    ratio2 = per_nm / per_hb
    print(f"2. HB vs Newmark per steady state, reduced model, {lines.size} lines "
          f"{lines[0]:g}-{lines[-1]:g} Hz at {FORCE:g} N (slip up to "
          f"{hb.slip_amplitude.max() / PHI_MAX:.3f} phi_max)")
    print(f"   HB (odd harmonics to 7, 256 samples, continuation): {1e3 * per_hb:.2f} ms/line "
          f"[{1e3 * np.median(w_hb) / lines.size:.2f}] ({hb.work.mean():.1f} Newton iterations, "
          f"median of {repeats})")
    print(f"   Newmark (state carried, tol 1e-6): {1e3 * per_nm:.1f} ms/line "
          f"[{1e3 * tw_nm / lines.size:.1f}] ({nm.work.mean():.0f} periods per line, one run)")
    ok2 = ratio2 >= TARGET_HB and max(rec_d2, slip_d2) <= TARGET_ACCURACY
    print(f"   Newmark / HB = {ratio2:.0f}x at amplitude difference: receptance {rec_d2:.2e}, "
          f"joint slips {slip_d2:.2e}   (target >= {TARGET_HB:g}x at <= "
          f"{100 * TARGET_ACCURACY:g} %: {'met' if ok2 else 'NOT met'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
