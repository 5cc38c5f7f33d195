"""Single-DOF Iwan oscillator: harmonic balance per line and Newmark per step, measured
side by side in one run, each with the accuracy it was measured at.

The oscillator (issue "Scale and speed"): a mass on a four-parameter Iwan joint
(K_T = 1.1e5 N/m, F_S = 400 N, chi = -0.5, beta = 4), the joint being the only
stiffness, ``m = K_T / (2 pi 100 Hz)^2`` = 0.2786 kg (stuck natural frequency 100 Hz),
viscous damping ``c = 2 (0.005) sqrt(K_T m)`` (0.5 % of critical, stuck), driven by
``P cos(w t)``.

(a) Harmonic balance per line. Three force levels whose phase-resonance slip amplitude
    is ``A0`` = 0.1, 0.5 and 2 ``phi_max`` (``P = A0 (k_q(A0) + w_r c)``,
    ``w_r^2 = k_in(A0)/m`` from the exact describing function); a sweep of
    ``--lines`` lines over ``w_r (1 -+ min(3 zeta_eq, 0.5))`` with natural-parameter
    continuation. Truth per line: the exact first-harmonic solution of the continuous
    Iwan joint, a root of the scalar equation
    ``|k_in(A) - m w^2 + i (k_q(A) + w c)| A = P`` (:func:`joints.describing.describing_function`,
    Brent's method to 1e-15 relative; the root nearest the method's amplitude where
    the equation has several); error = ``max |X - X_true| / |X_true|`` over the lines
    (complex first-harmonic slip). Methods:

    - ``exact DF``: :func:`fe.hb_exact.continuation_exact` (first harmonic,
      continuous Iwan joint, analytic Jacobian);
    - ``bank H=1``: :func:`fe.harmonic_balance.continuation` on a bank of 100 Jenkins
      sliders, first harmonic, AFT with 64 or 256 samples: its error against the exact
      DF is the discretization (``~ n^-2``) plus AFT sampling error;
    - ``bank H=1,3,5,7``: odd harmonics to 7, 256 samples: the difference from the DF
      is mostly the physics the first harmonic leaves out, not an error.

    Time per line: thread CPU time of each solved line (predictor included), median
    over the lines of a sweep, then median over ``--repeats`` interleaved sweeps.

(b) Newmark per step, 100 sliders, at the resonance of the 0.5 phi_max level, 256
    steps per period (frequency pre-warped, :mod:`runs.campaign`):

    - ``compiled loop``: :class:`fe.newmark.NewmarkIntegrator` (``@njit`` loop on
      :func:`joints.kernel.bank_update_kernel`), 600 periods in one call;
    - ``per period``: one ``run`` per period as the stepped-sine protocol calls it;
    - ``reference loop``: ``integrate(compiled=False)`` (Python loop over
      :func:`joints.jenkins.jenkins_update`);
    - ``plain numpy``: a straightforward average-acceleration Newmark step in numpy
      (``np.clip`` slider update, scalar Newton), written here.

    Accuracy: the compiled run's last-period first-harmonic slip against the HB steady
    state of the same bank (odd harmonics to 31, 1024 samples), and the largest
    difference between the trajectories of the plain numpy step and the compiled loop.

Everything runs on one thread (NUMBA/OPENBLAS/OMP/MKL_NUM_THREADS = 1 set before
numpy is imported). Usage::

    python benchmarks/bench_sdof.py            # about 10 s
    python benchmarks/bench_sdof.py --quick    # smoke run, ~2 s
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
from scipy.optimize import brentq  # noqa: E402

from fe.harmonic_balance import HBSettings, continuation, solve_hb  # noqa: E402
from fe.hb_exact import continuation_exact  # noqa: E402
from fe.newmark import NewmarkIntegrator, NewmarkSettings  # noqa: E402
from fe.reduction import JointBank, JointedSystem, reduced_basis  # noqa: E402
from joints.describing import describing_function  # noqa: E402
from joints.iwan import IwanParameters  # noqa: E402

JOINT = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)
F_STUCK = 100.0        # Hz
ZETA = 0.005
N_SLIDERS = 100
LEVELS = (0.1, 0.5, 2.0)          # phase-resonance slip amplitude / phi_max
TARGET_HB_MS = 1.0                 # per line, first harmonic
TARGET_HB_ERR = 1e-6
TARGET_NM_US = 1.0                 # per step, 100 sliders
STEPS_PER_PERIOD = 256


class LineClock:
    """Progress object for the continuations: records the thread time of each line."""

    def __init__(self):
        self.stamps = [time.thread_time()]
        self.wall = [time.perf_counter()]

    def update(self, n=1):
        self.stamps.append(time.thread_time())
        self.wall.append(time.perf_counter())

    def per_line(self):
        return np.diff(self.stamps), np.diff(self.wall)


def oscillator():
    mass = JOINT.K_T / (2 * np.pi * F_STUCK) ** 2
    c = 2 * ZETA * np.sqrt(JOINT.K_T * mass)
    system = JointedSystem(M=np.array([[mass]]), K=np.zeros((1, 1)), C=np.array([[c]]),
                           G=np.eye(1), K_T=np.array([JOINT.K_T]))
    return mass, c, reduced_basis(system)


def level_setup(A0, mass, c, n_lines):
    k_in, k_q = describing_function(JOINT, A0)
    w_r = np.sqrt(k_in / mass)
    P = A0 * (k_q + w_r * c)
    zeta_eq = (k_q + w_r * c) / (2 * k_in)
    span = min(3 * zeta_eq, 0.5)
    return P, w_r, zeta_eq, w_r * np.linspace(1 - span, 1 + span, n_lines)


def df_roots(P, w, mass, c):
    """All roots A of |k_in(A) - m w^2 + i (k_q(A) + w c)| A = P (exact DF)."""
    def residual(A):
        ki, kq = describing_function(JOINT, A)
        return np.abs(ki - mass * w * w + 1j * (kq + w * c)) * A - P

    grid = np.geomspace(1e-5, 100.0, 600) * JOINT.phi_max
    vals = residual(grid)
    idx = np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))
    roots = [brentq(residual, grid[i], grid[i + 1], xtol=1e-16 * JOINT.phi_max, rtol=1e-15)
             for i in idx]
    return np.array(roots)


def df_response(A, P, w, mass, c):
    ki, kq = describing_function(JOINT, A)
    return P / (ki - mass * w * w + 1j * (kq + w * c))


def errors_vs_df(sols, roots, P, mass, c):
    """Max and peak-line relative error of the first-harmonic slip against the DF."""
    errs = []
    for sol, rts in zip(sols, roots):
        X = sol.slip[list(sol.harmonics).index(1), 0]
        A_true = rts[np.argmin(np.abs(rts - abs(X)))]
        X_true = df_response(A_true, P, sol.omega, mass, c)
        errs.append(abs(X - X_true) / abs(X_true))
    errs = np.array(errs)
    peak = int(np.argmax([abs(s.slip[list(s.harmonics).index(1), 0]) for s in sols]))
    return errs.max(), errs[peak]


# ----------------------------------------------------------------- plain numpy Newmark


def plain_numpy_newmark(mass, c, k, phi, P, e, dt, tol=1e-12, max_iter=40):
    """Average-acceleration Newmark of m u'' + c u' + F(u) = P e(t), F a Jenkins bank
    updated with np.clip; Newton on u per step. Returns the displacement history."""
    beta, gamma = 0.25, 0.5
    n_steps = e.size - 1
    u = v = a = 0.0
    anchor = np.zeros_like(k)
    out = np.empty(n_steps + 1)
    out[0] = 0.0
    K_T = float(k.sum())
    lead = mass / (beta * dt * dt)
    for n in range(n_steps):
        u_t = u + dt * v + dt * dt * (0.5 - beta) * a
        v_t = v + dt * (1.0 - gamma) * a
        p1 = P * e[n + 1]
        u1 = u
        for _ in range(max_iter):
            new = np.clip(anchor, u1 - phi, u1 + phi)
            F = float(((u1 - new) * k).sum())
            kt = float(np.where(new == anchor, k, 0.0).sum())
            a1 = (u1 - u_t) / (beta * dt * dt)
            v1 = v_t + gamma * dt * a1
            r = mass * a1 + c * v1 + F - p1
            J = lead + c * gamma / (beta * dt) + kt
            du = r / J
            u1 -= du
            if abs(du) <= tol * (abs(u1) + 1e-3 * phi[0]):
                break
        new = np.clip(anchor, u1 - phi, u1 + phi)
        anchor = new
        a = (u1 - u_t) / (beta * dt * dt)
        v = v_t + gamma * dt * a
        u = u1
        out[n + 1] = u
    assert K_T > 0
    return out


def first_harmonic(y, theta):
    return (2.0 / theta.size) * (np.exp(-1j * theta) @ y)


def median(xs):
    return float(np.median(np.asarray(xs)))


# ----------------------------------------------------------------- sections


def section_hb(args, mass, c, model, bank):
    methods = {
        "exact DF": lambda m, load, w, clock: continuation_exact(m, JOINT, load, w,
                                                                 progress=clock),
        "bank H=1, N=64": lambda m, load, w, clock: continuation(
            m, bank, load, w, HBSettings(n_harmonics=1, n_time=64), progress=clock),
        "bank H=1, N=256": lambda m, load, w, clock: continuation(
            m, bank, load, w, HBSettings(n_harmonics=1, n_time=256), progress=clock),
        "bank H=1,3,5,7, N=256": lambda m, load, w, clock: continuation(
            m, bank, load, w, HBSettings(n_harmonics=7, n_time=256), progress=clock),
    }
    rows = []
    for level in LEVELS:
        A0 = level * JOINT.phi_max
        P, w_r, zeta_eq, omegas = level_setup(A0, mass, c, args.lines)
        load = model.load(np.array([P]))
        roots = [df_roots(P, w, mass, c) for w in omegas]
        n_multi = sum(len(r) > 1 for r in roots)
        for name, run in methods.items():        # warm-up (compilation, caches)
            run(model, load, omegas[:3], None)
        cpu = {name: [] for name in methods}
        wall = {name: [] for name in methods}
        sols = {}
        for _ in range(args.repeats):            # interleaved repetitions
            for name, run in methods.items():
                clock = LineClock()
                sols[name] = run(model, load, omegas, clock)
                t_cpu, t_wall = clock.per_line()
                cpu[name].append(np.median(t_cpu))
                wall[name].append(np.median(t_wall))
        for name in methods:
            err_max, err_peak = errors_vs_df(sols[name], roots, P, mass, c)
            peak_amp = max(abs(s.slip[list(s.harmonics).index(1), 0]) for s in sols[name])
            rows.append(dict(level=level, method=name, ms=1e3 * median(cpu[name]),
                             ms_wall=1e3 * median(wall[name]), err_max=err_max,
                             err_peak=err_peak, peak=peak_amp / JOINT.phi_max, P=P,
                             f_r=w_r / (2 * np.pi), zeta=zeta_eq, multi=n_multi,
                             iters=np.mean([s.iterations for s in sols[name]])))
    return rows


def section_newmark(args, mass, c, model, bank):
    A0 = 0.5 * JOINT.phi_max
    P, w_r, _, _ = level_setup(A0, mass, c, 3)
    N = STEPS_PER_PERIOD
    w_drive = w_r * np.pi / (N * np.tan(np.pi / N))       # pre-warped (runs.campaign)
    dt = 2 * np.pi / (w_drive * N)
    settings = NewmarkSettings(dt=dt)
    load = model.load(np.array([P]))
    periods = args.periods
    e = np.cos(w_drive * dt * np.arange(periods * N + 1))
    e_one = e[:N + 1]
    stepper = NewmarkIntegrator(model, bank, settings)
    stepper.run(load, e[:2 * N + 1])                      # warm-up
    n_plain = args.plain_steps
    k, phi = bank.stiffness[0], bank.slip_limit[0]
    plain_numpy_newmark(mass, c, k, phi, P, e[:20], dt)
    ref_steps = min(n_plain, 2000)
    times = {"compiled loop": [], "per period": [], "reference loop": [], "plain numpy": []}
    walls = {name: [] for name in times}
    for _ in range(args.repeats):
        t0, w0 = time.thread_time(), time.perf_counter()
        run = stepper.run(load, e)
        times["compiled loop"].append((time.thread_time() - t0) / periods / N)
        walls["compiled loop"].append((time.perf_counter() - w0) / periods / N)
        state = None
        n_pp = min(periods, 100)
        t0, w0 = time.thread_time(), time.perf_counter()
        for _p in range(n_pp):
            r1 = stepper.run(load, e_one, state)
            state = r1.state
        times["per period"].append((time.thread_time() - t0) / n_pp / N)
        walls["per period"].append((time.perf_counter() - w0) / n_pp / N)
        t0, w0 = time.thread_time(), time.perf_counter()
        ref = stepper.run(load, e[:ref_steps + 1], compiled=False)
        times["reference loop"].append((time.thread_time() - t0) / ref_steps)
        walls["reference loop"].append((time.perf_counter() - w0) / ref_steps)
        t0, w0 = time.thread_time(), time.perf_counter()
        plain = plain_numpy_newmark(mass, c, k, phi, P, e[:n_plain + 1], dt)
        times["plain numpy"].append((time.thread_time() - t0) / n_plain)
        walls["plain numpy"].append((time.perf_counter() - w0) / n_plain)
    u = run.q[:, 0] * model.basis[0, 0]
    traj_plain = np.abs(plain - u[:n_plain + 1]).max() / np.abs(u[:n_plain + 1]).max()
    traj_ref = (np.abs(ref.q[:, 0] - run.q[:ref_steps + 1, 0]).max()
                / np.abs(run.q[:ref_steps + 1, 0]).max())
    # steady state: first harmonic of the last two periods, vs HB of the same bank
    theta = w_drive * dt * np.arange(periods * N - N, periods * N)
    X_last = first_harmonic(run.slip[-N - 1:-1, 0], theta)
    theta2 = theta - 2 * np.pi
    X_prev = first_harmonic(run.slip[-2 * N - 1:-N - 1, 0], theta2)
    hb = solve_hb(model, bank, load, w_r, HBSettings(n_harmonics=31, n_time=1024))
    X_hb = hb.slip[0, 0]
    return dict(times=times, walls=walls, dt=dt, periods=periods,
                steady_err=abs(abs(X_last) / abs(X_hb) - 1),
                steady_cerr=abs(X_last - X_hb) / abs(X_hb),
                drift=abs(X_last - X_prev) / abs(X_last),
                traj_plain=traj_plain, traj_ref=traj_ref, A=abs(X_hb) / JOINT.phi_max,
                iters=run.newton_iterations / (periods * N), n_plain=n_plain,
                ref_steps=ref_steps)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run")
    ap.add_argument("--lines", type=int, default=None, help="lines per sweep (default 61)")
    ap.add_argument("--repeats", type=int, default=None, help="interleaved repetitions")
    args = ap.parse_args(argv)
    args.lines = args.lines or (21 if args.quick else 61)
    args.repeats = args.repeats or (3 if args.quick else 7)
    args.periods = 100 if args.quick else 600
    args.plain_steps = 1000 if args.quick else 4000

    import numba

    mass, c, model = oscillator()
    bank = JointBank.from_iwan(JOINT, N_SLIDERS, n_joints=1)
    print(f"SDOF Iwan oscillator: K_T = {JOINT.K_T:g} N/m, F_S = {JOINT.F_S:g} N, "
          f"chi = {JOINT.chi:g}, beta = {JOINT.beta:g}, phi_max = {JOINT.phi_max:.6g} m; "
          f"m = {mass:.6g} kg (stuck {F_STUCK:g} Hz), c = {c:.6g} N s/m ({100 * ZETA:g} %)")
    print(f"Python {platform.python_version()}, numpy {np.__version__}, numba "
          f"{numba.__version__}, {platform.processor() or platform.machine()}, one thread, "
          f"load average {os.getloadavg()[0]:.2f}; medians of {args.repeats} interleaved "
          f"repetitions of thread CPU time [wall time]")
    print()
    print(f"(a) harmonic balance per line ({args.lines} lines per sweep; error = max over "
          f"the lines of |X - X_DF|/|X_DF|, first-harmonic slip, vs the exact describing "
          f"function)")
    rows = section_hb(args, mass, c, model, bank)
    head = (f"{'A0/phi_max':>10} {'method':24} {'ms/line':>8} {'[wall]':>8} {'iters':>5} "
            f"{'max err':>9} {'err@peak':>9} {'peak A/phi_max':>14}")
    print(head)
    for r in rows:
        print(f"{r['level']:10g} {r['method']:24} {r['ms']:8.3f} {r['ms_wall']:8.3f} "
              f"{r['iters']:5.1f} {r['err_max']:9.2e} {r['err_peak']:9.2e} {r['peak']:14.4f}")
    for level in LEVELS:
        r0 = next(r for r in rows if r["level"] == level)
        print(f"   level {level:g} phi_max: P = {r0['P']:.5g} N, f_r = {r0['f_r']:.4f} Hz, "
              f"equivalent damping {100 * r0['zeta']:.3f} %, lines with several DF roots: "
              f"{r0['multi']}")
    ex = [r for r in rows if r["method"] == "exact DF"]
    b1 = [r for r in rows if r["method"] == "bank H=1, N=64"]
    b7 = [r for r in rows if r["method"] == "bank H=1,3,5,7, N=256"]
    print("   ratios (same run): " + ", ".join(
        f"{r['level']:g} phi_max: bank H=1 / exact {b['ms'] / r['ms']:.2f}x, "
        f"H=7 / exact {h['ms'] / r['ms']:.2f}x" for r, b, h in zip(ex, b1, b7)))
    worst_ms = max(r["ms"] for r in ex)
    worst_err = max(r["err_max"] for r in ex)
    ok_hb = worst_ms <= TARGET_HB_MS and worst_err <= TARGET_HB_ERR
    print(f"   target <= {TARGET_HB_MS:g} ms per first-harmonic line at <= {TARGET_HB_ERR:g} "
          f"error: exact DF {worst_ms:.3f} ms (worst level), error {worst_err:.1e}: "
          f"{'met' if ok_hb else 'NOT met'}; the 100-slider bank (H=1) reaches "
          f"{min(r['err_max'] for r in b1):.1e}..{max(r['err_max'] for r in b1):.1e} "
          f"(discretization + AFT sampling), so the target needs the exact-DF path")
    print()
    nm = section_newmark(args, mass, c, model, bank)
    t = nm["times"]
    w = nm["walls"]
    print(f"(b) Newmark per step, {N_SLIDERS} sliders, at resonance of the 0.5 phi_max level "
          f"(slip {nm['A']:.3f} phi_max), {STEPS_PER_PERIOD} steps per period, dt = "
          f"{nm['dt']:.4g} s, {nm['iters']:.2f} Newton iterations per step")
    for name in ("compiled loop", "per period", "reference loop", "plain numpy"):
        print(f"   {name:15s} {1e6 * median(t[name]):9.3f} us/step  [{1e6 * median(w[name]):.3f}]"
              f"   plain numpy / this = {median(t['plain numpy']) / median(t[name]):7.1f}x")
    print(f"   accuracy: steady state after {nm['periods']} periods vs HB (same bank, odd "
          f"harmonics to 31, 1024 samples): first-harmonic slip amplitude "
          f"{nm['steady_err']:.2e} (complex {nm['steady_cerr']:.2e}), last-period drift "
          f"{nm['drift']:.1e}; plain numpy vs compiled trajectory over {nm['n_plain']} steps: "
          f"{nm['traj_plain']:.1e}; reference loop vs compiled over {nm['ref_steps']} steps: "
          f"{nm['traj_ref']:.1e} (relative to the largest displacement)")
    ok_nm = median(t["compiled loop"]) * 1e6 <= TARGET_NM_US
    print(f"   target <= {TARGET_NM_US:g} us per step: {1e6 * median(t['compiled loop']):.3f} us "
          f"({'met' if ok_nm else 'NOT met'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
