"""Structures with slipping joints and their reduced bases.

A jointed structure is the linear model ``M, K, C`` plus ``n_joints`` zero-thickness
joints acting on the relative slips ``s = G u`` (``G``: one row per joint, e.g.
``s = u_j - u_i``). Each joint is a bank of Jenkins elements (paper eq. 1-2,
:mod:`joints.jenkins`) whose stuck stiffness is ``K_T``. The equation of motion is

    M u'' + C u' + K u + G^T F(G u) = f                                   (paper eq. 23)

and, adding and subtracting the stuck joint stiffness (paper eq. 25),

    M u'' + C u' + K_J u + G^T g(G u) = f,   K_J = K + G^T diag(K_T) G,
    g(s) = F(s) - K_T s,

so ``g`` is zero while the joints stick and only the slip-induced force ``g`` is
nonlinear. This is the formulation used by :mod:`fe.newmark` and
:mod:`fe.harmonic_balance`.

The reduced basis is the Ritz basis of the stuck-joint stiffness ``K_J``: its lowest
normal modes, optionally enriched by the static joint modes ``K_J^{-1} G^T`` (the
static response to a unit pair of joint forces), re-orthogonalized so that
``Phi^T M Phi = I`` and ``Phi^T K_J Phi = diag(omega^2)``. Joint slips follow from the
reduced coordinates by ``s = (G Phi) q``. SI units: kg, N/m, N s/m, m.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from fe.modal import normal_modes
from joints.bank import JointBank

__all__ = [
    "JointedSystem",
    "JointBank",
    "ReducedModel",
    "rayleigh_damping",
    "reduced_basis",
    "ritz_basis",
    "full_model",
]


def _dense(A) -> np.ndarray:
    return A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)


def rayleigh_damping(M, K, a: float, b: float):
    """Proportional damping ``C = a M + b K`` (paper eq. 40; ``a`` in 1/s, ``b`` in s)."""
    return a * M + b * K


@dataclass(frozen=True)
class JointedSystem:
    """Linear structure plus joints acting on slips ``s = G u``.

    Parameters
    ----------
    M, K, C : ndarray or sparse, shape (n, n)
        Mass (kg), stiffness *without* the joints (N/m) and viscous damping (N s/m).
    G : ndarray or sparse, shape (n_joints, n)
        Slip operator: ``s = G u`` (m) are the joints' relative displacements.
    K_T : ndarray, shape (n_joints,)
        Stuck stiffness of each joint (N/m).
    """

    M: object
    K: object
    C: object
    G: object
    K_T: np.ndarray

    def __post_init__(self):
        n = self.M.shape[0]
        for name in ("M", "K", "C"):
            if getattr(self, name).shape != (n, n):
                raise ValueError(f"{name} must be ({n}, {n}), got {getattr(self, name).shape}")
        K_T = np.atleast_1d(np.asarray(self.K_T, dtype=float))
        if self.G.shape != (K_T.size, n):
            raise ValueError(f"G must be ({K_T.size}, {n}), got {self.G.shape}")
        if np.any(K_T < 0):
            raise ValueError("joint stiffnesses K_T must be >= 0")
        object.__setattr__(self, "K_T", K_T)

    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    @property
    def n_joints(self) -> int:
        return self.K_T.size

    @property
    def K_J(self):
        """Stuck-joint stiffness ``K + G^T diag(K_T) G`` (paper eq. 25), N/m."""
        G = self.G
        if sp.issparse(G) or sp.issparse(self.K):
            Gs = sp.csr_matrix(G)
            return sp.csr_matrix(self.K) + Gs.T @ sp.diags(self.K_T) @ Gs
        G = np.asarray(G, dtype=float)
        return np.asarray(self.K, dtype=float) + G.T @ (self.K_T[:, None] * G)


@dataclass(frozen=True)
class ReducedModel:
    """Jointed structure projected on a mass-orthonormal basis ``u = Phi q``.

    Attributes
    ----------
    basis : ndarray, shape (n, r)
        ``Phi`` with ``Phi^T M Phi = I`` (the identity for :func:`full_model`).
    omega : ndarray, shape (r,)
        ``sqrt`` of the diagonal of ``Phi^T K_J Phi`` (rad/s): the stuck-joint natural
        frequencies (Ritz values when static joint modes are included).
    M, K, C : ndarray, shape (r, r)
        Reduced mass (identity), stuck-joint stiffness ``Phi^T K_J Phi`` (diagonal) and
        damping ``Phi^T C Phi``; for :func:`full_model` the physical ``M``, ``K_J``,
        ``C`` (the solvers take any symmetric ``M``, ``K``, ``C``).
    G : ndarray, shape (n_joints, r)
        Reduced slip operator: ``s = G q``.
    K_T : ndarray, shape (n_joints,)
        Stuck joint stiffnesses (N/m) already contained in ``K``.
    n_modes : int
        Number of normal modes in the basis (the rest are static joint modes).
    """

    basis: np.ndarray
    omega: np.ndarray
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    G: np.ndarray
    K_T: np.ndarray
    n_modes: int = field(default=0)

    @property
    def n_reduced(self) -> int:
        return self.basis.shape[1]

    @property
    def n_joints(self) -> int:
        return self.K_T.size

    def load(self, f) -> np.ndarray:
        """Reduced load ``Phi^T f``; ``f`` of shape (n,) or (n, m)."""
        return self.basis.T @ np.asarray(f)

    def expand(self, q) -> np.ndarray:
        """Physical displacements ``Phi q``; ``q`` of shape (r,) or (r, m)."""
        return self.basis @ np.asarray(q)

    def slip(self, q) -> np.ndarray:
        """Joint slips ``G Phi q`` (m)."""
        return self.G @ np.asarray(q)


def reduced_basis(system: JointedSystem, n_modes: int | None = None,
                  static_joint_modes: bool = False) -> ReducedModel:
    """Ritz basis of the stuck-joint structure.

    Parameters
    ----------
    system : JointedSystem
    n_modes : int, optional
        Number of lowest normal modes of ``(K_J, M)`` kept (paper eq. 27). Default: all
        (dense) — exact, for small models.
    static_joint_modes : bool
        Enrich the basis with ``K_J^{-1} G^T`` (one static mode per joint), so that the
        static joint compliance ``G K_J^{-1} G^T`` is reproduced exactly by the
        reduced model. The enriched space is re-diagonalized (Rayleigh-Ritz), hence
        ``Phi^T M Phi = I`` and ``Phi^T K_J Phi = diag(omega^2)`` still hold.

    Returns
    -------
    ReducedModel
    """
    n = system.n_dof
    K_J = system.K_J
    n_modes = n if n_modes is None else int(n_modes)
    if not 1 <= n_modes <= n:
        raise ValueError(f"n_modes must be in 1..{n}, got {n_modes}")
    omega, phi = normal_modes(K_J, system.M, n_modes)
    n_kept = n_modes
    if static_joint_modes and n_modes < n:
        Gd = _dense(system.G)
        if sp.issparse(K_J):
            import scipy.sparse.linalg as spla
            psi = spla.splu(sp.csc_matrix(K_J)).solve(Gd.T.copy())
        else:
            psi = la.solve(K_J, Gd.T, assume_a="pos")
        # M-orthogonalize the static modes against the kept modes and normalize them,
        # so that the Ritz step below is well conditioned
        Mphi = system.M @ phi
        psi = psi - phi @ (Mphi.T @ psi)
        psi = psi / np.sqrt(np.einsum("ij,ij->j", psi, system.M @ psi))
        V = np.hstack([phi, psi])
        Mr = V.T @ (system.M @ V)
        Kr = V.T @ (K_J @ V)
        # drop directions already spanned (static modes inside the modal space)
        s, U = la.eigh(Mr)
        keep = s > 1e-12 * s.max()
        T = U[:, keep] / np.sqrt(s[keep])
        lam, W = la.eigh(T.T @ Kr @ T)
        phi = V @ (T @ W)
        omega = np.sqrt(np.clip(lam, 0.0, None))
        imax = np.argmax(np.abs(phi), axis=0)
        phi = phi * np.sign(phi[imax, np.arange(phi.shape[1])])
    Mphi = system.M @ phi
    Mr = phi.T @ Mphi
    Kr = phi.T @ (K_J @ phi)
    Cr = phi.T @ (system.C @ phi)
    Gr = _dense(system.G @ phi) if sp.issparse(system.G) else np.asarray(system.G) @ phi
    # exact symmetric clean-up of round-off
    Mr = 0.5 * (Mr + Mr.T)
    Kr = 0.5 * (Kr + Kr.T)
    Cr = 0.5 * (Cr + Cr.T)
    return ReducedModel(basis=phi, omega=omega, M=Mr, K=Kr, C=Cr, G=np.asarray(Gr),
                        K_T=system.K_T.copy(), n_modes=n_kept)


def ritz_basis(system: JointedSystem, n_modes: int, zeta: float) -> ReducedModel:
    """Stuck-joint modes + static joint modes with modal damping.

    The Ritz basis of :func:`reduced_basis` with ``static_joint_modes`` (``n_modes``
    normal modes of ``(K_J, M)`` plus ``K_J^-1 G^T``, re-diagonalized so that ``Phi^T M
    Phi = I``, ``Phi^T K_J Phi = diag(omega^2)``), with modal damping ``C_r = diag(2
    zeta omega_r)`` (paper eq. 28 with one ratio for every vector) instead of the
    projected ``system.C``.

    Parameters
    ----------
    system : JointedSystem
    n_modes : int
    zeta : float
        Modal damping ratio.
    """
    red = reduced_basis(system, n_modes=int(n_modes), static_joint_modes=True)
    r, omega = red.n_reduced, red.omega
    return dataclasses.replace(red, M=np.eye(r), K=np.diag(omega ** 2),
                               C=np.diag(2.0 * zeta * omega))


def full_model(system: JointedSystem) -> ReducedModel:
    """The unreduced model in the same form: basis = identity, physical coordinates.

    ``M``, ``K = K_J`` and ``C`` are the structure's own matrices (dense), ``G`` the
    physical slip operator; :mod:`fe.newmark` and :mod:`fe.harmonic_balance` then solve
    the full equations of motion (paper eq. 23-25) with every DOF: the reference a
    reduced basis is measured against. ``omega`` holds the stuck-joint natural
    frequencies (rad/s) for information. Dense storage: for models of up to a few
    thousand DOFs.
    """
    M = _dense(system.M)
    K = _dense(system.K_J)
    C = _dense(system.C)
    n = system.n_dof
    lam = la.eigh(K, M, eigvals_only=True)
    return ReducedModel(basis=np.eye(n), omega=np.sqrt(np.clip(lam, 0.0, None)),
                        M=0.5 * (M + M.T), K=0.5 * (K + K.T), C=0.5 * (C + C.T),
                        G=np.asarray(_dense(system.G)), K_T=system.K_T.copy(), n_modes=n)
