"""Pseudo-arclength continuation of ``R(x, p) = 0`` through turning points (folds).

A branch of solutions of ``n`` equations in ``n + 1`` unknowns ``y = (x, p)`` (``p``: the
continuation parameter, e.g. the drive frequency in rad/s) is followed in the scaled
unknowns ``z = x / x_scale``, ``mu = p / p_scale`` (so the arclength weighs them
alike). From a converged point ``y_k`` with unit tangent ``t_k`` (the null vector of
``[R_z  R_mu]``, oriented by ``t_k . t_{k-1} > 0``; Keller 1977, Allgower & Georg 2003
Sec. 2) the predictor is ``y_k + ds t_k`` and the corrector is Newton's method on the
bordered system

    R(y) = 0,     t_k . (y - y_k) - ds = 0                                       (1)

whose Jacobian ``[[R_z, R_mu], [t_k^T]]`` stays regular at a fold, where ``R_z`` alone is
singular. The tangent at the new point solves

    [[R_z, R_mu], [t_k^T]] t = [0, 1]^T,    t <- t / |t|.                          (2)

Step size: after a corrector of ``m`` iterations ``ds <- ds clip(m* / m, 1/2, 2)``
(``m*`` the target count), capped at ``ds_max``; a corrector that fails, or lands at a
point whose tangent turns by more than ``max_turn`` (rad) — a jump to another branch —
halves ``ds`` (a turn is accepted once ``ds <= corner_ds``: a corner of a piecewise-smooth
branch, e.g. a contact starting at one AFT sample, that no step resolves) (down to ``ds_min``, then :class:`fe.newton_path.SteadyStateError`).

Folds (turning points in ``p``) are detected by a sign change of the ``mu`` component of
the tangent between two points and located by Brent's method on the arclength ``s`` from
the earlier point: ``f(s) = t_mu(s)``, each value from the corrector (1) at ``s`` and the
tangent (2) there, to ``1e-9 ds`` in ``s`` (the parameter at the fold is stationary in
``s``: its error is ``O(1e-18 ds^2)`` times the branch curvature); ``Fold.residual_tangent``
is the ``|t_mu|`` left.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import brentq

from fe.newton_path import SteadyStateError, damped_newton

__all__ = ["ContinuationSettings", "Fold", "Branch", "continue_branch", "branch_tangent"]


@dataclass(frozen=True)
class ContinuationSettings:
    """Arclength steps ``ds`` (first), ``ds_min``, ``ds_max`` in the scaled unknowns;
    corrector tolerance ``tol`` on the Newton update (scaled) and ``max_iter``;
    ``target_iter`` of the step control; ``max_turn`` (rad) of the tangent per step
    (not checked at ``ds <= corner_ds``);
    ``max_steps``."""

    ds: float = 0.02
    ds_min: float = 1e-7
    ds_max: float = 0.2
    tol: float = 1e-11
    max_iter: int = 12
    target_iter: int = 4
    max_turn: float = 0.35
    corner_ds: float = 1e-5
    max_steps: int = 2000

    def __post_init__(self):
        if not 0 < self.ds_min <= self.ds <= self.ds_max:
            raise ValueError("need 0 < ds_min <= ds <= ds_max")


@dataclass
class Fold:
    """A turning point in ``p``: ``x``, ``p`` and the unit tangent there (scaled
    unknowns), ``after``: index of the branch point just before it."""

    x: np.ndarray
    p: float
    tangent: np.ndarray
    after: int
    residual_tangent: float = 0.0


@dataclass
class Branch:
    """Points of a branch in order of arclength: ``x`` (n_points, n), ``p``
    (n_points,), unit tangents (n_points, n + 1) in the scaled unknowns, corrector
    iterations per point, the folds passed."""

    x: np.ndarray
    p: np.ndarray
    tangent: np.ndarray
    iterations: np.ndarray
    folds: list = field(default_factory=list)


class _Scaled:
    """``R`` and its Jacobian in the scaled unknowns ``y = (x / xs, p / ps)``."""

    def __init__(self, residual, x_scale, p_scale):
        self.residual, self.xs, self.ps = residual, x_scale, p_scale

    def __call__(self, y):
        r, Jx, Jp = self.residual(y[:-1] * self.xs, y[-1] * self.ps)
        return np.asarray(r, float), np.hstack([np.asarray(Jx) * self.xs,
                                                np.asarray(Jp).reshape(-1, 1) * self.ps])


def branch_tangent(J: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Unit tangent (eq. 2) of the branch with Jacobian ``J = [R_z, R_mu]`` (n, n+1),
    oriented along ``previous`` (n+1,)."""
    A = np.vstack([J, previous[None, :]])
    b = np.zeros(A.shape[0])
    b[-1] = 1.0
    t = np.linalg.solve(A, b)
    t /= np.linalg.norm(t)
    return t if t @ previous >= 0 else -t


def _corrector(f: _Scaled, y0, t0, ds, predictor, settings):
    """Newton on the bordered system (1) from ``predictor``; (y, iterations, J)."""

    def evaluate(y):
        r, J = f(y)
        return (np.concatenate([r, [t0 @ (y - y0) - ds]]), np.vstack([J, t0[None, :]]))

    y, it, _, _ = damped_newton(evaluate, predictor, settings.tol, settings.max_iter, 1.0,
                                relative_update=lambda y, d: float(np.abs(d).max()))
    _, J = f(y)
    return y, it, J


