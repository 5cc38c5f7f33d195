"""FRF sets of a random-excitation series: the response RMS of a mode, the test's signature.

``docs/formats/measured-data.md``, "Other test types": a ``random`` level is an H1 FRF
averaged over a broadband random record; its ``excitation`` is the drive RMS and its
``response_amplitude`` the response RMS in the mode's band.

Response RMS (:func:`mode_response_rms`): the mode's own share of the response, from
the identified mode's own FRF ``H_r`` in the file's quantity (residue over pole and its
conjugate; the other modes' share is not counted) and the drive's one-sided
autospectrum ``G_ff`` (per Hz),

    sigma^2 = int_0^inf G_ff(f) |H_r(f)|^2 df                                      (2)

with ``G_ff`` the file's ``force_psd`` column (the autospectrum the analyser averaged
for the H1; Bendat & Piersol 2010, eq. 6.29 for the output spectrum of a linear
system). Without that column the drive is taken flat over the file's lines,
``G_ff = e^2 / (f_last - f_first)`` (an assumption; a shaker's force drop at resonance
breaks it), so

    sigma = e sqrt( int_0^inf |H_r(f)|^2 df / (f_last - f_first) )                 (1)

Eq. (1) is the *expected* RMS under a drive of that spectrum; a finite record's drive
has, in the mode's band, a power that scatters about it by ``1/sqrt(B T)`` (``B`` the
mode's noise bandwidth, ``T`` the record): measured on the random series of
``benchmarks/bench_random_chi.py`` (150 s records) the levels' RMS by eq. (1) spanned
up to 7.1 % about the simulated one within a series, by eq. (2) at most 2.6 %
(docs/free-decay-and-random.md). Only ratios between levels enter chi, so this scatter
is what matters, not the absolute value (which the flat assumption sets, and with it
R).

Signature (:func:`random_signature`): a level not stated as random whose FRF looks
averaged. A ``coherence`` column belongs to an averaged (random) estimate; otherwise
the line-to-line noise is the fourth difference along frequency of the FRF less the
identified modes (what is left is smooth but for the noise) and is regressed on
``|H|`` in log-log: a stepped sine measures each line on its own and its noise follows
the response (slope near 1, as in the project's synthetic series); the noise of an H1
estimate from output noise averaged over a record is near-uniform across lines
(slope near 0). A stepped sine with a constant noise floor looks the same: the line
says "looks", and the test type in the file settles it.
"""
from __future__ import annotations

import numpy as np
from ident.poles import modal_receptance

_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}
GAUSS_NODES = 1000
#: Below this log-log slope of the line noise on |H| the noise is called uniform.
UNIFORM_NOISE_SLOPE = 0.5
#: Median line noise over |H| below which there is too little noise to judge.
MIN_NOISE = 1e-4


def mode_response_rms(mode, point: int, quantity: str, freq_hz, drive_rms: float,
                      drive_psd=None) -> float:
    """Response RMS of one identified mode at ``point`` (module doc, eq. 1 or 2), in the
    FRF's response unit.

    Parameters
    ----------
    mode : identified mode (``pole``, ``shape``).
    point : index of the point among the mode's shape entries.
    quantity : "receptance", "mobility" or "accelerance".
    freq_hz : (n,) the file's lines, Hz.
    drive_rms : RMS of the drive (N or its unit); used when ``drive_psd`` is None, as a
        drive flat over ``freq_hz`` (eq. 1).
    drive_psd : (n,) or None, the drive's one-sided autospectrum ``G_ff`` at the lines
        (unit^2/Hz, the file's ``force_psd``): then eq. 2, ``G_ff`` interpolated
        linearly between lines and held beyond the first and last.
    """
    f = np.asarray(freq_hz, float)
    shape = np.atleast_1d(mode.shape)[point]
    fd = mode.pole.imag / (2 * np.pi)
    hw = -mode.pole.real / (2 * np.pi)          # half-power half width, Hz
    if drive_psd is None:
        def psd(fr):
            return np.full(np.shape(fr), float(drive_rms) ** 2 / (f[-1] - f[0]))
    else:
        g = np.asarray(drive_psd, float)
        if g.shape != f.shape or np.any(~(g > 0)):
            raise ValueError("drive_psd needs one value > 0 per line")

        def psd(fr):
            return np.interp(fr, f, g)

    def h2(fr):
        h = modal_receptance(mode.pole, shape, fr)[:, 0] * (2 * np.pi * fr) ** _POWER[quantity]
        return np.abs(h) ** 2 * psd(fr)

    # Gauss-Legendre: above fd/2 in th with f = fd + hw tan(th), which spreads the
    # resonance peak evenly (an adaptive rule over f misses a narrow peak by percent;
    # 1000 nodes give 1e-14 on the closed form of tests/test_random_series.py), below
    # fd/2 in f, where |H| is smooth
    x, w = np.polynomial.legendre.leggauss(GAUSS_NODES)
    a, b = np.arctan(-0.5 * fd / hw), np.pi / 2
    th = 0.5 * (b - a) * x + 0.5 * (b + a)
    peak = 0.5 * (b - a) * np.sum(w * h2(fd + hw * np.tan(th)) * hw / np.cos(th) ** 2)
    low = 0.25 * fd * np.sum(w * h2(0.25 * fd * (x + 1)))
    return float(np.sqrt(peak + low))


def random_signature(freq_hz, frf, modes=(), quantity="receptance",
                     coherence=None) -> str | None:
    """One line if an FRF set looks like an averaged random estimate (module doc), else
    None. ``frf``: (n_lines, n_points) complex; ``modes``: identified modes (``pole``,
    ``shape``) subtracted first; ``coherence``: any column of them."""
    if coherence is not None:
        return "the file has a coherence column: an averaged (random-excitation) FRF"
    f = np.asarray(freq_hz, float)
    frf = np.asarray(frf).reshape(f.size, -1)
    h = np.abs(frf)
    rest = frf.astype(complex)
    for m in modes:
        rest = rest - modal_receptance(m.pole, m.shape, f) * (2j * np.pi * f[:, None]) \
            ** _POWER[quantity]
    d4 = np.abs(np.diff(rest, 4, axis=0)) / np.sqrt(70.0)
    mag = h[2:-2]
    keep = (mag > 0) & (d4 > 0)
    if keep.sum() < 16:
        return None
    x, y = np.log(mag[keep]), np.log(d4[keep])
    if np.median(d4[keep] / mag[keep]) < MIN_NOISE or np.ptp(x) < np.log(10.0):
        return None
    slope = float(np.polyfit(x, y, 1)[0])
    if slope < UNIFORM_NOISE_SLOPE:
        return (f"line-to-line noise uniform across lines (log-log slope {slope:.2f} on |H|; "
                "a stepped sine's follows the response, near 1): an averaged random FRF?")
    return None
