"""First-harmonic balance with the exact continuous Iwan joints (describing function).

:func:`solve_hb_exact` solves the condensed harmonic-balance equations of
:mod:`fe.harmonic_balance` with one harmonic and *continuous* Iwan joints: with one
harmonic the slips are sinusoids and the joint force harmonic is exactly the describing
function of :func:`joints.describing.describing_function`
(``F_1 = (k_in(A) + i k_q(A)) S_1``), so there is neither a slider discretization nor
time sampling; Newton uses the analytic derivative of the describing function
(:func:`iwan_describing`). :func:`continuation_exact` follows it over frequency lines.

SI units: rad/s, m, N.
"""
from __future__ import annotations

import numpy as np
from scipy import special

from fe.harmonic_balance import (HBOperator, HBSolution, check_joint_stiffness,
                                 natural_continuation)
from fe.reduction import ReducedModel
from joints.iwan import IwanParameters

__all__ = ["solve_hb_exact", "continuation_exact"]


class ExactIwanJoints:
    """Per-joint arrays of four-parameter Iwan joints for :func:`iwan_describing`."""

    def __init__(self, joints, n_joints: int):
        if isinstance(joints, IwanParameters):
            joints = [joints] * n_joints
        joints = list(joints)
        if len(joints) != n_joints:
            raise ValueError(f"need one IwanParameters per joint ({n_joints}), got "
                             f"{len(joints)}")
        self.chi = np.array([p.chi for p in joints])
        self.K_T = np.array([p.K_T for p in joints])
        self.R = np.array([p.R for p in joints])
        self.S = np.array([p.S for p in joints])
        self.phi_max = np.array([p.phi_max for p in joints])
        self.a = self.chi + 2.5
        self.beta_ab = special.beta(self.a, 1.5)
        self.c_in = 8.0 * self.R / (np.pi * (self.chi + 1.0))
        # micro-slip k_q = D/(pi A^2) = 4 R A^(chi+1)/(pi (chi+2)(chi+3))
        self.q_micro = 4.0 * self.R / (np.pi * (self.chi + 2.0) * (self.chi + 3.0))


def iwan_describing(J: ExactIwanJoints, A):
    """Exact describing function of each joint at slip amplitudes ``A`` (n_joints,) and
    its derivative in ``A``: ``(k_in, k_q, dk_in/dA, dk_q/dA)`` (N/m, N/m^2).

    Same closed form as :func:`joints.describing.describing_function` (there derived and
    checked against quadrature): with ``rho = min(1, phi_max/A)``,
    ``k_in = K_T I_rho(3/2, 3/2) - c A^(chi+1) B(rho; chi+5/2, 3/2)``,
    ``c = 8 R/(pi (chi+1))``, ``k_q = D/(pi A^2)`` with ``D`` the dissipation per cycle
    (Segalman 2005). Derivatives: ``dD/dA = 4 R a^(chi+2)/(chi+2) + 4 S phi_max [A >
    phi_max]`` (``a = min(A, phi_max)``), ``d rho/dA = -rho/A`` in macro-slip,
    ``d I_rho(3/2,3/2)/d rho = (8/pi) sqrt(rho (1-rho))``,
    ``d B(rho; a, 3/2)/d rho = rho^(a-1) sqrt(1-rho)``.
    """
    chi, pm = J.chi, J.phi_max
    A = np.maximum(np.asarray(A, dtype=float), 1e-300)
    macro = A > pm
    if not macro.any():            # micro-slip everywhere: rho = 1, closed forms
        Apow = A ** (chi + 1.0)
        k_in = J.K_T - J.c_in * J.beta_ab * Apow
        k_q = J.q_micro * Apow
        return k_in, k_q, (chi + 1.0) * (k_in - J.K_T) / A, (chi + 1.0) * k_q / A
    rho = np.where(macro, pm / A, 1.0)
    inc = special.betainc(J.a, 1.5, rho) * J.beta_ab
    g = special.betainc(1.5, 1.5, rho)
    Apow = A ** (chi + 1.0)
    k_in = J.K_T * g - J.c_in * Apow * inc
    a = np.minimum(A, pm)
    D = 4.0 * J.R * (A * a ** (chi + 2.0) / (chi + 2.0) - a ** (chi + 3.0) / (chi + 3.0))
    D = D + np.where(macro, 4.0 * J.S * pm * (A - pm), 0.0)
    k_q = D / (np.pi * A * A)
    dD = 4.0 * J.R * a ** (chi + 2.0) / (chi + 2.0) + np.where(macro, 4.0 * J.S * pm, 0.0)
    dk_q = (dD - 2.0 * D / A) / (np.pi * A * A)
    one_m = np.maximum(1.0 - rho, 0.0)
    drho = -rho / A
    dg = (8.0 / np.pi) * np.sqrt(rho * one_m)
    dinc = rho ** (J.a - 1.0) * np.sqrt(one_m)
    dk_in = (J.K_T * dg * drho
             - J.c_in * ((chi + 1.0) * Apow / A * inc + Apow * dinc * drho))
    return k_in, k_q, dk_in, dk_q


