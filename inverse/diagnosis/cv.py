"""Prediction errors on levels a fit did not see: the ``gain`` of a diagnosis, and the
held-out predictions with their intervals.

Error measure (the same for every model): the root-mean-square standardized
prediction error ``sqrt(mean(((y - y_pred) / sigma)^2))`` over the held-out levels and
all channels (omega2, zeta, and log response when present), ``sigma`` the total noise
of :mod:`inverse.judge`. A level is left out with all its repeats.

* Leave one level out (``gain``): each interior level (not the lowest, not the highest:
  an end level would test extrapolation, see below) is left out in turn, the model is
  refitted to the others from the starting points of its fit to all levels (not from
  that fit's optimum, which saw the left-out level) and the left-out level predicted.
  A fold whose refit fails is counted; an error over failed folds is None.
* Held out at the top (``gain_held_out``, the paper's protocol): the model is fitted to
  the lower levels only (a fresh global fit) and predicts the top
  ``max(1, round(0.3 n))`` levels (at least 4 levels are kept for the fit), which
  it never saw: extrapolation in amplitude.
* Held-out predictions (:func:`prediction_intervals`): for each row of a held-out top
  level, the predicted omega2 and zeta with a nominal 95 % prediction interval:
  ``y_hat +- q sigma sqrt(1 + g^T (J^T J)^+ g)``, ``J`` the Jacobian of the
  standardized model on the training rows and ``g`` that of the prediction, over the
  free parameters only (a parameter on its bound, a non-negative linear parameter at
  0, is held there, not treated as free); ``q`` the normal quantile with known noise,
  Student's t with the noise's degrees of freedom when the repeatability is estimated.
* Model-averaged (:func:`model_averaged`): the named model is one of several the data
  allow, and an interval conditional on it ignores that choice. The held-out
  predictions of the eligible candidates (Akaike weights ``w_i`` renormalized over
  them, those under :data:`W_MIN` dropped) are averaged, ``y = sum w_i y_i``, with
  the unconditional variance ``sum w_i (sd_i^2 + (y_i - y)^2)`` (Burnham & Anderson
  2002, sec. 4.3.2, eq. 4.9).

A model with as many parameters as training data cannot predict; its error is None
with the reason.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from inverse.diagnosis.fit import Fit, fit_folds, fit_model
from inverse.diagnosis.models import Observations, design
from inverse.judge import at_bound

__all__ = ["W_MIN", "leave_one_out", "held_out_top", "n_top", "prediction_intervals",
           "averaging_weights", "model_averaged"]

#: Candidates of smaller renormalized Akaike weight are left out of the average.
W_MIN = 0.01


def _rows(obs: Observations, mask):
    return np.tile(mask, len(obs.channels))


def leave_one_out(full: Fit, obs: Observations, iters: int = 12):
    """Leave-one-interior-level-out errors of ``full``'s model.

    Returns (rms error or None, standardized residuals (n, channels) with NaN rows at
    the end levels, reason or None, failed folds)."""
    nc = len(obs.channels)
    res = np.full((obs.n, nc), np.nan)
    labels = np.unique(obs.levels)
    interior = labels[1:-1]
    n_min = min(int(np.sum(obs.levels != lv)) for lv in interior) if interior.size else 0
    if not interior.size or n_min * nc <= full.n_params:
        return None, res, (f"{n_min * nc} data without one level for "
                           f"{full.n_params} parameters"), 0
    trains = np.array([obs.levels != lv for lv in interior])
    failed = 0
    for train, f in zip(trains, fit_folds(full, obs, trains, iters)):
        if f.failed:
            failed += 1
            continue
        res[~train] = f.residual.reshape(nc, obs.n).T[~train]
    if failed:
        return None, res, f"{failed} of {len(trains)} folds failed", failed
    return float(np.sqrt(np.nanmean(res**2))), res, None, 0


def n_top(n: int) -> int:
    """Number of top levels held out (module doc)."""
    return max(1, min(int(round(0.3 * n)), n - 4))


def _top_train(obs):
    labels = np.unique(obs.levels)
    top = n_top(labels.size)
    return obs.levels < labels[labels.size - top], top


def held_out_top(full: Fit, obs: Observations):
    """Fit the lower levels, predict the top ones (module doc).

    Returns (rms error or None, reason or None, the fit to the lower levels or None)."""
    train, top = _top_train(obs)
    n_train = int(train.sum()) * len(obs.channels)
    if n_train <= full.n_params:
        return None, (f"{int(train.sum())} lower rows give {n_train} data for "
                      f"{full.n_params} parameters"), None
    f = fit_model(full.model, obs, train, n_starts=2, iters=15)
    if f.failed:
        return None, "the fit to the lower levels failed", f
    r = f.residual[_rows(obs, ~train)]
    return float(np.sqrt(np.mean(r**2))), None, f


def _free(fit: Fit, obs: Observations, rtol: float = 1e-3):
    """Masks of the free nonlinear and linear parameters (not on a bound)."""
    nl = np.array([not at_bound(v, lo, hi, rtol)[0]
                   for v, (_, lo, hi, _) in zip(fit.theta, fit.model.nonlinear)], bool)
    nonneg = fit.model.nonneg(obs.log_r is not None)
    lin = np.array([not (j in nonneg and x <= 0.0) for j, x in enumerate(fit.linear)], bool)
    return nl, lin


def prediction_intervals(fit: Fit, obs: Observations, dof: float, level: float = 0.95):
    """Predicted omega2 and zeta of the rows ``fit`` did not see, with their nominal
    ``level`` prediction intervals (module doc). ``dof`` the noise's degrees of freedom
    (inf: known). Returns a list of dicts, one per held-out row."""
    train = np.asarray(fit.train, bool)
    rows = _rows(obs, train)
    nl_free, lin_free = _free(fit, obs)
    A, _, _ = design(fit.model, obs, fit.theta[None])
    A = A[0]
    cols = [A[:, lin_free]]
    lo = np.array([a[1] for a in fit.model.nonlinear])
    hi = np.array([a[2] for a in fit.model.nonlinear])
    for j in np.flatnonzero(nl_free):
        h = 1e-5 * (hi[j] - lo[j])
        step = -h if fit.theta[j] + h > hi[j] else h
        th = fit.theta.copy()
        th[j] += step
        Aj, _, _ = design(fit.model, obs, th[None])
        cols.append(((Aj[0] @ fit.linear - A @ fit.linear) / step)[:, None])
    J = np.hstack(cols)                                        # standardized model
    C = np.linalg.pinv(J[rows].T @ J[rows])
    q = _quantile(dof, level)
    n = obs.n
    out = []
    for i in np.flatnonzero(~train):
        item = {"level": int(obs.levels[i])}
        for c, ch in enumerate(("omega2", "zeta")):
            r = c * n + i
            g = J[r]
            sd = obs.sigma[ch][i] * math.sqrt(1.0 + float(g @ C @ g))
            y = [obs.omega2, obs.zeta][c][i]
            pred = y - fit.residual[r] * obs.sigma[ch][i]
            item[ch] = {"measured": float(y), "predicted": float(pred),
                        "interval": [float(pred - q * sd), float(pred + q * sd)],
                        "sd": float(sd), "inside": bool(abs(y - pred) <= q * sd)}
        out.append(item)
    return out


def _quantile(dof: float, level: float) -> float:
    return float(stats.norm.ppf(0.5 + level / 2) if math.isinf(dof)
                 else stats.t.ppf(0.5 + level / 2, dof))


def averaging_weights(selection) -> dict:
    """``{candidate: weight}`` of the model average (module doc): the eligible
    candidates of a :class:`inverse.judge.Selection`, renormalized, those under
    :data:`W_MIN` dropped; the closest candidate alone when ``unexplained``."""
    if not selection.eligible:
        return {selection.best: 1.0}
    w = {k: selection.weights[k] for k in selection.eligible}
    tot = sum(w.values()) or 1.0
    w = {k: v / tot for k, v in w.items() if v / tot >= W_MIN or k == selection.best}
    tot = sum(w.values())
    return {k: v / tot for k, v in w.items()}


def model_averaged(per_model: dict, weights: dict, dof: float, level: float = 0.95):
    """Model-averaged held-out predictions (module doc) from ``per_model``
    ``{candidate: rows of prediction_intervals}`` (candidates whose held-out fit failed
    left out) and ``weights`` ``{candidate: w}``; rows as :func:`prediction_intervals`."""
    names = [k for k in weights if per_model.get(k)]
    if not names:
        return []
    w = np.array([weights[k] for k in names])
    w = w / w.sum()
    q = _quantile(dof, level)
    out = []
    for rows in zip(*(per_model[k] for k in names)):
        item = {"level": rows[0]["level"]}
        for ch in ("omega2", "zeta"):
            y = rows[0][ch]["measured"]
            pred_i = np.array([r[ch]["predicted"] for r in rows])
            sd_i = np.array([r[ch]["sd"] for r in rows])
            pred = float(w @ pred_i)
            sd = math.sqrt(float(w @ (sd_i**2 + (pred_i - pred) ** 2)))
            item[ch] = {"measured": y, "predicted": pred,
                        "interval": [pred - q * sd, pred + q * sd], "sd": sd,
                        "inside": bool(abs(y - pred) <= q * sd)}
        out.append(item)
    return out
