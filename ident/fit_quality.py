"""Is an identified mode to be trusted? Fit error, pole stability, band sensitivity.

Three checks of one level's identification (:func:`ident.identify.identify`), each a
plain warning with its numbers (:func:`mode_warnings`):

* **fit error**: the relative rms misfit of the modal model over the band above
  :data:`FIT_ERROR_LIMIT`; the lag-1 correlation of the weighted residuals along
  frequency says whether the misfit is noise (near 0) or a model that does not follow
  the FRF (near 1: a force-controlled FRF distorted by a nonlinear joint, a missed mode).
* **stability**: the pole was stable at fewer than :data:`STABILITY_LIMIT` of the LSCF
  model orders, or its frequency lies outside the band.
* **band sensitivity** (:func:`band_shift`): the mode identified again, alone, on a
  narrower band around it, ``f_r +- BAND_HALF_WIDTHS zeta f_r`` but at most
  :data:`BAND_KEEP` of the band (so it always narrows) and clear of the other modes'
  ``+- BAND_HALF_WIDTHS zeta f``, must give the same frequency
  and damping within :data:`BAND_SHIFT_Z` standard uncertainties of their difference
  (``sqrt(s_narrow^2 + s_full^2)``, the identification's own, :mod:`ident.pole_uncertainty`)
  and by more than 1e-5 of the frequency or 0.1 % of zeta (floors for noise-free data).
  A linear mode in noise passes; an FRF that is no linear modal model (the joint's
  stiffness and damping change along a force-controlled sweep) gives band-dependent
  values, and then the identified values say more about the band than the structure.
"""
from __future__ import annotations

import math

import numpy as np

from ident.poles import modal_receptance, to_receptance

FIT_ERROR_LIMIT = 0.02
STABILITY_LIMIT = 0.3
CORRELATED = 0.5
BAND_HALF_WIDTHS = 3.0
BAND_KEEP = 0.6
BAND_SHIFT_Z = 3.0
#: Moves below these are not reported whatever their z-score (noise-free simulated FRFs
#: have tiny uncertainties): 1e-5 of the frequency (the 6 digits of a table), 0.1 % of zeta.
BAND_SHIFT_FLOOR_FREQ = 1e-5
BAND_SHIFT_FLOOR_ZETA = 1e-3
MIN_LINES = 12


def narrowed_band(freq_hz, band, frequency_hz, zeta, others=()):
    """The narrower band around a mode (module doc), kept clear of the other modes'
    resonances (``others``: their (frequency_hz, zeta); each keeps
    ``BAND_HALF_WIDTHS zeta f`` around it out), or None if it would hold fewer than
    :data:`MIN_LINES` lines."""
    freq_hz = np.asarray(freq_hz, float)
    lo, hi = band
    half = min(BAND_HALF_WIDTHS * zeta * frequency_hz, 0.5 * BAND_KEEP * (hi - lo))
    centre = min(max(frequency_hz, lo + half), hi - half)
    for f_o, z_o in others:
        clear = abs(f_o - centre) - BAND_HALF_WIDTHS * z_o * f_o
        half = min(half, max(clear, 0.0))
    new = (centre - half, centre + half)
    n = int(np.sum((freq_hz >= new[0]) & (freq_hz <= new[1])))
    return new if n >= MIN_LINES else None


def band_shift(freq_hz, frf, quantity, result, index, options=None, refit=None):
    """Identify mode ``index`` of ``result`` again, alone, on the narrowed band, from the
    FRF less the other modes as identified (their modal receptances), with the same
    ``options`` of :func:`ident.identify.identify`, then ``refit(freq_hz, receptance,
    narrow_identification)`` if given (the series' amplitude-dependent refit).

    Returns None when the band cannot be narrowed or the narrow fit fails, else a dict
    with the band (Hz), the changes of frequency (Hz) and zeta, and their z-scores."""
    from ident.identify import identify

    mode = result.modes[index]
    others = [m for k, m in enumerate(result.modes) if k != index]
    band = narrowed_band(freq_hz, result.band_hz, mode.frequency_hz, mode.zeta,
                         [(m.frequency_hz, m.zeta) for m in others])
    if band is None:
        return None
    H = to_receptance(freq_hz, frf, quantity)
    H = H.reshape(H.shape[0], -1) - sum((modal_receptance(m.pole, m.shape, freq_hz)
                                         for m in others), np.zeros((H.shape[0], 1)))
    try:
        narrow = identify(freq_hz, H, band=band, n_modes=1, quantity="receptance",
                          **(options or {}))
        narrow = (refit(freq_hz, H, narrow) if refit is not None else narrow).modes
    except ValueError:
        return None
    if not narrow:
        return None
    other = narrow[0]
    d_w2, d_z = other.omega2 - mode.omega2, other.zeta - mode.zeta
    s_w2 = math.hypot(other.omega2_std, mode.omega2_std)
    s_z = math.hypot(other.zeta_std, mode.zeta_std)
    if not (s_w2 > 0 and s_z > 0):      # NaN: no uncertainty, nothing to judge against
        return None
    d_f = other.frequency_hz - mode.frequency_hz
    return {"band_hz": band, "d_frequency_hz": d_f, "d_zeta": d_z,
            "z_frequency": (abs(d_w2) / s_w2
                            if abs(d_f) > BAND_SHIFT_FLOOR_FREQ * mode.frequency_hz else 0.0),
            "z_zeta": abs(d_z) / s_z if abs(d_z) > BAND_SHIFT_FLOOR_ZETA * mode.zeta else 0.0}


def mode_warnings(result, index, shift=None) -> list[str]:
    """Plain warnings for mode ``index`` of an Identification (module doc)."""
    mode = result.modes[index]
    out = []
    if result.fit_error > FIT_ERROR_LIMIT:
        corr = result.residual_correlation
        kind = ("residuals correlated along frequency (lag-1 {:.2f}): the modal model does "
                "not follow this FRF" if corr > CORRELATED else
                "residuals uncorrelated (lag-1 {:.2f}): noise").format(corr)
        out.append(f"fit error {100 * result.fit_error:.3g} % > {100 * FIT_ERROR_LIMIT:g} % "
                   f"({kind})")
    if mode.stability < STABILITY_LIMIT:
        out.append(f"unstable pole: stable at {100 * mode.stability:.0f} % of the LSCF model "
                   f"orders (< {100 * STABILITY_LIMIT:.0f} %)")
    lo, hi = result.band_hz
    if not lo <= mode.frequency_hz <= hi:
        out.append(f"pole at {mode.frequency_hz:.6g} Hz lies outside the band {lo:g}-{hi:g} Hz")
    if not (np.isfinite(mode.omega2_std) and np.isfinite(mode.zeta_std)):
        out.append("no uncertainty: the fit has no residual degrees of freedom")
    if shift is not None and max(shift["z_frequency"], shift["z_zeta"]) > BAND_SHIFT_Z:
        b = shift["band_hz"]
        out.append(
            f"band-sensitive: identified again on {b[0]:.6g}-{b[1]:.6g} Hz the frequency "
            f"moves by {shift['d_frequency_hz']:+.3g} Hz ({shift['z_frequency']:.1f} sigma) "
            f"and zeta by {100 * shift['d_zeta'] / mode.zeta:+.3g} % "
            f"({shift['z_zeta']:.1f} sigma): the FRF is not one linear mode over the band")
    return out
