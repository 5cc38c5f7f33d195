"""Command-line input of a series: one measured-data table or the FRF files of a series.

``iwanfe estimate`` and ``iwanfe diagnose`` take either (:func:`ident.series.load_series`)::

    from cli.series_options import add_series_arguments, series_from_args

    def register(subparsers):
        p = subparsers.add_parser("estimate", ...)
        add_series_arguments(p)                 # FILE... and the FRF options
    def run(args):
        data = series_from_args(args)           # MeasuredData; InputError on bad input

With FRF files (one per level) the identification runs first, as ``iwanfe identify``
would: ``--band``, ``--modes``, ``--quantity`` choose it; ``--excitation``,
``--control``, ``--run-order``, ``--reference`` and ``--test`` override the files'
headers. A free-decay time record (``time_s`` column, ``# test = free-decay``; CSV or
UFF 58 time data) is identified along its decay (:mod:`ident.free_decay_table`;
``--band`` and ``--rows`` choose it).
"""
from __future__ import annotations

import sys

from ident.free_decay import DEFAULT_ROWS
from ident.frf_header import CONTROLS, FRF_TESTS
from ident.poles import QUANTITIES
from ident.series import load_series

__all__ = ["add_series_arguments", "check_series_args", "series_from_args", "progress_bar"]


def add_series_arguments(parser, required: bool = True, files_help: str | None = None) -> None:
    """Add ``FILE...`` and the options of a series given as FRF files."""
    parser.add_argument("files", metavar="FILE", nargs="+" if required else "*",
                        help=files_help or "a measured-data CSV, or the FRF files of a "
                        "series (CSV/UFF, one per level; identified first)")
    group = parser.add_argument_group("FRF files (identification)")
    group.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"), default=None,
                       help="frequency band [Hz] of the identification (default: all lines)")
    group.add_argument("--modes", type=int, default=None, metavar="N",
                       help="modes per level (default: decided by stabilization)")
    group.add_argument("--quantity", choices=QUANTITIES, default=None,
                       help="FRF quantity where a file does not say (default receptance)")
    group.add_argument("--excitation", type=float, nargs="+", default=None, metavar="V",
                       help="held level of each FRF file, in file order (overrides the files)")
    group.add_argument("--control", choices=CONTROLS, default=None,
                       help="what every level held (overrides the files; default force)")
    group.add_argument("--run-order", type=int, nargs="+", default=None, metavar="K",
                       help="run order of each FRF file (overrides the files)")
    group.add_argument("--reference", default=None, metavar="POINT",
                       help="drive point label (overrides the files); of a time record: "
                            "the point whose amplitude is the abscissa")
    group.add_argument("--test", choices=FRF_TESTS, default=None,
                       help="test type of every FRF file (overrides the files; default "
                            "stepped-sine): random = H1 averaged over broadband random "
                            "excitation, --excitation its drive RMS")
    _add_amplitude_refit(group)
    group.add_argument("--rows", type=int, default=DEFAULT_ROWS, metavar="N",
                       help="free-decay record: geometric amplitude bins along the decay")


def _add_amplitude_refit(group) -> None:
    """``--amplitude-refit``: force-controlled levels refitted at their peak amplitudes
    (:mod:`ident.amplitude_poles`)."""
    group.add_argument("--amplitude-refit", action="store_true",
                       help="force control: refit each level's pole with its amplitude "
                            "dependence across the band and report the pole at the peak "
                            "(removes the linear fit's bias in micro-slip; not reliable "
                            "where the damping peaks within a band: docs/commands.md)")


def progress_bar(n):
    """A tqdm wrapper for the identification of n FRF files (none for 1-2 files)."""
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover
        return None
    return lambda it: tqdm(it, desc="identify", unit="file", file=sys.stderr,
                           disable=None if n > 2 else True, leave=False)


def check_series_args(args) -> None:
    """ValueError (one line) for a bad ``--modes`` or ``--band``."""
    if args.modes is not None and args.modes < 1:
        raise ValueError(f"--modes must be >= 1, got {args.modes}")
    if args.band is not None and not args.band[0] < args.band[1]:
        raise ValueError(f"--band needs LO < HI, got {args.band[0]:g} {args.band[1]:g}")
    if getattr(args, "rows", DEFAULT_ROWS) < 4:
        raise ValueError(f"--rows must be >= 4, got {args.rows}")


def series_from_args(args):
    """The :class:`ident.modal_data.MeasuredData` the arguments name."""
    check_series_args(args)
    return load_series(args.files, band=args.band, n_modes=args.modes, quantity=args.quantity,
                       excitation=args.excitation, control=args.control,
                       run_order=args.run_order, reference=args.reference,
                       progress=progress_bar(len(args.files)), test=args.test,
                       decay_options={"n_rows": args.rows},
                       amplitude_refit=args.amplitude_refit)
