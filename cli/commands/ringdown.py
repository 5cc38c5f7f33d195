"""``iwanfe ringdown``: a simulated free decay, identified like a measured one.

``iwanfe ringdown --case double-beam --mode 4`` starts the mode on its periodic orbit
(EPMC, Jenkins-bank path) with the most loaded joint at half its phi_max, integrates the
reduced model with its joints (:mod:`cases.ringdown_study`), writes the record as a
free-decay CSV, identifies it (:mod:`ident.free_decay`) and compares frequency and
damping against amplitude with the EPMC backbone and the response-controlled virtual
test (:mod:`cases.ringdown_routes`; all of it :func:`cases.ringdown_report.ringdown_report`).
Files in ``--out``: ``free_decay.csv`` (appended
while integrating), ``record.json`` (start, energy balance), ``identified.csv`` (the
measured-data rows of the decay), ``comparison.json`` and ``ringdown.png``; a rerun with
the same inputs reuses the complete record and the stored virtual test.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import math

from cli import validate
from cli.model_options import add_model_argument
from runs.jsonio import print_json

NAME = "ringdown"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME, help="simulated free decay of a mode, identified and compared with the backbone",
        description=(
            "Free decay (ring-down) of a case's mode: start on the mode's periodic orbit "
            "(EPMC, the shaker switched off at phase resonance) or from an impulse at the "
            "drive point, Newmark integration of the reduced model with its joints "
            "(Jenkins banks; a law without banks, Bouc-Wen, by its own step and exact "
            "first harmonic) (average acceleration, time axis pre-warped for the mode, "
            "energy balance checked for banks), the record written as a free-decay CSV "
            "and identified as a "
            "measured one (band-pass, Hilbert envelope and phase, end effects trimmed); "
            "frequency and damping against the drive-point amplitude compared with the "
            "EPMC backbone and a response-controlled virtual test at the same amplitudes."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--case", required=True, metavar="NAME|FILE",
                        help="a shipped case or a case file (.toml) with every joint "
                             "parameter given")
    parser.add_argument("--mode", type=int, required=True, help="1-based stuck-joint mode")
    add_model_argument(parser)
    parser.add_argument("--amplitude", type=float, default=0.5,
                        help="start: largest joint slip / its phi_max or the law's slip "
                             "scale (the joint that slips most in the mode)")
    parser.add_argument("--cycles", type=float, default=500.0,
                        help="record length in periods of the mode")
    parser.add_argument("--start", choices=("orbit", "impulse"), default="orbit")
    parser.add_argument("--steps-per-period", type=int, default=64)
    parser.add_argument("--window", type=float, nargs=2, default=(0.05, 0.8),
                        metavar=("LO", "HI"),
                        help="compared amplitudes, fractions of the start amplitude")
    parser.add_argument("--response-levels", type=int, default=4,
                        help="held amplitudes of the response-controlled virtual test "
                             "(0: skip it)")
    parser.add_argument("--out", default=None,
                        help="output folder (default results/ringdown-CASE-modeN)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def run(args) -> int:
    from cases.ringdown_report import ringdown_report
    from cases.ringdown_study import RingdownSettings

    lo, hi = args.window
    if not 0 < lo < hi <= 1:
        raise ValueError(f"--window must satisfy 0 < LO < HI <= 1, got {lo} {hi}")
    if not 0 <= args.response_levels <= 50:
        raise ValueError(f"--response-levels must be in 0..50, got {args.response_levels}")
    settings = RingdownSettings(mode=args.mode, amplitude=args.amplitude, cycles=args.cycles,
                                steps_per_period=args.steps_per_period, start=args.start)
    label = Path(args.case).stem if args.case.endswith(".toml") else args.case
    out = validate.output_dir(args.out or f"results/ringdown-{label}-mode{args.mode}",
                              "--out")
    out.mkdir(parents=True, exist_ok=True)
    report = ringdown_report(args.case, settings, out, (lo, hi), args.response_levels,
                             progress=not args.no_progress, model=args.model)
    if args.json:
        print_json(report)
        return 0
    print("\n".join(report_lines(report)))
    return 0


def report_lines(rep: dict) -> list[str]:
    """The report as text."""
    from cases.ringdown_routes import comparison_rows

    r, c = rep["record"], rep["comparison"]
    e = r["energy_J"]
    s = r["start"]
    start = (f"EPMC orbit ({s.get('path', 'bank')} path) with joint {s['joint']} at slip "
             f"{s['slip_m']:.4g} m" if s["start"] == "orbit" else
             f"impulse {s['impulse_Ns']:.4g} N s at the drive point")
    out = [f"{rep['case']}, mode {rep['mode']}: simulated free decay, {start}"
           + (f"; the orbit {s['reached']}" if s.get("reached") else ""),
           f"  {r['samples']} samples, {r['settings']['steps_per_period']} steps per period of "
           f"{r['omega0_rad_s'] / (2 * math.pi):.4f} Hz (time axis pre-warped), "
           f"integration {r['integration_s']:.2f} s" + (" (stored record reused)"
                                                        if r.get("loaded") else ""),
           "  energy balance: n/a (only Jenkins banks state their stored energy and "
           "friction work)" if e is None else
           f"  energy balance (J, computed): viscous {e['viscous']:.5g}, joint dissipation "
           f"{e['joint_dissipation']:.5g}, change of kinetic + strain + joint stored "
           f"{e['kinetic_change'] + e['strain_change'] + e['joint_stored_change']:.5g}; "
           f"relative residual {e['relative_residual']:.2e}"]
    w = c["window"]
    over = [r["over_start"] for r in c["rows"]]
    out.append(f"  compared window: {w['lo']:g}..{w['hi']:g} x the start amplitude "
               f"{w['start_amplitude_m']:.4g} m: {w['rows_in_window']} rows at "
               f"{min(over):.3g}..{max(over):.3g} x start (the window's rows and the "
               f"nearest beyond each end); {w['rows_outside']} further rows not compared")
    for note in rep["identification"].get("notes", []):
        out.append(f"  identification: {note}")
    out += comparison_rows(c)
    d = c["max_deviation"]["ringdown"]
    t = c["targets"]
    out.append(f"  ring-down vs EPMC: largest |df/f| {d['frequency']:.2e} (target "
               f"{t['frequency']:g}), |dzeta/zeta| {d['zeta']:.2e} (target {t['zeta']:g}): "
               + ("met" if c["met"] else "NOT met"))
    out.append("  files: " + ", ".join(rep["files"]) + f"; {rep['elapsed_s']:.1f} s")
    return out
