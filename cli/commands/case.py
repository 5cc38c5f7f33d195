"""``iwanfe case check FILE|NAME``: read a case file and print its model summary.

Example::

    iwanfe case check docs/case-files/bolted-lap-cantilever.toml
"""
from __future__ import annotations

from cases.registry import resolve_case
from runs.jsonio import print_json


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "case", help="case files: check one and print its model summary",
        description=("Case files describe a jointed beam assembly in TOML "
                     "(docs/case-files.md). 'check' reads one (or a shipped case by name), "
                     "calibrates what it asks to, and prints mass, first modes, the joint "
                     "elements with their stiffness shares and the kind of every parameter "
                     "(given, calibrated, fitted, default with its source), and reads and checks "
                     "its [measured] table. A bad file is one line naming table and key (or "
                     "the table's line and column), exit status 2."))
    p.add_argument("action", choices=("check",), help="what to do with the case file")
    p.add_argument("case", metavar="FILE|NAME", help="case file (.toml) or shipped name")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def _measured(case) -> dict | None:
    """The case's measured data read and checked against the measured-data spec (FRF
    files identified first): its path, modes and levels; None when it names none. A bad
    table raises the reader's one-line error (exit 2)."""
    if "measured_data" not in case.capabilities:
        return None
    from ident.measured import read_measured

    path = case.measured_data()
    data = read_measured(path)
    return {"file": str(path), "modes": [int(m) for m in data.modes],
            "levels": {int(m): len(set(data.for_mode(int(m)).level.tolist()))
                       for m in data.modes},
            "rows": len(data), "warnings": list(data.warnings)}


def run(args) -> int:
    from cases.casefile.summary import format_summary

    case = resolve_case(args.case)
    summary = case.summary()
    measured = _measured(case)
    if args.json:
        print_json({**summary, "measured_data": measured})
        return 0
    print(format_summary(summary))
    if measured is not None:
        levels = ", ".join(f"mode {m}: {n} levels" for m, n in measured["levels"].items())
        print(f"measured data: {measured['file']} read and checked ({measured['rows']} rows; "
              f"{levels})")
        for w in measured["warnings"]:
            print(f"warning: {w}")
    return 0
