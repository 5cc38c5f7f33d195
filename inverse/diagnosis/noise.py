"""The noise of one mode's data through the one judge (:func:`inverse.judge.noise_model`),
and the identification model error of a force-controlled test.

Channels: ``omega2`` and ``zeta`` (identification stds plus the test's repeatability,
from repeats or the scatter about a model-free smooth curve), and the log response
amplitude when present (no std column: its repeatability alone, floored at 0.01: the
resonant amplitude is read from an equivalent linear fit of a nonlinear FRF, whose
residue absorbs part of the FRF's distortion, and from a sensor calibrated to about
1 %).

Model error of the response channel (force control): a stepped sine at constant force
sweeps the amplitude from the peak down to 1/sqrt(2) of it across the half-power band,
``ln sqrt(2) = 0.35`` in log amplitude, and the equivalent linear fit averages the
damping over that span; its damping ratio, and with it the resonant amplitude read
from the fit, is off by about half of it times the local log-slope of the damping:
``0.17 |d ln zeta / d ln s|`` (:func:`distortion`), added in quadrature. The same error
touches omega2 and zeta (the equivalent linear fit sits between the values at the peak
and at the half-power amplitudes), by up to ``0.17 |d y / d ln s|`` of the fitted curve.
It is *not* added to their noise: :func:`test_chi2` computes the test with it added,
and the report says when that alone would bring the data within their noise (then an
``unexplained`` may come from the FRF distortion, not the structure).
"""
from __future__ import annotations

import numpy as np

from inverse.judge import NoiseModel, noise_model
from inverse.judge.prior import RIG_REPEATABILITY

__all__ = ["RESPONSE_FLOOR", "distortion", "log_slope", "one_mode_noise", "test_chi2"]

#: Floor of the log response amplitude's noise (module doc).
RESPONSE_FLOOR = 1e-2


def log_slope(levels, x, y):
    """``d y / d x`` over the level means, returned per row (0 with one level)."""
    lab, inv = np.unique(levels, return_inverse=True)
    if lab.size < 2:
        return np.zeros(len(y))
    cnt = np.bincount(inv)
    xm, ym = np.bincount(inv, x) / cnt, np.bincount(inv, y) / cnt
    return np.gradient(ym, xm)[inv]


def distortion(log_s, zeta, levels=None):
    """Model error of the log response amplitude of a force-controlled level (module
    doc): ``0.17 |d ln zeta / d ln s|`` per row (slopes over level means)."""
    levels = np.arange(len(zeta)) if levels is None else levels
    return 0.17 * np.abs(log_slope(levels, np.asarray(log_s), np.log(zeta)))


def one_mode_noise(obs, stds: dict, abscissa, run_order, at_peak=None,
                   prior=RIG_REPEATABILITY, cap: bool = True) -> NoiseModel:
    """The judge's noise model of ``obs`` (:class:`inverse.diagnosis.models.Observations`)
    with the table's ``stds`` (``{channel: (n,) or None}``). ``at_peak`` (n,) bool: rows
    whose pole and response were identified at the level's peak amplitude
    (``iwanfe identify --amplitude-refit``, :mod:`ident.amplitude_poles`): no
    distortion error on their response. ``prior``: the assumed rig repeatability
    (:mod:`inverse.judge.prior`; None: the data's estimate alone); ``cap``: as in
    :func:`inverse.judge.noise_model`."""
    values = {"omega2": obs.omega2, "zeta": obs.zeta}
    error = {}
    if obs.log_r is not None:
        values["response"] = obs.log_r
        error["response"] = distortion(np.log(obs.s), obs.zeta, obs.levels)
        if at_peak is not None:
            error["response"] = np.where(at_peak, 0.0, error["response"])
    return noise_model(abscissa, values, stds, obs.levels, run_order,
                       floors={"response": RESPONSE_FLOOR}, model_error=error, prior=prior,
                       cap=cap)


def test_chi2(residual, sigma, fitted, log_s, rows, force_control: bool, levels=None,
              at_peak=None) -> float:
    """``chi2`` of a fit with the identification model error of a force-controlled
    test added: standardized residuals ``residual`` (channels, n) of noise ``sigma``
    (channels, n), model error ``0.17 |d fitted / d ln s|`` of omega2 and zeta (module
    doc); ``rows`` (channels, n) the levels in the fit. ``at_peak`` (n,) bool: rows
    identified at their peak amplitude (``--amplitude-refit``), which carry no such
    error (as in :func:`one_mode_noise`)."""
    r = np.asarray(residual, float).copy()
    levels = np.arange(r.shape[1]) if levels is None else levels
    if force_control and len(np.unique(levels)) > 1:
        for i in (0, 1):
            e = 0.17 * np.abs(log_slope(levels, np.asarray(log_s), fitted[i]))
            if at_peak is not None:
                e = np.where(at_peak, 0.0, e)
            r[i] = r[i] * sigma[i] / np.sqrt(sigma[i] ** 2 + e**2)
    return float(np.sum(r[rows] ** 2))
