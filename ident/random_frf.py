"""FRF sets of a random-excitation series: the response RMS of a mode, the test's signature.

``docs/formats/measured-data.md``, "Other test types": a ``random`` level is an H1 FRF
averaged over a broadband random record; its ``excitation`` is the drive RMS and its
``response_amplitude`` the response RMS in the mode's band.

Response RMS (:func:`mode_response_rms`). With the drive's power spectral density flat
over the file's lines, ``S_ff = e^2 / (f_last - f_first)`` (one-sided, per Hz; an
assumption: a file gives no spectrum, and a shaker's force drop at resonance breaks
it), the mode's response RMS at a point is

    sigma = e sqrt( int_0^inf |H_r(f)|^2 df / (f_last - f_first) )

with ``H_r`` the identified mode's own FRF in the file's quantity (residue over pole
and its conjugate). Only ratios between levels enter chi; the assumption sets the
absolute value (and so R).

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


def mode_response_rms(mode, point: int, quantity: str, freq_hz, drive_rms: float) -> float:
    """Response RMS of one identified mode at ``point`` under a drive of RMS
    ``drive_rms`` flat over ``freq_hz`` (module doc), in the FRF's response unit."""
    f = np.asarray(freq_hz, float)
    shape = np.atleast_1d(mode.shape)[point]
    fd = mode.pole.imag / (2 * np.pi)
    hw = -mode.pole.real / (2 * np.pi)          # half-power half width, Hz

    def h2(fr):
        h = modal_receptance(mode.pole, shape, fr)[:, 0] * (2 * np.pi * fr) ** _POWER[quantity]
        return np.abs(h) ** 2

    # Gauss-Legendre: above fd/2 in th with f = fd + hw tan(th), which spreads the
    # resonance peak evenly (an adaptive rule over f misses a narrow peak by percent;
    # 1000 nodes give 1e-14 on the closed form of tests/test_random_series.py), below
    # fd/2 in f, where |H| is smooth
    x, w = np.polynomial.legendre.leggauss(GAUSS_NODES)
    a, b = np.arctan(-0.5 * fd / hw), np.pi / 2
    th = 0.5 * (b - a) * x + 0.5 * (b + a)
    peak = 0.5 * (b - a) * np.sum(w * h2(fd + hw * np.tan(th)) * hw / np.cos(th) ** 2)
    low = 0.25 * fd * np.sum(w * h2(0.25 * fd * (x + 1)))
    return float(drive_rms * np.sqrt((peak + low) / (f[-1] - f[0])))


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
