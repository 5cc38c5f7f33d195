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
from typing import Sequence

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from fe.modal import normal_modes
from joints.iwan import IwanParameters
from joints.jenkins import discretize, discretize_log, jenkins_update

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
class JointBank:
    """Jenkins banks of all joints (one row per joint).

    Parameters
    ----------
    stiffness, slip_limit : ndarray, shape (n_joints, n_sliders)
        Slider spring stiffnesses (N/m) and slip limits (m) (:mod:`joints.jenkins`).
    """

    stiffness: np.ndarray
    slip_limit: np.ndarray

    def __post_init__(self):
        k = np.atleast_2d(np.asarray(self.stiffness, dtype=float))
        phi = np.atleast_2d(np.asarray(self.slip_limit, dtype=float))
        if k.shape != phi.shape:
            raise ValueError("stiffness and slip_limit must have the same shape")
        if np.any(k < 0) or np.any(phi <= 0):
            raise ValueError("slider stiffnesses must be >= 0 and slip limits > 0")
        object.__setattr__(self, "stiffness", k)
        object.__setattr__(self, "slip_limit", phi)

    @classmethod
    def from_iwan(cls, params: IwanParameters | Sequence[IwanParameters], n_sliders: int,
                  n_joints: int | None = None) -> "JointBank":
        """Discretize Iwan joints (:func:`joints.jenkins.discretize`).

        ``params`` is one :class:`IwanParameters` shared by ``n_joints`` joints, or one
        per joint.
        """
        if isinstance(params, IwanParameters):
            if n_joints is None:
                raise ValueError("n_joints is required with a single IwanParameters")
            params = [params] * int(n_joints)
        return cls.from_discretizations([discretize(p, n_sliders) for p in params])

    @classmethod
    def from_discretizations(cls, discretizations) -> "JointBank":
        """Bank from one :class:`joints.jenkins.JenkinsDiscretization` per joint (e.g.
        :func:`joints.jenkins.discretize_log`); all must have the same number of sliders.
        """
        discs = list(discretizations)
        sizes = {d.n_sliders for d in discs}
        if len(sizes) != 1:
            raise ValueError(f"every joint's discretization needs the same number of "
                             f"sliders, got {sorted(sizes)}")
        return cls(np.array([d.stiffness for d in discs]), np.array([d.slip_limit for d in discs]))

    @classmethod
    def log_spaced(cls, params, a_low: float, sliders_per_octave: int = 16) -> "JointBank":
        """Jenkins banks with slip limits spaced geometrically, one row per joint.

        :func:`joints.jenkins.discretize_log` of every joint (``sliders_per_octave``
        sliders per octave of slip limit from ``phi_max`` down to ``a_low``, exact cell
        moments, stiffnesses summing to ``K_T``; its docstring states the accuracy). The
        joints share one slider grid, so they need the same ``phi_max`` and ``chi``.

        Parameters
        ----------
        params : sequence of IwanParameters
            One per joint, equal ``phi_max`` and ``chi``.
        a_low : float
            Lowest resolved slip limit (m), ``0 < a_low < phi_max``.
        sliders_per_octave : int
        """
        params = list(params)
        pm, chi = params[0].phi_max, params[0].chi
        if any(not np.isclose(p.phi_max, pm, rtol=1e-12) or p.chi != chi for p in params):
            raise ValueError("JointBank.log_spaced: all joints need the same phi_max and chi")
        return cls.from_discretizations(
            discretize_log(p, a_low, sliders_per_octave) for p in params)

    @property
    def n_joints(self) -> int:
        return self.stiffness.shape[0]

    @property
    def n_sliders(self) -> int:
        return self.stiffness.shape[1]

    @property
    def K_T(self) -> np.ndarray:
        """Stuck stiffness of each joint, ``sum_i k_i`` (N/m)."""
        return self.stiffness.sum(axis=1)

    @property
    def friction_force(self) -> np.ndarray:
        """Slider friction forces ``k_i phi_i`` (N), shape (n_joints, n_sliders)."""
        return self.stiffness * self.slip_limit

    def initial_anchor(self) -> np.ndarray:
        """Virgin state: every slider at zero (m), shape (n_joints, n_sliders)."""
        return np.zeros_like(self.stiffness)

    def update(self, slip, anchor):
        """Trial ``(force, tangent, anchor_new)`` (:func:`joints.jenkins.jenkins_update`)."""
        return jenkins_update(slip, anchor, self.stiffness, self.slip_limit)

    def stored_energy(self, slip, anchor) -> float:
        """Elastic energy of the slider springs ``sum 0.5 k_i (s - x_i)^2`` (J)."""
        stretch = np.asarray(slip, dtype=float)[:, None] - anchor
        return float(0.5 * np.sum(self.stiffness * stretch * stretch))

    def dissipated(self, anchor_old, anchor_new) -> float:
        """Friction work of a slider increment ``sum k_i phi_i |x_new - x_old|`` (J)."""
        return float(np.sum(self.friction_force * np.abs(anchor_new - anchor_old)))


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
