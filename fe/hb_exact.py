"""First-harmonic balance with any joint law through its describing function.

:func:`solve_hb_exact` solves the condensed harmonic-balance equations of
:mod:`fe.harmonic_balance` with one harmonic: the slips are sinusoids and the joint
force harmonic is exactly the law's describing function
(``F_1 = (k_in(A) + i k_q(A)) S_1``, :mod:`joints.law`; for Iwan parameters the exact
continuous Iwan joints of :func:`joints.describing.iwan_describing`), so there is
neither a slider discretization nor time sampling. Newton
(:func:`fe.newton_path.damped_newton`) uses the derivative of the describing function
through :func:`joints.law.describing_force`. :func:`continuation_exact` follows it over
frequency lines.

SI units: rad/s, m, N.
"""
from __future__ import annotations

import numpy as np

from fe.harmonic_balance import (HBOperator, HBSolution, check_joint_stiffness,
                                 natural_continuation)
from fe.newton_path import SteadyStateError, damped_newton, stall_words
from fe.reduction import ReducedModel
from joints.describing import ExactIwanJoints, as_joint_law, iwan_describing
from joints.law import describing_force

__all__ = ["solve_hb_exact", "continuation_exact", "ExactIwanJoints", "iwan_describing"]


def solve_hb_exact(model: ReducedModel, joints, load, omega: float, tol: float = 1e-13,
                   max_iter: int = 60, guess: np.ndarray | None = None,
                   _prepared=None) -> HBSolution:
    """First-harmonic balance with a joint law's describing function (module docstring).

    With one harmonic every joint slip is a sinusoid ``s_j = Re(S_j e^{i w t})`` and the
    first harmonic of the joint force is exactly
    ``F_j = (k_in(|S_j|) + i k_q(|S_j|)) S_j`` (the law's describing function; for Iwan
    joints paper eq. 14 in micro-slip), so ``g_j = F_j - K_T S_j`` and the condensed
    equations ``S = S_lin - R_1 N(S)`` (module docstring) are solved by Newton's method
    with the derivative of the describing function. No slider discretization and no
    time sampling: the only error is the truncation to the first harmonic.

    Parameters
    ----------
    model : ReducedModel
    joints : joints.law.JointLaw, or IwanParameters (one per joint or one shared)
        Any joint law through its describing function (continuous Iwan joints for
        parameters); ``K_T`` must equal ``model.K_T``.
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
    law = as_joint_law(joints, nj) if _prepared is None else _prepared
    check_joint_stiffness(law.K_T, model)
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
    diag = np.arange(nj)

    def balance(y):
        """Residual ``S - S_lin + R_1 N(S)`` and its Jacobian in ``[Re S, Im S]``."""
        S = y[:nj] + 1j * y[nj:]
        A = np.abs(S)
        k_in, k_q, dk_in, dk_q = law.describing_derivative(A)
        N, dx, dyy = describing_force((k_in - law.K_T) + 1j * k_q, dk_in + 1j * dk_q, S,
                                      np.maximum(A, 1e-300))
        res = S - S_lin + R1 @ N
        Jn = np.zeros((2 * nj, 2 * nj))
        Jn[diag, diag] = dx.real
        Jn[diag, nj + diag] = dyy.real
        Jn[nj + diag, diag] = dx.imag
        Jn[nj + diag, nj + diag] = dyy.imag
        return np.concatenate([res.real, res.imag]), eye + Rr @ Jn

    try:
        y, it, upd, _ = damped_newton(
            balance, np.concatenate([S.real, S.imag]), tol, max_iter, scale,
            relative_update=lambda y, d: np.abs(d).max() / max(
                np.abs(y[:nj] + 1j * y[nj:]).max(), scale * 1e-12))
    except SteadyStateError as exc:
        raise SteadyStateError(f"{omega / (2 * np.pi):.6g} Hz", exc.reason,
                               solver="describing-function balance") from None
    S = y[:nj] + 1j * y[nj:]
    A = np.abs(S)
    k_in, k_q = law.describing(A)
    N = ((k_in - law.K_T) + 1j * k_q) * S
    q = op.Xp[0] - op.XG[0] @ N
    return HBSolution(omega=float(omega), harmonics=np.array([1]), slip=S[None, :],
                      joint_force=N[None, :], q=q[None, :], slip_amplitude=A,
                      iterations=it, residual=float(upd), fallback=stall_words(upd, tol))


def continuation_exact(model: ReducedModel, joints, load, omegas, tol: float = 1e-13,
                       progress=None) -> list[HBSolution]:
    """:func:`fe.harmonic_balance.continuation` for :func:`solve_hb_exact` (exact Iwan
    joints, first harmonic)."""
    law = as_joint_law(joints, model.n_joints)
    return natural_continuation(lambda w, guess: solve_hb_exact(
        model, law, load, w, tol, guess=guess, _prepared=law), omegas, progress)
