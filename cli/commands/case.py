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
                     "(given, calibrated, fitted, default with its source). A bad file is "
                     "one line naming table and key, exit status 2."))
    p.add_argument("action", choices=("check",), help="what to do with the case file")
    p.add_argument("case", metavar="FILE|NAME", help="case file (.toml) or shipped name")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from cases.casefile.summary import format_summary

    summary = resolve_case(args.case).summary()
    if args.json:
        print_json(summary)
    else:
        print(format_summary(summary))
    return 0
