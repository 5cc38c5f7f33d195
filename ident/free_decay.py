"""Frequency and damping ratio against amplitude along a free decay (ring-down).

1. The mode, isolated (:func:`isolate_mode`): a zero-phase Butterworth band-pass (order
   4 per pass, ``scipy.signal.sosfiltfilt``) around the record's dominant spectral peak
   (+-30 % unless a band is given: room for the frequency drift of a slipping joint);
   with several points a modal filter: the band-passed records' first singular vector
   is the mode's shape, their projection on it the modal coordinate, shown at the
   reference point.
2. End effects. Filtering and the FFT Hilbert transform both see the record's ends:
   the band-pass starts up (rings at its band edges), and the transform treats the
   record as periodic (the jump from the decayed end to the full start leaks into the
   analytic signal with an error falling only as 1/(cycles from the edge)). So the
   record is first continued beyond both ends by linear prediction
   (:func:`continue_record`: the least-squares predictor of order
   :data:`PREDICTOR_ORDER` fitted on :data:`PREDICTOR_PERIODS` periods at that end, a
   sum of damped sinusoids carrying the mode, the other modes and slow trends across
   the junction), then filtered and transformed, and cut back. Only the half-width of
   the envelope smoothing of step 3 is trimmed: :data:`EDGE_PERIODS` period at each
   end, stated in the result. Measured on the FE double beam's mode 4 (1.3 % damping),
   the row 1-4 cycles after the start is within 3e-5 in frequency of the backbone when
   the record starts at an extremum, 1.1e-4 when it starts at a zero crossing; on a
   single-DOF Iwan decay within 4e-6 at any start phase. Amplitudes are divided by the
   band-pass gain at the row's frequency.
3. Hilbert (:func:`hilbert_track`): envelope ``a = |z|`` and phase ``theta =
   unwrap(arg z)``. The Hilbert envelope of a damped sinusoid ripples at twice its
   frequency (the negative-frequency half of its spectrum, relative amplitude about
   ``zeta/4``), which biases a slope fitted over ``k`` cycles by about ``4 %/k^2``
   (measured); two moving averages of one period remove it.
4. Peaks and zero crossings (:func:`peak_track`), the check: zero crossings by linear
   interpolation (the phase advances by pi between them), extrema by a parabola through
   three samples (the envelope).
5. Rows (:func:`decay_rows`): geometric amplitude bins between the top and the bottom of
   the usable envelope (``n_rows``, each at least :data:`MIN_CYCLES` cycles); in each a
   quadratic fit in time of ``theta`` and ``ln a`` gives at the bin's centre
   ``omega_d = theta'`` and ``sigma = -(ln a)'``, so ``omega2 = omega_d^2 + sigma^2``
   and ``zeta = sigma / sqrt(omega2)`` (exact for a linear mode; for an amplitude-
   dependent one the first-order averaging result ``da/dt = -zeta omega a`` of the
   EPMC backbone), amplitude ``exp(ln a)`` there. Standard uncertainties: least-squares
   standard errors, inflated by ``sqrt(n / n_eff)`` with ``n_eff`` the half cycles in the
   bin (the smoothed track is correlated within a half cycle) or, if fewer, the
   samples over the residuals' correlation length; never below the standard error the
   record's in-band noise level gives (:func:`noise_slope_std`).
SI units: s, Hz, rad/s; amplitudes in the record's quantity.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage, signal

BAND_HALF_WIDTH = 0.3
FILTER_ORDER = 4
#: Filter start-up: its impulse response down to this fraction of its peak (the
#: continuation beyond the record's ends is longer than this).
SETTLE_FRACTION = 5e-2
#: Periods trimmed at both ends: the half-width of the two one-period moving averages.
EDGE_PERIODS = 1
#: The continuation beyond the ends (module doc, 2): predictor order, the periods at
#: each end it is fitted on, periods continued beyond the filter start-up, and the
#: largest growth of the backward continuation (a decay grows backwards in time; the
#: forward one may not grow).
PREDICTOR_ORDER = 16
PREDICTOR_PERIODS = 8
PAD_PERIODS = 4
BACKWARD_GROWTH = 1e3
MIN_CYCLES = 3
#: The decay is taken to start where the smoothed envelope is last within this fraction
#: of its largest value (:func:`decay_onset`).
ONSET_DROP = 0.02
DEFAULT_ROWS = 12


@dataclass
class DecayTrack:
    """Frequency and damping against amplitude from one method, one entry per row."""

    method: str
    amplitude: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    omega2_std: np.ndarray
    zeta_std: np.ndarray
    t_center: np.ndarray
    cycles: np.ndarray

    @property
    def frequency_hz(self) -> np.ndarray:
        return np.sqrt(self.omega2) / (2 * np.pi)


@dataclass
class Isolated:
    """The mode's signal at the reference point (kept span only) and how it was got."""

    time_s: np.ndarray
    y: np.ndarray          # band-passed (modal) signal on the kept span
    extended: np.ndarray   # analytic signal (Hilbert) of the reflected record
    keep: slice            # the kept span within ``extended``
    band_hz: tuple
    frequency_hz: float    # dominant peak
    trim_s: tuple          # (start, end) trimmed from the record, s
    sos: np.ndarray | None = None   # the band-pass
    shape: np.ndarray | None = None
    notes: list = field(default_factory=list)

    @property
    def sample_rate(self) -> float:
        return (self.time_s.size - 1) / (self.time_s[-1] - self.time_s[0])

    def gain(self, frequency_hz):
        """Amplitude gain of the zero-phase band-pass (both passes) at a frequency."""
        _, h = signal.sosfreqz(self.sos, np.atleast_1d(frequency_hz), fs=self.sample_rate)
        return np.abs(h) ** 2


