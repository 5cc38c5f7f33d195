"""``iwanfe case check FILE|NAME``: read a case file and print its model summary.

Example::

    iwanfe case check docs/case-files/bolted-lap-cantilever.toml
"""
from __future__ import annotations

import numpy as np

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


def _measured(case, modes: list) -> dict | None:
    """The case's measured data read and checked against the measured-data spec (FRF
    files identified first): its path, modes and levels; None when it names none. A bad
    table raises the reader's one-line error (exit 2). ``modes``: the summary's modes,
    to say when the declared ``[measured] mode`` is not the bending mode nearest the
    table's lowest level (the one the FE loop follows)."""
    if "measured_data" not in case.capabilities:
        return None
    from ident.measured import read_measured

    path = case.measured_data()
    data = read_measured(path)
    warnings = list(data.warnings)
    declared = None
    if "calibrated_file" in case.capabilities:
        meas = case.require("calibrated_file")()[0].measured
        declared = getattr(meas, "mode", None)
    labels = [int(m) for m in data.modes]
    bending = [m for m in modes if m.get("bending_order")]
    if declared and bending:
        d = data.for_mode(declared if declared in labels else labels[0])
        f1 = float(np.sqrt(d.omega2[np.argmin(d.excitation)]) / (2 * np.pi))
        near = min(bending, key=lambda m: abs(m["frequency_hz"] - f1))
        if near["bending_order"] != declared:
            warnings.append(
                f"[measured] mode = {declared} (bending mode {declared}) but the table's "
                f"lowest level ({f1:.4g} Hz, measured) lies nearest bending mode "
                f"{near['bending_order']} ({near['frequency_hz']:.4g} Hz in the model as "
                f"given or calibrated), which the FE loop follows (the joint-slipping mode "
                f"nearest the measured frequency)")
    return {"file": str(path), "modes": labels,
            "levels": {int(m): len(set(data.for_mode(int(m)).level.tolist()))
                       for m in data.modes},
            "rows": len(data), "warnings": warnings}


def run(args) -> int:
    from casefile.summary import format_summary

    case = resolve_case(args.case)
    summary = case.summary()
    measured = _measured(case, summary.get("modes", []))
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
