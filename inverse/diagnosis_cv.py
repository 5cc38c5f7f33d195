"""Prediction errors on levels a fit did not see: the ``gain`` of a diagnosis.

Error measure (the same for every model): the root-mean-square standardized
prediction error ``sqrt(mean(((y - y_pred) / sigma)^2))`` over the held-out levels and
all channels (omega2, zeta, and log response when present), ``sigma`` the noise level
of :mod:`inverse.diagnosis_noise`.

* Leave one level out (``gain``): each interior level (not the lowest, not the highest:
  an end level would test extrapolation, see below) is left out in turn, the model is
  refitted to the others (starting from its fit to all levels) and the left-out level
  predicted.
* Held out at the top (``gain_held_out``, the paper's protocol): the model is fitted to
  the lower levels only (a fresh global fit) and predicts the top
  ``max(1, round(0.3 n))`` levels (at least 4 levels are kept for the fit), which
  it never saw: extrapolation in amplitude.

A model with as many parameters as training data cannot predict; its error is None
with the reason.
"""
from __future__ import annotations

import numpy as np

from inverse.diagnosis_fit import Fit, fit_folds, fit_model
from inverse.diagnosis_models import Observations

__all__ = ["leave_one_out", "held_out_top", "n_top"]


def _rows(obs: Observations, levels):
    mask = np.zeros(obs.n, bool)
    mask[levels] = True
    return np.tile(mask, len(obs.channels))


def leave_one_out(full: Fit, obs: Observations, iters: int = 6):
    """Leave-one-interior-level-out errors of ``full``'s model.

    Returns (rms error or None, standardized residuals (n, channels) with NaN rows at
    the end levels, reason or None)."""
    nc = len(obs.channels)
    res = np.full((obs.n, nc), np.nan)
    if (obs.n - 1) * nc <= full.n_params:
        return None, res, (f"{(obs.n - 1) * nc} data without one level for "
                           f"{full.n_params} parameters")
    trains = ~np.eye(obs.n, dtype=bool)[1:-1]
    for v, f in zip(range(1, obs.n - 1), fit_folds(full, obs, trains, iters)):
        res[v] = f.residual[_rows(obs, [v])]
    return float(np.sqrt(np.nanmean(res**2))), res, None


def n_top(n: int) -> int:
    """Number of top levels held out (module doc)."""
    return max(1, min(int(round(0.3 * n)), n - 4))


def held_out_top(full: Fit, obs: Observations):
    """Fit the lower levels, predict the top ones (module doc).

    Returns (rms error or None, reason or None)."""
    top = n_top(obs.n)
    train = np.ones(obs.n, bool)
    train[obs.n - top:] = False
    n_train = int(train.sum()) * len(obs.channels)
    if n_train <= full.n_params:
        return None, (f"{int(train.sum())} lower levels give {n_train} data for "
                      f"{full.n_params} parameters")
    f = fit_model(full.model, obs, train, n_starts=2, iters=15)
    r = f.residual[_rows(obs, np.arange(obs.n - top, obs.n))]
    return float(np.sqrt(np.mean(r**2))), None
