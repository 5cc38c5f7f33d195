"""``iwanfe identify``: natural frequencies, damping ratios and shapes from FRF files.

Each FILE holds one FRF set (one reference, one or more response points) as CSV or
UFF 58 (:mod:`ident.frf_files`). Several FILEs are several excitation levels: the
excitation of each comes from ``--excitation`` (one value per file, in file order) or
from the file (CSV line ``# excitation = V``; UFF ID line ``excitation=V``). Levels are
numbered by increasing excitation, the file order is the run order, and modes are
followed from level to level by frequency and MAC. ``--out`` writes the measured-data
CSV (``shared/spec/measured-data.md``) that ``iwanfe estimate`` reads.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from cli import validate
from ident.frf_files import read_frf
from ident.identify import identify
from ident.poles import QUANTITIES, mac
from ident.tracking import modal_data_from_levels
from runs.jsonio import print_json

NAME = "identify"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="modal parameters (frequency, damping, shape) from FRF files (CSV, UFF 58)",
        description=(
            "Identify the modes of FRF sets (one reference, one or more response points) "
            "by LSCF with automatic selection of the stable poles and residual-corrected "
            "refinement (ident.identify). One FILE per excitation level; with several "
            "FILEs the modes are followed across levels and --out writes the "
            "measured-data CSV for `iwanfe estimate`. CSV: freq_hz, re_<point>, "
            "im_<point> columns and optional '# quantity = ...', '# excitation = ...' "
            "lines; UFF: data sets 58 (FRF), excitation in an ID line 'excitation=V'."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("files", nargs="+", metavar="FILE", help="FRF files (.csv, .uff, .unv)")
    parser.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"), default=None,
                        help="frequency band [Hz] (default: all lines)")
    parser.add_argument("--modes", type=int, default=None, metavar="N",
                        help="number of modes per level (default: decided by stabilization)")
    parser.add_argument("--quantity", choices=QUANTITIES, default=None,
                        help="FRF quantity if the file does not say (default receptance)")
    parser.add_argument("--excitation", type=float, nargs="+", default=None, metavar="V",
                        help="excitation amplitude of each FILE, in file order (overrides "
                             "the files)")
    parser.add_argument("--max-order", type=int, default=None,
                        help="highest LSCF model order (default from the data)")
    parser.add_argument("--weighting", choices=("auto", "relative", "uniform"), default="auto",
                        help="weights of the maximum-likelihood refinement (default auto: a "
                             "noise model fitted to the residuals)")
    parser.add_argument("--no-pseudo-modes", dest="pseudo_modes", action="store_false",
                        help="no pseudo-modes below/above the band in the refinement")
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
    if args.excitation is not None and len(args.excitation) != len(files):
        raise ValueError(f"--excitation needs one value per FILE: got {len(args.excitation)} "
                         f"values for {len(files)} files")
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
    sets = [read_frf(f) for f in files]
    _check_args(args, sets)
    excitation = []
    for k, s in enumerate(sets):
        e = args.excitation[k] if args.excitation is not None else s.excitation
        if e is not None and not (np.isfinite(e) and e > 0):
            raise ValueError(f"excitation of {files[k]} must be > 0, got {e:g}")
        excitation.append(e)
    several = len(files) > 1
    if (several or args.out) and any(e is None for e in excitation):
        missing = files[excitation.index(None)]
        raise ValueError(f"excitation level of {missing} unknown: give --excitation V per "
                         "file, a CSV line '# excitation = V' or a UFF ID line 'excitation=V'")

    results = []
    try:
        from tqdm import tqdm
        iterator = tqdm(list(enumerate(sets)), desc="identify", unit="file", file=sys.stderr,
                        disable=None if len(sets) > 2 else True, leave=False)
    except ImportError:  # pragma: no cover
        iterator = enumerate(sets)
    for k, s in iterator:
        quantity = s.quantity or args.quantity or "receptance"
        if s.quantity and args.quantity and s.quantity != args.quantity:
            raise ValueError(f"{files[k]} holds {s.quantity}, --quantity says {args.quantity}")
        try:
            res = identify(s.freq_hz, s.frf, band=args.band, n_modes=args.modes,
                           quantity=quantity, max_order=args.max_order,
                           weighting=args.weighting, pseudo_modes=args.pseudo_modes)
        except ValueError as exc:
            raise ValueError(f"{files[k]}: {exc}") from None
        results.append((s, quantity, res))

    if args.plot:
        from viz.stabilization import plot_stabilization
        for k, (s, _, res) in enumerate(results):
            path = Path(args.plot)
            if several:
                path = path.with_name(f"{path.stem}-{k + 1}{path.suffix or '.png'}")
            d = res.diagram
            plot_stabilization(d.order, d.frequency_hz, d.status, indicator_hz=d.indicator_hz,
                               indicator=d.indicator, selected_hz=d.selected_hz,
                               title=Path(files[k]).name, path=path)

    table = None
    if several or args.out:
        table = modal_data_from_levels(excitation, [r.modes for _, _, r in results],
                                       sources=[Path(f).name for f in files])
        if args.out:
            from ident.measured import write_measured
            write_measured(args.out, table)
            short = [int(m) for m in table.modes if np.sum(table.mode == m) < 4]
            if short:
                print(f"iwanfe identify: note: mode(s) {', '.join(map(str, short))} have fewer "
                      "than 4 levels; estimate needs at least 4", file=sys.stderr)

    if args.json:
        print_json(_as_json(files, excitation, results, table))
        return 0
    for k, (s, quantity, res) in enumerate(results):
        _print_set(files[k], s, quantity, excitation[k], res, args.band)
    if table is not None and several:
        print("\nmodes across levels (level, excitation, mode, frequency_hz, zeta, MAC "
              "with the level below):")
        order = np.lexsort((table.level, table.mode))
        for i in order:
            print(f"  {table.level[i]:3d} {table.excitation[i]:10.4g}  mode {table.mode[i]:2d}"
                  f"  {table.extra['x_frequency_hz'][i]:12.5f}  {table.zeta[i]:.6f}"
                  f"  {table.extra['x_mac'][i]:.4f}")
    if args.out:
        print(f"wrote {args.out}")
    return 0


def _print_set(name, s, quantity, excitation, res, band):
    lo, hi = band if band is not None else (s.freq_hz[0], s.freq_hz[-1])
    exc = f", excitation {excitation:g}" if excitation is not None else ""
    print(f"{name}: {len(s.points)} point(s), {quantity}, {lo:g}-{hi:g} Hz{exc}, "
          f"{len(res.modes)} mode(s), fit error {100 * res.fit_error:.3g} %")
    head = f"  {'mode':>4} {'frequency_hz':>13} {'omega2':>13} {'zeta':>10} {'stable':>6}"
    if len(s.points) > 1:
        head += "  shape (" + " ".join(s.points) + ")"
    print(head)
    for i, m in enumerate(res.modes, start=1):
        line = (f"  {i:4d} {m.frequency_hz:13.6f} {m.omega2:13.6e} {m.zeta:10.6f} "
                f"{m.stability:6.2f}")
        if len(s.points) > 1:
            line += "  " + " ".join(f"{v.real:+.3f}" for v in _normalized_shape(m.shape))
        print(line)
    if len(res.modes) > 1 and len(s.points) > 1:
        A = np.stack([m.shape for m in res.modes], axis=1)
        off = mac(A, A) - np.eye(len(res.modes))
        print(f"  largest off-diagonal auto-MAC: {off.max():.3f}")


def _as_json(files, excitation, results, table):
    sets = []
    for k, (s, quantity, res) in enumerate(results):
        sets.append({
            "file": files[k], "points": s.points, "quantity": quantity,
            "excitation": excitation[k], "fit_error": res.fit_error,
            "modes": [{"frequency_hz": m.frequency_hz, "omega2": m.omega2, "zeta": m.zeta,
                       "stability": m.stability,
                       "shape_re": np.real(m.shape), "shape_im": np.imag(m.shape)}
                      for m in res.modes]})
    out = {"sets": sets}
    if table is not None:
        out["levels"] = [{"level": table.level[i], "excitation": table.excitation[i],
                          "mode": table.mode[i], "omega2": table.omega2[i],
                          "zeta": table.zeta[i], "run_order": table.run_order[i],
                          "frequency_hz": table.extra["x_frequency_hz"][i],
                          "mac": table.extra["x_mac"][i], "file": table.extra["x_source"][i]}
                         for i in np.lexsort((table.level, table.mode))]
    return out
