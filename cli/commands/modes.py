"""``iwanfe modes``: natural modes of a case in a frequency band.

Example::

    iwanfe modes --case double-beam --band 50 450 --json
"""
from __future__ import annotations

from cases.mode_report import mode_report
from cli.model_options import add_model_argument, case_of
from cases.registry import DEFAULT_CASE, SHIPPED
from runs.jsonio import print_json


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "modes",
        help="natural modes of a case in a band (frequency, kind, joint slip)",
        description=(
            "Natural frequencies of the case's linear model (joints stuck) in a band, with "
            "the mode kind, the glue-slip participation (fraction of the mode's strain "
            "energy in the joints' tangential springs = d ln(omega^2)/d ln K_T) and which "
            "mode matches the case's measured frequency (within 0.5 %)."
        ),
    )
    p.add_argument("--case", default=DEFAULT_CASE, metavar="NAME|FILE",
                   help=f"shipped case ({', '.join(SHIPPED)}) or case file (.toml); "
                        f"default {DEFAULT_CASE}")
    add_model_argument(p)
    p.add_argument("--band", nargs=2, type=float, metavar=("LO", "HI"), default=None,
                   help="frequency band in Hz (default: 0 to 1000 Hz, or to 1.8 times the "
                        "case's measured frequency where that is higher, within what the "
                        "mesh represents)")
    p.add_argument("--element-size", type=float, default=None, metavar="M",
                   help="element size in m (default: the case file's [mesh])")
    p.add_argument("--uncalibrated", action="store_true",
                   help="use the file's values instead of the calibrated ones")
    p.add_argument("--json", action="store_true",
                   help="print the modes as a JSON list (index, frequency_hz, omega2, kind, "
                        "bending_order, glue_slip, matches_measured) instead of a table")
    p.set_defaults(func=run)


def run(args) -> int:
    report = mode_report(case_of(args), band=args.band,
                         element_size=args.element_size, uncalibrated=args.uncalibrated)
    if args.json:  # a list of mode objects; the calibration statement is in the table
        print_json(report["modes"])
        return 0
    print(f"{report['case']} ({report['model']} model, {report['n_free_dofs']} free DOFs), "
          f"modes in {report['band_hz'][0]:g}-{report['band_hz'][1]:g} Hz")
    print(f"{'index':>5}  {'freq_Hz':>9}  {'kind':<22} {'bend#':>5}  {'glue_slip':>9}  match")
    for r in report["modes"]:
        bend = str(r["bending_order"]) if r["bending_order"] else "-"
        print(f"{r['index']:>5}  {r['frequency_hz']:9.2f}  {r['kind']:<22} {bend:>5}  "
              f"{r['glue_slip']:9.2e}  {'<- measured' if r['matches_measured'] else ''}")
    if not report["modes"]:
        print("  (no modes in the band)")
    cal = report["calibration"]
    for p in cal["parameters"] if cal else ():
        print(f"calibrated {p['parameter']}: {p['initial']:.6g} -> {p['calibrated']:.7g}"
              + (" (at a bound)" if p["at_bound"] else ""))
    for t in cal["targets"] if cal else ():
        print(f"  bending mode {t['bending_mode']}: {t['calibrated_hz']:.2f} Hz, measured "
              f"{t['frequency_hz']:g} Hz; at the file's values {t['initial_hz']:.2f} Hz "
              f"({100 * (t['initial_hz'] / t['frequency_hz'] - 1):+.1f} %)")
    return 0
