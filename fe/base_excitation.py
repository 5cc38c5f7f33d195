"""Base excitation of a grounded structure: the load in coordinates relative to the base,
and a reduced basis that carries it.

The supports move together as one base in transverse translation ``w_b(t)``. With the
absolute displacement ``u = u_rel + r w_b`` (``r``: the rigid-body influence vector of
the base motion, 1 on every node's ``w``, 0 on ``u`` and ``theta``) and ``K r = 0`` (a
rigid translation strains nothing; a grounded spring is grounded to the base), the
equation of the free DOFs in relative coordinates is (Chopra 2012, *Dynamics of
Structures*, sec. 9.4 and 9.7)

    M u_rel'' + C u_rel' + K u_rel = -(M_all r)_free a_b(t),

``M_all`` the mass matrix over all DOFs before the supports are removed: with consistent
(Hermite) masses the elements that reach into a clamp load the free DOFs through
``M_fb r_b`` too, and ``-(M_all r)_free`` is exactly the consistent nodal load of the
distributed inertia ``-rho A a_b`` (a clamped-free beam's static relative tip deflection
is then ``-rho A a_b L^4 / (8 E I)`` at the nodes). Amplitudes solved for are relative to
the base. SI units: kg, m, N, m/s^2.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fe.beam import W
from fe.reduction import JointedSystem, ReducedModel

__all__ = ["transverse_influence", "base_load", "enrich_basis"]


def transverse_influence(dofmaps) -> np.ndarray:
    """``r`` over all DOFs of the strips (``dofmaps``: :class:`fe.mesh.DofMap` each): 1 on
    every node's ``w``, 0 on ``u`` and ``theta`` (a transverse base translation of 1 m)."""
    n = max(dm.stop for dm in dofmaps)
    r = np.zeros(n)
    for dm in dofmaps:
        r[dm.dof(np.arange(dm.n_nodes), W)] = 1.0
    return r


def base_load(model) -> np.ndarray:
    """``-(M_all r)_free`` (N per m/s^2 of base acceleration) of a
    :class:`fe.stacked.StackedModel` (module docstring): its free-DOF mass ``M`` (strips
    and point masses) on ``r_free`` plus the strips' mass coupling ``M_fb r_b`` from the
    supported DOFs."""
    r = transverse_influence(model.dofmaps)
    free = np.asarray(model.free, dtype=int)
    fixed = np.setdiff1d(np.arange(r.size), free)
    Ms = sp.csr_matrix(model.strip_mass_matrix)
    f = model.M @ r[free]
    if fixed.size:
        f = f + Ms[free][:, fixed] @ r[fixed]
    return -np.asarray(f, dtype=float).ravel()


def enrich_basis(red: ReducedModel, system: JointedSystem, load, zeta: float,
                 n_vectors: int = 2) -> ReducedModel:
    """``red`` with the load-dependent Ritz vectors of ``load`` added to its basis
    (Wilson, Yuan & Dickens 1982: the Krylov sequence ``psi_1 = K_J^-1 f``,
    ``psi_{k+1} = K_J^-1 M psi_k``), re-diagonalized by Rayleigh-Ritz (``Phi^T M Phi =
    I``, ``Phi^T K_J Phi = diag(omega^2)``) with modal damping ``C_r = diag(2 zeta
    omega)`` (as :func:`fe.reduction.ritz_basis`).

    The reduced model then reproduces the static response to ``f`` exactly (the
    quasi-static part of a base excitation, which a truncated modal basis misses) and its
    first frequency correction: on the base-driven lap of ``tests/test_base_drive.py``
    (12 modes) the response away from resonance from 1.4e-7 (one vector) to 2.7e-9 (two)
    of the full model's at 200 Hz.

    Parameters
    ----------
    red : ReducedModel
        Mass-orthonormal basis of ``system`` (free DOFs).
    system : JointedSystem
        ``M`` (kg), ``K_J`` (N/m) and the physical slip rows ``G`` of the structure.
    load : (n,)
        The load (N) whose Ritz vectors join the basis.
    zeta : float
        Modal damping ratio of every Ritz vector.
    n_vectors : int
        Length of the Krylov sequence (>= 1).

    Returns
    -------
    ReducedModel
        ``n_reduced`` grows by the vectors not already in the span.
    """
    M, K_J = system.M, system.K_J
    solve = (spla.splu(sp.csc_matrix(K_J)).solve if sp.issparse(K_J)
             else (lambda b: la.solve(K_J, b, assume_a="pos")))
    vecs = [solve(np.asarray(load, dtype=float).ravel().copy())]
    for _ in range(int(n_vectors) - 1):
        vecs.append(solve(np.asarray(M @ vecs[-1]).ravel()))
    psi = np.column_stack(vecs)
    phi = red.basis
    for _ in range(2):                                   # M-orthogonal to the basis
        psi = psi - phi @ (phi.T @ (M @ psi))
    psi = psi / np.sqrt(np.einsum("ij,ij->j", psi, M @ psi))
    V = np.hstack([phi, psi])
    Mr, Kr = V.T @ (M @ V), V.T @ (K_J @ V)
    s, U = la.eigh(0.5 * (Mr + Mr.T))
    keep = s > 1e-12 * s.max()                           # a load already in the span
    T = U[:, keep] / np.sqrt(s[keep])
    lam, Wr = la.eigh(T.T @ (0.5 * (Kr + Kr.T)) @ T)
    basis = V @ (T @ Wr)
    imax = np.argmax(np.abs(basis), axis=0)
    basis = basis * np.sign(basis[imax, np.arange(basis.shape[1])])
    omega = np.sqrt(np.clip(lam, 0.0, None))
    G = system.G @ basis
    G = np.asarray(G.toarray() if sp.issparse(G) else G)
    return dataclasses.replace(red, basis=basis, omega=omega, M=np.eye(omega.size),
                               K=np.diag(omega ** 2), C=np.diag(2.0 * zeta * omega), G=G)
