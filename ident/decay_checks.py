"""What can spoil a free-decay record: clipping, noise, too short a decay (one line each).

* Clipped (:func:`clipping`): flat tops (:func:`flat_tops`, digital clipping: three or
  more equal samples at the largest magnitude), or, with noise on the flat tops, the
  record's own peaks falling short of the band-passed envelope. Unclipped, each half cycle's
  largest magnitude equals the envelope of the mode (up to the joint's weak harmonics and
  the noise); a clipped sine keeps a fundamental above its clip level
  (``(2/pi)(arcsin c + c sqrt(1-c^2))`` of the unclipped amplitude: 0.987 at ``c`` = 0.95,
  0.896 at 0.8), so its peaks fall ``1 - c / a1`` (3.7 %, 11 %) short. Three half cycles
  short by more than :data:`CLIP_DEFICIT`, plus what sampling alone takes off a crest (up to
  half a sample away: ``1 - cos(pi / (2 n))`` with ``n`` samples per half cycle, 11 % at 6.7
  samples per cycle), plus 3 noise standard deviations are named (only half cycles
  whose envelope is above :data:`TOP_SHARE` of its largest value, after the band-pass
  start-up: the Hilbert end effects of the faint tail are not judged).
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
CLIP_DEFICIT = 0.02
#: Half cycles judged for clipping: envelope above this share of its largest value.
TOP_SHARE = 0.3


def flat_tops(x) -> int:
    """Runs of 3 or more successive samples at the record's largest magnitude (within
    1e-9 of it): digital clipping. A sinusoid would need 10^5 samples per cycle."""
    a = np.abs(np.asarray(x, float))
    at = (a >= a.max() * (1 - 1e-9)).astype(int)
    edges = np.diff(np.r_[0, at, 0])
    runs = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    return int(np.sum(runs >= 3))


def clipping(time_s, signals, points, sos, noise_rms) -> list[str]:
    """One line per clipped point (module doc). ``sos``: the mode's band-pass;
    ``noise_rms``: broadband noise standard deviation per point."""
    out = []
    t = np.asarray(time_s)
    fs = (t.size - 1) / (t[-1] - t[0])
    h = signal.sosfilt(sos, np.r_[1.0, np.zeros(int(4 * fs) - 1)])
    skip = int(np.flatnonzero(np.abs(h) > 0.05 * np.abs(h).max())[-1]) + 1
    for j, p in enumerate(points):
        x = np.asarray(signals)[:, j]
        if not np.any(x):
            out.append(f"point {p}: the record is all zero")
            continue
        flat = flat_tops(x)
        if flat:
            out.append(f"point {p}: clipped: {flat} flat tops at magnitude {np.abs(x).max():.4g} "
                       "(3 or more equal samples): the top of the decay is distorted")
            continue
        y = signal.sosfiltfilt(sos, x)
        env = np.abs(signal.hilbert(y))
        z = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
        z = z[(z >= skip) & (z < x.size - skip)]
        short, top = [], env[skip:x.size - skip].max()
        if z.size > 1:      # what sampling takes off a crest half a sample away
            sampled = 1 - np.cos(np.pi / (2 * np.mean(np.diff(z))))
        for a, b in zip(z[:-1], z[1:]):
            k = a + int(np.argmax(np.abs(x[a:b + 1])))
            if env[k] < TOP_SHARE * top:
                continue            # clipping is at the top; the tail has end effects
            deficit = 1 - abs(x[k]) / env[k]
            if deficit > CLIP_DEFICIT + sampled + 3 * noise_rms[j] / env[k]:
                short.append(deficit)
        if len(short) >= 3:
            out.append(f"point {p}: clipped: {len(short)} half cycles peak up to "
                       f"{100 * max(short):.3g} % below the mode's envelope (flat tops): the "
                       "top of the decay is distorted")
    return out


def broadband_noise_rms(time_s, x, band_hz) -> float:
    """Standard deviation of the noise over the whole record bandwidth, from the in-band
    estimate (white noise: its variance scales with bandwidth); 0 if unknown."""
    fs = (len(time_s) - 1) / (time_s[-1] - time_s[0])
    var = noise_variance_in_band(time_s, x, band_hz)
    return 0.0 if var is None else float(np.sqrt(var * (fs / 2) / (band_hz[1] - band_hz[0])))


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
