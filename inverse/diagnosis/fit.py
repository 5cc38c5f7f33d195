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
saw the left-out level.

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

from inverse.diagnosis.models import Model, Observations, design

__all__ = ["Fit", "solve_nonneg", "evaluate", "refine", "fit_model", "fit_folds",
           "profile_interval", "information_criteria"]


@dataclass
class Fit:
    """A fitted model.

    ``residual`` holds the standardized residuals (data - model)/sigma of *every* row
    (omega2 rows, zeta rows, response rows), so rows left out of the fit are prediction
    errors in noise units; ``train`` the levels used."""

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


_LAMBDAS = np.array([1e-3, 1e-2, 1e-1, 1.0, 10.0])


def refine(model, obs, theta, rows, iters, fixed=None):
    """Levenberg-Marquardt on the nonlinear parameters of ``B`` independent problems at
    once (starts, or cross-validation folds): ``theta`` (B, d), ``rows`` (B, N) bool.

    Box bounds by clipping. Each iteration is two batched evaluations: the forward-
    difference Jacobians of every problem, then five trial steps each (damping 1e-3 ...
    10 times the diagonal of J^T J); a problem stops when no trial lowers its chi2.
    ``fixed`` (d,) bool: coordinates held at their start (a profile). Returns the
    refined theta (B, d)."""
    lo, hi = _bounds(model)
    theta = np.array(theta, float)
    B, d = theta.shape
    rows = np.asarray(rows, bool)
    wgt = rows.astype(float)
    h = 1e-4 * (hi - lo)
    _, r0, _ = evaluate(model, obs, theta, rows)
    r0 = r0 * wgt
    f0 = np.sum(r0**2, axis=1)
    live = np.ones(B, bool)
    L = _LAMBDAS.size
    for _ in range(iters):
        idx = np.flatnonzero(live)
        if idx.size == 0:
            break
        th, rw, m = theta[idx], r0[idx], rows[idx]
        step = np.where(th + h > hi, -h, h)                             # (b, d)
        pts = (th[:, None, :] + step[:, :, None] * np.eye(d)).reshape(-1, d)
        _, rj, _ = evaluate(model, obs, pts, np.repeat(m, d, axis=0))
        rj = rj.reshape(idx.size, d, -1) * wgt[idx][:, None, :]
        J = (rj - rw[:, None, :]) / step[:, :, None]                    # (b, d, N)
        if fixed is not None:
            J[:, np.asarray(fixed, bool), :] = 0.0
        JtJ = np.einsum("bdn,ben->bde", J, J)
        g = np.einsum("bdn,bn->bd", J, rw)
        diag = np.maximum(np.einsum("bdd->bd", JtJ),
                          1e-12 * np.maximum(np.einsum("bdd->b", JtJ), 1e-300)[:, None])
        Mt = JtJ[:, None] + _LAMBDAS[None, :, None, None] * (diag[:, None, :, None]
                                                            * np.eye(d))
        with np.errstate(all="ignore"):
            delta = np.linalg.solve(Mt, np.broadcast_to(g[:, None, :, None],
                                                        (idx.size, L, d, 1)))[..., 0]
        trial = np.clip(th[:, None, :] - np.nan_to_num(delta), lo, hi).reshape(-1, d)
        _, rt, _ = evaluate(model, obs, trial, np.repeat(m, L, axis=0))
        rt = rt.reshape(idx.size, L, -1) * wgt[idx][:, None, :]
        ft = np.sum(rt**2, axis=2)
        ft = np.where(np.isfinite(ft), ft, np.inf)
        best = np.argmin(ft, axis=1)
        fb = ft[np.arange(idx.size), best]
        better = fb < f0[idx]
        small = f0[idx] - fb < 1e-7 * np.maximum(fb, 1.0)
        upd = idx[better]
        theta[upd] = trial.reshape(idx.size, L, d)[better, best[better]]
        r0[upd] = rt[better, best[better]]
        f0[upd] = fb[better]
        live[idx[~better | small]] = False
    return theta


def _finish(model, obs, cands, train, starts=None):
    """The best of the candidate thetas on ``train`` as a :class:`Fit` (chi2 inf when
    no candidate gives a finite one: a failed fit)."""
    rows = np.tile(train, len(obs.channels))
    x, r, log_s = evaluate(model, obs, cands, rows)
    f = np.sum(r[:, rows] ** 2, axis=1)
    i = int(np.argmin(np.where(np.isfinite(f), f, np.inf)))
    k = model.n_params(obs.log_r is not None)
    n = int(rows.sum())
    chi2 = float(f[i]) if np.isfinite(f[i]) else float("inf")
    aic, aicc, bic = information_criteria(chi2, k, n)
    return Fit(model=model, theta=cands[i], linear=x[i], residual=r[i], log_s=log_s[i],
               train=train, chi2=chi2, n_data=n, n_params=k, aic=aic, aicc=aicc,
               bic=bic, starts=starts)


def fit_model(model: Model, obs: Observations, train=None, start=None, iters: int = 25,
              n_starts: int = 3, extra_starts=None) -> Fit:
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
    cands = refine(model, obs, theta0, np.repeat(rows[None], theta0.shape[0], 0), iters)
    return _finish(model, obs, cands, train, theta0)


def fit_folds(full: Fit, obs: Observations, trains, iters: int = 12) -> list:
    """Refits of ``full``'s model to each training set of ``trains`` (F, n) bool, every
    fold refined from each of ``full.starts`` (the starting points of the fit to all
    levels, not its optimum). Returns a list of :class:`Fit` (``failed`` when no start
    gave a finite chi2)."""
    trains = np.asarray(trains, bool)
    starts = full.starts if full.starts is not None else full.theta[None]
    S, F = starts.shape[0], trains.shape[0]
    rows = np.repeat(np.tile(trains, (1, len(obs.channels))), S, axis=0)
    th = refine(full.model, obs, np.tile(starts, (F, 1)), rows, iters)
    return [_finish(full.model, obs, th[i * S:(i + 1) * S], trains[i]) for i in range(F)]


def profile_interval(fit: Fit, obs: Observations, j: int, threshold: float,
                     n_points: int = 13):
    """Profile interval of nonlinear parameter ``j`` of ``fit``: the range of values on
    a grid over its box (plus the fitted value) where the chi2 minimized over the other
    nonlinear parameters (from the fit's starts and its optimum) stays within
    ``threshold`` of the fit's chi2 (3.84: 95 % for one parameter, Wilks). Returns
    ``((lower, upper), failures)``; the interval reaches a bound when the bound is
    inside it."""
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
    th = refine(fit.model, obs, theta0, np.repeat(rows[None], theta0.shape[0], 0), 15, fixed)
    _, r, _ = evaluate(fit.model, obs, th, rows)
    chi2 = np.sum(r[:, rows] ** 2, axis=1).reshape(S, values.size)
    chi2 = np.where(np.isfinite(chi2), chi2, np.inf).min(axis=0)
    failures = int(np.sum(~np.isfinite(chi2)))
    inside = values[chi2 - min(fit.chi2, chi2.min()) <= threshold]
    return (float(inside.min()), float(inside.max())), failures
