"""Beam strips as slabs: corner fibres and their displacements, drawing scales.

Each strip (:class:`fe.interface.StripGeometry`) is an Euler-Bernoulli beam lying along
x, of given width (y) and thickness (z), with nodal axial displacement ``u``, transverse
displacement ``w`` (along +z) and rotation ``theta = dw/dx`` (the convention of
:mod:`fe.beam`). A fibre at height ``zeta`` above the centroid line moves axially by
``u - zeta * theta`` (:func:`fe.interface.fibre_axial_displacement`), so the
through-thickness fibres tilt with the rotation and the slip between stacked strips
shows as a step across their interface.

Between nodes the fields are interpolated as the element does: cubic Hermite for ``w``
(its derivative for ``theta``), linear for ``u``. Numpy only (no pyvista): the renders
(:mod:`viz.render`) and the exports (:mod:`viz.export`) draw these fields.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fe.interface import StripGeometry, fibre_axial_displacement

__all__ = ["SlabField", "refine_hermite", "slab_fields", "auto_scales"]


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


def _check_strip(strip: StripGeometry) -> np.ndarray:
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


def slab_fields(strip: StripGeometry, disp: Mapping | None = None,
                subdivisions: int = 1) -> SlabField:
    """Corner fibres of a strip's slab and their Euler-Bernoulli displacements.

    A fibre at height ``zeta = z - z_center`` moves by ``(u - zeta * theta, 0, w)``
    (plane sections normal to the centroid line; :func:`fe.interface.fibre_axial_displacement`).

    Parameters
    ----------
    strip : fe.interface.StripGeometry
        Geometry (x, z_center, thickness, width), m (any object with these attributes).
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
    disp3[..., 0] = fibre_axial_displacement(ur[:, None], tr[:, None], zeta[None, :])[:, None, :]
    disp3[..., 2] = wr[:, None, None]
    return SlabField(xr, y, z, points, disp3, np.arange(x.size) * int(subdivisions))


def auto_scales(fields: Sequence[SlabField], deflection_fraction: float = 0.1,
                min_height_fraction: float = 0.08, thickness_scale: float | None = None):
    """Drawing scales that make a mode visible.

    Returns ``(scale, thickness_scale)``: the stack's thickness is exaggerated by
    ``thickness_scale`` (>= 1) until its height is ``min_height_fraction`` of the length,
    and ``scale`` brings the largest drawn displacement to ``deflection_fraction`` of the
    length (a given ``thickness_scale`` is kept). Axial displacements are drawn multiplied by
    ``thickness_scale`` too (they are proportional to thickness x rotation), so the picture is
    that of a stack ``thickness_scale`` times thicker with the same transverse shape.
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
