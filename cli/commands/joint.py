"""``iwanfe joint``: properties of one four-parameter Iwan joint.

Prints the density parameters (R, phi_max, S), the micro-slip coefficients kappa1,
kappa2 (exact and as printed in the paper), and for each slip amplitude the exact
first-harmonic stiffnesses, the dissipation per cycle and the in-phase stiffness the
paper's kappa2 would give (micro-slip only).
"""
from __future__ import annotations

import argparse

import numpy as np

from cases.iwan_joint import joint_summary
from cli import validate
from joints.iwan import IwanParameters, backbone, steady_loop
from runs.jsonio import print_json

NAME = "joint"
DEFAULT_FRACTIONS = (0.1, 0.5, 1.0, 2.0)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="stiffness, damping and dissipation of a four-parameter Iwan joint",
        description=(
            "Exact properties of a four-parameter Iwan joint (Segalman 2005): density "
            "parameters R, phi_max, S; for each slip amplitude A the first-harmonic "
            "in-phase and quadrature stiffnesses (dissipation per cycle = pi A^2 "
            "k_quadrature) and the in-phase stiffness K_T - kappa2_paper A^(chi+1) of "
            "the paper's approximate kappa2 (micro-slip only). Without --amplitude, "
            "A = 0.1, 0.5, 1 and 2 phi_max."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--chi", type=float, required=True,
                        help="density exponent, in (-1, 0)")
    parser.add_argument("--kt", type=float, required=True, help="joint stiffness K_T [N/m]")
    parser.add_argument("--fs", type=float, required=True,
                        help="macro-slip force F_S [N]")
    parser.add_argument("--beta", type=float, required=True,
                        help="Dirac-to-continuous stiffness ratio beta (>= 0)")
    parser.add_argument("--amplitude", type=float, nargs="+", action="extend", metavar="A",
                        default=None,
                        help="slip amplitudes [m]")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--plot", metavar="FILE.png", default=None,
                        help="draw the backbone and the loops at the amplitudes")
    parser.set_defaults(func=run)


def _table(summary: dict) -> str:
    s = summary
    e = s["chi"] + 2.0
    lines = [
        f"Iwan joint  chi = {s['chi']:g}, K_T = {s['K_T']:g} N/m, "
        f"F_S = {s['F_S']:g} N, beta = {s['beta']:g}",
        f"  R       = {s['R']:.6e} N/m^{e:g}",
        f"  phi_max = {s['phi_max']:.6e} m",
        f"  S       = {s['S']:.6e} N/m",
        f"  kappa1  = {s['kappa1']:.6e} N/m^{e:g}   (paper A15, exact)",
        f"  kappa2  = {s['kappa2_exact']:.6e} N/m^{e:g}   (exact)",
        f"  kappa2  = {s['kappa2_paper']:.6e} N/m^{e:g}   (paper A12-A15, "
        f"{100.0 * (s['kappa2_paper'] / s['kappa2_exact'] - 1.0):+.2f} %)",
        "",
        f"  {'A [m]':>11}  {'regime':6}  {'k_in_phase':>12}  {'k_quadrature':>12}  "
        f"{'D/cycle [J]':>11}  {'k_in (paper)':>12}",
    ]
    for r in s["amplitudes"]:
        paper = r["stiffness_in_phase_paper_kappa2"]
        paper = f"{paper:12.6e}" if paper is not None else f"{'n/a':>12}"
        lines.append(
            f"  {r['amplitude']:11.4e}  {r['regime']:6}  {r['stiffness_in_phase']:12.6e}  "
            f"{r['stiffness_quadrature']:12.6e}  {r['dissipation_per_cycle']:11.4e}  {paper}")
    lines.append("  stiffnesses in N/m; k_in (paper) = K_T - kappa2_paper A^(chi+1), "
                 "micro-slip only")
    return "\n".join(lines)


def _plot(p: IwanParameters, amplitudes, path: str) -> None:
    from viz.hysteresis import plot_hysteresis

    a_max = max(float(np.max(amplitudes)), p.phi_max) * 1.1
    u = np.linspace(-a_max, a_max, 801)
    loops, labels = [], []
    for A in amplitudes:
        _, ul, fl = steady_loop(p, A, 721)
        loops.append((ul, fl))
        labels.append(f"A = {A:.3g} m ({'micro' if A < p.phi_max else 'macro'})")
    plot_hysteresis(u, backbone(p, u), loops, labels, slip_limit=p.phi_max,
                    title=f"Iwan joint: chi={p.chi:g}, K_T={p.K_T:g} N/m, "
                          f"F_S={p.F_S:g} N, beta={p.beta:g}",
                    path=path)


def _joint(args):
    """The joint and its amplitudes, every value checked (exit 2 with one line)."""
    for name, value in (("--chi", args.chi), ("--kt", args.kt), ("--fs", args.fs),
                        ("--beta", args.beta)):
        validate.finite(value, name)
    try:
        p = IwanParameters(chi=args.chi, K_T=args.kt, F_S=args.fs, beta=args.beta)
    except ValueError as exc:   # names chi, K_T, F_S, beta with their values
        raise ValueError(f"--chi/--kt/--fs/--beta: {exc}") from None
    if args.amplitude:
        for a in args.amplitude:
            validate.positive(a, "--amplitude")
        amplitudes = np.asarray(args.amplitude, dtype=float)
    else:
        amplitudes = np.asarray(DEFAULT_FRACTIONS) * p.phi_max
    if args.plot:
        validate.output_file(args.plot, "--plot", (".png",))
    try:
        summary = joint_summary(p, amplitudes)
    except ValueError as exc:
        raise ValueError(f"--amplitude: {exc}") from None
    return p, amplitudes, summary


def run(args) -> int:
    p, amplitudes, summary = _joint(args)
    if args.plot:
        _plot(p, amplitudes, args.plot)
    if args.json:
        print_json(summary)
    else:
        print(_table(summary))
        if args.plot:
            print(f"  plot written to {args.plot}")
    return 0
