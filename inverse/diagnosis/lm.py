"""Batched Levenberg-Marquardt over many independent small least-squares problems in a
box, stopped by a statistical convergence test rather than an iteration count.

Problem ``b`` minimizes ``chi2_b(theta) = sum_n r_bn(theta)^2`` over ``theta`` in the
box ``[lo, hi]`` (d,), ``r`` in noise units (standardized residuals), so one unit of
``chi2`` is one unit of the Gaussian log-likelihood's ``-2 ln L``.

Convergence: the Gauss-Newton decrement of :mod:`inverse.decrement` within the box
(eq. 2 there: how far below the current chi2 the Gauss-Newton model puts the best
point within reach of the box; ``g_F^T (J_F^T J_F)^+ g_F`` when that is reached), ``F``
the coordinates not held: not ``fixed``, not on
a bound the gradient pushes against (descent would leave the box), not at a kink
(below). A problem stops when ``delta <= tol`` (default
:data:`~inverse.decrement.DECREMENT_TOL` = 1e-4: chi2 within 1e-4 of the local optimum,
theta within 0.01 standard errors of it) and is converged when its last ``delta`` is
at most :data:`~inverse.decrement.ACCEPT_TOL` = 1e-2 (the margin of
:mod:`inverse.decrement`). A problem that reaches the iteration cap, or whose steps no
longer lower chi2 at any damping (stalled), above that is *not* converged, and says so.

Jacobian: forward differences, step ``h`` (a fraction of the box, into the box), one
batched evaluation of ``d`` points per problem, for the steps. Their ``O(h)`` error
biases ``delta`` by about ``(h / 2 s)^2`` (``s`` a parameter's standard error), which
may be above ``tol`` for a well-determined parameter; so a forward decrement below
``tol`` is confirmed with second-order differences before a problem is declared
converged: the central difference where ``theta - h`` is in the box, else the
one-sided three-point rule ``(-3 r(theta) + 4 r(theta + h) - r(theta + 2h)) / 2h``;
both ``O(h^2)``. A problem keeps second-order Jacobians once a step failed or its best
trial was the most damped (the Gauss-Newton model is poor there).

Kinks. A model may be continuous but not differentiable in a nonlinear parameter (a
clipped onset weight: ``geometric-hardening``'s ``s_contact`` at a level's amplitude).
Coordinate ``j`` is *at a kink* when chi2 rises on both sides, ``chi2(theta +- h e_j) >
chi2(theta)``, and its one-sided Jacobians ``(r(theta + h e_j) - r) / h`` and ``(r -
r(theta - h e_j)) / h`` differ by more than :data:`KINK_JUMP` = 10 % of their size (a
smooth residual changes its slope by ``O(h)`` relative over one step, 1e-4 of the box).
Such a coordinate is at a local minimum along itself to within ``h`` and is held, like
one on a bound, in the decrement and in the next step; the others must still converge.
Without this a problem crawls towards the kink at ever larger damping and never meets
the decrement test.

Steps: seven trial steps per iteration, evaluated in one batch: dampings ``mu (1e-3,
1e-2, 0.1, 1, 10)`` times the diagonal of ``J^T J`` (Marquardt 1963; in box units
floored at :data:`DAMPING_FLOOR` of its largest entry: Marquardt's scaling makes the
step of a coordinate with an almost vanishing column as large as any other's in its own
units, which for a bounded parameter means many box widths, clipped, at every damping),
and the step of damping ``mu`` 3 and 9 times longer (in a long curved valley, where the
Gauss-Newton model is trusted only at high damping, the damped steps point along the
valley but crawl); on the free coordinates, clipped to the box (a projected step:
descent when small enough); the best is taken when it lowers ``chi2``. ``mu``
(initially 1) adapts per problem: times ``10^(i - 2)`` after a step whose best damping
was the ``i``-th (a longer step counts as the second; ``mu`` at least 1), back to 1 when
a new kink is held, times 1e4 after an iteration with no lower trial (the Jacobian is
then reused, but a forward one is first replaced by a second-order one: its error may
be what failed), stalled beyond :data:`MU_MAX`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from inverse.decrement import ACCEPT_TOL, DECREMENT_TOL, gauss_newton_decrement

__all__ = ["DECREMENT_TOL", "MU_MAX", "DAMPING_FLOOR", "KINK_JUMP", "Refined", "decrement",
           "levenberg_marquardt"]

#: Damping multiplier beyond which a problem whose trials no longer lower chi2 stalls.
MU_MAX = 1e12
_LAMBDAS = np.array([1e-3, 1e-2, 1e-1, 1.0, 10.0])
#: The step of damping ``mu`` (``_LAMBDAS[_STRETCHED]`` = 1 times it) is also tried
#: this many times longer (module doc).
_STRETCHED, _STRETCH = 3, np.array([3.0, 9.0])
#: Least damping diagonal of a coordinate, in box units, relative to the largest.
DAMPING_FLOOR = 1e-6
#: A coordinate whose one-sided Jacobians differ by more than this fraction of their
#: size, chi2 uphill on both sides, is at a kink (module doc).
KINK_JUMP = 0.1


@dataclass
class Refined:
    """The outcome of :func:`levenberg_marquardt` for ``B`` problems: ``theta`` (B, d),
    ``chi2`` (B,), ``converged`` (B,) bool (eq. 1 below the tolerance), ``iterations``
    (B,) steps taken, ``decrement`` (B,) the last eq. (1) (inf: never computed, e.g. a
    start with no finite chi2)."""

    theta: np.ndarray
    chi2: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    decrement: np.ndarray

    def take(self, index) -> "Refined":
        """The problems ``index`` (a slice or indices)."""
        return Refined(self.theta[index], self.chi2[index], self.converged[index],
                       self.iterations[index], self.decrement[index])


def _active(theta, g, lo, hi, fixed=None) -> np.ndarray:
    """Coordinates (B, d) held: ``fixed`` ((d,) or (B, d)), or on a bound that the
    gradient ``g`` of ``chi2 / 2`` pushes against (descent would leave the box)."""
    span = np.asarray(hi, float) - np.asarray(lo, float)
    active = (((theta <= lo + 1e-12 * span) & (g > 0))
              | ((theta >= hi - 1e-12 * span) & (g < 0)))
    if fixed is not None:
        active |= np.asarray(fixed, bool)
    return active


def decrement(J, r, theta, lo, hi, fixed=None) -> np.ndarray:
    """The Gauss-Newton decrement (:func:`inverse.decrement.gauss_newton_decrement`,
    chi2 units) of a batch: ``J`` (B, d, N) the Jacobian of the residuals ``r`` (B, N)
    at ``theta`` (B, d) in the box ``[lo, hi]``, ``fixed`` (d,) or (B, d) bool held, and
    so is a coordinate on a bound that the gradient pushes against."""
    return gauss_newton_decrement(
        J, r, _active(theta, np.einsum("bdn,bn->bd", J, r), lo, hi, fixed),
        np.asarray(hi, float) - np.asarray(lo, float))


def _points(theta, h, lo, hi):
    """Difference steps (b, d) into the box, whether the opposite point is in the box
    (b, d), and the points (b, d, d) of the forward and of the second evaluation
    (opposite, else twice the step)."""
    d = theta.shape[1]
    step = np.where(theta + h > hi, -h, h)
    opposite = theta - step
    inside = (opposite >= lo) & (opposite <= hi)
    other = np.where(inside, opposite, theta + 2.0 * step)
    eye = np.eye(d, dtype=bool)[None]
    forward = theta[:, None, :] + step[:, :, None] * eye
    return step, inside, forward, np.where(eye, other[:, None, :], theta[:, None, :])


def _second_order(r0, r1, ro, step, inside):
    """Second-order Jacobian (b, d, N) from the residuals at the forward points ``r1``
    and the second ones ``ro`` (b, d, N): central where the opposite point is in the
    box, else the one-sided three-point rule; and the coordinates at a kink (module
    doc), (b, d) bool."""
    s = step[:, :, None]
    central = (r1 - ro) / (2.0 * s)
    three = (-3.0 * r0[:, None, :] + 4.0 * r1 - ro) / (2.0 * s)
    J2 = np.where(inside[:, :, None], central, three)
    f0 = np.sum(r0**2, axis=1)[:, None]
    f1, fo = np.sum(r1**2, axis=2), np.sum(ro**2, axis=2)
    Jf, Jb = (r1 - r0[:, None, :]) / s, (r0[:, None, :] - ro) / s
    jump = np.linalg.norm(Jf - Jb, axis=2)
    size = np.maximum(np.linalg.norm(Jf, axis=2), np.linalg.norm(J2, axis=2))
    kink = inside & (f1 > f0) & (fo > f0) & (jump > KINK_JUMP * size)
    return J2, kink


def _jacobians(residuals, theta, rows, r0, h, lo, hi, exact, fixed, tol):
    """Jacobians (b, d, N), the coordinates held (fixed, at a kink) and the decrements
    of a batch: forward differences, second-order ones for the problems ``exact`` and
    for those whose forward decrement is under ``tol`` (module doc). The forward
    points and the second points of the ``exact`` problems are one evaluation."""
    b, d = theta.shape
    step, inside, fwd, other = _points(theta, h, lo, hi)
    ex = np.flatnonzero(exact)
    pts = np.concatenate([fwd.reshape(-1, d), other[ex].reshape(-1, d)])
    m = np.concatenate([np.repeat(rows, d, axis=0), np.repeat(rows[ex], d, axis=0)])
    rr = residuals(pts, m)
    r1 = rr[:b * d].reshape(b, d, -1)
    J = (r1 - r0[:, None, :]) / step[:, :, None]
    hold = np.broadcast_to(fixed, (b, d)).copy()
    dec = decrement(J, r0, theta, lo, hi, hold)
    near = np.flatnonzero((dec <= tol) & ~exact)
    ro = np.empty((b, d, r0.shape[1]))
    ro[ex] = rr[b * d:].reshape(ex.size, d, r0.shape[1])
    if near.size:
        ro[near] = residuals(other[near].reshape(-1, d), np.repeat(rows[near], d, axis=0)
                             ).reshape(near.size, d, r0.shape[1])
    two = np.union1d(ex, near)
    if two.size:
        J[two], kink = _second_order(r0[two], r1[two], ro[two], step[two], inside[two])
        hold[two] |= kink
        dec[two] = decrement(J[two], r0[two], theta[two], lo, hi, hold[two])
    return J, hold, dec


def levenberg_marquardt(residuals: Callable, theta, rows, lo, hi, iters: int,
                        fixed=None, tol: float = DECREMENT_TOL,
                        rel_step: float = 1e-4) -> Refined:
    """Minimize ``B`` independent ``chi2`` at once (module doc).

    Parameters
    ----------
    residuals : callable
        ``residuals(theta (G, d), rows (G, N) bool) -> r (G, N)``, noise units, zero
        on the rows a problem does not fit.
    theta : (B, d) starts; rows : (B, N) bool, the rows each problem fits.
    lo, hi : (d,) the box.
    iters : the most steps per problem.
    fixed : (d,) bool, coordinates held at their start (a profile), or None.
    tol : eq. (1)'s tolerance in chi2 units; rel_step : ``h`` as a fraction of the box.
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    theta = np.array(theta, float)
    rows = np.asarray(rows, bool)
    B, d = theta.shape
    h = rel_step * (hi - lo)
    fixed = np.zeros(d, bool) if fixed is None else np.asarray(fixed, bool)
    r0 = residuals(theta, rows)
    f0 = np.sum(r0**2, axis=1)
    live = np.isfinite(f0)
    f0 = np.where(live, f0, np.inf)
    conv = np.zeros(B, bool)
    its = np.zeros(B, int)
    dec = np.full(B, np.inf)
    mu = np.ones(B)
    J = np.zeros((B, d, rows.shape[1]))
    hold = np.broadcast_to(fixed, (B, d)).copy()   # fixed, or at a kink
    stale = np.ones(B, bool)                    # theta moved: a new Jacobian is due
    exact = np.zeros(B, bool)                   # second-order Jacobians from now on
    for k in range(iters + 1):
        idx = np.flatnonzero(live & stale)
        if idx.size:
            was = hold[idx]
            J[idx], hold[idx], dec[idx] = _jacobians(residuals, theta[idx], rows[idx],
                                                     r0[idx], h, lo, hi, exact[idx],
                                                     fixed, tol)
            mu[idx[np.any(hold[idx] & ~was, axis=1)]] = 1.0      # a new kink held
            stale[idx] = False
            conv[idx[dec[idx] <= tol]] = True
            live[idx[dec[idx] <= tol]] = False
        idx = np.flatnonzero(live)
        if k == iters or idx.size == 0:
            break
        took, damped = _step(residuals, theta, rows, r0, f0, J, mu, idx, lo, hi, hold[idx])
        its[idx] += 1
        exact[idx[damped]] = True
        # no trial lowered chi2: with a forward Jacobian, first make it second-order
        # (its error may be what failed) at the same damping; else damp more
        redo = idx[~took & ~exact[idx]]
        exact[redo] = True
        more = idx[~took & ~np.isin(idx, redo)]
        mu[more] *= 1e4
        stale[idx[took]] = True
        stale[redo] = True
        live[more[mu[more] > MU_MAX]] = False
    conv |= dec <= ACCEPT_TOL          # converged within the margin (inverse.decrement)
    return Refined(theta, f0, conv, its, dec)


