"""Choosing among fitted simulator extensions: AICc, cross-validation, held-out levels.

Works on :class:`inverse.update.UpdateProblem` / :class:`inverse.update.Fit` pairs (any
simulator, e.g. the FE double beam and its cause extensions,
:mod:`cases.double_beam.fe_diagnosis`). Errors are root-mean-square residuals in noise
units over both channels (omega2 and zeta), ``sqrt(mean r^2)``:

* :func:`cross_validate`: leave-one-level-out over the interior fit levels (the lowest
  and highest fit level always stay in: they anchor the amplitude range), each left-out
  level predicted by a refit that did not see it;
* :func:`held_out_errors`: the levels outside the fit, predicted by the fit itself.

:func:`select_extension` names the extension with the largest AICc drop against the
base if the drop exceeds ``threshold`` (6) and its cross-validated error is below the
base's (gain > 1), else ``none``. :func:`prediction_sd` gives linearized prediction
standard deviations (delta method).
"""
from __future__ import annotations

import math

import numpy as np

from inverse.update import Fit, UpdateProblem, fit

__all__ = ["held_out_errors", "cross_validate", "select_extension", "prediction_sd"]


def held_out_errors(problem: UpdateProblem, values: dict) -> float:
    """rms residual (noise units) at the levels outside ``problem.fit_mask``."""
    held = ~np.asarray(problem.fit_mask, dtype=bool)
    if not held.any():
        return math.nan
    r = problem.residuals(values, held)
    return float(np.sqrt(np.mean(r * r)))


def cross_validate(problem: UpdateProblem, result: Fit) -> float:
    """Leave-one-level-out rms error over the interior fit levels (module docstring)."""
    idx = np.flatnonzero(problem.fit_mask)
    r2 = []
    for i in idx[1:-1]:
        m = problem.fit_mask.copy()
        m[i] = False
        f = fit(problem, result.free, start=result.values, mask=m)
        one = np.zeros_like(m)
        one[i] = True
        r = problem.residuals(f.values, one)
        r2.extend((r * r).tolist())
    return float(np.sqrt(np.mean(r2))) if r2 else math.nan


def select_extension(base_problem: UpdateProblem, base: Fit, candidates: dict,
                     threshold: float = 6.0, progress=None) -> dict:
    """Name the best extension (module docstring).

    ``candidates``: ``cause -> (problem, fit)``. Returns ``cause``, ``candidates`` (those
    past the AICc threshold, best first), ``evidence`` (per cause: ``delta_aicc``,
    ``chi2``, ``extra_parameters`` and, when cross-validated, ``cv_error``, ``cv_gain``),
    ``base_cv_error``, ``cv_error`` and ``gain`` of the named cause (the base's own for
    ``none``).
    """
    say = progress or (lambda s: None)
    evidence = {c: {"delta_aicc": base.aicc - f.aicc, "chi2": f.chi2,
                    "extra_parameters": f.k - base.k}
                for c, (p, f) in candidates.items()}
    passing = sorted((c for c in candidates if evidence[c]["delta_aicc"] > threshold),
                     key=lambda c: -evidence[c]["delta_aicc"])
    say("cross-validation: base")
    base_cv = cross_validate(base_problem, base)
    cause = "none"
    for c in passing:
        say(f"cross-validation: {c}")
        p, f = candidates[c]
        e = cross_validate(p, f)
        evidence[c]["cv_error"] = e
        evidence[c]["cv_gain"] = base_cv / e if e > 0 else math.inf
    for c in passing:                                   # largest AICc drop that also
        if evidence[c]["cv_gain"] > 1.0:                # predicts left-out levels better
            cause = c
            break
    cv = evidence[cause]["cv_error"] if cause != "none" else base_cv
    return {"cause": cause, "candidates": passing, "evidence": evidence,
            "base_cv_error": base_cv, "cv_error": cv,
            "gain": base_cv / cv if cv > 0 else math.inf}


def prediction_sd(problem: UpdateProblem, result: Fit, mask, rel_step: float = 1e-3) -> dict:
    """Standard deviations of the predicted frequency (Hz) and zeta at the levels
    ``mask``: ``J C J^T`` with ``C`` the fit's covariance times its misfit scale and
    ``J`` by forward differences (``rel_step`` of each parameter's ``step``)."""
    m = np.asarray(mask, dtype=bool)
    n = int(m.sum())
    if result.cov is None or not result.free or n == 0:
        return {"frequency_hz": [math.nan] * n, "zeta": [math.nan] * n}

    def out(v):
        om2, ze = problem.simulate(v)
        return np.concatenate([np.sqrt(om2[m]) / (2 * math.pi), ze[m]])

    y0 = out(result.values)
    J = np.empty((y0.size, result.k))
    for j, name in enumerate(result.free):
        h = rel_step * problem.parameters[name].step
        v = dict(result.values)
        v[name] = v[name] + h
        J[:, j] = (out(v) - y0) / h
    var = np.einsum("ij,jk,ik->i", J, result.cov * result.misfit_scale, J)
    sd = np.sqrt(np.maximum(var, 0.0))
    return {"frequency_hz": sd[:n].tolist(), "zeta": sd[n:].tolist()}
