"""Random-excitation test, simulated: band-limited Gaussian force, Newmark response, H1.

The industrial test of a jointed structure: a shaker drives broadband Gaussian noise at
a few RMS levels and each level gives an H1 FRF averaged over the record (``random`` in
``docs/formats/measured-data.md``). Here the reduced model with its joints
(:mod:`fe.reduction`) is driven by ``f(t) = e(t) * load`` with ``e`` a seeded Gaussian
sequence whose spectrum is flat in ``band_hz`` and zero outside (:func:`band_limited_noise`,
scaled to the RMS asked), integrated by the average-acceleration rule on the pre-warped
time axis of :func:`runs.ringdown.warped_step` (``steps_per_period`` samples per period
of the reference frequency, exact there), and the H1 estimate and the coherence are
formed by Welch averaging (Hann window, 50 % overlap; Bendat & Piersol 2010, eq. 9.53):

    H1(f) = G_fx(f) / G_ff(f),   gamma^2(f) = |G_fx|^2 / (G_ff G_xx).

The first ``settle`` seconds (the transient from rest) are integrated and discarded.
SI units: s, Hz, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from fe.newmark import NewmarkIntegrator, NewmarkSettings, NewmarkState
from fe.reduction import JointBank, ReducedModel
from runs.ringdown import warped_step

__all__ = ["RandomLevel", "band_limited_noise", "h1_estimate", "h1_spectra", "random_level"]


@dataclass
class RandomLevel:
    """One simulated random level.

    Attributes
    ----------
    freq_hz : (n_f,) lines of the estimate (Hz) inside the band.
    h1 : (n_f, n_out) complex H1 receptance (m/N); coherence : (n_f, n_out).
    force_psd : (n_f,) the drive's one-sided autospectrum ``G_ff`` of the H1 (N^2/Hz).
    drive_rms : RMS of the force actually applied (N).
    response_rms : (n_out,) RMS displacement at the outputs (m).
    slip_rms : (n_joints,) RMS joint slip (m).
    n_averages : Welch segments; duration_s : the analysed record (s).
    seed : the generator's seed.
    """

    freq_hz: np.ndarray
    h1: np.ndarray
    coherence: np.ndarray
    force_psd: np.ndarray
    drive_rms: float
    response_rms: np.ndarray
    slip_rms: np.ndarray
    n_averages: int
    duration_s: float
    seed: int


def band_limited_noise(n: int, dt: float, band_hz, rms: float, seed: int) -> np.ndarray:
    """``n`` samples (step ``dt`` s) of Gaussian noise with a flat spectrum in
    ``band_hz = (lo, hi)`` and none outside, scaled to RMS ``rms``
    (``numpy.random.default_rng(seed)``)."""
    lo, hi = band_hz
    if not 0 <= lo < hi < 0.5 / dt:
        raise ValueError(f"band {band_hz} Hz must lie within 0..{0.5 / dt:.4g} Hz (Nyquist)")
    from scipy.fft import next_fast_len

    m = next_fast_len(int(n), real=True)       # an FFT size with small factors
    x = np.random.default_rng(int(seed)).standard_normal(m)
    X = np.fft.rfft(x)
    f = np.fft.rfftfreq(m, dt)
    X[(f < lo) | (f > hi)] = 0.0
    y = np.fft.irfft(X, m)[:int(n)]
    return y * (float(rms) / np.sqrt(np.mean(y * y)))


def h1_estimate(force, response, fs: float, nperseg: int):
    """Welch H1 and coherence (module docstring): ``(freq_hz, H1 (n_f, n_out),
    coherence (n_f, n_out), n_averages)``; ``response`` (n, n_out)."""
    f, H, coh, n_avg, _ = h1_spectra(force, response, fs, nperseg)
    return f, H, coh, n_avg


def h1_spectra(force, response, fs: float, nperseg: int):
    """:func:`h1_estimate` and the drive's autospectrum ``G_ff`` it divides by:
    ``(freq_hz, H1, coherence, n_averages, G_ff (n_f,))``, ``G_ff`` one-sided per Hz."""
    force = np.asarray(force, dtype=float)
    response = np.atleast_2d(np.asarray(response, dtype=float).T).T
    kw = {"fs": fs, "window": "hann", "nperseg": int(nperseg), "noverlap": int(nperseg) // 2}
    f, Gff = signal.welch(force, **kw)
    H, coh = [], []
    for j in range(response.shape[1]):
        _, Gfx = signal.csd(force, response[:, j], **kw)
        _, Gxx = signal.welch(response[:, j], **kw)
        H.append(Gfx / Gff)
        coh.append(np.abs(Gfx) ** 2 / (Gff * Gxx))
    n_avg = 1 + (force.size - int(nperseg)) // (int(nperseg) - int(nperseg) // 2)
    return f, np.array(H).T, np.array(coh).T, n_avg, Gff


def random_level(model: ReducedModel, bank: JointBank, load, outputs, rms: float, band_hz,
                 omega_ref: float, duration: float, resolution_hz: float, seed: int,
                 steps_per_period: int = 64, settle: float = 0.0,
                 chunk: int = 1 << 16, progress=None) -> RandomLevel:
    """Simulate one random level and estimate its H1 (module docstring).

    Parameters
    ----------
    model, bank : the reduced model and its joints.
    load : (r,) reduced load pattern (``Phi^T e_d``) per newton.
    outputs : (n_out, r) rows of the recorded displacements.
    rms : drive RMS (N).
    band_hz : (lo, hi) band of the drive (Hz).
    omega_ref : rad/s, the frequency the time axis is exact at (the mode's).
    duration : analysed record (s); ``settle``: discarded start (s).
    resolution_hz : line spacing of the estimate (segment length ``1/resolution_hz``).
    seed : seed of the drive.
    progress : tqdm-like bar or None (ticks in seconds of record).
    """
    outputs = np.atleast_2d(np.asarray(outputs, dtype=float))
    dt, dt_rec = warped_step(omega_ref, steps_per_period)
    n_settle = int(round(settle / dt_rec))
    n = n_settle + int(round(duration / dt_rec))
    nperseg = int(round(1.0 / (resolution_hz * dt_rec)))
    if nperseg > n - n_settle:
        raise ValueError(f"record of {duration:g} s is shorter than one segment "
                         f"(1/{resolution_hz:g} Hz)")
    e = band_limited_noise(n + 1, dt_rec, band_hz, rms, seed)
    integ = NewmarkIntegrator(model, bank, NewmarkSettings(dt=dt))
    state = NewmarkState.rest(model, bank)
    state.a = np.linalg.solve(model.M, np.asarray(load, float) * e[0])
    state.e = e[0]
    y = np.empty((n + 1, outputs.shape[0]))
    s2 = np.zeros(model.n_joints)
    n_kept = 0
    y[0] = outputs @ state.q
    done = 0
    while done < n:
        m = min(chunk, n - done)
        run = integ.run(load, e[done:done + m + 1], state, energy=False)
        state = run.state
        y[done + 1:done + m + 1] = run.q[1:] @ outputs.T
        keep = np.arange(done + 1, done + m + 1) >= n_settle
        s2 += np.sum(run.slip[1:][keep] ** 2, axis=0)
        n_kept += int(keep.sum())
        done += m
        if progress is not None:
            progress.update(m * dt_rec)
    f_rec, y_rec = e[n_settle:], y[n_settle:]
    f, H, coh, n_avg, gff = h1_spectra(f_rec, y_rec, 1.0 / dt_rec, nperseg)
    band = (f >= band_hz[0]) & (f <= band_hz[1]) & (f > 0)
    return RandomLevel(freq_hz=f[band], h1=H[band], coherence=coh[band],
                       force_psd=gff[band], drive_rms=float(np.sqrt(np.mean(f_rec ** 2))),
                       response_rms=np.sqrt(np.mean(y_rec ** 2, axis=0)),
                       slip_rms=np.sqrt(s2 / max(n_kept, 1)), n_averages=int(n_avg),
                       duration_s=float((n - n_settle) * dt_rec), seed=int(seed))