def solve_hb_exact(model: ReducedModel, joints, load, omega: float, tol: float = 1e-13,
                   max_iter: int = 60, guess: np.ndarray | None = None,
                   _prepared: ExactIwanJoints | None = None) -> HBSolution:
    """First-harmonic balance with the exact continuous Iwan joints (describing function).

    With one harmonic every joint slip is a sinusoid ``s_j = Re(S_j e^{i w t})`` and the
    first harmonic of the joint force is exactly
    ``F_j = (k_in(|S_j|) + i k_q(|S_j|)) S_j`` (:func:`joints.describing.describing_function`;
    paper eq. 14 in micro-slip), so ``g_j = F_j - K_T S_j`` and the condensed equations
    ``S = S_lin - R_1 N(S)`` (module docstring) are solved by Newton's method with the
    analytic derivative of the describing function (:func:`iwan_describing`). No slider
    discretization and no time sampling: the only error is the truncation to the first
    harmonic.

    Parameters
    ----------
    model : ReducedModel
    joints : IwanParameters or sequence of IwanParameters
        One per joint (or one shared by all); ``K_T`` must equal ``model.K_T``.
    load : ndarray, shape (r,)
        Reduced complex load amplitude (N).
    omega : float
        Drive frequency (rad/s).
    tol : float
        Bound on the relative Newton update.
    guess : ndarray, shape (1, n_joints), complex, optional
        Initial slip harmonics (default: the stuck-joint linear solution).

    Returns
    -------
    HBSolution
        ``harmonics = [1]``; ``slip_amplitude = |S_1|``.
    """
    nj = model.n_joints
    J = ExactIwanJoints(joints, nj) if _prepared is None else _prepared
    check_joint_stiffness(J.K_T, model)
    op = HBOperator(model, load, omega, None, harmonics=np.array([1]))
    R1 = op.R[0]
    S_lin = op.s_lin[0]
    S = S_lin.copy() if guess is None else np.asarray(guess, dtype=complex).reshape(nj).copy()
    scale = max(np.abs(S_lin).max(), 1e-300)
    eye = np.eye(2 * nj)
    Rr = np.empty((2 * nj, 2 * nj))
    Rr[:nj, :nj] = R1.real
    Rr[:nj, nj:] = -R1.imag
    Rr[nj:, :nj] = R1.imag
    Rr[nj:, nj:] = R1.real
    Jn = np.zeros((2 * nj, 2 * nj))
    diag = np.arange(nj)
    rhs = np.empty(2 * nj)
    it, upd = 0, np.inf
    for it in range(1, max_iter + 1):
        A = np.abs(S)
        k_in, k_q, dk_in, dk_q = iwan_describing(J, A)
        kap = (k_in - J.K_T) + 1j * k_q
        N = kap * S
        res = S - S_lin + R1 @ N
        # dN/dRe S = kap + S kap' Re S/A,  dN/dIm S = i kap + S kap' Im S/A
        dkap = (dk_in + 1j * dk_q) / np.maximum(A, 1e-300)
        dx = kap + S * dkap * S.real
        dyy = 1j * kap + S * dkap * S.imag
        Jn[diag, diag] = dx.real
        Jn[diag, nj + diag] = dyy.real
        Jn[nj + diag, diag] = dx.imag
        Jn[nj + diag, nj + diag] = dyy.imag
        Jac = eye + Rr @ Jn
        rhs[:nj] = -res.real
        rhs[nj:] = -res.imag
        d = np.linalg.solve(Jac, rhs)
        S = S + (d[:nj] + 1j * d[nj:])
        upd = np.abs(d).max() / max(np.abs(S).max(), scale * 1e-12)
        if upd < tol:
            break
    else:
        raise RuntimeError(f"describing-function balance did not converge at "
                           f"{omega / (2 * np.pi):.4g} Hz (relative update {upd:.2e})")
    A = np.abs(S)
    k_in, k_q, _, _ = iwan_describing(J, A)
    N = ((k_in - J.K_T) + 1j * k_q) * S
    q = op.Xp[0] - op.XG[0] @ N
    return HBSolution(omega=float(omega), harmonics=np.array([1]), slip=S[None, :],
                      joint_force=N[None, :], q=q[None, :], slip_amplitude=A,
                      iterations=it, residual=float(upd))


def continuation_exact(model: ReducedModel, joints, load, omegas, tol: float = 1e-13,
                       progress=None) -> list[HBSolution]:
    """:func:`fe.harmonic_balance.continuation` for :func:`solve_hb_exact` (exact Iwan
    joints, first harmonic)."""
    J = ExactIwanJoints(joints, model.n_joints)
    return natural_continuation(lambda w, guess: solve_hb_exact(
        model, joints, load, w, tol, guess=guess, _prepared=J), omegas, progress)
