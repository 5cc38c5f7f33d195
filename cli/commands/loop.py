"""``iwanfe loop``: the main job, the whole loop on one page (``make run``).

Parses, asks the case for its ``update`` capability, calls
:func:`cases.loop_report.run_loop` (``--model``: a model of ``update`` checked at every
level beside the loop's update), prints the short summary
(:func:`cases.loop_report.format_summary`) or the JSON document.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from cli import validate
from cli.executor_options import add_executor_arguments, executor_from_args
from cli.model_options import add_model_argument
from runs.jsonio import print_json

NAME = "loop"


def register(subparsers) -> None:
    from cases.registry import DEFAULT_CASE

    parser = subparsers.add_parser(
        NAME, help="the whole loop: update the FE model, say what it gets wrong, name the "
                   "cause, measure the extended model's gain on held-out levels",
        description=(
            "The main job. The case's FE model is updated to the lower measured levels "
            "(iwanfe update), the one judge chooses between the base model and its "
            "extensions (iwanfe diagnose --case), and the page reports what the updated "
            "base model gets wrong (with numbers), the cause named, the extended model and "
            "its gain at the levels no fit saw. Writes report.md (one page, with its "
            "figure), loop.json and the update's files in DIR/update. With --model, the "
            "page also says what that updated model gets wrong at every level."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--case", default=DEFAULT_CASE, metavar="NAME|FILE",
                        help="a case with measured levels and FE model updating")
    parser.add_argument("--out", metavar="DIR", default="results/loop",
                        help="output folder (profiles are kept: a rerun resumes)")
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_model_argument(parser, help=(
        "also check this model of iwanfe update on the case (same data and mode; any "
        "fit levels, any candidate) at every level beside the loop's own update: its "
        "predictions against the measured values in noise sd, rms at its fit levels and "
        "at the others (the loop's fits start from the data, not from a nominal joint, "
        "so the model does not change them); a model of another case or data: exit 2"))
    parser.add_argument("--fit-modes", default=None, metavar="M1[,M2]",
                        help="one joint fitted to these measured modes (every level) instead "
                             "of the one-mode loop; with --predict-modes the others are "
                             "predicted from it at every level, with intervals, and judged")
    parser.add_argument("--predict-modes", default=None, metavar="M1[,M2]",
                        help="modes predicted from the joint of --fit-modes (their viscous "
                             "damping and stuck frequency calibrated to their lowest level)")
    add_executor_arguments(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    from cases.loop_report import format_summary, run_loop
    from cases.registry import resolve_case

    if args.predict_modes is not None and args.fit_modes is None:
        raise ValueError("--predict-modes needs --fit-modes")
    if args.fit_modes is not None:
        from cli.commands.update import run_modes
        from feloop.modes_run import parse_modes

        args.out = str(validate.output_dir(args.out, "--out"))
        args.data, args.force_scale = None, 1.0
        return run_modes(args, parse_modes(args.fit_modes, "--fit-modes"),
                         parse_modes(args.predict_modes, "--predict-modes")
                         if args.predict_modes else ())
    case = resolve_case(args.case)
    case.require("update")
    out = validate.output_dir(args.out, "--out")
    s = run_loop(case, out, executor=executor_from_args(args),
                 progress=not args.no_progress, model=args.model)
    if args.json:
        print_json(s)
    else:
        print(format_summary(s))
        print(f"report: {Path(out) / 'report.md'}")
    return 0
