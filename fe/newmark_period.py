"""Reaching a periodic steady state of the Newmark integration faster: a period-map
Newton step with the linearized monodromy.

Integrated period after period, a driven structure reaches its steady state as its
transient decays: near resonance the mode's own transient falls by ``exp(-2 pi zeta)``
per period (0.92 at 1.3 %), so a mismatch of 1e-2 takes ~100 periods to fall below 1e-5.
The period map ``x_{p+1} = P(x_p)`` of the state ``x = [q, v]`` has the fixed point
``x*`` sought; near it ``P(x) ~ x* + A (x - x*)`` with ``A`` the monodromy, so

    x* ~ x_p + (I - A)^{-1} (P(x_p) - x_p)                                       (1)

(Newton's method on ``P(x) - x = 0``). :func:`linear_monodromy` computes ``A`` of the
average-acceleration rule (Newmark 1959, ``beta = 1/4``, ``gamma = 1/2``) over ``n``
steps for the linear model ``M, C + G^T diag(c_j) G, K + G^T diag(k_j) G``: the joints
replaced by the spring and dashpot of their first harmonic on the orbit (``k_j + i w c_j
= G_1j / S_1j``, from a harmonic-balance solution, :func:`joint_equivalent`). Where the
joints are nearly linear on the orbit the step (1) then removes the transient of every
mode at once; the rest converges at the rate ``|lambda - lambda_lin| / |1 - lambda_lin|``
of the linearization's error on each multiplier ``lambda``. The step is a change of the
start of the next period only: the integration between steps is the plain scheme, and
the steady state it converges to is the scheme's own (:func:`period_step`).

SI units: s, m, N.
"""
from __future__ import annotations

import numpy as np

from fe.newmark import NewmarkState
from fe.reduction import JointBank, ReducedModel

__all__ = ["joint_equivalent", "linear_monodromy", "PeriodNewton", "period_step"]


def joint_equivalent(slip_harmonics, g_harmonics, harmonics, omega: float):
    """Equivalent stiffness (N/m) and viscous coefficient (N s/m) per joint of the
    slip-induced force ``g`` on a periodic orbit: ``k + i omega c = G_1 / S_1`` (first
    harmonics; zero where a joint does not move)."""
    h = np.asarray(harmonics)
    i1 = int(np.flatnonzero(h == 1)[0])
    S1 = np.asarray(slip_harmonics)[i1]
    G1 = np.asarray(g_harmonics)[i1]
    ok = np.abs(S1) > 1e-300
    ratio = np.zeros(S1.shape, dtype=complex)
    ratio[ok] = G1[ok] / S1[ok]
    return ratio.real, ratio.imag / float(omega)


def linear_monodromy(model: ReducedModel, dt: float, n_steps: int, k_joint=None,
                     c_joint=None) -> np.ndarray:
    """Monodromy ``A`` (2r, 2r) of ``[q, v]`` over ``n_steps`` steps of the
    average-acceleration rule for the model with the joints' stuck stiffness changed by
    ``k_joint`` and a dashpot ``c_joint`` per joint (module docstring); the homogeneous
    part of the scheme's one-step map raised to the power ``n_steps``."""
    M, C, K, G = model.M, model.C, model.K, model.G
    r = model.n_reduced
    if k_joint is not None:
        K = K + G.T @ (np.asarray(k_joint, dtype=float)[:, None] * G)
    if c_joint is not None:
        C = C + G.T @ (np.asarray(c_joint, dtype=float)[:, None] * G)
    be, ga = 0.25, 0.5
    S = M + ga * dt * C + be * dt * dt * K
    # a1 = -S^-1 (C v~ + K q~), q~ = q + dt v + dt^2 (1/2 - beta) a, v~ = v + dt (1 - gamma) a
    I, Z = np.eye(r), np.zeros((r, r))
    Pq = np.hstack([I, dt * I, dt * dt * (0.5 - be) * I])
    Pv = np.hstack([Z, I, dt * (1.0 - ga) * I])
    A1 = -np.linalg.solve(S, C @ Pv + K @ Pq)                      # (r, 3r)
    T = np.vstack([Pq + be * dt * dt * A1, Pv + ga * dt * A1, A1])  # (3r, 3r)
    Tn = np.linalg.matrix_power(T, int(n_steps))
    # a consistent with [q, v] in the homogeneous system: a = -M^-1 (K q + C v)
    E = np.vstack([np.hstack([I, Z]), np.hstack([Z, I]),
                   -np.linalg.solve(M, np.hstack([K, C]))])           # (3r, 2r)
    return Tn[:2 * r] @ E


class PeriodNewton:
    """Newton's method on ``F(x) = P(x) - x`` (eq. 1) whose Jacobian ``A - I`` starts
    from a linearized monodromy ``A`` and is corrected after every period by Broyden's
    rank-one update from the observed change of ``F`` (Broyden 1965, the "good"
    update): where the joints make ``P`` far from the linearization (macro-slip), the
    directions the transient actually takes are learned."""

    def __init__(self, monodromy):
        A = np.asarray(monodromy, dtype=float)
        self._J0 = A - np.eye(A.shape[0])
        self.reset()

    def reset(self) -> None:
        """Back to the linearized monodromy, forgetting the updates."""
        self.J = self._J0.copy()
        self._last = None

    def __call__(self, x0, x1):
        """The next start from the start ``x0`` and end ``x1`` of a period."""
        F = x1 - x0
        if self._last is not None:
            dx, dF = x0 - self._last[0], F - self._last[1]
            nx = float(dx @ dx)
            if nx > 0:
                self.J += np.outer(dF - self.J @ dx, dx) / nx
        self._last = (x0, F)
        return x0 - np.linalg.solve(self.J, F)


def period_step(model: ReducedModel, bank: JointBank, start: NewmarkState,
                end: NewmarkState, newton, load) -> NewmarkState:
    """The start of the next period by eq. (1): ``[q, v]`` from ``newton(x0, x1)`` (a
    :class:`PeriodNewton`) with ``x0``, ``x1`` the states ``[q, v]`` of ``start`` and
    ``end``, the slider anchors of ``end`` returned onto the new slips
    (:meth:`JointBank.update`: a slider stretched beyond its limit slips), ``g`` from
    them and ``a`` from the equation of motion with the load ``load * end.e``.
    """
    r = model.n_reduced
    x = newton(np.concatenate([start.q, start.v]), np.concatenate([end.q, end.v]))
    q, v = x[:r], x[r:]
    s = model.G @ q
    F, _, anchor = bank.update(s, end.anchor)
    g = F - model.K_T * s
    f = np.asarray(load, dtype=float) * end.e - model.C @ v - model.K @ q - model.G.T @ g
    return NewmarkState(t=end.t, q=q, v=v, a=np.linalg.solve(model.M, f), anchor=anchor,
                        g=g, e=end.e)
