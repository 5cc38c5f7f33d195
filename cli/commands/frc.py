"""``iwanfe frc``: forced-response curves of a one-DOF Iwan oscillator through folds, with
stability.

``iwanfe frc --force 0.5 1 2`` follows the multi-harmonic balance of ``m x'' + c x' + k x
+ F_iwan(x) = F cos(w t)`` (four-parameter Iwan joint, marched by its exact time step,
AFT; :func:`fe.frc.forced_response`) by pseudo-arclength continuation over the frequency
range, locates the folds and judges each point by Hill's method. Per point: frequency_hz,
amplitude (first harmonic of x, m), peak (half peak-to-peak of x, m), the largest Floquet
multiplier modulus and ``stable``; ``--json`` prints the curves. ``--case NAME|FILE``
takes a case's jointed model instead (driven and observed at its drive DOF; ``--path
bank``: its Jenkins banks with the compiled AFT, ``exact``: its law marched by its step).
A case file with ``[drive] kind = "base"`` is driven by its base instead: the load
``A Phi^T (-(M_all r)_free)`` (:mod:`fe.base_excitation`) at the file's acceleration
amplitude ``A`` (m/s^2) or at ``--acceleration``, observed at its sensor; amplitudes are
relative to the base (the JSON's ``drive`` and ``amplitude_is`` say so).
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

from runs.jsonio import print_json

NAME = "frc"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME, help="forced-response curves through folds, with stability (one-DOF Iwan "
                   "oscillator)",
        description=(
            "Forced response of m x'' + c x' + k x + F_iwan(x) = F cos(w t): the "
            "four-parameter Iwan joint (chi, K_T, F_S, beta; Segalman 2005) in parallel "
            "with a linear spring k, viscous damping c = 2 zeta sqrt((k + K_T) m). "
            "Multi-harmonic balance with the joint marched by its exact time step over "
            "the period (alternating frequency-time), pseudo-arclength continuation from "
            "the low end of the range (folds located by the tangent), stability of every "
            "point by Hill's method. Per point: frequency_hz, amplitude (first harmonic "
            "of x, m), peak (half peak-to-peak of x, m), max_multiplier (largest Floquet "
            "multiplier modulus), stable. --json prints one curve per force. A case file "
            "with [drive] kind = \"base\" is driven by its base (--acceleration, m/s^2; "
            "amplitudes relative to the base)."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--force", type=float, nargs="+", default=None, metavar="F",
                        help="drive amplitudes (N), one curve each (required, unless "
                             "--case is base-driven)")
    parser.add_argument("--acceleration", type=float, nargs="+", default=None, metavar="A",
                        help="with a base-driven --case ([drive] kind = \"base\"): base "
                             "acceleration amplitudes (m/s^2), one curve each (default: the "
                             "file's)")
    parser.add_argument("--case", default=None, metavar="NAME|FILE",
                        help="a case's jointed model instead of the one-DOF oscillator "
                             "(shipped case or case file; driven and observed at its drive "
                             "DOF; the one-DOF options are then not used)")
    parser.add_argument("--mode", type=int, default=None,
                        help="with --case: 1-based stuck-joint mode whose frequency sets "
                             "the default range (default: the case's studied mode)")
    parser.add_argument("--path", choices=("bank", "exact"), default="bank",
                        help="with --case: the joints as Jenkins banks (compiled AFT, exact "
                             "Jacobian) or the exact law marched by its step (finite-"
                             "difference Jacobian, slow for many joints)")
    parser.add_argument("--mass", type=float, default=1.0, help="mass m (kg)")
    parser.add_argument("--stiffness", type=float, default=2000.0,
                        help="linear spring k in parallel with the joint (N/m)")
    parser.add_argument("--kt", type=float, default=2000.0, help="joint stiffness K_T (N/m)")
    parser.add_argument("--fs", type=float, default=1.0, help="macro-slip force F_S (N)")
    parser.add_argument("--chi", type=float, default=-0.5, help="Iwan exponent chi")
    parser.add_argument("--beta", type=float, default=1.0, help="Iwan beta")
    parser.add_argument("--zeta", type=float, default=0.01,
                        help="viscous damping ratio at the stuck-joint frequency")
    parser.add_argument("--range", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                        help="frequency range (Hz; default 0.6 to 1.3 times the "
                             "stuck-joint frequency)")
    parser.add_argument("--harmonics", type=int, default=5,
                        help="highest odd harmonic H (harmonics 1, 3, ..., H)")
    parser.add_argument("--n-time", type=int, default=128, help="AFT samples per period")
    parser.add_argument("--floquet", choices=("period_map", "tangent"), default=None,
                        help="also the largest Floquet multiplier of the Newmark period map "
                             "at every point (period_map: central differences of the "
                             "nonlinear map, 1024 steps; tangent: the scheme linearized on "
                             "the orbit, which omits a hysteretic joint's memory)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(func=run)


def _model(args):
    """The one-DOF model and the Iwan law (ValueError on a bad value)."""
    from fe.reduction import ReducedModel
    from joints.describing import IwanJoints
    from joints.iwan import IwanParameters

    for name in ("mass", "stiffness", "zeta"):
        v = getattr(args, name)
        if not (math.isfinite(v) and v >= 0) or (name == "mass" and v == 0):
            raise ValueError(f"--{name} must be finite and {'> 0' if name == 'mass' else '>= 0'}"
                             f", got {v}")
    p = IwanParameters(chi=args.chi, K_T=args.kt, F_S=args.fs, beta=args.beta)
    k = args.stiffness + p.K_T
    c = 2.0 * args.zeta * math.sqrt(k * args.mass)
    model = ReducedModel(basis=np.eye(1), omega=np.array([math.sqrt(k / args.mass)]),
                         M=np.array([[args.mass]]), K=np.array([[k]]), C=np.array([[c]]),
                         G=np.eye(1), K_T=np.array([p.K_T]), n_modes=1)
    return model, IwanJoints(p, 1), p


def _check(args):
    for name in ("force", "acceleration"):
        v = getattr(args, name)
        if v is not None and not (v and all(math.isfinite(f) and f > 0 for f in v)):
            raise ValueError(f"--{name} must be finite and > 0, got {v}")
    if args.acceleration is not None and args.case is None:
        raise ValueError("--acceleration needs a base-driven --case ([drive] kind = \"base\")")
    if args.force is None and args.case is None:
        raise ValueError("--force is required (drive amplitudes, N)")
    if not (args.harmonics >= 1 and args.harmonics % 2 == 1 and args.harmonics <= 31):
        raise ValueError(f"--harmonics must be an odd number in 1..31, got {args.harmonics}")
    if args.n_time < 4 * args.harmonics + 4 or args.n_time > 8192:
        raise ValueError(f"--n-time must be in {4 * args.harmonics + 4}..8192, got "
                         f"{args.n_time}")
    if args.range is not None:
        lo, hi = args.range
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
            raise ValueError(f"--range must satisfy 0 < LO < HI, got {lo} {hi}")


def _case_model(args):
    """A case's reduced model, joints (bank or law), unit load and observed row."""
    from cli.model_options import case_of

    if args.mode is not None and args.mode < 1:
        raise ValueError(f"--mode must be >= 1, got {args.mode}")
    case = case_of(args).nonlinear_model(mode=args.mode)
    law = case.bank if args.path == "bank" else case.law
    if law is None:
        raise ValueError(f"{case.name}: no Jenkins banks for law {case.law_name} (use "
                         f"--path exact)")
    return case, law