def _first_point(f: _Scaled, y0, settings):
    """Newton at fixed parameter from ``y0``: (y, J)."""
    p = y0[-1]

    def evaluate(z):
        r, J = f(np.append(z, p))
        return r, J[:, :-1]

    z, _, _, _ = damped_newton(evaluate, y0[:-1], settings.tol, 4 * settings.max_iter, 1.0,
                               relative_update=lambda y, d: float(np.abs(d).max()))
    y = np.append(z, p)
    return y, f(y)[1]


def _locate_fold(f: _Scaled, y0, t0, ds, settings):
    """Brent's method on ``t_mu(s)`` over ``(0, ds)`` from the point ``y0`` (module
    docstring): the fold's (y, t)."""
    cache = {}

    def t_mu(s):
        y, _, J = _corrector(f, y0, t0, s, y0 + s * t0, settings)
        t = branch_tangent(J, t0)
        cache[s] = (y, t)
        return t[-1]

    a, b = 0.0, ds
    fa, fb = t0[-1], t_mu(b)
    if fa * fb > 0:
        raise SteadyStateError("fold", "tangent's parameter component has no sign change",
                               solver="continuation")
    s = brentq(t_mu, a, b, xtol=1e-9 * ds, rtol=4 * np.finfo(float).eps, maxiter=100)
    if s not in cache:
        t_mu(s)
    return cache[s]


def continue_branch(residual: Callable, x0: np.ndarray, p0: float, p_range,
                    settings: ContinuationSettings = ContinuationSettings(),
                    x_scale=1.0, p_scale: float = 1.0, direction: int = 1,
                    locate_folds: bool = True) -> Branch:
    """Follow the branch of ``residual(x, p) = 0`` from near ``(x0, p0)`` until ``p``
    leaves ``p_range`` (module docstring).

    Parameters
    ----------
    residual : callable
        ``residual(x, p) -> (R (n,), dR/dx (n, n), dR/dp (n,))``.
    x0 : ndarray, shape (n,)
        Guess at ``p0``, corrected by Newton's method at fixed ``p0`` first.
    p0 : float
    p_range : (p_lo, p_hi)
        The branch ends at the first point outside; the last point is put on the bound
        (Newton at that ``p`` from the secant of the two last points).
    settings : ContinuationSettings
    x_scale : float or ndarray, shape (n,); p_scale : float
        Scales of ``x`` and ``p`` (their units); the arclength is measured in
        ``x / x_scale``, ``p / p_scale``.
    direction : +1 or -1
        Initial sense in ``p``.
    locate_folds : bool
        Locate every fold passed (Brent on the tangent, module docstring).

    Returns
    -------
    Branch
        In the caller's units (``x``, ``p``); tangents in the scaled unknowns.

    Raises
    ------
    fe.newton_path.SteadyStateError
        When the step would shrink below ``ds_min`` or ``max_steps`` are used.
    """
    xs = np.broadcast_to(np.asarray(x_scale, float), np.shape(x0)).copy()
    f = _Scaled(residual, xs, float(p_scale))
    lo, hi = (min(p_range) / p_scale, max(p_range) / p_scale)
    y, J = _first_point(f, np.append(np.asarray(x0, float) / xs, p0 / p_scale), settings)
    e = np.zeros(y.size)
    e[-1] = 1.0 if direction >= 0 else -1.0
    t = branch_tangent(J, e)
    ys, ts, its, folds = [y], [t], [0], []
    ds = settings.ds
    for _ in range(settings.max_steps):
        y1, t1, it, ds = _step(f, y, t, ds, settings)
        if locate_folds and t[-1] * t1[-1] < 0:
            yf, tf = _locate_fold(f, y, t, ds, settings)
            folds.append(Fold(x=yf[:-1] * xs, p=float(yf[-1] * p_scale), tangent=tf,
                              after=len(ys) - 1, residual_tangent=float(abs(tf[-1]))))
        if not lo <= y1[-1] <= hi:
            y1 = _onto_bound(f, y, y1, lo if y1[-1] < lo else hi, settings)
            ys.append(y1)
            ts.append(t1)
            its.append(it)
            break
        ys.append(y1)
        ts.append(t1)
        its.append(it)
        y, t = y1, t1
        ds = float(np.clip(ds * np.clip(settings.target_iter / max(it, 1), 0.5, 2.0),
                           settings.ds_min, settings.ds_max))
    else:
        raise SteadyStateError(f"p = {y[-1] * p_scale:.6g}", f"{settings.max_steps} steps "
                               "used before the end of the range", solver="continuation")
    Y = np.array(ys)
    return Branch(x=Y[:, :-1] * xs, p=Y[:, -1] * p_scale, tangent=np.array(ts),
                  iterations=np.array(its), folds=folds)


def _step(f, y, t, ds, settings):
    """One accepted predictor-corrector step, halving ``ds`` on failure: (y, t, it, ds)."""
    while True:
        try:
            y1, it, J = _corrector(f, y, t, ds, y + ds * t, settings)
            t1 = branch_tangent(J, t)
            if (ds <= settings.corner_ds
                    or np.arccos(np.clip(t1 @ t, -1.0, 1.0)) <= settings.max_turn):
                return y1, t1, it, ds
            reason = "tangent turned too far"
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            reason = getattr(exc, "reason", str(exc))
        ds *= 0.5
        if ds < settings.ds_min:
            raise SteadyStateError(f"p = {y[-1] * f.ps:.6g}", f"step below ds_min "
                                   f"({reason})", solver="continuation")


def _onto_bound(f, y0, y1, bound, settings):
    """The point at ``mu = bound`` between ``y0`` and ``y1`` (Newton at fixed ``mu`` from
    the secant)."""
    w = (bound - y0[-1]) / (y1[-1] - y0[-1])
    guess = y0 + w * (y1 - y0)
    guess[-1] = bound
    return _first_point(f, guess, settings)[0]
