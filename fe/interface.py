"""Kinematics of the interface between two stacked Euler-Bernoulli strips.

Each strip is a chain of 2-D frame elements (:mod:`fe.beam`, DOFs ``u, w, theta =
dw/dx``) along its own centroid line. Plane sections stay normal to the centroid line,
so a fibre at height ``zeta`` above it moves axially by::

    u_fibre = u - zeta theta                                                  (1)

An upper strip (thickness ``h_up``) lying on a lower one (``h_lo``) touches it with its
bottom face (``zeta = -h_up/2``) on the lower strip's top face (``zeta = +h_lo/2``), so
the tangential slip of the upper strip over the lower one is::

    s = (u_up + (h_up/2) theta_up) - (u_lo - (h_lo/2) theta_lo)      [m]      (2)

(identical to ``(u_up - (h/2) phi_up) - (u_lo + (h/2) phi_lo)`` written with the
opposite rotation sign ``phi = -dw/dx``), and the normal gap is ``w_up - w_lo``.
Two identical strips split a motion exactly into an in-phase and an out-of-phase part
(:func:`stacked_energy_split`). The FE model builds its joint rows from (2)
(:func:`tangential_slip_rows`), the renders draw the fibres of (1) (:mod:`viz.slab`): the
step between the drawn interface fibres is the model's slip.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fe.assembly import coupling_rows
from fe.beam import THETA, U, W
from fe.mesh import DofMap

__all__ = [
    "StripGeometry",
    "stacked_strips",
    "fibre_axial_displacement",
    "slip_coefficients",
    "tangential_slip_rows",
    "normal_gap_rows",
    "stacked_energy_split",
]


@dataclass(frozen=True)
class StripGeometry:
    """One strip of a stack in the x-z plane, extruded over its width in y.

    Parameters
    ----------
    x : ndarray, shape (n_nodes,)
        Node positions along the axis, m, increasing.
    z_center : float
        Height of the centroid line, m.
    thickness : float
        Section height (along z), m.
    width : float
        Section width (along y), m; the strip spans ``-width/2 <= y <= width/2``.
    """

    x: np.ndarray
    z_center: float
    thickness: float
    width: float


def stacked_strips(x, thickness: float, width: float) -> list[StripGeometry]:
    """``[lower, upper]``: two equal strips on the same nodes ``x`` (m), centroids at
    ``z = -h/2`` and ``+h/2``, interface at ``z = 0``."""
    h = thickness
    return [StripGeometry(np.array(x, dtype=float), -0.5 * h, h, width),
            StripGeometry(np.array(x, dtype=float), 0.5 * h, h, width)]


def fibre_axial_displacement(u, theta, zeta):
    """Eq. (1): axial displacement ``u - zeta theta`` of the fibre at height ``zeta``
    (m) above the centroid line; ``u`` (m), ``theta = dw/dx`` (rad), broadcast."""
    return u - zeta * theta


def _fibre_coefficients(zeta: float) -> tuple[float, float]:
    """Coefficients of ``u`` and ``theta`` in eq. (1)."""
    return 1.0, -zeta


def slip_coefficients(h_upper: float, h_lower: float) -> list[float]:
    """Coefficients of ``(u_up, theta_up, u_lo, theta_lo)`` in the slip (2):
    ``[1, h_up/2, -1, h_lo/2]`` (dimensionless, m, dimensionless, m)."""
    cu, ct = _fibre_coefficients(-0.5 * h_upper)
    lu, lt = _fibre_coefficients(0.5 * h_lower)
    return [cu, ct, -lu, -lt]


def tangential_slip_rows(upper: DofMap, lower: DofMap, nodes, h_upper: float,
                         h_lower: float, n_dofs: int) -> sp.csr_matrix:
    """Rows of the slip (2) at ``nodes`` (shared node numbers of both strips).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (len(nodes), n_dofs)
        ``s = G x`` (m) for a displacement vector ``x`` of all DOFs.
    """
    dofs = np.column_stack([upper.dof(nodes, U), upper.dof(nodes, THETA),
                            lower.dof(nodes, U), lower.dof(nodes, THETA)])
    return coupling_rows(dofs, slip_coefficients(h_upper, h_lower), n_dofs)


def normal_gap_rows(upper: DofMap, lower: DofMap, nodes, n_dofs: int) -> sp.csr_matrix:
    """Rows of the normal gap ``w_up - w_lo`` (m) at ``nodes``, shape (len(nodes), n_dofs)."""
    return coupling_rows(np.column_stack([upper.dof(nodes, W), lower.dof(nodes, W)]),
                         [1.0, -1.0], n_dofs)


def stacked_energy_split(lower, upper, strip_mass) -> dict:
    """Kinetic-energy fractions of a motion of two identical stacked strips.

    With the strip mass matrix ``M_s`` the pair's kinetic energy ``x_lo^T M_s x_lo +
    x_up^T M_s x_up = 2 (a^T M_s a + d^T M_s d)`` with ``a = (x_up + x_lo)/2`` (in phase)
    and ``d = (x_up - x_lo)/2`` (out of phase); the frame element has no
    axial-transverse mass coupling, so each splits exactly into axial (u) and transverse
    (w, theta) parts.

    Parameters
    ----------
    lower, upper : (3 n_nodes,) node-major ``u, w, theta`` of each strip (m, m, rad).
    strip_mass : (3 n_nodes, 3 n_nodes) mass matrix of one strip (kg).

    Returns
    -------
    dict
        ``in_phase_axial``, ``in_phase_bending``, ``out_of_phase_axial``,
        ``out_of_phase_bending``, summing to 1.
    """
    lo, up = lower, upper
    a, d = 0.5 * (up + lo), 0.5 * (up - lo)
    axial = np.zeros(lo.size, dtype=bool)
    axial[U::3] = True
    Ms = strip_mass
    parts = {}
    for name, v in (("in_phase", a), ("out_of_phase", d)):
        va, vt = np.where(axial, v, 0.0), np.where(axial, 0.0, v)
        parts[f"{name}_axial"] = float(va @ (Ms @ va))
        parts[f"{name}_bending"] = float(vt @ (Ms @ vt))
    total = sum(parts.values())
    return {k: v / total for k, v in parts.items()}