def _curve(model, law, F: float, load, band_hz, settings, observe=None,
           key: str = "force_N") -> dict:
    """One drive amplitude's curve (:func:`fe.frc.forced_response` over ``band_hz``, Hz)
    as the JSON's ``curves`` entry (``key``: ``force_N``, or ``acceleration_m_s2`` for a
    base drive); a steady state not found is one line naming the amplitude."""
    from fe.frc import forced_response
    from fe.newton_path import SteadyStateError

    lo, hi = band_hz
    try:
        r = forced_response(model, law, load, (2 * math.pi * lo, 2 * math.pi * hi),
                            observe=observe, settings=settings)
    except SteadyStateError as exc:
        what = f"force {F:g} N" if key == "force_N" else f"base acceleration {F:g} m/s^2"
        raise ValueError(f"{what}: {exc}") from None
    return {key: F, "points": r.to_points(),
            "folds": [{"frequency_hz": f["frequency_hz"], "amplitude": f["amplitude"],
                       "peak": f["peak"]} for f in r.folds]}


def run(args) -> int:
    _check(args)
    if args.case is not None:
        return _run_case(args)
    from fe.frc import FRCSettings

    model, law, p = _model(args)
    f0 = float(model.omega[0]) / (2 * math.pi)
    lo, hi = args.range if args.range is not None else (0.6 * f0, 1.3 * f0)
    settings = FRCSettings(harmonics=tuple(range(1, args.harmonics + 1, 2)),
                           n_time=args.n_time, floquet=args.floquet)
    curves = []
    t0 = time.perf_counter()
    for F in args.force:
        curves.append(_curve(model, law, F, np.array([F]), (lo, hi), settings))
    elapsed = time.perf_counter() - t0
    if args.json:
        print_json({"model": {"mass_kg": args.mass, "stiffness_N_per_m": args.stiffness,
                              "chi": p.chi, "K_T": p.K_T, "F_S": p.F_S, "beta": p.beta,
                              "phi_max_m": p.phi_max, "zeta": args.zeta,
                              "stuck_frequency_hz": f0, "harmonics": list(settings.harmonics),
                              "n_time": args.n_time},
                    "curves": curves, "elapsed_s": elapsed})
        return 0
    print(f"one-DOF Iwan oscillator: m = {args.mass:g} kg, k = {args.stiffness:g} N/m, joint "
          f"chi = {p.chi:g}, K_T = {p.K_T:g} N/m, F_S = {p.F_S:g} N, beta = {p.beta:g} "
          f"(phi_max = {p.phi_max:.4g} m), zeta = {args.zeta:g}; stuck {f0:.5g} Hz; "
          f"harmonics {list(settings.harmonics)}, {args.n_time} samples; {elapsed:.1f} s")
    _print_curves(curves)
    return 0


