"""``iwanfe estimate``: Iwan chi and R from the growth of damping between levels.

Reads a measured-data CSV (``docs/formats/measured-data.md``) or the FRF files of a
series (one per level, identified first: :mod:`cli.series_options`), fits chi and
``|kappa1| B`` to the successive damping differences of the chosen levels (paper eq.
33-35 with the factor 2 of eq. 45 restored), predicts frequency and damping at every
level (eq. 43, 46), and with ``--case`` computes B~ and R~ from the FE model (eq. 37).
A response-controlled series is regressed on the response amplitude each level held.
What the data show that no Iwan joint can do is printed as contradictions.
"""
from __future__ import annotations

import argparse
import math

from cli import validate
from cases.registry import resolve_case
from cli.rig_options import add_rig_argument, rig_from_args
from cli.series_options import add_series_arguments, series_from_args
from inverse.estimate import (
    DEFAULT_CONFIDENCE,
    DEFAULT_FORCE_SCALE,
    METHODS,
    estimate,
    format_levels,
)
from runs.jsonio import print_json

NAME = "estimate"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="identify the Iwan chi and R from damping growth; predict other levels",
        description=(
            "Fit chi and |kappa1|B to the damping differences between successive levels "
            "(paper eq. 33-35, with the factor 2 that the printed eq. 45 drops), predict "
            "the loss of omega^2 and the growth of zeta at every level (eq. 43, 46), and "
            "with --case compute B~ and R~ from the FE model (eq. 37). Differences <= 0 "
            "are excluded and listed. Methods: paper = printed kappa2 (eq. A15), zeta_n "
            "omega_n/omega ~ zeta_n, joint amplitude proportional to excitation; exact = "
            "exact kappa2 and eq. 45 without that approximation; amplitude = as exact but "
            "regressed on the file's response_amplitude column. A response-controlled "
            "series (control = response) is always regressed on the response amplitude "
            "each level held. Input: a measured-data CSV or the FRF files of a series "
            "(identified first, as by `iwanfe identify`)."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_series_arguments(parser)
    add_rig_argument(parser)
    parser.add_argument("--case", metavar="NAME|FILE", default=None,
                        help="FE model for B~ and R~: a shipped case or a case file "
                             "(without it B and R are null)")
    parser.add_argument("--fit-levels", default=None, metavar="LEVELS",
                        help="levels used in the fit, e.g. 1-7 or 1,3-7 (default: all)")
    parser.add_argument("--method", choices=METHODS, default="paper", help="see above")
    parser.add_argument("--mode", type=int, default=None,
                        help="mode label in the file (default: the only one)")
    parser.add_argument("--fe-mode", type=int, default=None,
                        help="1-based FE mode for --case (default: the slipping mode "
                             "nearest the measured frequency)")
    parser.add_argument("--force-scale", type=float, default=DEFAULT_FORCE_SCALE,
                        metavar="N_PER_UNIT",
                        help="force in N per unit of the excitation column (N/V for drive "
                             "voltage; an assumption, R~ scales as its -(chi+1) power)")
    parser.add_argument("--confidence", type=float, default=DEFAULT_CONFIDENCE,
                        help="level of the t-intervals")
    parser.add_argument("--backbone", action="store_true",
                        help="with --case: predict every level from the FE model's EPMC "
                             "backbone with the estimated joint (iwanfe backbone)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--plot", metavar="FILE.png", default=None,
                        help="write the log-slope plot (paper Fig. 8)")
    parser.set_defaults(func=run)


def run(args) -> int:
    if not math.isfinite(args.force_scale) or args.force_scale <= 0:
        raise ValueError(f"--force-scale must be a positive number, got {args.force_scale}")
    if args.plot:
        validate.output_file(args.plot, "--plot", (".png",))   # cli.validate: one rule
    data = series_from_args(args)
    data.rig_repeatability = rig_from_args(args)
    model = None if args.case is None else resolve_case(args.case).fe_model()
    est = estimate(data, fit_levels=args.fit_levels, method=args.method, mode=args.mode,
                   model=model, case_name=args.case or "model", force_scale=args.force_scale,
                   fe_mode=args.fe_mode, confidence=args.confidence)
    backbone = _backbone(args, data, est)
    if args.plot:
        from viz.logslope import plot_estimate

        plot_estimate(est, args.plot, title=f"{_short(args.files)}: mode {est.mode}")
    if args.json:
        out = est.to_dict()
        out["file"] = args.files[0]
        out["files"] = list(args.files)
        if backbone is not None:
            out["backbone"] = backbone
        print_json(out)
    else:
        print(format_table(est, _short(args.files)))
        if backbone is not None:
            from cli.commands.backbone import format_prediction
            print(format_prediction(backbone))
        if args.plot:
            print(f"plot written to {args.plot}")
    return 0


def _short(files) -> str:
    return files[0] if len(files) == 1 else f"{files[0]} .. {files[-1]} ({len(files)} FRF files)"


def _kappa_label(est) -> str:
    if not est.chi_in_range:
        return ("eq. A15 evaluated at a chi outside -1 < chi < 0: no Iwan joint has this "
                "value")
    return "printed eq. A15" if est.method == "paper" else "exact"


def _backbone(args, data, est):
    """The backbone predictions of ``--backbone`` (:mod:`feloop.backbone` on the
    case's FE-levels model), or None."""
    if not args.backbone:
        return None
    if args.case is None:
        raise ValueError("--backbone needs --case (the FE model the joint is put into)")
    from feloop.backbone import predict_from_backbone

    levels = resolve_case(args.case).require("fe_levels")
    return predict_from_backbone(data, est, levels, args.force_scale, case_name=args.case)


def format_table(est, source: str = "") -> str:
    """Readable report of an :class:`~inverse.estimate_result.Estimate` (without --json)."""
    c = est.confidence
    lines = [f"iwanfe estimate {source}  mode {est.mode}  method {est.method}  "
             f"fit levels {format_levels(est.fit_levels)}  abscissa {est.abscissa}"]
    ci = est.chi_interval
    ki = est.kappa1_B_interval
    lines.append(f"  chi          = {est.chi:.5f}   ({c:.0%} interval {ci[0]:.3f} .. {ci[1]:.3f})")
    at = {"free-decay": f"envelope {est.reference_amplitude:g} along the decay",
          "random": f"response RMS {est.reference_amplitude:g}, drive RMS "
                    f"{est.reference_excitation:g}"}.get(est.test)
    at = at or (f"response amplitude {est.reference_amplitude:g}, held; force "
                f"{est.reference_excitation:g}" if est.control == "response"
                else f"excitation {est.reference_excitation:g}")
    lines.append(f"  |kappa1| B   = {est.kappa1_B:.4g} 1/s^2   ({ki[0]:.3g} .. {ki[1]:.3g}), "
                 f"at level {est.reference_level} ({at})")
    lines.append(f"  kappa2/|kappa1| = {est.kappa2_over_kappa1:.4f} ({_kappa_label(est)})")
    if est.rayleigh_factor is not None:
        lines.append(f"  random test: Rayleigh factor c(chi) = {est.rayleigh_factor:.4f} "
                     f"(calculated, inverse.random_amplitude); as a stepped sine at the "
                     f"reference RMS |kappa1| B = {est.kappa1_B_sine:.4g} 1/s^2")
    if est.ratio_z is not None:
        lines.append(f"  eq. 35: z = {est.ratio_z:.4g}, slope chi+1 = {est.chi + 1:.5f}, "
                     f"intercept a0 = {est.intercept_a0:.4f}, residual std {est.residual_std:.3g} "
                     f"(ln units), dof {est.dof}")
    if est.case is not None:
        cs = est.case
        ri = est.R_interval
        lines.append(f"  case {cs.name}: FE mode {cs.fe_mode} ({cs.fe_frequency_hz:.2f} Hz), "
                     f"force {cs.reference_force:.4g} N at level {est.reference_level} "
                     f"({cs.force_scale:g} N per excitation unit)")
        lines.append(f"  B~ = {est.B:.4g} m^(chi+1)/kg   R~ = {est.R:.4g} N/m^(chi+2)   "
                     f"({ri[0]:.3g} .. {ri[1]:.3g})")
    else:
        lines.append("  B, R: not computed (no --case)")
    used = ", ".join(f"{p['from_level']}->{p['to_level']}" for p in est.points_used)
    lines.append(f"  points used: {used}")
    if est.points_excluded:
        lines.append("  points excluded: " + ", ".join(
            f"{p['from_level']}->{p['to_level']} ({p['delta_d']:.3g})"
            for p in est.points_excluded))
    lines.append("")
    lines.append(" level  held  loss omega^2 [rad^2/s^2]        growth zeta [%]              "
                 "omega^2 [rad^2/s^2]       zeta [%]")
    lines.append("              pred     meas   err%        pred       meas      err%     "
                 "pred        meas         pred     meas")
    for p in est.predictions:
        if p["delta_omega2"] is None:
            dpart = " " * 60
        else:
            e1 = p["delta_omega2_error_percent"]
            e2 = p["delta_zeta_error_percent"]
            dpart = (f"{p['delta_omega2']:8.2f} {p['measured_delta_omega2']:8.2f} "
                     f"{e1 if e1 is not None else float('nan'):6.1f}   "
                     f"{100 * p['delta_zeta']:10.4e} {100 * p['measured_delta_zeta']:10.4e} "
                     f"{e2 if e2 is not None else float('nan'):7.1f}")
        lines.append(f" {p['level']:5d}  {'*' if p['held_out'] else ' ':>4}  {dpart}  "
                     f"{p['omega2']:11.1f} {p['measured_omega2']:11.1f}  "
                     f"{100 * p['zeta']:7.4f}  {100 * p['measured_zeta']:7.4f}")
    lines.append("  (* = held out of the fit; loss = omega^2[v-1] - omega^2[v]; "
                 "err% = 100 (pred - meas)/meas)")
    for c in est.contradictions:
        lines.append(f"contradiction: {c}")
    for w in est.data_warnings:
        lines.append(f"warning: {w}")
    return "\n".join(lines)
