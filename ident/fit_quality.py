"""Is an identified mode to be trusted? Fit error, pole stability, band sensitivity.

Three checks of one level's identification (:func:`ident.identify.identify`), each a
plain warning with its numbers (:func:`mode_warnings`):

* **fit error**: the relative rms misfit of the modal model over the band above
  :data:`FIT_ERROR_LIMIT`; the lag-1 correlation of the weighted residuals along
  frequency says whether the misfit is noise (near 0) or a model that does not follow
  the FRF (near 1: a force-controlled FRF distorted by a nonlinear joint, a missed mode).
* **stability**: the pole was stable at fewer than :data:`STABILITY_LIMIT` of the LSCF
  model orders, or its frequency lies outside the band.
* **band sensitivity** (:func:`band_shift`): the mode identified again on a narrower
  band around it, ``f_r +- BAND_HALF_WIDTHS zeta f_r`` but at most
  :data:`BAND_KEEP` of the band (so it always narrows), must give the same frequency
  and damping within :data:`BAND_SHIFT_Z` standard uncertainties of their difference
  (``sqrt(s_narrow^2 + s_full^2)``, the identification's own, :mod:`ident.pole_uncertainty`).
  A linear mode in noise passes; an FRF that is no linear modal model (the joint's
  stiffness and damping change along a force-controlled sweep) gives band-dependent
  values, and then the identified values say more about the band than the structure.
"""
from __future__ import annotations

import math

import numpy as np

FIT_ERROR_LIMIT = 0.02
STABILITY_LIMIT = 0.3
CORRELATED = 0.5
BAND_HALF_WIDTHS = 3.0
BAND_KEEP = 0.6
BAND_SHIFT_Z = 3.0
MIN_LINES = 12


def narrowed_band(freq_hz, band, frequency_hz, zeta):
    """The narrower band around a mode (module doc), or None if it would hold fewer than
    :data:`MIN_LINES` lines."""
    freq_hz = np.asarray(freq_hz, float)
    lo, hi = band
    half = min(BAND_HALF_WIDTHS * zeta * frequency_hz, 0.5 * BAND_KEEP * (hi - lo))
    centre = min(max(frequency_hz, lo + half), hi - half)
    new = (centre - half, centre + half)
    n = int(np.sum((freq_hz >= new[0]) & (freq_hz <= new[1])))
    return new if n >= MIN_LINES else None


def band_shift(identify_on, freq_hz, result, index):
    """Identify mode ``index`` of ``result`` again on the narrowed band.

    ``identify_on(band, n_modes)`` runs the same identification on another band.
    Returns None when the band cannot be narrowed or the narrow fit fails, else a dict
    with the band (Hz), the changes of frequency (Hz) and zeta, and their z-scores."""
    mode = result.modes[index]
    band = narrowed_band(freq_hz, result.band_hz, mode.frequency_hz, mode.zeta)
    if band is None:
        return None
    inside = [m for m in result.modes if band[0] <= m.frequency_hz <= band[1]] or [mode]
    try:
        narrow = identify_on(band, len(inside)).modes
    except ValueError:
        return None
    if not narrow:
        return None
    other = min(narrow, key=lambda m: abs(m.frequency_hz - mode.frequency_hz))
    d_w2, d_z = other.omega2 - mode.omega2, other.zeta - mode.zeta
    s_w2 = math.hypot(other.omega2_std, mode.omega2_std)
    s_z = math.hypot(other.zeta_std, mode.zeta_std)
    if not (s_w2 > 0 and s_z > 0):      # NaN: no uncertainty, nothing to judge against
        return None
    return {"band_hz": band, "d_frequency_hz": other.frequency_hz - mode.frequency_hz,
            "d_zeta": d_z, "z_frequency": abs(d_w2) / s_w2, "z_zeta": abs(d_z) / s_z}


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
