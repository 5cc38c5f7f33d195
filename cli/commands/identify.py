"""``iwanfe identify``: natural frequencies, damping ratios and shapes from FRF files.

Each FILE holds one FRF set (one reference, one or more response points) as CSV or
UFF 58 (:mod:`ident.frf_files`). Several FILEs are the levels of a stepped-sine series
(:mod:`ident.series`): each file's header says what the level held (``# excitation``),
under which ``# control`` (force or response) and when (``# run_order``); the command
line overrides the files. Levels are numbered by increasing held level, the levels
agree on the number of modes in the band, modes are followed from level to level by
frequency and MAC, and every mode carries its fit warnings (fit error, stability, band
sensitivity). ``--out`` writes the measured-data CSV (``docs/formats/measured-data.md``)
that ``iwanfe estimate`` and ``iwanfe diagnose`` read.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from cli import validate
from cli.commands.identify_decay import run_free_decay
from ident.time_records import is_time_record
from ident.poles import mac
from ident.series import identify_series, read_series_sets
from ident.series_table import series_table
from cli.series_options import add_series_arguments, check_series_args, progress_bar
from runs.jsonio import print_json

NAME = "identify"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="modal parameters (frequency, damping, shape) from FRF files (CSV, UFF 58)",
        description=(
            "A free-decay time record (CSV time_s,<point>... with '# test = free-decay', "
            "or UFF 58 time data) gives frequency and damping against amplitude along "
            "the decay instead (Hilbert envelope and phase, checked by peaks and zero "
            "crossings; docs/free-decay-and-random.md). "
            "Identify the modes of FRF sets (one reference, one or more response points) "
            "by LSCF with automatic selection of the stable poles and residual-corrected "
            "refinement (ident.identify). One FILE per excitation level; with several "
            "FILEs the modes are followed across levels and --out writes the "
            "measured-data CSV for `iwanfe estimate` and `iwanfe diagnose`. CSV: freq_hz, "
            "re_<point>, im_<point> and an optional force column (N per line), optional "
            "'# quantity|control|run_order|excitation|reference = ...' lines; UFF: data "
            "sets 58 (FRF), the same keys as key=value in an ID line. excitation is the "
            "level the test held: the drive amplitude under force control, the "
            "drive-point response amplitude under response control."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_series_arguments(parser, files_help="FRF files (.csv, .uff, .unv), one per level")
    parser.add_argument("--no-band-check", dest="band_check", action="store_false",
                        help="skip the band-sensitivity check (one more identification "
                             "per mode and level)")
    parser.add_argument("--max-order", type=int, default=None,
                        help="highest LSCF model order (default from the data)")
    parser.add_argument("--weighting", choices=("auto", "relative", "uniform"), default="auto",
                        help="weights of the maximum-likelihood refinement (default auto: a "
                             "noise model fitted to the residuals)")
    parser.add_argument("--no-pseudo-modes", dest="pseudo_modes", action="store_false",
                        help="no fixed out-of-band poles (F-tested linear terms below/above "
                             "the band) in the refinement")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--plot", metavar="FILE.png", default=None,
                        help="stabilization diagram (several FILEs: FILE-<level>.png)")
    parser.add_argument("--out", metavar="FILE.csv", default=None,
                        help="write the identified modal data as measured-data CSV")
    parser.set_defaults(func=run)


def _normalized_shape(shape) -> np.ndarray:
    """Residue vector rotated so its largest entry is real and positive, max |.| = 1."""
    shape = np.asarray(shape)
    k = np.argmax(np.abs(shape))
    return shape / shape[k] if shape[k] != 0 else shape


#: Lines per LSCF pole. An order-n model has n poles, and a pole's frequency and damping
#: are fixed by the lines of its half-power band, about two either side of the peak: n
#: poles need about 4 n lines, and orders above (lines in the band)/4 only add poles that
#: fit the noise (the default order, ident.identify._default_max_order, stops there too).
#: The cost grows as n^4 (measured: 4.6 s at order 60, 24 s at order 240 for 961 lines x
#: 4 points; order 100000 would allocate 149 GiB).
LINES_PER_POLE = 4
MIN_LINES = 8           # ident.identify: fewer lines in the band are refused


def _check_args(args, sets) -> None:
    """Every option against the files, before any identification (one-line errors)."""
    files = args.files
    for e in args.excitation or ():
        validate.positive(e, "--excitation")
    if args.band is not None:
        validate.band(args.band)
    for k, s in enumerate(sets):
        lo, hi = args.band if args.band is not None else (s.freq_hz[0], s.freq_hz[-1])
        n_lines = int(np.sum((s.freq_hz >= lo) & (s.freq_hz <= hi)))
        if n_lines < MIN_LINES:
            raise ValueError(f"--band {lo:g} {hi:g}: {files[k]} has {n_lines} lines in it, "
                             f"at least {MIN_LINES} are needed")
        top = n_lines // LINES_PER_POLE
        for option, value in (("--max-order", args.max_order), ("--modes", args.modes)):
            if value is not None and not 1 <= value <= top:
                raise ValueError(f"{option} {value}: must be in 1..{top} for {files[k]} "
                                 f"({n_lines} lines in the band, {LINES_PER_POLE} per LSCF "
                                 "pole)")
    if args.plot:
        validate.output_file(args.plot, "--plot", (".png",))
    if args.out:
        validate.output_file(args.out, "--out", (".csv",))


def run(args) -> int:
    files = list(args.files)
    check_series_args(args)
    if any(is_time_record(f) for f in files):
        return run_free_decay(args)
    sets = read_series_sets(files, args.excitation, args.control, args.run_order,
                            args.reference, args.test)
    _check_args(args, sets)
    options = dict(max_order=args.max_order, weighting=args.weighting,
                   pseudo_modes=args.pseudo_modes)
    fits = identify_series(sets, band=args.band, n_modes=args.modes, quantity=args.quantity,
                           options=options, progress=progress_bar(len(sets)),
                           check_band=args.band_check, amplitude_refit=args.amplitude_refit)

    if args.plot:
        from viz.stabilization import plot_stabilization
        for k, fit in enumerate(fits):
            path = Path(args.plot)
            if len(files) > 1:
                path = path.with_name(f"{path.stem}-{k + 1}{path.suffix or '.png'}")
            d = fit.result.diagram
            plot_stabilization(d.order, d.frequency_hz, d.status, indicator_hz=d.indicator_hz,
                               indicator=d.indicator, selected_hz=d.selected_hz,
                               title=Path(files[k]).name, path=path)

    table = None
    if len(files) > 1 or args.out:
        table = series_table(fits)
        if args.out:
            from ident.measured import write_measured
            write_measured(args.out, table)
            short = [int(m) for m in table.modes if np.sum(table.mode == m) < 4]
            if short:
                print(f"iwanfe identify: note: mode(s) {', '.join(map(str, short))} have fewer "
                      "than 4 levels; estimate needs at least 4", file=sys.stderr)

    if args.json:
        print_json(_as_json(files, fits, table))
        return 0
    for k, fit in enumerate(fits):
        _print_set(files[k], fit, args.band)
    if table is not None and len(files) > 1:
        _print_levels(table)
    if args.out:
        print(f"wrote {args.out}")
    return 0


def _print_levels(table):
    held = "response_amplitude" if table.response_abscissa else "excitation"
    test = "" if table.test[0] == "stepped-sine" else f"test {table.test[0]}, "
    print(f"\nmodes across levels ({test}control {table.control[0]}; levels by {held}; "
          "std = the identification's standard uncertainty; MAC with the level below):")
    print(f"  {'level':>5} {'excitation':>11} {'response':>11} {'mode':>4} {'frequency_hz':>12}"
          f" {'std_hz':>8} {'zeta':>9} {'std':>8} {'fit_err%':>8} {'MAC':>6}")
    x = table.extra
    for i in np.lexsort((table.level, table.mode)):
        f = x["x_frequency_hz"][i]
        s_f = (table.omega2_std[i] / (8 * np.pi ** 2 * f) if table.omega2_std is not None
               else float("nan"))
        s_z = table.zeta_std[i] if table.zeta_std is not None else float("nan")
        print(f"  {table.level[i]:5d} {table.excitation[i]:11.4g} "
              f"{table.response_amplitude[i]:11.4g} {table.mode[i]:4d} {f:12.5f} {s_f:8.2g} "
              f"{table.zeta[i]:9.6f} {s_z:8.2g} {100 * x['x_fit_error'][i]:8.3g} "
              f"{x['x_mac'][i]:6.4f}")
    refit = np.isfinite(np.asarray(x.get("x_omega2_slope", []), float))
    if refit.any():
        rest = ("" if refit.all() else "; the other levels keep the linear fit (their "
                "warnings say why)")
        print(f"  frequency, zeta and response at each level's peak amplitude (fitted with "
              f"their slopes across the band, --amplitude-refit) at levels "
              f"{', '.join(map(str, np.unique(table.level[refit])))}{rest}")
    for w in table.warnings:
        print(f"warning: {w}")


def _print_set(name, fit, band):
    s, res = fit.frfset, fit.result
    lo, hi = res.band_hz
    held = f", {fit.control} control, held {s.excitation:g}" if s.excitation is not None else ""
    print(f"{name}: {len(s.points)} point(s), {fit.quantity}, {lo:g}-{hi:g} Hz{held}, "
          f"{len(res.modes)} mode(s), fit error {100 * res.fit_error:.3g} %")
    head = (f"  {'mode':>4} {'frequency_hz':>13} {'omega2':>13} {'zeta':>10} {'std_zeta':>9} "
            f"{'stable':>6}")
    if len(s.points) > 1:
        head += "  shape (" + " ".join(s.points) + ")"
    print(head)
    for i, m in enumerate(res.modes, start=1):
        line = (f"  {i:4d} {m.frequency_hz:13.6f} {m.omega2:13.6e} {m.zeta:10.6f} "
                f"{m.zeta_std:9.2g} {m.stability:6.2f}")
        if len(s.points) > 1:
            line += "  " + " ".join(f"{v.real:+.3f}" for v in _normalized_shape(m.shape))
        print(line)
    if len(res.modes) > 1 and len(s.points) > 1:
        A = np.stack([m.shape for m in res.modes], axis=1)
        off = mac(A, A) - np.eye(len(res.modes))
        print(f"  largest off-diagonal auto-MAC: {off.max():.3f}")
    for i, warns in enumerate(fit.warnings, start=1):
        for w in warns:
            print(f"  warning: mode {i}: {w}")


def _as_json(files, fits, table):
    sets = []
    for k, fit in enumerate(fits):
        s, res = fit.frfset, fit.result
        sets.append({
            "file": files[k], "points": s.points, "quantity": fit.quantity,
            "control": fit.control, "excitation": s.excitation, "run_order": s.run_order,
            "reference": s.reference, "band_hz": list(res.band_hz),
            "fit_error": res.fit_error, "residual_correlation": res.residual_correlation,
            "modes": [{"frequency_hz": m.frequency_hz, "omega2": m.omega2, "zeta": m.zeta,
                       "omega2_std": m.omega2_std, "zeta_std": m.zeta_std,
                       "stability": m.stability, "warnings": fit.warnings[i],
                       "shape_re": np.real(m.shape), "shape_im": np.imag(m.shape)}
                      for i, m in enumerate(res.modes)]})
    out = {"sets": sets}
    if table is not None:
        x = table.extra

        def opt(a, i):
            return None if a is None else a[i]

        out["control"] = str(table.control[0])
        out["test"] = str(table.test[0])
        out["levels"] = [{"level": table.level[i], "excitation": table.excitation[i],
                          "response_amplitude": opt(table.response_amplitude, i),
                          "mode": table.mode[i], "omega2": table.omega2[i],
                          "omega2_std": opt(table.omega2_std, i), "zeta": table.zeta[i],
                          "zeta_std": opt(table.zeta_std, i), "run_order": table.run_order[i],
                          "frequency_hz": x["x_frequency_hz"][i], "mac": x["x_mac"][i],
                          "fit_error": x["x_fit_error"][i], "file": x["x_source"][i],
                          "warnings": [w for w in str(x["x_warning"][i]).split(" | ") if w]}
                         for i in np.lexsort((table.level, table.mode))]
        out["data_warnings"] = table.warnings
    return out
