"""A free-decay record identified: both methods, their disagreement, the warnings, the table.

:func:`identify_free_decay` runs :mod:`ident.free_decay` on a
:class:`ident.time_records.TimeRecord` (the mode isolated, the Hilbert track and the
peak/zero-crossing check in the same amplitude bins) with the checks of
:mod:`ident.decay_checks`. Where the methods differ by more than 3 combined standard
uncertainties and more than 1e-5 (frequency, relative) or 1 % (damping), the row says
so. :func:`free_decay_table` writes the spec's rows (``test = free-decay``,
``control = response``: the envelope is the abscissa; no ``excitation``): ``level`` 1
the smallest amplitude, ``run_order`` 1 the first in time; ``omega2``, ``zeta`` from
the Hilbert method; their stds are the fit's (``x_omega2_std_fit``, ``x_zeta_std_fit``)
combined with an allowance for what a decay is not: a steady state. Along a decay
every hysteresis loop starts from a larger one, so a slipping joint dissipates per
cycle slightly otherwise than on the steady loop of the EPMC backbone or a stepped
sine; measured on simulated Iwan decays (tests/test_free_decay.py) the damping differs
by 0.4-0.7 of the log decrement ``delta = 2 pi zeta`` (relative) and omega^2 by less
than ``delta^2 / 4``; the allowance is ``0.5 delta zeta`` and ``delta^2 omega2 / 4``
(:data:`TRANSIENT_ZETA`, :data:`TRANSIENT_OMEGA2`), so the diagnosis judges the rows
with the noise of their own test type; ``x_frequency_hz_peaks``, ``x_zeta_peaks`` the
check; ``x_snr_db``, ``x_cycles``, ``x_t_center_s``; warnings in ``x_warning`` (record-wide
ones on the first row in time).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ident import decay_checks
from ident.errors import InputError
from ident.free_decay import (DEFAULT_ROWS, ONSET_DROP, PREDICTOR_ORDER, DecayTrack,
                              Isolated, decay_bins, decay_onset, decay_rows, hilbert_track,
                              isolate_mode)
from ident.modal_data import MeasuredData, annotation_warnings
from ident.time_records import TimeRecord

#: Disagreement thresholds of the two methods (module doc).
SIGMAS, FREQ_REL, ZETA_REL = 3.0, 1e-5, 0.01
#: Transient-loop allowances (module doc): fractions of the log decrement.
TRANSIENT_ZETA, TRANSIENT_OMEGA2 = 0.5, 0.25
#: A record whose envelope peaks later than this many periods after its start is cut
#: there (a forced part or a pre-trigger before the decay).
ONSET_PERIODS = 1.5


@dataclass
class FreeDecayResult:
    """Both methods' rows, what was trimmed and why, SNR per row and the warnings."""

    hilbert: DecayTrack
    peaks: DecayTrack
    isolated: Isolated
    snr_db: np.ndarray
    warnings: list = field(default_factory=list)        # record-wide
    row_warnings: list = field(default_factory=list)    # per row

    @property
    def trim_statement(self) -> str:
        s, e = self.isolated.trim_s
        f = self.isolated.frequency_hz
        return (f"end effects trimmed: {s:.4g} s ({s * f:.1f} cycles) at the start, {e:.4g} s "
                f"({e * f:.1f} cycles) at the end (the one-period smoothing; the record was "
                f"continued beyond both ends by linear prediction of order "
                f"{PREDICTOR_ORDER} before the band-pass and Hilbert transform; "
                "ident.free_decay)")


def _disagreement(h: DecayTrack, p: DecayTrack, k: int) -> str | None:
    out = []
    for name, a, b, sa, sb, rel in (
            ("frequency", h.frequency_hz[k], p.frequency_hz[k],
             h.omega2_std[k] / (8 * np.pi ** 2 * h.frequency_hz[k]),
             p.omega2_std[k] / (8 * np.pi ** 2 * p.frequency_hz[k]), FREQ_REL),
            ("zeta", h.zeta[k], p.zeta[k], h.zeta_std[k], p.zeta_std[k], ZETA_REL)):
        d = abs(a - b)
        if d > SIGMAS * np.hypot(sa, sb) and d > rel * abs(a):
            out.append(f"{name} {a:.6g} (Hilbert) vs {b:.6g} (peaks)")
    return ("Hilbert and peak methods disagree: " + ", ".join(out)) if out else None


