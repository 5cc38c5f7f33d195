"""``iwanfe backbone``: nonlinear modes (EPMC) of a shipped case, and the route comparison.

``iwanfe backbone --case double-beam --mode 4`` continues the nonlinear mode of the
case's jointed model from deep micro-slip into macro-slip (:func:`fe.epmc.epmc_backbone`,
Krack 2015) and prints per amplitude the largest joint slip over phi_max, the frequency,
the damping ratio ``xi/(2 omega)`` and the energy; ``--json`` prints the list of points.
``--compare`` runs the three routes of :mod:`cases.backbones` (EPMC, response- and
force-controlled virtual tests, each fed to the estimator) against the true joint.
:func:`run_response_control` is ``iwanfe reproduce TARGET --control response``.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from cli import validate
from cli.model_options import add_model_argument, case_of

from cases.registry import SHIPPED
from casefile.laws import SLIP_SCALE
from runs.jsonio import print_json

NAME = "backbone"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME, help="nonlinear modes (EPMC backbones) of a case's jointed model",
        description=(
            "Backbone of a nonlinear mode by the extended periodic motion concept (Krack "
            "2015): the autonomous model with an artificial damping -xi M q' that balances "
            "the dissipation, continued in the amplitude of the joint that slips most, from "
            "deep micro-slip into macro-slip. Per point: amplitude = largest joint slip / "
            "phi_max (a case file of law jenkins: fs/kt; bouc-wen: z_u), frequency_hz, "
            "zeta = xi/(2 omega) (the mode's damping ratio; M-"
            "proportional, so independent of the shape's scaling), energy = peak kinetic "
            "energy (J). Paths: exact = the joint law (continuous Iwan joints, a Jenkins "
            "slider, Bouc-Wen) through its exact describing function, first harmonic; bank "
            "= Jenkins banks through AFT with the case's harmonics (not for bouc-wen). "
            "--json prints the list of points. --compare (law iwan4): EPMC vs "
            "response-controlled vs force-controlled virtual tests, each fed to the "
            "estimator against the true joint."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--case", required=True, metavar="NAME|FILE",
                        help=f"shipped case ({', '.join(SHIPPED)}) or case file (.toml) with "
                             "every joint parameter given")
    parser.add_argument("--mode", type=int, default=None,
                        help="1-based stuck-joint mode (default: the case's studied mode)")
    add_model_argument(parser)
    parser.add_argument("--path", choices=("exact", "bank"), default="exact",
                        help="joint path of the harmonic balance")
    parser.add_argument("--range", type=float, nargs=2, default=(1e-3, 3.0),
                        metavar=("LO", "HI"), help="amplitudes (slip / phi_max, or the "
                        "law's slip scale, of the joint that slips most in the linear "
                        "mode), log-spaced")
    parser.add_argument("--points", type=int, default=50, help="points on the backbone")
    parser.add_argument("--compare", action="store_true",
                        help="the three routes fed to the estimator (cases.backbones)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--plot", metavar="FILE.png", default=None,
                        help="write frequency and damping against amplitude")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def run(args) -> int:
    lo, hi = args.range
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ValueError(f"--range must satisfy 0 < LO < HI, got {lo} {hi}")
    if not 2 <= args.points <= 10_000:   # continuation steps: 10,000 resolve any backbone
        raise ValueError(f"--points must be in 2..10000, got {args.points}")
    if args.plot:
        validate.output_file(args.plot, "--plot", (".png",))   # cli.validate: one rule
    if args.mode is not None and args.mode < 1:
        raise ValueError(f"--mode must be >= 1, got {args.mode}")
    case = case_of(args).nonlinear_model(mode=args.mode)
    case.require_point_drive("backbone")    # its drive amplitude and force at resonance
    if args.compare:
        case.require_iwan("--compare (the Iwan estimator against the true joint)")
        return _compare(case, args)
    scale = SLIP_SCALE.get(case.law_name, "phi_max")
    from fe.epmc import epmc_backbone

    t0 = time.perf_counter()
    bar = None
    if not args.no_progress:
        from tqdm import tqdm
        bar = tqdm(total=args.points, desc="EPMC", unit="point", leave=False)
    try:
        bb = epmc_backbone(case.model, case.joint_harmonics(args.path), case.mode,
                           np.geomspace(lo, hi, args.points) * case.phi_max, at="slip",
                           progress=bar)
    except RuntimeError as exc:
        raise ValueError(str(exc)) from None
    finally:
        if bar is not None:
            bar.close()
    elapsed = time.perf_counter() - t0
    points = bb.to_points(case.phi_max_per_joint)
    drive = bb.dof_amplitude(case.drive_dof)
    for p, x in zip(points, drive):
        p["drive_amplitude_m"] = float(x)
    if args.plot:
        from viz.backbone_plot import plot_backbones

        plot_backbones([{"label": f"EPMC ({args.path} path)", "style": "-",
                         "amplitude": [p["amplitude"] for p in points],
                         "frequency_hz": bb.frequency_hz, "zeta": bb.zeta}],
                       xlabel=f"largest joint slip / {scale}", marks=[(1.0, scale)],
                       title=f"{case.name}, mode {case.mode}", path=args.plot)
    if args.json:
        print_json(points)
        return 0
    print(f"{case.name}, mode {case.mode}: nonlinear mode by EPMC (Krack 2015), {args.path} "
          f"path, {len(points)} points in {elapsed:.2f} s")
    if case.law_name == "iwan4":
        print(f"  joint: chi = {case.chi:.5f}, R = {case.R:.5g} N/m^(chi+2) (total), phi_max = "
              f"{case.phi_max:.5g} m; {case.joint_source}")
    else:
        print(f"  joint: law {case.law_name} (chi, R: n/a), {scale} = {case.phi_max:.5g} m; "
              f"{case.joint_source}")
    print(f"  stuck-joint frequency {bb.omega_linear / (2 * math.pi):.4f} Hz; amplitude = "
          f"largest slip / {scale}; zeta = xi/(2 omega); energy = peak kinetic energy")
    print("  amplitude  frequency_hz     zeta_%      energy_J   drive_amplitude_m")
    for p in points:
        print(f"  {p['amplitude']:9.4g}  {p['frequency_hz']:12.6f}  {100 * p['zeta']:9.6f}  "
              f"{p['energy']:12.5e}  {p['drive_amplitude_m']:12.5e}")
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def _compare(case, args) -> int:
    from cases.backbones import compare_routes
    from viz.backbone_plot import plot_backbones

    t0 = time.perf_counter()
    cmp = compare_routes(case, args.path, case.fit_levels, progress=not args.no_progress)
    d = cmp.to_dict()
    if args.plot:
        bb = cmp.backbone
        curves = [{"label": "EPMC backbone", "style": "-",
                   "amplitude": bb.dof_amplitude(case.drive_dof),
                   "frequency_hz": bb.frequency_hz, "zeta": bb.zeta}]
        for name, style in (("response", "o"), ("force", "s")):
            data = cmp.data[name]
            curves.append({"label": f"{name}-controlled test (LSCF)", "style": style,
                           "amplitude": data.response_amplitude,
                           "frequency_hz": data.omega_hz, "zeta": data.zeta})
        plot_backbones(curves, xlabel="drive-point amplitude at resonance (m)", path=args.plot,
                       title=f"{case.name}, mode {case.mode}: three backbones ({args.path})")
    if args.json:
        d["elapsed_s"] = time.perf_counter() - t0
        print_json(d)
        return 0
    print(f"{case.name}, mode {case.mode}: EPMC vs response- vs force-controlled virtual "
          f"tests ({args.path} path), true chi = {case.chi:.5f}, R = {case.R:.5g}")
    print(" level  drive_amp_m  slip/phi_max  f_epmc_Hz     force: df/f   dzeta/zeta"
          "   response: df/f   dzeta/zeta")
    dev_f, dev_r = cmp.deviation("force"), cmp.deviation("response")
    e = cmp.data["epmc"]
    for i, lv in enumerate(e.level):
        print(f" {lv:5d}  {e.response_amplitude[i]:11.4e}  "
              f"{cmp.slip['epmc'][i].max() / case.phi_max:12.4g}"
              f"  {e.omega_hz[i]:10.5f}  {dev_f['frequency'][i]:+12.2e} {dev_f['zeta'][i]:+11.2e}"
              f"  {dev_r['frequency'][i]:+15.2e} {dev_r['zeta'][i]:+11.2e}")
    print(f"estimates (fit levels {case.fit_levels}); bias of chi = slip law + slip per modal "
          f"amplitude + rest (cases/backbones.py)")
    print("  route     method     abscissa             chi      bias   slip-law  per-modal"
          "     rest   R~ error")
    for r in d["estimates"]:
        if r["error"]:
            print(f"  {r['route']:9s} {r['method']:10s} {r['abscissa']:18s} failed: {r['error']}")
            continue
        print(f"  {r['route']:9s} {r['method']:10s} {r['abscissa']:18s} {r['chi']:8.4f} "
              f"{r['chi_bias']:+8.4f} {r['chi_bias_slip_law']:+9.4f} "
              f"{r['chi_bias_slip_per_modal_amplitude']:+9.4f} {r['chi_bias_rest']:+8.4f} "
              f"{100 * r['R_relative_error']:+9.1f} %")
    print(f"time {time.perf_counter() - t0:.1f} s" + (f"; plot written to {args.plot}"
                                                       if args.plot else ""))
    return 0


def run_response_control(args) -> int:
    """``iwanfe reproduce TARGET --control response`` (:mod:`cases.response_study`)."""
    from cases.response_study import response_reproduction
    from cli.executor_options import executor_from_args

    if args.protocol != "default":
        raise ValueError("--control response runs harmonic balance (no --protocol)")
    out = Path(args.out or f"results/{args.target}-response")
    rep = response_reproduction(args.target, out, progress=not args.no_progress,
                                executor=executor_from_args(args))
    if args.json:
        print_json(rep)
        return 0
    j, e = rep["joint"], rep["estimate"]
    print(f"{rep['case']}, mode {rep['mode']}: response-controlled stepped sine ({rep['path']} "
          f"path), each level holding the drive-point amplitude of the stuck structure at the "
          f"case's force level")
    print(f"  true joint: chi = {j['chi']:.5f}, R = {j['R']:.5g} ({j['source']})")
    print(" level  held_amp_m   force_N    f_LSCF_Hz    f_EPMC_Hz   zeta_LSCF_%  zeta_EPMC_%"
          "  slip/phi_max")
    for r in rep["levels"]:
        print(f" {r['level']:5d}  {r['held_amplitude_m']:10.4e} {r['force_N']:9.4g} "
              f"{r['frequency_hz']:12.6f} {r['epmc_frequency_hz']:12.6f} "
              f"{100 * r['zeta']:12.6f} {100 * r['epmc_zeta']:12.6f} "
              f"{r['slip_over_phi_max']:13.4g}")
    print(f"estimate (amplitude method on the held amplitude, levels {e['fit_levels']}): chi = "
          f"{e['chi']:.5f} (error {e['chi_error']:+.4f}), R~ = {e['R']:.4g} "
          f"({100 * e['R_relative_error']:+.1f} %)")
    print("files: " + ", ".join(rep["files"]) + f"; {rep['timings']['total_s']:.1f} s",
          file=sys.stdout)
    return 0


def format_prediction(pred: dict) -> str:
    """Table of :func:`feloop.backbone.predict_from_backbone` (``estimate
    --backbone``, ``diagnose --backbone``)."""
    def f(x, spec):
        return "n/a" if x is None else format(x, spec)

    lines = ["", f"FE backbone prediction ({pred['case']}, FE mode {pred['fe_mode']}, EPMC "
             f"{pred['path']} path, {pred['points']} points): the estimated joint chi = "
             f"{pred['chi']:.5f}, R~ = {pred['R']:.4g} over the joint elements, read at the "
             f"resonance of each level's force",
             " level  held  force_N   omega^2 pred    omega^2 meas    zeta pred %  "
             "zeta meas %  slip/phi_max"]
    for r in pred["levels"]:
        lines.append(f" {r['level']:5d}  {'*' if r['held_out'] else ' ':>4}  {r['force_N']:7.4g} "
                     f"{f(r['omega2'], '14.1f'):>14s}  {r['measured_omega2']:14.1f}  "
                     f"{f(r['zeta'] and 100 * r['zeta'], '11.5f'):>11s}  "
                     f"{100 * r['measured_zeta']:11.5f}  {f(r['slip_over_phi_max'], '12.4g'):>12s}")
    lines.append("  (* = held out of the fit; n/a = force beyond the computed backbone)")
    return "\n".join(lines)
