"""``iwanfe export``: write a case's mesh and mode shapes for ParaView (.vtu / .xdmf).

Example::

    iwanfe export --case double-beam --out modes.vtu --modes 6
"""
from __future__ import annotations

from pathlib import Path

from cases.registry import CASES, build_case, case_modes


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "export",
        help="write mesh + mode shapes to .vtu or .xdmf (ParaView)",
        description=(
            "Write the strips of a case with its lowest mode shapes as point data "
            "mode_1, mode_2, ... (displacement 3-vectors, mass-normalized) and the natural "
            "frequencies as field data 'frequency_hz' (.vtu; for .xdmf in the .h5 file). "
            "Format from the suffix of --out."
        ),
    )
    p.add_argument("--case", choices=CASES, default="double-beam", help="study (default: double-beam)")
    p.add_argument("--out", required=True, metavar="FILE.vtu|FILE.xdmf", help="file to write")
    p.add_argument("--modes", type=int, default=6, metavar="N",
                   help="number of modes from the lowest (default: 6)")
    p.add_argument("--geometry", choices=("lines", "slabs"), default="lines",
                   help="centroid lines with rotations (default) or hexahedral slabs")
    p.set_defaults(func=run)


def run(args) -> int:
    from viz.export import EXPORT_SUFFIXES, write_modes

    out = Path(args.out)
    if out.suffix.lower() not in EXPORT_SUFFIXES:
        raise ValueError(
            f"unknown export format '{out.suffix or out.name}': --out must end in "
            + " or ".join(EXPORT_SUFFIXES)
        )
    if args.modes < 1:
        raise ValueError(f"--modes must be >= 1, got {args.modes}")
    model = build_case(args.case)
    freqs, shapes = case_modes(model, args.modes)
    modes = [model.strip_displacements(shapes[:, k]) for k in range(shapes.shape[1])]
    written = write_modes(out, model.strips, modes, freqs, geometry=args.geometry)
    n_points = sum(len(s.x) for s in model.strips)
    print(
        f"wrote {', '.join(str(p) for p in written)}: {len(modes)} modes, "
        f"{len(model.strips)} strips, {n_points} nodes ({args.geometry}); f = "
        + ", ".join(f"{f:.2f}" for f in freqs) + " Hz"
    )
    return 0