def dominant_frequency(time_s, x) -> float:
    """The strongest spectral peak (Hz) of the records ``x`` (n, n_points), above 3 / T."""
    x = np.atleast_2d(np.asarray(x, float).T).T
    n = x.shape[0]
    dt = (time_s[-1] - time_s[0]) / (n - 1)
    spec = np.sum(np.abs(np.fft.rfft(x - x.mean(0), 4 * n, axis=0)) ** 2, axis=1)
    f = np.fft.rfftfreq(4 * n, dt)
    spec[f < 3.0 / (n * dt)] = 0.0
    return float(f[np.argmax(spec)])


def band_pass(band_hz, fs):
    """Butterworth band-pass (second-order sections) of :data:`FILTER_ORDER`."""
    lo, hi = band_hz
    if not 0 < lo < hi < fs / 2:
        raise ValueError(f"band {lo:g}-{hi:g} Hz must lie in (0, {fs / 2:g}) Hz (Nyquist)")
    return signal.butter(FILTER_ORDER, [lo, hi], btype="bandpass", fs=fs, output="sos")


def settle_time(sos, fs, fraction=SETTLE_FRACTION) -> float:
    """Time after which the filter's impulse response stays below ``fraction`` of its
    peak, s (the start-up of one pass)."""
    n = 1 << 12
    while True:
        h = signal.sosfilt(sos, np.r_[1.0, np.zeros(n - 1)])
        above = np.flatnonzero(np.abs(h) > fraction * np.abs(h).max())
        if above[-1] < n // 2 or n > 1 << 24:
            return (above[-1] + 1) / fs
        n *= 2


def _extrema(y) -> np.ndarray:
    d = np.diff(y)
    return np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0) + 1


