"""``iwanfe export``: write a case's mesh and mode shapes for ParaView (.vtu / .xdmf).

Example::

    iwanfe export --case double-beam --out modes.vtu --modes 6
"""
from __future__ import annotations

from cli.model_options import add_model_argument, case_of
from cases.registry import DEFAULT_CASE, SHIPPED, case_modes
from cli import validate
from runs.jsonio import print_json

#: Largest --modes: the double beam has 39 modes below 23 kHz (``iwanfe modes
#: --band 0 23000``); above that the Euler-Bernoulli model and its mesh say nothing true.
MAX_MODES = 39


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "export",
        help="write mesh + mode shapes to .vtu or .xdmf (ParaView)",
        description=(
            "Write the strips of a case with its lowest mode shapes as point data "
            "mode_1, mode_2, ... (displacement 3-vectors, mass-normalized) and each "
            "natural frequency as point data frequency_hz_1, frequency_hz_2, ... (the same "
            "at every point; .vtu also as field data 'frequency_hz'). Format from the "
            "suffix of --out (.xdmf comes with its .h5)."
        ),
    )
    p.add_argument("--case", default=DEFAULT_CASE, metavar="NAME|FILE",
                   help=f"shipped case ({', '.join(SHIPPED)}) or case file (.toml); "
                        f"default {DEFAULT_CASE}")
    add_model_argument(p)
    p.add_argument("--out", required=True, metavar="FILE.vtu|FILE.xdmf",
                   help="file to write (its folder must exist)")
    p.add_argument("--modes", type=int, default=6, metavar="N",
                   help=f"number of modes from the lowest, 1..{MAX_MODES}")
    p.add_argument("--geometry", choices=("lines", "slabs"), default="lines",
                   help="centroid lines with rotations (default) or hexahedral slabs")
    p.add_argument("--json", action="store_true",
                   help="print JSON (files, modes with frequency and kind) instead of a line")
    p.set_defaults(func=run)


def run(args) -> int:
    from viz.export import EXPORT_SUFFIXES, write_modes

    out = validate.output_file(args.out, "--out", EXPORT_SUFFIXES)
    if not 1 <= args.modes <= MAX_MODES:
        raise ValueError(f"--modes {args.modes}: must be in 1..{MAX_MODES}")
    case = case_of(args)
    model = case.fe_model()
    freqs, shapes = case_modes(model, args.modes)
    modes = [model.strip_displacements(shapes[:, k]) for k in range(shapes.shape[1])]
    written = write_modes(out, model.strips, modes, freqs, geometry=args.geometry)
    n_points = sum(len(s.x) for s in model.strips)
    if args.json:
        print_json({"case": case.name, "files": [str(p) for p in written],
                    "geometry": args.geometry, "n_strips": len(model.strips),
                    "n_nodes": n_points,
                    "modes": [{"mode": k + 1, "frequency_hz": float(f),
                               "kind": model.classify_mode(shapes[:, k])}
                              for k, f in enumerate(freqs)]})
        return 0
    print(
        f"wrote {', '.join(str(p) for p in written)}: {len(modes)} modes, "
        f"{len(model.strips)} strips, {n_points} nodes ({args.geometry}); f = "
        + ", ".join(f"{f:.2f}" for f in freqs) + " Hz"
    )
    return 0
