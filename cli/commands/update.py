"""``iwanfe update``: the FE model's joint, damping and frequency fitted to measured levels.

Parses, asks the case (:func:`cases.registry.resolve_case`) for its ``update``
capability (:func:`feloop.update.run_update` on its FE-levels model),
prints (:mod:`feloop.update_report`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from cli.executor_options import add_executor_arguments, executor_from_args
from cli.rig_options import add_rig_argument, rig_from_args
from runs.jsonio import print_json

NAME = "update"


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return v


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME, help="fit the FE model's glue joint, damping and frequency to measured levels",
        description=(
            "Model updating by the nonlinear FE simulation itself: the case's FE model with "
            "its joint law on every joint node (four-parameter Iwan, Jenkins or Bouc-Wen; "
            "first-harmonic balance, exact describing function, phase resonance of the "
            "measured mode) fitted to omega^2 and zeta of the fit levels: the joint (Iwan: "
            "chi and the modal damping at level 1, R~; Jenkins and Bouc-Wen: the slip "
            "scale, and Bouc-Wen's alpha), the "
            "viscous damping and the stuck frequency, plus the FE realization of the cause "
            "the one judge selects (the same choice as diagnose --case: fit test, cost per "
            "cause, held-out gain > 1); the glue stiffness K_T by its profile (grip "
            "re-calibrated for each). updated_model.json is the selected model. Reports "
            "at_bound and intervals of every fitted parameter (profile likelihood on a "
            "bound), the misfit, and how the held-out predictions move with the "
            "undetermined ones."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--case", required=True, metavar="NAME|FILE",
                        help="the FE model: a shipped case or a case file (.toml) whose "
                             "joints have one law and a kt and which names its measured "
                             "data")
    parser.add_argument("--data", metavar="FILE", default=None,
                        help="measured-data CSV (default: the case's measured data)")
    parser.add_argument("--mode", type=int, default=None,
                        help="mode label in the data (default: the case's)")
    parser.add_argument("--modes", default=None, metavar="M1,M2",
                        help="fit one joint to several measured modes (labels in the data; "
                             "the first is the reference): one set of joint parameters, each "
                             "mode its own viscous damping and stuck frequency; reports each "
                             "mode's fit test and whether one joint explains them "
                             "(docs/case-file-loop.md)")
    parser.add_argument("--fit-levels", default=None,
                        help="levels fitted, others predicted (default: the case's)")
    parser.add_argument("--force-scale", type=_positive, default=1.0, metavar="N_PER_UNIT",
                        help="N per excitation unit (assumed; omega^2 and zeta do not depend "
                             "on it, R~ and phi_max do)")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="write updated_model.json, update.json, report.md and figures; "
                             "finished profile branches are kept in DIR/profiles (a rerun "
                             "resumes)")
    parser.add_argument("--profiles", choices=("bound", "all"), default="bound",
                        help="profile likelihoods of the fitted parameters on a bound "
                             "(others linearized), or of all of them and of K_T (slower)")
    parser.add_argument("--assumptions", action="store_true",
                        help="also refit under each assumed property of the case changed "
                             "(E, rho, masses, joint elements; slower)")
    add_rig_argument(parser)
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    add_executor_arguments(parser)
    parser.set_defaults(func=run)


def run_modes(args, fit_modes, predict_modes=()) -> int:
    """One joint over several modes (``update --modes``, ``loop --fit-modes``)."""
    from cases.registry import resolve_case
    from feloop.modes_report import format_text, summary, write_modes

    run = resolve_case(args.case).require("update_modes")
    r = run(fit_modes=fit_modes, predict_modes=predict_modes, data_path=args.data,
            fit_levels=getattr(args, "fit_levels", None), force_scale=args.force_scale,
            rig_repeatability=rig_from_args(args))
    return _report(args, r, write_modes, summary, format_text)


def _report(args, result, write, summary, format_text) -> int:
    """Write ``result`` into ``--out`` (``write``), print its JSON or its text."""
    if args.out:
        write(result, args.out)
    s = summary(result)
    if args.json:
        print_json(s)
    else:
        print(format_text(s))
        if args.out:
            print(f"report: {Path(args.out) / 'report.md'}")
    return 0


def run(args) -> int:
    from feloop.update_report import format_text, summary, write_update
    from cases.registry import resolve_case
    from feloop.modes_run import parse_modes

    if args.modes is not None:
        if args.mode is not None or args.assumptions or args.profiles != "bound":
            raise ValueError("--modes takes none of --mode, --assumptions, --profiles all")
        return run_modes(args, parse_modes(args.modes))
    update = resolve_case(args.case).require("update")
    spec = executor_from_args(args)
    store = None if args.out is None else str(Path(args.out) / "profiles")
    result = update(executor=spec, progress=True, store=store, data_path=args.data,
                    mode_label=args.mode, fit_levels=args.fit_levels,
                    force_scale=args.force_scale, profiles=args.profiles,
                    assumptions=args.assumptions,
                    rig_repeatability=rig_from_args(args))
    return _report(args, result, write_update, summary, format_text)
