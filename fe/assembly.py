"""Sparse assembly, Dirichlet constraints by free-DOF reduction, coupling elements.

Assembly is vectorized over elements: element matrices ``(n_el, nd, nd)`` and their
DOF indices ``(n_el, nd)`` become one COO triplet list (duplicates summed) and then CSR.

A *coupling* is a row vector ``g`` over the DOFs and a stiffness ``k``: it measures a
relative displacement ``s = g . x`` (e.g. the tangential slip between two facing
surfaces) and stores the energy ``k s^2 / 2``, i.e. adds ``k g^T g`` to the stiffness.
Many couplings stack into a sparse ``G`` (one row each) and add ``G^T diag(k) G``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def assemble(element_matrices: np.ndarray, element_dofs: np.ndarray, n_dofs: int) -> sp.csr_matrix:
    """Sum element matrices into a global sparse matrix.

    Parameters
    ----------
    element_matrices : ndarray, shape (n_el, nd, nd)
    element_dofs : ndarray of int, shape (n_el, nd)
        Global DOF index of each local DOF.
    n_dofs : int

    Returns
    -------
    A : scipy.sparse.csr_matrix, shape (n_dofs, n_dofs)
    """
    Ke = np.asarray(element_matrices, dtype=float)
    dofs = np.asarray(element_dofs, dtype=np.int64)
    if Ke.ndim != 3 or Ke.shape[1] != Ke.shape[2] or dofs.shape != Ke.shape[:2]:
        raise ValueError("element matrices must be (n_el, nd, nd) with DOFs (n_el, nd)")
    nd = dofs.shape[1]
    rows = np.repeat(dofs, nd, axis=1).ravel()
    cols = np.tile(dofs, (1, nd)).ravel()
    A = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(n_dofs, n_dofs))
    return A.tocsr()  # duplicates are summed


def coupling_rows(dofs, coefficients, n_dofs: int) -> sp.csr_matrix:
    """Sparse matrix G whose row i is ``sum_j coefficients[i, j] * e_{dofs[i, j]}``.

    Parameters
    ----------
    dofs : array_like of int, shape (n_c, m)
        DOFs that each coupling reads.
    coefficients : array_like, shape (n_c, m)
        Their coefficients (dimensionless for displacements, m for rotations).
    n_dofs : int

    Returns
    -------
    G : scipy.sparse.csr_matrix, shape (n_c, n_dofs)
    """
    dofs = np.atleast_2d(np.asarray(dofs, dtype=np.int64))
    coef = np.broadcast_to(np.asarray(coefficients, dtype=float), dofs.shape)
    n_c, m = dofs.shape
    rows = np.repeat(np.arange(n_c), m)
    return sp.csr_matrix((coef.ravel(), (rows, dofs.ravel())), shape=(n_c, n_dofs))


def coupling_stiffness(G: sp.spmatrix, stiffness) -> sp.csr_matrix:
    """Stiffness of linear couplings ``G^T diag(k) G`` (strain energy ``sum k_i s_i^2/2``).

    Parameters
    ----------
    G : sparse, shape (n_c, n_dofs)
        Coupling rows (relative displacement of each coupling from the DOFs).
    stiffness : array_like, shape (n_c,) or scalar
        Coupling stiffness, N/m.
    """
    G = sp.csr_matrix(G)
    k = np.broadcast_to(np.asarray(stiffness, dtype=float), (G.shape[0],))
    return (G.T @ sp.diags(k) @ G).tocsr()


def point_masses(dofs, masses, n_dofs: int) -> sp.csr_matrix:
    """Diagonal mass matrix of point masses (kg) on the given translational DOFs."""
    dofs = np.atleast_1d(np.asarray(dofs, dtype=np.int64))
    m = np.broadcast_to(np.asarray(masses, dtype=float), dofs.shape)
    return sp.csr_matrix((m, (dofs, dofs)), shape=(n_dofs, n_dofs))


def free_dofs(n_dofs: int, fixed) -> np.ndarray:
    """Sorted indices of the DOFs not in ``fixed`` (homogeneous Dirichlet constraints)."""
    mask = np.ones(n_dofs, dtype=bool)
    mask[np.asarray(fixed, dtype=np.int64)] = False
    return np.flatnonzero(mask)


def restrict(A: sp.spmatrix, free: np.ndarray) -> sp.csr_matrix:
    """Rows and columns ``free`` of a square sparse matrix (free-DOF reduction)."""
    A = sp.csr_matrix(A)
    return A[free][:, free].tocsr()


def restrict_columns(G: sp.spmatrix, free: np.ndarray) -> sp.csr_matrix:
    """Columns ``free`` of a sparse matrix (e.g. coupling rows over free DOFs)."""
    return sp.csc_matrix(G)[:, free].tocsr()


def expand(x_free: np.ndarray, free: np.ndarray, n_dofs: int) -> np.ndarray:
    """Full DOF vector(s) with zeros on the constrained DOFs.

    ``x_free`` has shape (n_free,) or (n_free, k); the result (n_dofs,) or (n_dofs, k).
    """
    x_free = np.asarray(x_free)
    out = np.zeros((n_dofs,) + x_free.shape[1:], dtype=x_free.dtype)
    out[free] = x_free
    return out


def free_index(free: np.ndarray, dof: int) -> int:
    """Position of a full-model DOF in the free-DOF numbering; ValueError if constrained."""
    i = int(np.searchsorted(free, dof))
    if i >= free.size or free[i] != dof:
        raise ValueError(f"DOF {dof} is constrained")
    return i
