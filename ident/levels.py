"""The mode of a stepped-sine campaign identified level by level.

Every level's FRF at one response point goes through the LSCF identification
(:func:`ident.identify.identify`), the levels agree on the number of modes in the band
(:func:`ident.tracking.agree_on_modes`: a level the nonlinearity distorts into two
poles is identified again with the count of the other levels), the mode nearest a
target frequency is kept and
the campaign's amplitudes (joint slips, response) are read "at resonance", i.e.
interpolated by a cubic spline over the lines at the identified frequency. The modal
filter (:mod:`ident.modal_filter`) is the identification-free check of the same levels.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LevelIdentification", "spline_at", "identify_levels"]


@dataclass
class LevelIdentification:
    """Per level: identified ``frequency_hz``, ``omega2`` (rad^2/s^2), ``zeta``; joint slip
    amplitudes at the identified frequency ``slip`` (n_levels, n_joints) (m); ``slip_eff``
    (B-weighted, m); ``response`` displacement amplitude at the response DOF there (m)."""

    frequency_hz: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    slip: np.ndarray
    slip_eff: np.ndarray
    response: np.ndarray


def spline_at(freq, values, f0):
    """Cubic-spline interpolation of ``values`` (n_lines, ...) at ``f0`` (Hz)."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(freq, values, axis=0)(f0)


def identify_levels(freq_hz, receptance, slip_amplitude, force, band, target_hz, weights,
                    options=None, progress=None) -> LevelIdentification:
    """Identify the mode nearest ``target_hz`` at every level; amplitudes at resonance.

    Parameters
    ----------
    freq_hz : (n_lines,) Hz.
    receptance : (n_levels, n_lines) complex, m/N at the response DOF.
    slip_amplitude : (n_levels, n_lines, n_joints) half peak-to-peak slips (m).
    force : (n_levels,) N.
    band : (lo, hi) Hz.
    target_hz : float
    weights : (n_joints,) ``q_m = w_m (g_m . phi)^2`` for the effective amplitude.
    options : dict, optional
        Keyword options of :func:`ident.identify.identify`.
    progress : tqdm bar or None (one tick per level).
    """
    from ident.identify import Identification, identify
    from ident.tracking import agree_on_modes

    f = np.asarray(freq_hz, dtype=float)
    sel = (f >= band[0]) & (f <= band[1])
    L = receptance.shape[0]
    nj = slip_amplitude.shape[2]
    f_id, om2, ze, resp = (np.full(L, np.nan) for _ in range(4))
    slip = np.full((L, nj), np.nan)

    def fit(lv, n_modes=None):
        try:
            return identify(f[sel], receptance[lv, sel], band=band, n_modes=n_modes,
                            **(options or {}))
        except ValueError:
            return Identification([], None, float("nan"))

    results = []
    for lv in range(L):
        results.append(fit(lv))
        if progress is not None:
            progress.update(1)
    if not (options or {}).get("n_modes"):
        results = agree_on_modes(results, fit)[0]
    for lv in range(L):
        modes = results[lv].modes
        if modes:
            m = min(modes, key=lambda m: abs(m.frequency_hz - target_hz))
            f_id[lv], om2[lv], ze[lv] = m.frequency_hz, m.omega2, m.zeta
            slip[lv] = spline_at(f[sel], slip_amplitude[lv, sel], m.frequency_hz)
            resp[lv] = spline_at(f[sel], np.abs(receptance[lv, sel]), m.frequency_hz) * force[lv]
    w = np.asarray(weights, dtype=float)
    return LevelIdentification(f_id, om2, ze, slip, slip @ w / w.sum(), resp)
