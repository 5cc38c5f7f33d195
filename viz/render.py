"""Off-screen 3-D renders of beam mode shapes: strips drawn as deformed slabs.

The slabs' fibres and scales come from :mod:`viz.slab`; :func:`render_mode_shape`
imports pyvista lazily and chooses a head-less OpenGL window
(:func:`viz.offscreen.select_offscreen_backend`) before the first window is made.
"""
from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fe.interface import StripGeometry
from viz.offscreen import select_offscreen_backend
from viz.slab import auto_scales, slab_fields

__all__ = ["RenderResult", "render_mode_shape"]


@dataclass(frozen=True)
class RenderResult:
    """What :func:`render_mode_shape` wrote."""

    path: Path
    scale: float  # multiplier of the transverse displacement in the picture
    thickness_scale: float  # thickness (and axial displacement) exaggeration
    backend: str  # VTK render-window class used
    seconds: float


def _combined_grid(fields, scale, t_scale, z_ref, deformed: bool):
    import pyvista as pv

    blocks = []
    for f in fields:
        pts = f.points.copy()
        pts[..., 2] = z_ref + t_scale * (pts[..., 2] - z_ref)
        if deformed:
            pts[..., 0] += scale * t_scale * f.displacement[..., 0]
            pts[..., 2] += scale * f.displacement[..., 2]
        grid = pv.StructuredGrid(pts[..., 0], pts[..., 1], pts[..., 2])
        mag = np.linalg.norm(f.displacement, axis=-1)
        grid.point_data["displacement"] = mag.ravel(order="F")
        blocks.append(grid)
    return blocks


def _front_face_lines(fields, scale, t_scale, z_ref):
    """Lines on the -y face (facing the camera): the through-thickness fibres at the
    nodes and the bottom and top edges of every strip."""
    import pyvista as pv

    points, lines, start = [], [], 0
    for f in fields:
        pts = f.points[:, 0].copy()  # (m, 2 faces, 3)
        pts[..., 2] = z_ref + t_scale * (pts[..., 2] - z_ref)
        d = f.displacement[:, 0]
        pts[..., 0] += scale * t_scale * d[..., 0]
        pts[..., 2] += scale * d[..., 2]
        pts[..., 1] -= 2e-3 * (f.y[1] - f.y[0])  # just in front of the face
        m = pts.shape[0]
        points.append(pts.reshape(-1, 3))  # index 2 i + k
        nodes = start + 2 * f.node_station
        fibres = np.column_stack([np.full(nodes.size, 2), nodes, nodes + 1])
        edges = [np.concatenate([[m], start + 2 * np.arange(m) + k]) for k in (0, 1)]
        lines.extend([fibres.ravel(), *edges])
        start += 2 * m
    return pv.PolyData(np.concatenate(points), lines=np.concatenate(lines))


def render_mode_shape(
    strips: Sequence[StripGeometry],
    displacements: Sequence[Mapping],
    path,
    *,
    mode_number: int | None = None,
    frequency_hz: float | None = None,
    kind: str | None = None,
    title: str | None = None,
    scale: float | None = None,
    thickness_scale: float | None = None,
    deflection_fraction: float = 0.1,
    subdivisions: int = 4,
    window_size: tuple[int, int] = (1400, 800),
    scalar_label: str = "displacement magnitude (mode-shape units)",
    show_fibres: bool = True,
) -> RenderResult:
    """Render the deformed strips as 3-D slabs off-screen and write a PNG.

    Draws the deformed slabs coloured by the magnitude of the (unscaled) fibre
    displacement, with a scalar bar, a translucent undeformed ghost, the through-thickness
    fibres at the nodes (their tilt is the rotation, their step at an interface the slip)
    and a title ``Mode N  f Hz  kind``.

    Parameters
    ----------
    strips : sequence of fe.interface.StripGeometry
        Strip geometries (x, z_center, thickness, width), m.
    displacements : sequence of mappings
        Per strip, ``{'u', 'w', 'theta'}`` arrays of shape (n_nodes,), m and rad,
        ``theta = dw/dx``.
    path : str or Path
        PNG file to write.
    scale : float, optional
        Multiplier of the displacements in the picture; default brings the largest drawn
        displacement to ``deflection_fraction`` of the length (:func:`auto_scales`).
    thickness_scale : float, optional
        Exaggeration of the thickness (and, consistently, of the axial displacements);
        default makes the stack 8 % of the length when it is thinner.
    subdivisions : int
        Hermite sub-intervals per element for smooth slabs.

    Returns
    -------
    RenderResult
    """
    t0 = time.perf_counter()
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"render output must be a .png file, got '{path.name}'")
    scene = _scene(strips, displacements, scale, thickness_scale, deflection_fraction,
                   subdivisions)
    backend = select_offscreen_backend()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.set_background("white")
        _add_slabs(plotter, scene, scalar_label, show_fibres)
        if title is None:
            title = _mode_title(mode_number, frequency_hz, kind)
        _annotate(plotter, title, scene)
        path.parent.mkdir(parents=True, exist_ok=True)
        plotter.screenshot(str(path))
        used = plotter.render_window.GetClassName() if plotter.render_window else str(backend)
    finally:
        plotter.close()
    return RenderResult(path, scene.scale, scene.t_scale, used, time.perf_counter() - t0)