def _step(residuals, theta, rows, r0, f0, J, mu, idx, lo, hi, hold) -> np.ndarray:
    """One damped step of the problems ``idx`` (in place: ``theta``, ``r0``, ``f0``,
    ``mu`` after a step that moved), the coordinates ``hold`` (b, d) held. Returns
    which of them moved (a trial lowered chi2)."""
    L, d = _LAMBDAS.size, theta.shape[1]
    Ji, th = J[idx], theta[idx]
    Ji = np.where(_active(th, np.einsum("bdn,bn->bd", Ji, r0[idx]), lo, hi, hold)[:, :, None],
                  0.0, Ji)                  # the step on the free coordinates only
    JtJ = np.einsum("bdn,ben->bde", Ji, Ji)
    g = np.einsum("bdn,bn->bd", Ji, r0[idx])
    span2 = (np.asarray(hi, float) - np.asarray(lo, float)) ** 2
    diag = np.einsum("bdd->bd", JtJ)
    floor = DAMPING_FLOOR * np.maximum(np.max(diag * span2, axis=1), 1e-300)
    diag = np.maximum(diag, floor[:, None] / span2)     # box units: module doc
    lam = mu[idx, None] * _LAMBDAS[None, :]                                 # (b, L)
    Mt = JtJ[:, None] + lam[:, :, None, None] * (diag[:, None, :, None] * np.eye(d))
    with np.errstate(all="ignore"):
        delta = np.linalg.solve(Mt, np.broadcast_to(g[:, None, :, None],
                                                    (idx.size, L, d, 1)))[..., 0]
    delta = np.nan_to_num(np.concatenate([delta, _STRETCH[None, :, None]
                                          * delta[:, _STRETCHED, None, :]], axis=1))
    T = delta.shape[1]
    trial = np.clip(th[:, None, :] - delta, lo, hi).reshape(-1, d)
    rt = residuals(trial, np.repeat(rows[idx], T, axis=0)).reshape(idx.size, T, -1)
    ft = np.sum(rt**2, axis=2)
    ft = np.where(np.isfinite(ft), ft, np.inf)
    best = np.argmin(ft, axis=1)
    fb = ft[np.arange(idx.size), best]
    better = fb < f0[idx]
    upd = idx[better]
    theta[upd] = trial.reshape(idx.size, T, d)[better, best[better]]
    r0[upd] = rt[better, best[better]]
    f0[upd] = fb[better]
    rank = np.where(best < L, best, 1)[better]          # a longer step: less damping
    mu[upd] = np.maximum(mu[upd] * 10.0 ** (rank - 2), 1.0)
    return better, better & (best == L - 1)
