"""The noise level every diagnosis model is judged against, and the test of fit.

Sources, per channel (``omega2``, ``zeta``, log response):

* **identification** -- the table's ``omega2_std``/``zeta_std`` (the identification's
  own standard uncertainty of each level). The spec's choice: a noise level estimated
  only from the residuals of the model being judged lets a misfit hide as noise.
* **scatter** (no std column; always for the response channel, which has none) -- the
  level-to-level roughness of the residuals of the best-fitting candidate: for each
  interior level the residual minus its linear interpolation from the two neighbouring
  levels (in log amplitude), ``d_v = r_v - a r_(v-1) - b r_(v+1)``, whose variance is
  ``sigma^2 (1 + a^2 + b^2)`` for white noise of level ``sigma``, so
  ``sigma^2 = mean(d_v^2 / (1 + a^2 + b^2))`` with ``n - 2`` degrees of freedom. A
  misfit that varies smoothly with amplitude (a wrong power, a missing bend, a wrong
  tie) cancels in ``d_v`` (to second order in the level spacing), so, unlike the rms
  residual, this estimate does not grow with a smooth misfit; what it cannot tell from
  noise is a misfit that changes sign from one level to the next (e.g. an effect that
  follows a shuffled run order and is in no candidate). The first estimate, from the
  raw data (an upper bound: the trend's own curvature adds to it), only weights the
  channels for the first round of fits.
* floors: 1e-9 of omega2 and 1e-7 of zeta (the digits a table prints); 1 % for the
  response amplitude (log response 0.01): the resonant amplitude is read from an
  equivalent linear fit of a nonlinear FRF, whose residue absorbs part of the FRF's
  distortion, and from a sensor calibrated to about 1 %; a smooth departure of that
  size says nothing about the drive.
* model error of the response channel (force control): a stepped sine at constant
  force sweeps the amplitude from the peak down to 1/sqrt(2) of it across the
  half-power band, ``ln sqrt(2) = 0.35`` in log amplitude, and the equivalent linear
  fit averages the damping over that span; its damping ratio, and with it the
  resonant amplitude read from the fit, is off by about half of it times the local
  log-slope of the damping: ``0.17 |d ln zeta / d ln s|`` (:func:`distortion`), added
  in quadrature.

Test of fit (``unexplained``). With known noise the best fit's ``chi2`` follows a
chi-square law with ``N - k`` degrees of freedom; with a scatter estimate of ``nu``
degrees of freedom, ``(chi2 / (N - k))`` follows an F law ``F(N - k, nu)``. The data
are outside their noise when the tail probability is below :data:`P_UNEXPLAINED` =
1e-3: one series in a thousand with a correct model and correct noise levels would be
called unexplained, and a misfit has to exceed the noise clearly (for ``N - k = 20``
known-noise data, an rms residual 1.5x the noise). Under force control the same
identification model error as above touches omega2 and zeta (the equivalent linear fit
sits between the values at the peak and at the half-power amplitudes), by up to
``0.17 |d y / d ln s|`` of the fitted curve. It is *not* added to the noise (the spec:
the identification's stds are the noise): :func:`test_chi2` computes the test with it
added, and the report says when that alone would bring the data within their noise
(then an ``unexplained`` may come from the FRF distortion, not the structure).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

__all__ = ["P_UNEXPLAINED", "Noise", "interpolation_scatter", "distortion", "initial_noise",
           "noise_from_residuals", "test_chi2", "fit_test"]

#: Tail probability below which the best fit leaves the data outside their noise.
P_UNEXPLAINED = 1e-3
_FLOOR = {"omega2": 1e-9, "zeta": 1e-7, "response": 1e-2}


@dataclass
class Noise:
    """Noise level per channel and level (``sigma[ch]`` (n,)), its source per channel
    (``identification`` or ``scatter``), the degrees of freedom of a scatter
    estimate (``dof[ch]``, inf for the identification's stds) and the model error
    added in quadrature (``model_error[ch]``)."""

    sigma: dict
    source: dict
    dof: dict
    model_error: dict = field(default_factory=dict)


def interpolation_scatter(x, r):
    """Noise level of ``r`` (n,) over the abscissa ``x`` (n,) from the residual of
    linear interpolation between neighbours (module doc); (sigma, dof)."""
    order = np.argsort(x, kind="stable")
    x, r = np.asarray(x, float)[order], np.asarray(r, float)[order]
    if r.size < 3:
        return 0.0, 0
    span = x[2:] - x[:-2]
    a = np.where(span > 0, (x[2:] - x[1:-1]) / np.where(span > 0, span, 1.0), 0.5)
    b = 1.0 - a
    d = r[1:-1] - a * r[:-2] - b * r[2:]
    return float(np.sqrt(np.mean(d**2 / (1.0 + a**2 + b**2)))), int(d.size)


def _floor(ch, y):
    return _FLOOR[ch] * (float(np.median(np.abs(y))) if ch != "response" else 1.0)


def distortion(log_s, zeta):
    """Model error of the log response amplitude of a force-controlled level (module
    doc): ``0.17 |d ln zeta / d ln s|`` per level."""
    if len(zeta) < 2:
        return np.zeros(len(zeta))
    return 0.17 * np.abs(np.gradient(np.log(zeta), log_s))


def _with_error(sigma, error):
    return sigma if error is None else np.sqrt(sigma**2 + error**2)


def initial_noise(log_s, channels: dict, stds: dict, model_error=None) -> Noise:
    """First noise levels: the identification's stds where given, else the scatter of
    the raw channel values (``channels[ch]`` (n,)) over ``log_s``; ``model_error``
    (``{channel: (n,)}``) is added in quadrature to scatter-sourced levels."""
    model_error = model_error or {}
    sigma, source, dof = {}, {}, {}
    for ch, y in channels.items():
        if stds.get(ch) is not None:
            sigma[ch] = np.maximum(np.asarray(stds[ch], float), _floor(ch, y))
            source[ch], dof[ch] = "identification", np.inf
        else:
            s, nu = interpolation_scatter(log_s, y)
            sigma[ch] = _with_error(np.full(len(y), max(s, _floor(ch, y))),
                                    model_error.get(ch))
            source[ch], dof[ch] = "scatter", nu
    return Noise(sigma, source, dof, model_error)


def noise_from_residuals(noise: Noise, log_s, residual: dict, values: dict) -> Noise:
    """Replace every scatter-sourced level by the scatter of a fit's residuals
    (``residual[ch]`` in the units of the channel)."""
    sigma, dof = dict(noise.sigma), dict(noise.dof)
    for ch, src in noise.source.items():
        if src == "scatter":
            s, nu = interpolation_scatter(log_s, residual[ch])
            sigma[ch] = _with_error(np.full(len(residual[ch]), max(s, _floor(ch, values[ch]))),
                                    noise.model_error.get(ch))
            dof[ch] = nu
    return Noise(sigma, dict(noise.source), dof, noise.model_error)


def test_chi2(residual, sigma, fitted, log_s, rows, force_control: bool) -> float:
    """``chi2`` of a fit with the identification model error of a force-controlled
    test added: standardized residuals ``residual`` (channels, n) of noise ``sigma``
    (channels, n), model error ``0.17 |d fitted / d ln s|`` of omega2 and zeta (module
    doc); ``rows`` (channels, n) the levels in the fit."""
    r = np.asarray(residual, float).copy()
    if force_control and len(log_s) > 1:
        for i in (0, 1):
            e = 0.17 * np.abs(np.gradient(fitted[i], log_s))
            r[i] = r[i] * sigma[i] / np.sqrt(sigma[i] ** 2 + e**2)
    return float(np.sum(r[rows] ** 2))


def fit_test(chi2: float, n_data: int, n_params: int, noise: Noise) -> dict:
    """Is a fit within the noise? (module doc). Returns ``p_value``,
    ``rms_standardized`` (sqrt(chi2 / N)), ``dof`` and the ``test`` used."""
    dof = n_data - n_params
    rms = float(np.sqrt(chi2 / max(n_data, 1)))
    if dof <= 0:
        return {"p_value": None, "rms_standardized": rms, "dof": dof,
                "test": f"none possible ({n_data} data, {n_params} parameters)"}
    nu = sum(noise.dof[ch] for ch in ("omega2", "zeta") if noise.source[ch] == "scatter")
    if nu == 0:
        p = float(stats.chi2.sf(chi2, dof))
        test = f"chi-square, {dof} degrees of freedom (noise from the identification)"
    else:
        p = float(stats.f.sf(chi2 / dof, dof, nu))
        test = (f"F({dof}, {nu}) (noise from the level-to-level scatter of the "
                f"residuals)")
    return {"p_value": p, "rms_standardized": rms, "dof": dof, "test": test}
