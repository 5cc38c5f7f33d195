"""``iwanfe render``: off-screen 3-D picture of one mode shape of a case (PNG).

Example::

    iwanfe render --case double-beam --mode 2 --out mode2.png
"""
from __future__ import annotations

import math

from cli.model_options import add_model_argument, case_of
from cases.registry import DEFAULT_CASE, SHIPPED, case_modes
from cli import validate
from cli.commands.export import MAX_MODES
from runs.jsonio import print_json


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "render",
        help="off-screen 3-D render of a mode shape (PNG)",
        description=(
            "Render one mode shape of a case as deformed 3-D slabs (pyvista, off-screen): "
            "colour = displacement magnitude, translucent undeformed ghost, through-"
            "thickness fibres showing rotation and interface slip. Modes are numbered "
            "from 1 (lowest frequency). Thickness and axial motion are exaggerated by the "
            "same factor so the slip stays consistent with the drawn thickness."
        ),
    )
    p.add_argument("--case", default=DEFAULT_CASE, metavar="NAME|FILE",
                   help=f"shipped case ({', '.join(SHIPPED)}) or case file (.toml); "
                        f"default {DEFAULT_CASE}")
    add_model_argument(p)
    p.add_argument("--mode", type=int, required=True, metavar="N",
                   help=f"mode number, 1 = lowest frequency (1..{MAX_MODES})")
    p.add_argument("--out", required=True, metavar="FILE.png",
                   help="PNG file to write (its folder must exist)")
    p.add_argument("--scale", type=float, default=None, metavar="S",
                   help="displacement multiplier (default: peak deflection = 10%% of length)")
    p.add_argument("--thickness-scale", type=float, default=None, metavar="T",
                   help="thickness exaggeration (default: stack height = 8%% of length)")
    p.add_argument("--size", type=int, nargs=2, default=(1400, 800), metavar=("W", "H"),
                   help="image size in pixels (default: 1400 800)")
    p.add_argument("--json", action="store_true",
                   help="print JSON (file, mode, frequency, kind, scales) instead of a line")
    p.set_defaults(func=run)


def _check_args(args) -> None:
    validate.output_file(args.out, "--out", (".png",))
    if not 1 <= args.mode <= MAX_MODES:
        raise ValueError(f"--mode {args.mode}: must be in 1..{MAX_MODES}")
    if args.scale is not None and not (math.isfinite(args.scale) and args.scale != 0
                                       and abs(args.scale) < 1e12):
        raise ValueError(f"--scale {args.scale:g}: must be finite, non-zero and below 1e12 "
                         "(mass-normalized shapes are O(1) m/sqrt(kg); 1e12 moves any point "
                         "out of the picture)")
    if args.thickness_scale is not None and not (math.isfinite(args.thickness_scale)
                                                 and 0 < args.thickness_scale <= 1e4):
        raise ValueError(f"--thickness-scale {args.thickness_scale:g}: must be in (0, 1e4] "
                         "(1e4 draws a 1 mm strip 10 m thick)")
    if min(args.size) < 16 or max(args.size) > 8192:
        raise ValueError(f"--size {args.size[0]} {args.size[1]}: must be between 16 and 8192 "
                         "pixels")


def run(args) -> int:
    _check_args(args)
    from viz.render import render_mode_shape

    case = case_of(args)
    model = case.fe_model()
    freqs, shapes = case_modes(model, args.mode)
    shape = shapes[:, args.mode - 1]
    kind = model.classify_mode(shape)
    result = render_mode_shape(
        model.strips, model.strip_displacements(shape), args.out,
        mode_number=args.mode, frequency_hz=float(freqs[-1]), kind=kind,
        scale=args.scale, thickness_scale=args.thickness_scale, window_size=tuple(args.size),
        scalar_label="displacement magnitude (mass-normalized, m/sqrt(kg))",
    )
    if args.json:
        print_json({"case": case.name, "file": str(result.path), "mode": args.mode,
                    "frequency_hz": float(freqs[-1]), "kind": kind, "scale": result.scale,
                    "thickness_scale": result.thickness_scale, "seconds": result.seconds})
        return 0
    print(
        f"wrote {result.path}: mode {args.mode}, {freqs[-1]:.2f} Hz, {kind} "
        f"(displacement x{result.scale:.3g}, thickness x{result.thickness_scale:.3g}, "
        f"{result.seconds:.1f} s)"
    )
    return 0