def _print_curves(curves) -> None:
    """The text table of every curve."""
    for c in curves:
        folds = ", ".join(f"{f['frequency_hz']:.6g} Hz" for f in c["folds"]) or "none"
        amp = (f"force {c['force_N']:g} N" if "force_N" in c
               else f"base acceleration {c['acceleration_m_s2']:g} m/s^2")
        print(f"{amp}: {len(c['points'])} points, folds: {folds}")
        floq = any("floquet_multiplier" in q for q in c["points"])
        print("  frequency_hz    amplitude_m       peak_m   max|mu|  stable"
              + ("  floquet|mu|" if floq else ""))
        for q in c["points"]:
            print(f"  {q['frequency_hz']:12.6f}  {q['amplitude']:12.5e}  {q['peak']:12.5e}"
                  f"  {q['max_multiplier']:8.5f}  {'yes' if q['stable'] else 'no ':>6s}"
                  + (f"  {q['floquet_multiplier']:11.5f}" if floq else ""))


def _drive(args, case) -> tuple[list, np.ndarray, str, dict]:
    """The case's drive: amplitudes (N or m/s^2), reduced unit load, the curves' key and
    the JSON's drive entries; ValueError (one line) on options of the other drive."""
    if case.drive_kind == "base":
        if args.force is not None:
            raise ValueError(f"{case.name} is base-driven ([drive] kind = \"base\"): give "
                             f"--acceleration (m/s^2), not --force")
        acc = args.acceleration or [case.base_acceleration]
        return acc, case.base_load, "acceleration_m_s2", {
            "drive": {"kind": "base", "acceleration_m_s2": case.base_acceleration},
            "amplitude_is": "relative to the base"}
    if args.acceleration is not None:
        raise ValueError(f"--acceleration needs a base-driven case ([drive] kind = "
                         f"\"base\"); {case.name} is driven at a point: give --force")
    if args.force is None:
        raise ValueError("--force is required (drive amplitudes, N)")
    return args.force, case.load(), "force_N", {}


def _run_case(args) -> int:
    """``--case``: the same curves for a case's jointed model at its drive DOF (or driven
    by its base, observed at its response DOF)."""
    from fe.frc import FRCSettings

    case, law = _case_model(args)
    amplitudes, load, key, drive = _drive(args, case)
    model = case.model
    f0 = float(model.omega[case.mode - 1]) / (2 * math.pi)
    lo, hi = args.range if args.range is not None else (0.9 * f0, 1.05 * f0)
    settings = FRCSettings(harmonics=tuple(range(1, args.harmonics + 1, 2)),
                           n_time=args.n_time, floquet=args.floquet)
    observe = np.asarray(model.basis[case.response_dof], dtype=float)
    curves = []
    t0 = time.perf_counter()
    for F in amplitudes:
        curves.append(_curve(model, law, F, F * load, (lo, hi), settings, observe, key))
    elapsed = time.perf_counter() - t0
    head = {"case": case.name, "mode": case.mode, "path": args.path,
            "stuck_frequency_hz": f0, "drive_dof": case.drive_dof,
            "response_dof": case.response_dof, "harmonics": list(settings.harmonics),
            "n_time": args.n_time, **drive}
    if drive:
        del head["drive_dof"]                   # a base drive has no drive point
    if args.json:
        print_json({"model": head, "curves": curves, "elapsed_s": elapsed})
        return 0
    how = (f"driven by its base, observed at DOF {case.response_dof} relative to the base"
           if drive else f"driven and observed at DOF {case.response_dof}")
    print(f"{case.name}, mode {case.mode} (stuck {f0:.5g} Hz): {how}, joints: {args.path}; "
          f"harmonics {list(settings.harmonics)}, {args.n_time} samples; {elapsed:.1f} s")
    _print_curves(curves)
    return 0