def isolate_mode(time_s, x, band_hz=None, reference=0) -> Isolated:
    """The mode's signal and analytic signal at the reference point (module doc, 1-2).

    ``x``: (n,) or (n, n_points) raw records; ``band_hz``: (lo, hi) or None (dominant
    peak +-30 %)."""
    t = np.asarray(time_s, float)
    x = np.atleast_2d(np.asarray(x, float).T).T
    fs = (t.size - 1) / (t[-1] - t[0])
    if band_hz is None:
        f_pk = dominant_frequency(t, x)
        band = (f_pk * (1 - BAND_HALF_WIDTH), min(f_pk * (1 + BAND_HALF_WIDTH), 0.45 * fs))
    else:
        band = tuple(map(float, band_hz))
    sos = band_pass(band, fs)
    notes, shape = [], None
    y_all = signal.sosfiltfilt(sos, x, axis=0)
    if band_hz is not None:
        f_pk = dominant_frequency(t, y_all)         # the mode in the given band
    if x.shape[1] > 1:                          # modal filter
        _, _, vt = np.linalg.svd(y_all, full_matrices=False)
        shape = vt[0] * np.sign(vt[0, reference] or 1.0)
        weights = shape * shape[reference]      # modal coordinate, seen at the reference
        notes.append(f"modal filter over {x.shape[1]} points (first singular vector)")
    else:
        weights = np.array([1.0])
    raw = x @ weights
    t_f = settle_time(sos, fs)
    period = int(round(fs / f_pk))
    i0 = int(np.ceil(t_f * fs))
    edge = EDGE_PERIODS * period
    if t.size < 2 * edge + 2 * MIN_CYCLES * period:
        raise ValueError(f"record too short: {t.size / period:.1f} cycles of the mode at "
                         f"{f_pk:.4g} Hz; two rows of {MIN_CYCLES} cycles and the trimmed "
                         f"{EDGE_PERIODS} at each end need {2 * (EDGE_PERIODS + MIN_CYCLES)}")
    L = i0 + PAD_PERIODS * period
    fit = min(max(PREDICTOR_PERIODS * period, 4 * PREDICTOR_ORDER), t.size // 2)
    head, head_ok = continue_record(raw[:fit][::-1], L, growth=BACKWARD_GROWTH)
    tail, tail_ok = continue_record(raw[-fit:], L, growth=1.0)
    head = head[::-1]
    for ok, end in ((head_ok, "start"), (tail_ok, "end")):
        if not ok:
            notes.append(f"the record's {end} could not be continued by linear prediction "
                         "(ill-conditioned: round-off or noise there); its mirror image was "
                         f"used, and the rows near the {end} may carry end effects")
    extended = signal.sosfiltfilt(sos, np.concatenate([head, raw, tail]))
    z = signal.hilbert(extended)
    keep = slice(L + edge, L + t.size - edge)
    return Isolated(time_s=t[edge:t.size - edge], y=np.real(z[keep]), extended=z,
                    keep=keep, band_hz=band, frequency_hz=f_pk,
                    trim_s=(edge / fs, edge / fs), sos=sos, shape=shape, notes=notes)


def continue_record(y, n, order=None, growth=1.0) -> tuple[np.ndarray, bool]:
    """(the ``n`` samples that continue ``y``, whether the predictor did it): ``y`` (1-D,
    in time order) continued by its least-squares
    linear predictor of ``order`` (forward linear prediction: a sum of damped sinusoids,
    every mode and trend of the segment); fed a time-reversed segment it continues the
    record backwards. The predictor's roots are held within ``growth ** (1 / n)`` in
    modulus: the continuation grows at most ``growth`` times over its length. Where the
    predictor is ill-conditioned (a segment of round-off or noise: the continuation
    exceeds ``2 growth`` times the segment) the segment's mirror image is used."""
    p = order or PREDICTOR_ORDER
    win = np.lib.stride_tricks.sliding_window_view(y, p + 1)
    c, *_ = np.linalg.lstsq(win[:, :-1][:, ::-1], win[:, -1], rcond=None)
    r = np.roots(np.r_[1.0, -c])
    cap = growth ** (1.0 / n)
    r = np.where(np.abs(r) > cap, r / np.abs(r) * cap, r)
    a = np.real(np.poly(r))
    zi = signal.lfiltic([1.0], a, y=y[::-1][:p])
    out = signal.lfilter([1.0], a, np.zeros(n), zi=zi)[0]
    if np.all(np.isfinite(out)) and np.abs(out).max() <= 2 * growth * np.abs(y).max():
        return out, True
    return np.r_[y[-2::-1], np.zeros(n)][:n], False     # ill-conditioned: mirror image


def decay_onset(t, ln_a, period_s, drop=ONSET_DROP) -> float:
    """Time (s) from which a record is a free decay. A record whose smoothed log-envelope
    ``ln_a`` falls from its start at least half as fast as after the last time it is
    within ``drop`` of its largest value is a decay from its start (``t[0]``);
    otherwise it held a steady forced response before the shaker was switched off, or
    a pre-trigger before an impact, and the decay starts at that last time."""
    i = int(np.flatnonzero(ln_a >= ln_a.max() + np.log1p(-drop))[-1])
    if i == 0:
        return float(t[0])
    j = min(ln_a.size - 1, i + max(i, int(3 * period_s / (t[1] - t[0]))))
    early = (ln_a[i] - ln_a[0]) / (t[i] - t[0])
    late = (ln_a[j] - ln_a[i]) / (t[j] - t[i])
    return float(t[0] if early < 0.5 * late else t[i])


def _smooth(v, period):
    """Two moving averages of one period (module doc, 3)."""
    return ndimage.uniform_filter1d(ndimage.uniform_filter1d(v, period, mode="nearest"),
                                    period, mode="nearest")


def hilbert_track(iso: Isolated):
    """(t, ln a, theta, samples per half cycle) of the Hilbert track, smoothed on the
    reflected record and cut to the kept span."""
    period = max(1, int(round(iso.sample_rate / iso.frequency_hz)))
    ln_a = _smooth(np.log(np.abs(iso.extended)), period)[iso.keep]
    theta = _smooth(np.unwrap(np.angle(iso.extended)), period)[iso.keep]
    return iso.time_s, ln_a, theta, period / 2.0


def peak_track(iso: Isolated):
    """(t_peak, ln a_peak, t_zero, theta_zero) of the extrema and zero crossings."""
    t, y = iso.time_s, iso.y
    dt = t[1] - t[0]
    k = _extrema(y)
    k = k[(k > 0) & (k < y.size - 1)]
    ym, y0, yp = y[k - 1], y[k], y[k + 1]
    den = ym - 2 * y0 + yp
    off = np.where(den != 0, 0.5 * (ym - yp) / np.where(den != 0, den, 1), 0.0)
    peak = y0 - 0.25 * (ym - yp) * off
    z = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
    tz = t[z] + dt * y[z] / (y[z] - y[z + 1])
    return t[k] + off * dt, np.log(np.abs(peak)), tz, np.pi * np.arange(tz.size)


def correlation_length(res) -> float:
    """Integrated autocorrelation time of residuals, in samples: ``1 + 2 sum rho_k``
    over the lags before the first negative autocorrelation (>= 1)."""
    r = res - res.mean()
    n = r.size
    acf = np.fft.irfft(np.abs(np.fft.rfft(r, 2 * n)) ** 2)[:n]
    if acf[0] <= 0:
        return 1.0
    rho = acf / acf[0]
    neg = np.flatnonzero(rho < 0)
    stop = neg[0] if neg.size else n
    return max(1.0, 1.0 + 2.0 * float(np.sum(rho[1:stop])))


def _slope_at_centre(t, v, tc, n_eff):
    """Slope of a quadratic least-squares fit at ``tc`` and its standard error,
    inflated by ``sqrt(n / n_eff)`` with ``n_eff`` the smaller of the given one and
    ``n`` over the residuals' correlation length; also the fitted value at ``tc``."""
    X = np.column_stack([np.ones_like(t), t - tc, (t - tc) ** 2])
    coef, *_ = np.linalg.lstsq(X, v, rcond=None)
    res = v - X @ coef
    dof = max(t.size - 3, 1)
    n_eff = max(min(n_eff, t.size / correlation_length(res)), 1.0)
    cov = np.linalg.inv(X.T @ X) * (res @ res) / dof * max(t.size / n_eff, 1.0)
    return coef[1], np.sqrt(cov[1, 1]), coef[0]


def noise_slope_std(t, ln_a, tc, noise_psd) -> float:
    """Standard error of a least-squares slope of ``ln a`` or ``theta`` over ``t`` (s)
    at ``tc`` from additive white noise of two-sided PSD ``noise_psd`` (per Hz) in the
    band: each of the noise's in-phase and quadrature parts, over the envelope ``a``,
    perturbs ``ln a`` and ``theta`` with that PSD at low frequency, so
    ``var = N0 int tau^2 / a^2 dt / (int tau^2 dt)^2`` (``tau = t - tc``)."""
    dt = t[1] - t[0]
    tau2 = (t - tc) ** 2
    return float(np.sqrt(noise_psd * np.sum(tau2 * np.exp(-2 * ln_a)) * dt)
                 / (np.sum(tau2) * dt))


def _row(t_a, ln_a, t_th, theta, t0, t1, n_eff, floor):
    tc = 0.5 * (t0 + t1)
    ia = (t_a >= t0) & (t_a <= t1)
    it = (t_th >= t0) & (t_th <= t1)
    if ia.sum() < 4 or it.sum() < 4:
        return None
    w, sw, _ = _slope_at_centre(t_th[it], theta[it], tc, n_eff(it.sum()))
    s, ss, la = _slope_at_centre(t_a[ia], ln_a[ia], tc, n_eff(ia.sum()))
    sw, ss = max(sw, floor(tc, t0, t1)), max(ss, floor(tc, t0, t1))
    sigma = -s
    om2 = w * w + sigma * sigma
    om2_std = np.hypot(2 * w * sw, 2 * sigma * ss)
    zeta = sigma / np.sqrt(om2)
    zeta_std = np.hypot(ss / np.sqrt(om2), sigma * om2_std / (2 * om2 ** 1.5))
    return np.exp(la), om2, zeta, om2_std, zeta_std, tc


def decay_bins(t, ln_a, n_rows=DEFAULT_ROWS, floor=0.0, period_s=0.0):
    """Time intervals of geometric amplitude bins along a decaying log-envelope, from its
    top down to ``floor`` (an amplitude), each at least :data:`MIN_CYCLES` periods."""
    env = np.minimum.accumulate(np.exp(ln_a))
    top = env[0]
    bottom = max(env[-1], floor)
    if not bottom < top:
        return []
    edges = np.geomspace(top, bottom, n_rows + 1)
    times = [t[min(np.searchsorted(-env, -e), t.size - 1)] for e in edges]
    bins, start = [], times[0]
    for end in times[1:]:
        if end - start >= MIN_CYCLES * period_s:
            bins.append((start, end))
            start = end
    return bins


def decay_rows(iso: Isolated, bins, noise_var=None) -> tuple[DecayTrack, DecayTrack]:
    """Both methods' rows in the given time bins (module doc, 5); ``noise_var``: the
    in-band noise variance (:func:`ident.decay_checks.noise_variance_in_band`), which
    sets a floor under the slopes' standard errors (:func:`noise_slope_std`)."""
    t, ln_a, theta, half = hilbert_track(iso)
    tp, lnp, tz, thz = peak_track(iso)
    psd = (noise_var or 0.0) / (iso.band_hz[1] - iso.band_hz[0])

    def floor(tc, t0, t1):
        i = (t >= t0) & (t <= t1)
        return noise_slope_std(t[i], ln_a[i], tc, psd) if psd > 0 and i.sum() > 2 else 0.0

    out = []
    for name, args in (("hilbert", (t, ln_a, t, theta, lambda n: n / half)),
                       ("peaks", (tp, lnp, tz, thz, lambda n: n))):
        rows = [_row(*args[:4], t0, t1, args[4], floor) for t0, t1 in bins]
        rows = [r if r is not None else (np.nan,) * 6 for r in rows]
        cols = np.array(rows, float).reshape(-1, 6).T
        cycles = np.array([(t1 - t0) * iso.frequency_hz for t0, t1 in bins])
        with np.errstate(invalid="ignore"):
            cols[0] = cols[0] / iso.gain(np.sqrt(np.nan_to_num(cols[1], nan=1.0)) / (2 * np.pi))
        out.append(DecayTrack(name, cols[0], cols[1], cols[2], cols[3], cols[4], cols[5], cycles))
    return out[0], out[1]
