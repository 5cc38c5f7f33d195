"""What can spoil a free-decay record: clipping, noise, too short a decay (one line each).

* Clipped (:func:`clipping`): a flat top, three or more successive samples within 1e-6
  of the record's largest magnitude, or two separate extrema there (an unclipped
  sinusoid would need over 4000 samples per cycle for the first).
* Noise (:func:`noise_variance_in_band`): the level of the Welch power spectral density
  of the record outside the mode's band (its median above 2x the band's top, or below
  half its bottom where there is no room above: harmonics of a slipping joint are
  peaks the median ignores), taken as white across the band: the noise variance the
  band-pass lets through. A row's SNR is ``(a^2/2) / variance`` in dB; rows below
  :data:`SNR_FLOOR_DB` are not formed, rows below :data:`SNR_WARN_DB` are flagged.
* Too short (:func:`short_record`): fewer than :data:`MIN_ROWS` rows, or an amplitude
  span below a factor :data:`MIN_SPAN` along the usable record.
"""
from __future__ import annotations

import numpy as np
from scipy import signal

SNR_FLOOR_DB = 10.0
SNR_WARN_DB = 20.0
MIN_ROWS = 4
MIN_SPAN = 2.0


def clipping(signals, points) -> list[str]:
    """One line per clipped point (module doc)."""
    out = []
    for j, p in enumerate(points):
        x = np.abs(np.asarray(signals)[:, j])
        top = x.max()
        if top == 0:
            out.append(f"point {p}: the record is all zero")
            continue
        at = x >= top * (1 - 1e-6)
        runs = np.diff(np.flatnonzero(np.diff(np.r_[0, at.astype(int), 0])))[::2]
        if runs.max() >= 3 or runs.size >= 2:
            out.append(f"point {p}: clipped: {int(at.sum())} samples at the largest magnitude "
                       f"{top:.4g} ({runs.size} flat top(s)); the top of the decay is "
                       "distorted")
    return out


def noise_variance_in_band(time_s, x, band_hz) -> float | None:
    """Noise variance the band-pass lets through (module doc), or None if the record
    has no room outside the band."""
    fs = (len(time_s) - 1) / (time_s[-1] - time_s[0])
    lo, hi = band_hz
    nper = int(min(len(x), max(256, 16 * fs / lo)))
    f, psd = signal.welch(x, fs=fs, nperseg=nper)
    out = psd[(f > 2 * hi) & (f < 0.45 * fs)]
    if out.size < 8:
        out = psd[(f < lo / 2) & (f > 3 * fs / nper)]
    if out.size < 8:
        return None
    return float(np.median(out) * (hi - lo))


def snr_db(amplitude, noise_var) -> np.ndarray:
    """SNR of a sinusoid of ``amplitude`` over the in-band noise variance, dB."""
    a = np.asarray(amplitude, float)
    if not noise_var:
        return np.full(a.shape, np.inf)
    return 10 * np.log10(a * a / 2 / noise_var)


def snr_floor_amplitude(noise_var) -> float:
    """Amplitude at which the SNR falls to :data:`SNR_FLOOR_DB`."""
    return 0.0 if not noise_var else float(np.sqrt(2 * noise_var * 10 ** (SNR_FLOOR_DB / 10)))


def short_record(n_rows, top, bottom, cycles) -> str | None:
    """One line when the usable decay is too short (module doc), else None."""
    span = top / bottom if bottom > 0 else np.inf
    if n_rows < MIN_ROWS or span < MIN_SPAN:
        return (f"record too short: {cycles:.0f} usable cycles, amplitude falls by a factor "
                f"{span:.3g} ({n_rows} rows); record the decay longer or start it higher")
    return None
