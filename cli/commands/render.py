"""``iwanfe render``: off-screen 3-D picture of one mode shape of a case (PNG).

Example::

    iwanfe render --case double-beam --mode 2 --out mode2.png
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cases.registry import CASES, build_case, case_modes


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
    p.add_argument("--case", choices=CASES, default="double-beam", help="study (default: double-beam)")
    p.add_argument("--mode", type=int, required=True, metavar="N",
                   help="mode number, 1 = lowest frequency")
    p.add_argument("--out", required=True, metavar="FILE.png", help="PNG file to write")
    p.add_argument("--scale", type=float, default=None, metavar="S",
                   help="displacement multiplier (default: peak deflection = 10%% of length)")
    p.add_argument("--thickness-scale", type=float, default=None, metavar="T",
                   help="thickness exaggeration (default: stack height = 8%% of length)")
    p.add_argument("--size", type=int, nargs=2, default=(1400, 800), metavar=("W", "H"),
                   help="image size in pixels (default: 1400 800)")
    p.set_defaults(func=run)


def run(args) -> int:
    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise ValueError(f"--out must end in .png, got '{out.name}'")
    if args.mode < 1:
        raise ValueError(f"--mode must be >= 1, got {args.mode}")
    if args.scale is not None and not (np.isfinite(args.scale) and args.scale != 0):
        raise ValueError(f"--scale must be finite and non-zero, got {args.scale}")
    if args.thickness_scale is not None and not (np.isfinite(args.thickness_scale)
                                                 and args.thickness_scale > 0):
        raise ValueError(f"--thickness-scale must be positive, got {args.thickness_scale}")
    if min(args.size) < 16 or max(args.size) > 8192:
        raise ValueError(f"--size must be between 16 and 8192 pixels, got {args.size}")

    from viz.render import render_mode_shape

    model = build_case(args.case)
    freqs, shapes = case_modes(model, args.mode)
    shape = shapes[:, args.mode - 1]
    kind = model.classify_mode(shape)
    result = render_mode_shape(
        model.strips, model.strip_displacements(shape), out,
        mode_number=args.mode, frequency_hz=float(freqs[-1]), kind=kind,
        scale=args.scale, thickness_scale=args.thickness_scale, window_size=tuple(args.size),
        scalar_label="displacement magnitude (mass-normalized, m/sqrt(kg))",
    )
    print(
        f"wrote {result.path}: mode {args.mode}, {freqs[-1]:.2f} Hz, {kind} "
        f"(displacement x{result.scale:.3g}, thickness x{result.thickness_scale:.3g}, "
        f"{result.seconds:.1f} s)"
    )
    return 0