@dataclass(frozen=True)
class _Scene:
    """The strips' slab fields and the scales they are drawn at (``z_ref``: the
    stack's mid-height, about which the thickness is exaggerated)."""

    fields: list
    scale: float
    t_scale: float
    z_ref: float


def _scene(strips: Sequence[StripGeometry], displacements: Sequence[Mapping],
           scale: float | None, thickness_scale: float | None, deflection_fraction: float,
           subdivisions: int) -> _Scene:
    """The slab fields of every strip and the checked scales of the picture."""
    if len(strips) != len(displacements) or not strips:
        raise ValueError("need one displacement mapping per strip (and at least one strip)")
    fields = [slab_fields(s, d, subdivisions) for s, d in zip(strips, displacements)]
    auto_s, t_scale = auto_scales(fields, deflection_fraction, thickness_scale=thickness_scale)
    s_scale = float(scale) if scale is not None else auto_s
    if not (np.isfinite(s_scale) and np.isfinite(t_scale) and t_scale > 0):
        raise ValueError("scale and thickness_scale must be finite, thickness_scale > 0")
    zs = np.concatenate([f.z for f in fields])
    return _Scene(fields, s_scale, t_scale, 0.5 * float(zs.min() + zs.max()))


def _add_slabs(plotter, scene: _Scene, scalar_label: str, show_fibres: bool) -> None:
    """The undeformed ghost, the deformed slabs coloured by displacement magnitude with
    a scalar bar and, optionally, the fibres on the front face."""
    args = (scene.fields, scene.scale, scene.t_scale, scene.z_ref)
    deformed = _combined_grid(*args, True)
    ghost = _combined_grid(*args, False)
    mags = np.concatenate([g.point_data["displacement"] for g in deformed])
    clim = [0.0, float(mags.max()) if mags.max() > 0 else 1.0]
    for g in ghost:
        plotter.add_mesh(g, color="lightgray", opacity=0.25, show_edges=False,
                         show_scalar_bar=False)
    for i, g in enumerate(deformed):
        plotter.add_mesh(
            g, scalars="displacement", clim=clim, cmap="viridis", smooth_shading=False,
            show_scalar_bar=(i == 0),
            scalar_bar_args=dict(title=scalar_label, color="black", vertical=False,
                                 position_x=0.3, position_y=0.03, width=0.4, height=0.08,
                                 fmt="%.2e", title_font_size=16, label_font_size=14),
        )
    if show_fibres:
        plotter.add_mesh(_front_face_lines(*args), color="black", line_width=1.5)


def _mode_title(mode_number: int | None, frequency_hz: float | None, kind: str | None) -> str:
    """The default title ``Mode N   f Hz   kind`` of the parts given."""
    parts = []
    if mode_number is not None:
        parts.append(f"Mode {mode_number}")
    if frequency_hz is not None:
        parts.append(f"{frequency_hz:.2f} Hz")
    if kind:
        parts.append(str(kind))
    return "   ".join(parts)


def _annotate(plotter, title: str, scene: _Scene) -> None:
    """The title, the scales drawn at, and the camera."""
    if title:
        plotter.add_text(title, position="upper_edge", font_size=14, color="black")
    plotter.add_text(
        f"displacement x{scene.scale:.3g}, thickness x{scene.t_scale:.3g}",
        position="lower_left", font_size=9, color="dimgray",
    )
    plotter.view_xz()
    plotter.camera.azimuth = -15
    plotter.camera.elevation = 12
    plotter.reset_camera()
    plotter.camera.zoom(1.5)
