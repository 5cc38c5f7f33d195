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
* Held-out predictions with their intervals, per candidate and model-averaged:
  :mod:`inverse.diagnosis.intervals`, from the fits of :func:`held_out_top`.

A model with as many parameters as training data cannot predict; its error is None
with the reason.
"""
from __future__ import annotations

import numpy as np

from inverse.diagnosis.fit import Fit, fit_folds, fit_model
from inverse.diagnosis.models import Observations

__all__ = ["leave_one_out", "untestable_gain", "held_out_top", "n_top"]


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


def untestable_gain(entry, base) -> str | None:
    """Why no held-out gain can be measured at all (too few levels to leave one out),
    from the :func:`leave_one_out` answers of a candidate (``entry``) and of the base
    model (``base``); None when the gain was measured or a fold failed (a failure
    is counted, not a property of the data)."""
    err, _, why, failed = entry
    base_err, _, base_why, base_failed = base
    if (err is not None and base_err is not None) or failed or base_failed:
        return None
    return why or base_why


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
    r = f.residual[obs.channel_rows(~train)]
    return float(np.sqrt(np.mean(r**2))), None, f
