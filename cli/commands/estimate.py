"""``iwanfe estimate``: Iwan chi and R from the growth of damping between levels.

Reads a measured-data CSV (``shared/spec/measured-data.md``), fits chi and
``|kappa1| B`` to the successive damping differences of the chosen levels (paper eq.
33-35 with the factor 2 of eq. 45 restored), predicts frequency and damping at every
level (eq. 43, 46), and with ``--case`` computes B~ and R~ from the FE model (eq. 37).
"""
from __future__ import annotations

import argparse
import math

from inverse.estimate import (
    CASES,
    DEFAULT_CONFIDENCE,
    DEFAULT_FORCE_SCALE,
    METHODS,
    estimate,
    format_table,
)
from runs.jsonio import print_json
from ident.measured import read_measured

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
            "regressed on the file's response_amplitude column."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", help="measured-data CSV file")
    parser.add_argument("--case", choices=CASES, default=None,
                        help="FE model for B~ and R~ (without it B and R are null)")
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
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--plot", metavar="FILE.png", default=None,
                        help="write the log-slope plot (paper Fig. 8)")
    parser.set_defaults(func=run)


def run(args) -> int:
    if not math.isfinite(args.force_scale) or args.force_scale <= 0:
        raise ValueError(f"--force-scale must be a positive number, got {args.force_scale}")
    data = read_measured(args.file)
    est = estimate(data, fit_levels=args.fit_levels, method=args.method, mode=args.mode,
                   case=args.case, force_scale=args.force_scale, fe_mode=args.fe_mode,
                   confidence=args.confidence)
    if args.plot:
        from viz.logslope import plot_estimate

        plot_estimate(est, args.plot, title=f"{args.file}: mode {est.mode}")
    if args.json:
        out = est.to_dict()
        out["file"] = args.file
        print_json(out)
    else:
        print(format_table(est, args.file))
        if args.plot:
            print(f"plot written to {args.plot}")
    return 0
