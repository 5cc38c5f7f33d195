"""Weighted least-squares fits of the diagnosis models (:mod:`inverse.diagnosis.models`).

The noise level of every channel and level is known when a model is fitted (from the
identification's stds or estimated beforehand: :mod:`inverse.diagnosis.noise`), so the
Gaussian log-likelihood is ``-chi2/2`` up to a constant shared by every model, with
``chi2`` the sum of squared standardized residuals. For each point of the nonlinear
parameters the linear ones are solved exactly (variable projection), non-negative
where the physics says so (exact: the best feasible solution over the faces of the
constraint set), for a whole batch of points at once (normal equations with one step
of refinement, Bjorck 1987). The nonlinear parameters are searched on a grid (global
in chi and in every extension's shape) and refined by Levenberg-Marquardt steps whose
Jacobian and trial steps are one batched evaluation each. A refit on a subset of the
levels (cross-validation) starts from the same starting points as the fit to all
levels (the grid points and extra starts it refined), never from its optimum, which
saw the left-out level. Every refinement stops on the Gauss-Newton decrement
(:mod:`inverse.diagnosis.lm`: ``chi2`` within 1e-4 of the local optimum), not on an
iteration count; a fit whose best start did not get there is not ``converged`` and the
diagnosis counts it (a fold that did not converge is a failed fold).

Information criteria (``k`` model parameters, ``N`` data in the fit; the noise levels
are not fitted): ``AIC = chi2 + 2k``, defined when ``N > k``. With known noise levels
the expected optimism of ``chi2`` is exactly ``2k`` for a linear model, so AIC needs
no small-sample correction; the AICc term ``2k(k+1)/(N-k-1)`` (Hurvich & Tsai 1989)
corrects for a noise variance estimated from the model's own residuals, which is not
done here (it is reported, not used). ``BIC = chi2 + k ln N``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from inverse.diagnosis.lm import DECREMENT_TOL, Refined, levenberg_marquardt
from inverse.diagnosis.models import Model, Observations, design

__all__ = ["MAX_ITERS", "Fit", "solve_nonneg", "evaluate", "refine", "fit_model",
           "fit_folds", "profile_interval", "information_criteria"]

#: Most Levenberg-Marquardt steps of any start (fit, fold, profile point): a cap that
#: converged fits do not reach (:mod:`inverse.diagnosis.lm`); one that does is reported.
MAX_ITERS = 200


@dataclass
class Fit:
    """A fitted model.

    ``residual`` holds the standardized residuals (data - model)/sigma of *every* row
    (omega2 rows, zeta rows, response rows), so rows left out of the fit are prediction
    errors in noise units; ``train`` the levels used. ``converged``: the start that gave
    ``chi2`` reached the decrement tolerance (:mod:`inverse.diagnosis.lm`), in
    ``iterations`` steps, its last Gauss-Newton ``decrement`` (chi2 units);
    ``unconverged_starts``: how many of the other starts did not."""

    model: Model
    theta: np.ndarray
    linear: np.ndarray
    residual: np.ndarray
    log_s: np.ndarray
    train: np.ndarray
    chi2: float
    n_data: int
    n_params: int
    aic: float | None
    aicc: float | None
    bic: float
    parameters: dict = field(default_factory=dict)
    starts: np.ndarray | None = None
    converged: bool = True
    iterations: int = 0
    decrement: float = 0.0
    unconverged_starts: int = 0

    @property
    def failed(self) -> bool:
        """The fit did not give a finite chi2 (no usable start)."""
        return not np.isfinite(self.chi2)

    @property
    def chi(self) -> float:
        return float(self.theta[0] - 1.0)


def _face_solve(An, b, free):
    """Unconstrained least squares on the columns ``free`` of the column-scaled stack
    ``An``: normal equations and one step of refinement (Bjorck 1987)."""
    Af = An[:, :, free]
    M = np.einsum("gnk,gnl->gkl", Af, Af) + 1e-13 * np.eye(len(free))
    y = np.linalg.solve(M, np.einsum("gnk,gn->gk", Af, b)[..., None])[..., 0]
    r = np.einsum("gnk,gk->gn", Af, y) - b
    return y - np.linalg.solve(M, np.einsum("gnk,gn->gk", Af, r)[..., None])[..., 0]


def solve_nonneg(A, b, nonneg):
    """``min |A x - b|`` for stacks ``A`` (G, N, k), ``b`` (G, N) with ``x_j >= 0`` on
    ``nonneg``: the unconstrained solution where it is feasible (then it is the
    optimum of the convex problem), else the best feasible solution over the faces of
    the constraint set. Returns x (G, k)."""
    G, N, k = A.shape
    scale = np.sqrt(np.einsum("gnk,gnk->gk", A, A))
    scale = np.where(scale > 0, scale, 1.0)
    An = A / scale[:, None, :]
    x = _face_solve(An, b, list(range(k)))
    bad = np.flatnonzero(np.any(x[:, nonneg] < 0.0, axis=1)) if nonneg else np.zeros(0, int)
    if bad.size:
        Ab, bb = An[bad], b[bad]
        best = np.zeros((bad.size, k))
        best_rss = np.full(bad.size, np.inf)
        for mask in range(1, 2 ** len(nonneg)):
            zeroed = [c for i, c in enumerate(nonneg) if mask >> i & 1]
            free = [j for j in range(k) if j not in zeroed]
            y = np.zeros((bad.size, k))
            y[:, free] = _face_solve(Ab, bb, free)
            r = np.einsum("gnk,gk->gn", Ab, y) - bb
            rss = np.einsum("gn,gn->g", r, r)
            ok = np.all(y[:, nonneg] >= 0.0, axis=1) & (rss < best_rss)
            best[ok], best_rss[ok] = y[ok], rss[ok]
        x[bad] = best
    return x / scale


def evaluate(model: Model, obs: Observations, theta, rows):
    """Linear solution for every point of ``theta`` (G, d), fitted on the rows ``rows``
    (bool, (N,) for all points or (G, N) per point).

    Returns (x (G, k), residual on all rows (G, N): data - model, log_s (G, n))."""
    A, b, log_s = design(model, obs, theta)
    w = np.broadcast_to(np.asarray(rows, float), b.shape)
    x = solve_nonneg(A * w[..., None], b * w, model.nonneg(obs.log_r is not None))
    return x, b - np.einsum("gnk,gk->gn", A, x), log_s


def information_criteria(chi2: float, k: int, n: int):
    """(AIC or None when ``n <= k``, AICc or None when ``n <= k + 1``, BIC) with known
    noise levels (module doc)."""
    aic = chi2 + 2 * k if n > k else None
    aicc = chi2 + 2 * k + 2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else None
    return aic, aicc, chi2 + k * np.log(n)


def _bounds(model):
    nl = model.nonlinear
    return np.array([a[1] for a in nl]), np.array([a[2] for a in nl])


def _grid(model):
    axes = [a[3] for a in model.nonlinear]
    return np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)


def _rss(model, obs, theta, rows, chunk=4096):
    out = []
    for i in range(0, theta.shape[0], chunk):
        _, r, _ = evaluate(model, obs, theta[i:i + chunk], rows)
        out.append(np.sum(r[:, rows] ** 2, axis=1))
    return np.concatenate(out)


def refine(model, obs, theta, rows, iters, fixed=None) -> Refined:
    """Levenberg-Marquardt on the nonlinear parameters of ``B`` independent problems at
    once (starts, or cross-validation folds): ``theta`` (B, d), ``rows`` (B, N) bool,
    at most ``iters`` steps each, the coordinates ``fixed`` (d,) bool held at their start
    (a profile); stopped on the Gauss-Newton decrement
    (:func:`inverse.diagnosis.lm.levenberg_marquardt`: Jacobians by differences with
    steps of 1e-4 of the box). Returns its :class:`~inverse.diagnosis.lm.Refined`
    (theta, chi2, converged, iterations, decrement per problem)."""
    lo, hi = _bounds(model)

    def residuals(th, m):
        return evaluate(model, obs, th, m)[1] * m

    return levenberg_marquardt(residuals, theta, rows, lo, hi, iters, fixed)


def _finish(model, obs, ref: Refined, train, starts=None):
    """The best of the refined starts ``ref`` on ``train`` as a :class:`Fit` (chi2 inf
    when no start gives a finite one: a failed fit), converged when that start is.

    "Best": the first start (in the order of the starts) whose chi2 is within
    :data:`~inverse.diagnosis.lm.DECREMENT_TOL` of the lowest. Converged starts are
    that close to their optimum, so a closer margin is round-off: two starts that tie
    (a direction the training data do not determine, along which the prediction of a
    left-out level may still move) are not told apart by the last bits of a sum."""
    rows = np.tile(train, len(obs.channels))
    x, r, log_s = evaluate(model, obs, ref.theta, rows)
    f = np.sum(r[:, rows] ** 2, axis=1)
    f = np.where(np.isfinite(f), f, np.inf)
    i = int(np.argmax(f <= f.min() + DECREMENT_TOL)) if np.isfinite(f.min()) else 0
    k = model.n_params(obs.log_r is not None)
    n = int(rows.sum())
    chi2 = float(f[i]) if np.isfinite(f[i]) else float("inf")
    aic, aicc, bic = information_criteria(chi2, k, n)
    others = np.delete(ref.converged, i)
    return Fit(model=model, theta=ref.theta[i], linear=x[i], residual=r[i],
               log_s=log_s[i], train=train, chi2=chi2, n_data=n, n_params=k, aic=aic,
               aicc=aicc, bic=bic, starts=starts,
               converged=bool(ref.converged[i]) and np.isfinite(chi2),
               iterations=int(ref.iterations[i]), decrement=float(ref.decrement[i]),
               unconverged_starts=int(np.sum(~others)))


def fit_model(model: Model, obs: Observations, train=None, start=None,
              iters: int = MAX_ITERS, n_starts: int = 3, extra_starts=None) -> Fit:
    """Fit ``model`` to the levels ``train`` (bool per row; default: all).

    Without ``start``: grid search over the nonlinear parameters, then refinement from
    the ``n_starts`` best grid points that are not neighbours, and from every theta of
    ``extra_starts`` (a pair of causes also starts from the fits of each cause alone).
    With ``start`` (a theta or several): refinement from there only. The starts are
    kept (``Fit.starts``) for the cross-validation folds.
    """
    train = np.ones(obs.n, bool) if train is None else np.asarray(train, bool)
    rows = np.tile(train, len(obs.channels))
    if start is None:
        grid = _grid(model)
        rss = _rss(model, obs, grid, rows)
        order = np.argsort(np.where(np.isfinite(rss), rss, np.inf))
        span = np.ptp(grid, axis=0) + 1e-300
        starts = []
        for i in order:
            if all(np.max(np.abs(grid[i] - grid[j]) / span) > 0.25 for j in starts):
                starts.append(i)
            if len(starts) == n_starts:
                break
        theta0 = grid[starts]
        if extra_starts:
            lo, hi = _bounds(model)
            theta0 = np.vstack([theta0, np.clip(np.asarray(extra_starts, float), lo, hi)])
    else:
        theta0 = np.atleast_2d(np.asarray(start, float))
    ref = refine(model, obs, theta0, np.repeat(rows[None], theta0.shape[0], 0), iters)
    return _finish(model, obs, ref, train, theta0)


def fit_folds(full: Fit, obs: Observations, trains, iters: int = MAX_ITERS) -> list:
    """Refits of ``full``'s model to each training set of ``trains`` (F, n) bool, every
    fold refined from each of ``full.starts`` (the starting points of the fit to all
    levels, not its optimum). Returns a list of :class:`Fit` (``failed`` when no start
    gave a finite chi2, not ``converged`` when its best start did not converge)."""
    trains = np.asarray(trains, bool)
    starts = full.starts if full.starts is not None else full.theta[None]
    S, F = starts.shape[0], trains.shape[0]
    rows = np.repeat(np.tile(trains, (1, len(obs.channels))), S, axis=0)
    ref = refine(full.model, obs, np.tile(starts, (F, 1)), rows, iters)
    return [_finish(full.model, obs, ref.take(slice(i * S, (i + 1) * S)), trains[i])
            for i in range(F)]


def profile_interval(fit: Fit, obs: Observations, j: int, threshold: float,
                     n_points: int = 13, iters: int = MAX_ITERS):
    """Profile interval of nonlinear parameter ``j`` of ``fit``: the range of values on
    a grid over its box (plus the fitted value) where the chi2 minimized over the other
    nonlinear parameters (from the fit's starts and its optimum) stays within
    ``threshold`` of the fit's chi2 (3.84: 95 % for one parameter, Wilks). Returns
    ``((lower, upper), failures, unconverged)``: the points with no finite chi2, and
    those whose best start did not converge (their chi2 may be too high: the interval
    may be too narrow there); the interval reaches a bound when the bound is inside
    it."""
    _, lo, hi, _ = fit.model.nonlinear[j]
    values = np.unique(np.r_[np.linspace(lo, hi, n_points), fit.theta[j]])
    starts = np.vstack([fit.theta[None], fit.starts]) if fit.starts is not None \
        else fit.theta[None]
    S = starts.shape[0]
    theta0 = np.repeat(starts, values.size, axis=0)
    theta0[:, j] = np.tile(values, S)
    rows = np.tile(fit.train, len(obs.channels))
    fixed = np.zeros(theta0.shape[1], bool)
    fixed[j] = True
    ref = refine(fit.model, obs, theta0, np.repeat(rows[None], theta0.shape[0], 0), iters,
                 fixed)
    _, r, _ = evaluate(fit.model, obs, ref.theta, rows)
    chi2 = np.sum(r[:, rows] ** 2, axis=1).reshape(S, values.size)
    chi2 = np.where(np.isfinite(chi2), chi2, np.inf)
    best = np.argmin(chi2, axis=0)
    conv = ref.converged.reshape(S, values.size)[best, np.arange(values.size)]
    chi2 = chi2.min(axis=0)
    failures = int(np.sum(~np.isfinite(chi2)))
    unconverged = int(np.sum(~conv & np.isfinite(chi2)))
    inside = values[chi2 - min(fit.chi2, chi2.min()) <= threshold]
    return (float(inside.min()), float(inside.max())), failures, unconverged
