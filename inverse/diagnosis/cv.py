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
  A fold whose refit fails, or does not converge (:mod:`inverse.diagnosis.lm`: its
  prediction would depend on where an iteration cap stopped it), is a failed fold,
  counted; an error over failed folds is None.
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

from typing import NamedTuple

import numpy as np

from inverse.diagnosis.fit import MAX_ITERS, Fit, fit_folds, fit_model
from inverse.diagnosis.models import Observations

__all__ = ["Folds", "leave_one_out", "untestable_gain", "held_out_top", "n_top"]


class Folds(NamedTuple):
    """The answer of :func:`leave_one_out`: the rms ``error`` (None over failed folds or
    too few data), the standardized ``residuals`` (n, channels) of the left-out rows
    (NaN at the end levels and where a fold failed), the ``reason`` when there is no
    error, the ``failed`` folds (no finite chi2 or not converged) and, of them, the
    ``unconverged`` ones."""

    error: float | None
    residuals: np.ndarray
    reason: str | None
    failed: int
    unconverged: int = 0


def leave_one_out(full: Fit, obs: Observations, iters: int = MAX_ITERS) -> Folds:
    """Leave-one-interior-level-out errors of ``full``'s model (module doc), each fold at
    most ``iters`` steps from each start (:func:`inverse.diagnosis.fit.fit_folds`)."""
    nc = len(obs.channels)
    res = np.full((obs.n, nc), np.nan)
    labels = np.unique(obs.levels)
    interior = labels[1:-1]
    n_min = min(int(np.sum(obs.levels != lv)) for lv in interior) if interior.size else 0
    if not interior.size or n_min * nc <= full.n_params:
        return Folds(None, res, (f"{n_min * nc} data without one level for "
                                 f"{full.n_params} parameters"), 0)
    trains = np.array([obs.levels != lv for lv in interior])
    failed = unconverged = 0
    for train, f in zip(trains, fit_folds(full, obs, trains, iters)):
        if f.failed or not f.converged:
            failed += 1
            unconverged += not f.failed
            continue
        res[~train] = f.residual.reshape(nc, obs.n).T[~train]
    if failed:
        what = "failed" if not unconverged else (
            "did not converge" if unconverged == failed
            else f"failed ({unconverged} did not converge)")
        return Folds(None, res, f"{failed} of {len(trains)} folds {what}", failed,
                     unconverged)
    return Folds(float(np.sqrt(np.nanmean(res**2))), res, None, 0)


def untestable_gain(entry, base) -> str | None:
    """Why no held-out gain can be measured at all (too few levels to leave one out),
    from the :func:`leave_one_out` answers of a candidate (``entry``) and of the base
    model (``base``); None when the gain was measured or a fold failed (a failure
    is counted, not a property of the data)."""
    err, why, failed = entry[0], entry[2], entry[3]
    base_err, base_why, base_failed = base[0], base[2], base[3]
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


def held_out_top(full: Fit, obs: Observations, iters: int = MAX_ITERS):
    """Fit the lower levels, predict the top ones (module doc); at most ``iters`` steps
    per start.

    Returns (rms error or None, reason or None, the fit to the lower levels or None)."""
    train, top = _top_train(obs)
    n_train = int(train.sum()) * len(obs.channels)
    if n_train <= full.n_params:
        return None, (f"{int(train.sum())} lower rows give {n_train} data for "
                      f"{full.n_params} parameters"), None
    f = fit_model(full.model, obs, train, n_starts=2, iters=iters)
    if f.failed:
        return None, "the fit to the lower levels failed", f
    if not f.converged:
        return None, (f"the fit to the lower levels did not converge in {f.iterations} "
                      f"steps"), f
    r = f.residual[obs.channel_rows(~train)]
    return float(np.sqrt(np.mean(r**2))), None, f
