"""Off-screen 3-D renders of beam mode shapes: strips drawn as deformed slabs.

Each strip is an Euler-Bernoulli beam lying along x, of given width (y) and thickness
(z), with nodal axial displacement ``u``, transverse displacement ``w`` (along +z) and
rotation ``theta = dw/dx`` (the convention of :mod:`fe.beam`). A fibre at height
``zeta`` above the centroid line moves axially by ``u - zeta * theta`` (plane sections
stay normal to the centroid line), so the through-thickness fibres tilt with the
rotation and the slip between stacked strips shows as a step across their interface.

Between nodes the fields are interpolated as the element does: cubic Hermite for ``w``
(its derivative for ``theta``), linear for ``u``.

The numpy part (:func:`refine_hermite`, :func:`slab_fields`) does not import pyvista;
:func:`render_mode_shape` imports it lazily and chooses a head-less OpenGL window
(:func:`select_offscreen_backend`) before the first window is made.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

__all__ = [
    "StripLike",
    "SlabGeometry",
    "SlabField",
    "RenderResult",
    "RenderingUnavailableError",
    "refine_hermite",
    "slab_fields",
    "auto_scales",
    "select_offscreen_backend",
    "probe_offscreen",
    "render_mode_shape",
]


class StripLike(Protocol):
    """Anything with the strip geometry attributes (e.g. the double-beam model's strips)."""

    x: np.ndarray
    z_center: float
    thickness: float
    width: float


@dataclass(frozen=True)
class SlabGeometry:
    """Geometry of one strip (beam) in the x-z plane, extruded over its width in y.

    Parameters
    ----------
    x : ndarray, shape (n_nodes,)
        Node positions along the axis, m, increasing.
    z_center : float
        Height of the centroid line, m.
    thickness : float
        Section height (along z), m.
    width : float
        Section width (along y), m; the slab spans ``-width/2 <= y <= width/2``.
    """

    x: np.ndarray
    z_center: float
    thickness: float
    width: float


@dataclass(frozen=True)
class SlabField:
    """Reference corner fibres of one slab and their (physical) displacements.

    ``points[i, j, k]`` and ``displacement[i, j, k]`` (3-vectors, m) belong to station
    ``x[i]``, side ``y[j]`` (-b/2, +b/2) and face ``z[k]`` (bottom, top).
    """

    x: np.ndarray  # (m,)
    y: np.ndarray  # (2,)
    z: np.ndarray  # (2,)
    points: np.ndarray  # (m, 2, 2, 3)
    displacement: np.ndarray  # (m, 2, 2, 3)
    node_station: np.ndarray  # (n_nodes,) index into x of each original node


class RenderingUnavailableError(OSError):
    """No usable OpenGL library for off-screen rendering on this machine."""


def _check_strip(strip: StripLike) -> np.ndarray:
    x = np.asarray(strip.x, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ValueError("strip.x must be a 1-D array of at least two node positions")
    if np.any(np.diff(x) <= 0):
        raise ValueError("strip.x must be strictly increasing")
    if not (strip.thickness > 0 and strip.width > 0):
        raise ValueError("strip thickness and width must be positive")
    return x


def _nodal(disp: Mapping | None, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if disp is None:
        z = np.zeros(n)
        return z, z, z
    out = []
    for key in ("u", "w", "theta"):
        a = np.asarray(disp[key], dtype=float)
        if a.shape != (n,):
            raise ValueError(f"displacement '{key}' has shape {a.shape}, expected ({n},)")
        out.append(a)
    return out[0], out[1], out[2]


def refine_hermite(x, u, w, theta, subdivisions: int = 1):
    """Interpolate nodal beam fields at ``subdivisions`` equal sub-intervals per element.

    ``w`` and ``theta = dw/dx`` use the cubic Hermite shape functions of the
    Euler-Bernoulli element (Cook et al. eq. 2.3-5), ``u`` the linear bar shape functions.

    Parameters
    ----------
    x, u, w, theta : ndarray, shape (n,)
        Node positions (m), axial and transverse displacements (m), rotations (rad).
    subdivisions : int
        Sub-intervals per element (1 returns the nodes).

    Returns
    -------
    xr, ur, wr, thetar : ndarray, shape ((n - 1) * subdivisions + 1,)
    """
    x = np.asarray(x, dtype=float)
    u, w, theta = (np.asarray(a, dtype=float) for a in (u, w, theta))
    s = int(subdivisions)
    if s < 1:
        raise ValueError("subdivisions must be >= 1")
    if s == 1:
        return x.copy(), u.copy(), w.copy(), theta.copy()
    h = np.diff(x)[:, None]  # (ne, 1)
    xi = (np.arange(s) / s)[None, :]  # (1, s) local coordinate in [0, 1)
    n1 = 1 - 3 * xi**2 + 2 * xi**3
    n2 = xi - 2 * xi**2 + xi**3
    n3 = 3 * xi**2 - 2 * xi**3
    n4 = -(xi**2) + xi**3
    d1 = (-6 * xi + 6 * xi**2) / h
    d2 = 1 - 4 * xi + 3 * xi**2
    d3 = (6 * xi - 6 * xi**2) / h
    d4 = -2 * xi + 3 * xi**2
    w0, w1, t0, t1 = w[:-1, None], w[1:, None], theta[:-1, None], theta[1:, None]
    wr = n1 * w0 + n2 * h * t0 + n3 * w1 + n4 * h * t1
    tr = d1 * w0 + d2 * t0 + d3 * w1 + d4 * t1
    ur = (1 - xi) * u[:-1, None] + xi * u[1:, None]
    xr = x[:-1, None] + xi * h

    def close(a, last):
        return np.concatenate([a.ravel(), [last]])

    return close(xr, x[-1]), close(ur, u[-1]), close(wr, w[-1]), close(tr, theta[-1])


def slab_fields(strip: StripLike, disp: Mapping | None = None, subdivisions: int = 1) -> SlabField:
    """Corner fibres of a strip's slab and their Euler-Bernoulli displacements.

    A fibre at height ``zeta = z - z_center`` moves by ``(u - zeta * theta, 0, w)``
    (plane sections normal to the centroid line; :mod:`fe.beam`).

    Parameters
    ----------
    strip : StripLike
        Geometry (x, z_center, thickness, width), m.
    disp : mapping with 'u', 'w', 'theta', each (n_nodes,), optional
        Nodal displacements (m, m, rad); zero when omitted.
    subdivisions : int
        Hermite sub-intervals per element (see :func:`refine_hermite`).
    """
    x = _check_strip(strip)
    u, w, theta = _nodal(disp, x.size)
    xr, ur, wr, tr = refine_hermite(x, u, w, theta, subdivisions)
    half_t, half_b = 0.5 * float(strip.thickness), 0.5 * float(strip.width)
    zeta = np.array([-half_t, half_t])
    y = np.array([-half_b, half_b])
    z = float(strip.z_center) + zeta
    m = xr.size
    X, Y, Z = np.meshgrid(xr, y, z, indexing="ij")
    points = np.stack([X, Y, Z], axis=-1)
    disp3 = np.zeros((m, 2, 2, 3))
    disp3[..., 0] = (ur[:, None] - tr[:, None] * zeta[None, :])[:, None, :]
    disp3[..., 2] = wr[:, None, None]
    return SlabField(xr, y, z, points, disp3, np.arange(x.size) * int(subdivisions))


def auto_scales(fields: Sequence[SlabField], deflection_fraction: float = 0.1,
                min_height_fraction: float = 0.08, thickness_scale: float | None = None):
    """Drawing scales that make a mode visible.

    Returns ``(scale, thickness_scale)``: the stack's thickness is exaggerated by
    ``thickness_scale`` (>= 1) until its height is ``min_height_fraction`` of the length,
    and ``scale`` brings the largest drawn displacement to ``deflection_fraction`` of the
    length (a given ``thickness_scale`` is kept). Axial displacements are drawn multiplied by ``thickness_scale`` too (they are
    proportional to thickness x rotation), so the picture is that of a stack
    ``thickness_scale`` times thicker with the same transverse shape.
    """
    xs = np.concatenate([f.x for f in fields])
    zs = np.concatenate([f.z for f in fields])
    length = float(xs.max() - xs.min())
    height = float(zs.max() - zs.min())
    if length <= 0:
        raise ValueError("strips have zero length")
    if thickness_scale is not None:
        t_scale = float(thickness_scale)
    else:
        t_scale = max(1.0, min_height_fraction * length / height) if height > 0 else 1.0
    drawn = np.concatenate([
        np.hypot(t_scale * f.displacement[..., 0], f.displacement[..., 2]).ravel() for f in fields
    ])
    peak = float(drawn.max()) if drawn.size else 0.0
    scale = deflection_fraction * length / peak if peak > 0 else 1.0
    return scale, t_scale


# --------------------------------------------------------------------------- backend


def _loadable(*names: str) -> bool:
    for name in names:
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


def select_offscreen_backend() -> str | None:
    """Choose the VTK OpenGL window class for head-less rendering; returns its name.

    VTK >= 9.4 wheels load libGL/libEGL/libOSMesa at run time and try X first, which
    prints "bad X server connection" without a display. Without ``DISPLAY`` (or
    ``WAYLAND_DISPLAY``) this sets ``VTK_DEFAULT_OPENGL_WINDOW`` to
    ``vtkEGLRenderWindow`` (libEGL.so.1) or ``vtkOSOpenGLRenderWindow`` (libOSMesa), so
    no X attempt is made. A value already in the environment is respected. Returns
    ``None`` when a display is present (VTK's default X window is used).

    Raises
    ------
    RenderingUnavailableError
        No display and neither libEGL nor libOSMesa can be loaded.
    """
    chosen = os.environ.get("VTK_DEFAULT_OPENGL_WINDOW")
    if chosen:
        return chosen
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None
    if _loadable("libEGL.so.1", "libEGL.so"):
        chosen = "vtkEGLRenderWindow"
    elif _loadable("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"):
        chosen = "vtkOSOpenGLRenderWindow"
    else:
        raise RenderingUnavailableError(
            "no display and no off-screen OpenGL library: install libegl1 libegl-mesa0 "
            "libgl1-mesa-dri (EGL) or libosmesa6 (OSMesa)"
        )
    os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = chosen
    return chosen


_PROBE = """
import sys
sys.path.insert(0, sys.argv[2])
from viz.render import SlabGeometry, render_mode_shape
import numpy as np
x = np.linspace(0.0, 1.0, 5)
r = render_mode_shape([SlabGeometry(x, 0.0, 0.05, 0.1)],
                      [dict(u=0 * x, w=x**2, theta=2 * x)], sys.argv[1],
                      window_size=(160, 120), subdivisions=1)
"""


def probe_offscreen(timeout: float = 120.0, env: Mapping[str, str] | None = None) -> tuple[bool, str]:
    """Try a tiny render in a child process; ``(ok, message)``.

    A machine without working GL libraries can crash the process (segmentation fault)
    instead of raising, so the attempt is isolated in ``subprocess.run``.
    """
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        png = Path(tmp) / "probe.png"
        try:
            proc = subprocess.run(
                [sys.executable, "-c", _PROBE, str(png), str(Path(__file__).resolve().parents[1])],
                capture_output=True, text=True,
                timeout=timeout, env=None if env is None else dict(env),
            )
        except subprocess.TimeoutExpired:
            return False, f"off-screen render probe timed out after {timeout:.0f} s"
        if proc.returncode != 0:
            lines = [ln for ln in (proc.stderr or "").strip().splitlines() if ln.strip()]
            tail = lines[-1] if lines else ""
            return False, f"off-screen render probe failed (exit {proc.returncode}) {tail}".strip()
        if not png.is_file() or png.stat().st_size == 0:
            return False, "off-screen render probe wrote no image"
    return True, "off-screen rendering works"


# --------------------------------------------------------------------------- render


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
    strips: Sequence[StripLike],
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
    strips : sequence of StripLike
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
    if len(strips) != len(displacements) or not strips:
        raise ValueError("need one displacement mapping per strip (and at least one strip)")
    fields = [slab_fields(s, d, subdivisions) for s, d in zip(strips, displacements)]
    auto_s, t_scale = auto_scales(fields, deflection_fraction, thickness_scale=thickness_scale)
    s_scale = float(scale) if scale is not None else auto_s
    if not (np.isfinite(s_scale) and np.isfinite(t_scale) and t_scale > 0):
        raise ValueError("scale and thickness_scale must be finite, thickness_scale > 0")
    zs = np.concatenate([f.z for f in fields])
    z_ref = 0.5 * float(zs.min() + zs.max())

    backend = select_offscreen_backend()
    import pyvista as pv

    deformed = _combined_grid(fields, s_scale, t_scale, z_ref, True)
    ghost = _combined_grid(fields, s_scale, t_scale, z_ref, False)
    mags = np.concatenate([g.point_data["displacement"] for g in deformed])
    clim = [0.0, float(mags.max()) if mags.max() > 0 else 1.0]

    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.set_background("white")
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
            plotter.add_mesh(_front_face_lines(fields, s_scale, t_scale, z_ref),
                             color="black", line_width=1.5)
        if title is None:
            parts = []
            if mode_number is not None:
                parts.append(f"Mode {mode_number}")
            if frequency_hz is not None:
                parts.append(f"{frequency_hz:.2f} Hz")
            if kind:
                parts.append(str(kind))
            title = "   ".join(parts)
        if title:
            plotter.add_text(title, position="upper_edge", font_size=14, color="black")
        plotter.add_text(
            f"displacement x{s_scale:.3g}, thickness x{t_scale:.3g}", position="lower_left",
            font_size=9, color="dimgray",
        )
        plotter.view_xz()
        plotter.camera.azimuth = -15
        plotter.camera.elevation = 12
        plotter.reset_camera()
        plotter.camera.zoom(1.5)
        path.parent.mkdir(parents=True, exist_ok=True)
        plotter.screenshot(str(path))
        used = plotter.render_window.GetClassName() if plotter.render_window else str(backend)
    finally:
        plotter.close()
    return RenderResult(path, s_scale, t_scale, used, time.perf_counter() - t0)