def identify_free_decay(record, band=None, n_rows: int = DEFAULT_ROWS) -> FreeDecayResult:
    """Frequency and damping against amplitude along a free decay (module doc).

    Parameters
    ----------
    record : ident.time_records.TimeRecord
    band : (lo, hi) Hz or None (the dominant peak +-30 %).
    n_rows : number of geometric amplitude bins (rows).
    """
    where = record.source or "time record"
    if n_rows < decay_checks.MIN_ROWS:
        raise InputError(f"{where}: n_rows must be >= {decay_checks.MIN_ROWS}, got {n_rows}")
    try:
        iso = isolate_mode(record.time_s, record.signals, band, record.reference)
        t, ln_a, _, _ = hilbert_track(iso)
        onset = decay_onset(t, ln_a, 1 / iso.frequency_hz)
        loud = t[np.argmax(ln_a >= ln_a.max() + np.log1p(-ONSET_DROP))] - 1 / iso.frequency_hz
        full = record                   # judged for clipping from where it is loud
        onset_note = None
        if onset - record.time_s[0] > ONSET_PERIODS / iso.frequency_hz:
            keep = record.time_s >= onset
            record = TimeRecord(record.time_s[keep], record.signals[keep], record.points,
                                record.quantity, record.reference, record.source)
            onset_note = (f"decay analysed from t = {onset:.6g} s, where the mode's "
                          f"envelope is last within {100 * ONSET_DROP:g} % of its largest "
                          "value (what precedes it, a forced response, a pre-trigger or "
                          f"the decay's first {100 * ONSET_DROP:g} %, is not analysed)")
            iso = isolate_mode(record.time_s, record.signals, band, record.reference)
    except ValueError as exc:
        raise InputError(f"{where}: {exc}") from None
    judged = full.time_s >= min(loud, record.time_s[0])
    warnings = decay_checks.clipping(full.time_s[judged], full.signals[judged], full.points,
                                     iso.sos, [decay_checks.broadband_noise_rms(
                                         full.time_s, x, iso.band_hz) for x in full.signals.T])
    ref_raw = record.signals[:, record.reference]
    noise = decay_checks.noise_variance_in_band(record.time_s, ref_raw, iso.band_hz)
    t, ln_a, _, _ = hilbert_track(iso)
    floor = decay_checks.snr_floor_amplitude(noise)
    bins = decay_bins(t, ln_a, n_rows, floor=floor, period_s=1 / iso.frequency_hz)
    top = float(np.exp(ln_a[0]))
    bottom = max(float(np.exp(ln_a.min())), floor)
    if floor > np.exp(ln_a.min()):
        warnings.append(f"noise: the decay reaches the noise floor (SNR "
                        f"{decay_checks.SNR_FLOOR_DB:g} dB at amplitude {floor:.3g}); "
                        "rows stop there")
    short = decay_checks.short_record(len(bins), top, bottom,
                                      (t[-1] - t[0]) * iso.frequency_hz)
    if short:
        warnings.append(short)
    if not bins:
        raise InputError(f"{where}: {short or 'no amplitude bin above the noise'}")
    h, p = decay_rows(iso, bins, noise)
    snr = decay_checks.snr_db(h.amplitude, noise)
    rows = []
    for k in range(len(bins)):
        w = [_disagreement(h, p, k)]
        if snr[k] < decay_checks.SNR_WARN_DB:
            w.append(f"noisy: SNR {snr[k]:.1f} dB in the band")
        rows.append([x for x in w if x])
    notes = iso.notes + ([onset_note] if onset_note else [])
    return FreeDecayResult(h, p, iso, snr, notes + warnings, rows)


def free_decay_table(record, band=None, n_rows: int = DEFAULT_ROWS,
                     result: FreeDecayResult | None = None) -> MeasuredData:
    """The measured-data rows of a free decay (module doc)."""
    res = result or identify_free_decay(record, band, n_rows)
    h, p = res.hilbert, res.peaks
    lo, hi = res.isolated.band_hz
    valid = np.isfinite(h.omega2) & np.isfinite(h.zeta) & (h.zeta > 0) & (h.zeta < 1)
    in_band = valid & (h.frequency_hz > lo) & (h.frequency_hz < hi)
    ok = np.flatnonzero(in_band)
    where = record.source or "time record"
    dropped = [f"{(valid & ~in_band).sum()} row(s) centred at t = "
               f"{', '.join(f'{t:.4g}' for t in np.sort(h.t_center[valid & ~in_band]))} s "
               "dropped: "
               f"their frequency lies outside the band {lo:.4g}-{hi:.4g} Hz (the band holds "
               "other content than the mode there: the other modes, noise or round-off)"
               ] if (valid & ~in_band).any() else []
    if ok.size < decay_checks.MIN_ROWS:
        raise InputError(f"{where}: {ok.size} usable rows along the decay, at least "
                         f"{decay_checks.MIN_ROWS} are needed ("
                         + ("; ".join(res.warnings) or "record too short") + ")")
    order = ok[np.argsort(h.amplitude[ok])]                   # level 1 = smallest
    n = order.size
    first_in_time = int(np.argmin(h.t_center[order]))
    warn = [" | ".join(res.row_warnings[k] + (res.warnings if i == first_in_time else []))
            for i, k in enumerate(order)]
    run_order = np.argsort(np.argsort(h.t_center[order])) + 1
    zeta, omega2 = h.zeta[order], h.omega2[order]
    delta = 2 * np.pi * zeta
    zeta_std = np.hypot(h.zeta_std[order], TRANSIENT_ZETA * delta * zeta)
    omega2_std = np.hypot(h.omega2_std[order], TRANSIENT_OMEGA2 * delta ** 2 * omega2)
    data = MeasuredData(
        level=np.arange(1, n + 1), excitation=np.full(n, np.nan), omega2=omega2,
        zeta=zeta, mode=np.ones(n, int), run_order=run_order,
        response_amplitude=h.amplitude[order], omega2_std=omega2_std, zeta_std=zeta_std,
        control=np.full(n, "response"), test=np.full(n, "free-decay"),
        extra={"x_frequency_hz": h.frequency_hz[order],
               "x_frequency_hz_peaks": p.frequency_hz[order], "x_zeta_peaks": p.zeta[order],
               "x_omega2_std_fit": h.omega2_std[order], "x_zeta_std_fit": h.zeta_std[order],
               "x_snr_db": res.snr_db[order], "x_cycles": h.cycles[order],
               "x_t_center_s": h.t_center[order],
               "x_source": np.full(n, Path(where).name),
               "x_warning": np.array(warn, dtype=str)},
        source=where)
    data.warnings = ([f"{where}: {res.trim_statement}"] + [f"{where}: {d}" for d in dropped]
                     + annotation_warnings(data))
    return data
