"""Two-dimensional Euler-Bernoulli frame element: axial bar + cubic Hermite bending.

Element DOF order (per element, local = global because elements lie on the x axis)::

    [u1, w1, theta1, u2, w2, theta2]

``u`` is the axial displacement of the centroid line (m), ``w`` the transverse
displacement along +z (m) and ``theta = dw/dx`` the cross-section rotation (rad,
counter-clockwise when x points right and z up). With this convention a fibre at height
``zeta`` above the centroid moves axially by ``u - zeta * theta`` (Euler-Bernoulli
kinematics, plane sections stay normal to the centroid line).

Matrices (e.g. Przemieniecki, *Theory of Matrix Structural Analysis*, 1968, ch. 5 and 11;
Cook et al., *Concepts and Applications of FEA*, 4th ed., eqs. 2.3-5, 11.3-5):

- axial stiffness ``EA/L [[1, -1], [-1, 1]]``, consistent axial mass
  ``rho A L / 6 [[2, 1], [1, 2]]``;
- bending stiffness ``EI/L^3 [[12, 6L, -12, 6L], [6L, 4L^2, -6L, 2L^2], ...]``,
  consistent bending mass ``rho A L / 420 [[156, 22L, 54, -13L], ...]``
  (translational inertia only, no rotary inertia: Euler-Bernoulli).

All functions are vectorized over elements: element properties are arrays of shape
``(n_elements,)`` (scalars broadcast) and the matrices come back as
``(n_elements, 6, 6)``. SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DOFS_PER_NODE = 3
U, W, THETA = 0, 1, 2  # component index inside a node


@dataclass(frozen=True)
class Section:
    """Homogeneous rectangular section and material.

    Parameters
    ----------
    E : float
        Young's modulus, Pa.
    rho : float
        Density, kg/m^3.
    width : float
        Section width b, m.
    thickness : float
        Section height h, m.
    """

    E: float
    rho: float
    width: float
    thickness: float

    def __post_init__(self) -> None:
        for name in ("E", "rho", "width", "thickness"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"Section.{name} must be positive and finite, got {value!r}")

    @property
    def area(self) -> float:
        """Cross-section area A = b h, m^2."""
        return self.width * self.thickness

    @property
    def second_moment(self) -> float:
        """Second moment of area about the centroid I = b h^3 / 12, m^4."""
        return self.width * self.thickness**3 / 12.0

    @property
    def EA(self) -> float:
        """Axial rigidity, N."""
        return self.E * self.area

    @property
    def EI(self) -> float:
        """Bending rigidity, N m^2."""
        return self.E * self.second_moment

    @property
    def mass_per_length(self) -> float:
        """rho A, kg/m."""
        return self.rho * self.area


def frame_stiffness(length, EA, EI) -> np.ndarray:
    """Element stiffness matrices of the 2-D Euler-Bernoulli frame element.

    Parameters
    ----------
    length : array_like, shape (n,)
        Element lengths L, m.
    EA, EI : array_like, broadcastable to (n,)
        Axial rigidity (N) and bending rigidity (N m^2).

    Returns
    -------
    K : ndarray, shape (n, 6, 6)
        Stiffness in DOF order (u1, w1, theta1, u2, w2, theta2), N/m, N, N m.
    """
    L = np.atleast_1d(np.asarray(length, dtype=float))
    EA, EI = np.broadcast_arrays(np.asarray(EA, dtype=float), np.asarray(EI, dtype=float), L)[:2]
    if np.any(L <= 0):
        raise ValueError("element lengths must be positive")
    n = L.size
    K = np.zeros((n, 6, 6))
    a = EA / L
    ia, ib = np.ix_([0, 3], [0, 3])
    K[:, ia, ib] = a[:, None, None] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    c = EI / L**3
    Lc = L[:, None, None]
    kb = np.array([[12.0, 6.0, -12.0, 6.0],
                   [6.0, 4.0, -6.0, 2.0],
                   [-12.0, -6.0, 12.0, -6.0],
                   [6.0, 2.0, -6.0, 4.0]])
    # powers of L multiplying each entry: rows/cols with theta carry one L each
    p = np.array([0, 1, 0, 1])
    ib_, jb_ = np.ix_([1, 2, 4, 5], [1, 2, 4, 5])
    K[:, ib_, jb_] = c[:, None, None] * kb * Lc ** (p[:, None] + p[None, :])
    return K


def frame_mass(length, mass_per_length) -> np.ndarray:
    """Consistent element mass matrices of the 2-D Euler-Bernoulli frame element.

    Parameters
    ----------
    length : array_like, shape (n,)
        Element lengths L, m.
    mass_per_length : array_like, broadcastable to (n,)
        rho A, kg/m.

    Returns
    -------
    M : ndarray, shape (n, 6, 6)
        Consistent mass (linear axial shape functions, cubic Hermite bending shape
        functions), kg, kg m, kg m^2. Translational entries of each direction sum to
        rho A L.
    """
    L = np.atleast_1d(np.asarray(length, dtype=float))
    m = np.broadcast_to(np.asarray(mass_per_length, dtype=float), L.shape)
    if np.any(L <= 0):
        raise ValueError("element lengths must be positive")
    n = L.size
    M = np.zeros((n, 6, 6))
    mL = m * L
    ia, ib = np.ix_([0, 3], [0, 3])
    M[:, ia, ib] = (mL / 6.0)[:, None, None] * np.array([[2.0, 1.0], [1.0, 2.0]])
    mb = np.array([[156.0, 22.0, 54.0, -13.0],
                   [22.0, 4.0, 13.0, -3.0],
                   [54.0, 13.0, 156.0, -22.0],
                   [-13.0, -3.0, -22.0, 4.0]])
    p = np.array([0, 1, 0, 1])
    ib_, jb_ = np.ix_([1, 2, 4, 5], [1, 2, 4, 5])
    M[:, ib_, jb_] = ((mL / 420.0)[:, None, None] * mb
                      * L[:, None, None] ** (p[:, None] + p[None, :]))
    return M


def fibre_axial_row(zeta) -> np.ndarray:
    """Coefficients giving the axial displacement of a fibre from nodal (u, w, theta).

    Euler-Bernoulli kinematics with ``theta = dw/dx``: ``u_fibre = u - zeta * theta``
    for a fibre at height ``zeta`` (m) above the centroid.

    Returns
    -------
    row : ndarray, shape (..., 3)
        Coefficients for (u, w, theta).
    """
    zeta = np.asarray(zeta, dtype=float)
    row = np.zeros(zeta.shape + (3,))
    row[..., U] = 1.0
    row[..., THETA] = -zeta
    return row
