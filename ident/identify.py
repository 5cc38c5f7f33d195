"""Modal parameters from FRFs: the automatic identification (LSCF, pole selection,
refinement) and its results.

Pipeline of :func:`identify` (single reference, one or more response points):

1. **LSCF** poles for model orders 1..max_order on the band only
   (:func:`ident.lscf.lscf_poles`; basis and equations in :mod:`ident.lscf`).
2. **Stabilization**: stability status of every pole and chains of linked poles
   across orders (:mod:`ident.lscf`);
   a chain present at >= max(3, 20 %) of the orders (half that near a peak of the
   mode-indicator function ``sum_o |H_o|^2``, the peak-picking seed) is a candidate
   mode; shorter chains within 0.5 % or a half-power width of a longer one are the
   same mode. ``n_modes`` given: the n longest chains.
3. **Refinement** (:mod:`ident.refine`): the selected poles are refined by
   variable-projection nonlinear least squares of the modal model (receptance form,
   residual-corrected LSFD) with relative weights ``1 / |H_o(w)|``, pseudo-modes below
   and above the band when an F-test says they explain the misfit. Poles that leave
   the band, whose removal
   does not raise the weighted misfit significantly (F-test) or whose fitted peak is
   below 1 % of the local FRF level are dropped and the rest refitted (a pole just
   outside the band is kept when a peak of the mode indicator inside the band lies
   within its half-power half-width); then the
   weights are replaced by those of a noise model fitted to the residuals
   (:func:`ident.refine.noise_weights`) and the refinement repeated. The returned shape
   is the residue vector ``A_r`` (receptance, complex).

Measured (tests/test_identify.py): 3 modes in 50-450 Hz, zeta 0.5-5 %, 0.5 Hz lines,
1 % noise: the frequency and damping errors scatter as the Cramer-Rao bound of the
modal model (rms error / bound = 1.0 over 40 random systems, no bias); that bound is
1e-5 to 4e-5 (relative frequency) with 4 points and 2e-5 to 2.2e-4 with one point.

Why not sdypy-EMA's ``Model.get_poles('lscf')``: it builds the normal equations by FFT,
which needs a uniform frequency grid starting at 0 Hz (stepped-sine grids are not),
maps [0, f_upper] with real coefficients (a narrow band at high frequency occupies a
sliver of the unit circle: ill-conditioned), has no automatic selection, and its
least-squares poles are biased: with the true frequencies as seeds
(``select_closest_poles``) it gave frequency errors 2e-4 to 1.5e-3 and damping errors
up to 5 % on the systems above, against 0.01 % / 2 % required.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import find_peaks
from threadpoolctl import threadpool_limits

from ident.lscf import (LINK_MAC, STABLE_FREQ, ZETA_MAX, StabilizationDiagram,
                        chain_representatives, lscf_poles, stabilization)
from ident.lsfd import lsfd
from ident.pole_uncertainty import modal_std, pole_covariance
from ident.poles import mac, pole_to_modal, to_receptance
from ident.refine import noise_weights, refine_selected


@dataclass
class IdentifiedMode:
    """One identified mode.

    Attributes
    ----------
    frequency_hz : float
        Undamped natural frequency ``|lambda| / (2 pi)``, Hz.
    omega2 : float
        ``|lambda|^2``, rad^2/s^2.
    zeta : float
        Damping ratio ``-Re(lambda) / |lambda|`` (fraction).
    shape : ndarray, complex (n_points,)
        Residues ``A_r`` of the receptance at each response point (residual-corrected
        LSFD), m/N/s units of receptance x rad/s.
    pole : complex
        ``lambda = -zeta omega_n + i omega_n sqrt(1 - zeta^2)``, rad/s.
    stability : float
        Fraction of model orders at which the pole was stable (1 if not from LSCF).
    omega2_std, zeta_std : float
        Standard uncertainties of ``omega2`` (rad^2/s^2) and ``zeta`` from the
        refinement's least squares (:mod:`ident.pole_uncertainty`); NaN if unknown.
    response_at_peak : float
        Drive-point response amplitude the pole refers to (the FRF's quantity times N:
        m, m/s or m/s^2), set by :mod:`ident.amplitude_poles`; NaN for a linear fit.
    omega2_slope, zeta_slope : float
        ``d ln omega2 / d ln a`` and ``d ln zeta / d ln a`` across the level's lines
        (:mod:`ident.amplitude_poles`); NaN for a linear fit.
    """

    frequency_hz: float
    omega2: float
    zeta: float
    shape: np.ndarray
    pole: complex = 0j
    stability: float = 1.0
    omega2_std: float = float("nan")
    zeta_std: float = float("nan")
    response_at_peak: float = float("nan")
    omega2_slope: float = float("nan")
    zeta_slope: float = float("nan")


@dataclass
class Identification:
    """Modes (sorted by frequency), the stabilization diagram, the relative rms misfit
    of the final model over the band, the band used (Hz) and the lag-1 correlation of
    the weighted residuals along frequency (near 0 for noise, near 1 for a model that
    cannot follow the data), the pseudo-modes the refinement kept outside the band
    (rad/s poles) and notes on what was done to the fit."""

    modes: list
    diagram: StabilizationDiagram
    fit_error: float
    band_hz: tuple = (float("nan"), float("nan"))
    residual_correlation: float = float("nan")
    pseudo_poles: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    notes: list = field(default_factory=list)


def _prepare(freq_hz, frf, band):
    freq_hz = np.asarray(freq_hz, float)
    frf = np.asarray(frf)
    if frf.ndim == 1:
        frf = frf[:, None]
    if freq_hz.ndim != 1 or frf.ndim != 2 or frf.shape[0] != freq_hz.size:
        raise ValueError(f"frf must have shape (n_freq,) or (n_freq, n_points) with "
                         f"n_freq = {freq_hz.size}, got {np.shape(frf)}")
    if not np.all(np.isfinite(freq_hz)) or not np.all(np.isfinite(frf)):
        raise ValueError("frequencies and FRF values must be finite")
    if np.any(np.diff(freq_hz) <= 0):
        raise ValueError("frequencies must be strictly increasing")
    lo, hi = (freq_hz[0], freq_hz[-1]) if band is None else map(float, band)
    if not lo < hi:
        raise ValueError(f"band must satisfy lo < hi, got ({lo:g}, {hi:g}) Hz")
    keep = (freq_hz >= lo) & (freq_hz <= hi) & (freq_hz > 0)
    if keep.sum() < 8:
        raise ValueError(f"band {lo:g}-{hi:g} Hz holds {keep.sum()} frequency lines (> 0 Hz); "
                         "at least 8 are needed")
    return freq_hz[keep], frf[keep], (lo, hi)


def _default_max_order(n_lines, n_peaks):
    return int(min(max(24, 4 * n_peaks + 16), 60, max(4, n_lines // 4)))


def _one_blas_thread(func):
    """Run ``func`` with BLAS on one thread. The refinement of a strongly distorted FRF
    (force control deep in macro-slip) has nearly equal optima, and the summation order
    of a multi-threaded BLAS picks among them (docs/judge.md, session 9): on one thread
    the identification gives the same numbers in a script, the CLI and a worker."""
    @functools.wraps(func)
    def one_thread(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)
    return one_thread


@_one_blas_thread
def identify(freq_hz, frf, band=None, n_modes=None, quantity="receptance",
             max_order=None, weighting="auto", pseudo_modes=True) -> Identification:
    """Identify the modes in ``band`` from FRFs of one reference.

    Parameters
    ----------
    freq_hz : (K,) frequencies, Hz, strictly increasing (any spacing).
    frf : (K,) or (K, P) complex FRFs of ``quantity`` (receptance m/N, mobility m/s/N,
        accelerance m/s^2/N); converted to receptance before fitting.
    band : (lo, hi) Hz or None for all lines.
    n_modes : number of modes, or None to decide from stabilization (module doc).
    max_order : highest LSCF order (default from the number of peaks and lines).
    weighting : weights of the refinement: "relative" (1/|H|), "uniform", or "auto"
        (default): relative, then 1/sigma of the noise model fitted to the residuals
        (:func:`ident.refine.noise_weights`) and refined again.
    pseudo_modes : add one pseudo-mode below and one above the band to the refinement
        (:func:`ident.refine.refine_poles`); they are not returned.

    Returns
    -------
    Identification (modes sorted by frequency, stabilization diagram, fit error).
    """
    f, H, (lo, hi) = _prepare(freq_hz, frf, band)
    if n_modes is not None and int(n_modes) < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes}")
    if weighting not in ("auto", "relative", "uniform"):
        raise ValueError(f"weighting must be 'auto', 'relative' or 'uniform', "
                         f"got {weighting!r}")
    H = to_receptance(f, H, quantity)
    w = 2 * np.pi * f
    Hn = H / np.sqrt(np.mean(np.abs(H) ** 2, axis=0))
    mif = np.sum(np.abs(Hn) ** 2, axis=1)
    peaks, _ = find_peaks(np.log(mif), prominence=0.1)
    if max_order is None:
        max_order = _default_max_order(f.size, peaks.size)
    max_order = int(max_order)
    if max_order < 1:
        raise ValueError(f"max_order must be >= 1, got {max_order}")
    pole_sets = lscf_poles(f, Hn, max_order)
    order, lam, status, link, label = stabilization(f, Hn, pole_sets, (w[0], w[-1]))
    chains = chain_representatives(lam, link, label, order)
    wn_d, z_d = pole_to_modal(lam)
    diagram = StabilizationDiagram(order=order, frequency_hz=wn_d / (2 * np.pi), zeta=z_d,
                                   status=status, indicator_hz=f, indicator=mif)
    if not chains:
        if n_modes is None and peaks.size == 0:
            return Identification([], diagram, float("nan"))
        raise ValueError(f"no stable pole in {lo:g}-{hi:g} Hz up to model order "
                         f"{max_order}: widen the band or raise the order")
    rep = np.array([c[0] for c in chains])
    count = np.array([c[1] for c in chains])
    # one chain per physical mode: drop shorter chains within 1 % / a half-power width
    wn_r, z_r = pole_to_modal(rep)
    keep = np.ones(rep.size, bool)
    for i in np.argsort(-count):
        if not keep[i]:
            continue
        close = (np.abs(wn_r - wn_r[i]) < np.maximum(0.5 * STABLE_FREQ * wn_r[i],
                                                     z_r[i] * wn_r[i])) & keep
        close[i] = False
        keep[close & (count <= count[i])] = False
    rep, count = rep[keep], count[keep]
    wn_r, z_r = pole_to_modal(rep)

    n_orders = max_order
    if n_modes is None:
        need = max(3, int(np.ceil(0.2 * n_orders)))
        near_peak = np.zeros(rep.size, bool)
        if peaks.size:
            dist = np.abs(f[peaks][None, :] * 2 * np.pi - wn_r[:, None])
            near_peak = np.any(dist < np.maximum(2 * z_r * wn_r, 2 * np.diff(w).max())[:, None],
                               axis=1)
        chosen = np.flatnonzero((count >= need) | (near_peak & (count >= max(2, need // 2))))
    else:
        chosen = np.argsort(-count, kind="stable")[: int(n_modes)]
        if chosen.size < int(n_modes):
            raise ValueError(f"only {chosen.size} stable mode(s) found in {lo:g}-{hi:g} Hz, "
                             f"{n_modes} requested")
    poles = rep[chosen]
    stab = count[chosen] / n_orders

    Wt = None if weighting == "uniform" else 1.0 / np.maximum(np.abs(Hn), 1e-300)
    band_w = (w[0], w[-1]) if pseudo_modes else None

    def fit(p):
        return refine_selected(f, Hn, p, Wt, band_w)

    def physical(p):
        """Refined poles in the band with damping in (1e-7, ZETA_MAX), or just outside it
        while a peak of the mode indicator inside the band lies within their half-power
        half-width (a resonance the band cuts: a force-controlled FRF of a softening
        joint pulls the fitted pole below its peak); not a neighbour's tail."""
        wn_p, z_p = pole_to_modal(p)
        inside = (p.imag >= w[0]) & (p.imag <= w[-1])
        if peaks.size:
            reach = -p.real + 2 * np.diff(w).max()
            inside |= np.any(np.abs(w[peaks][None, :] - p.imag[:, None]) < reach[:, None],
                             axis=1)
        return inside & (z_p > 1e-7) & (z_p < ZETA_MAX)

    def significant(p, ps):
        """Keep mode r when dropping it (poles fixed, residues refitted) raises the
        weighted misfit chi^2 significantly: F = ((chi_-r - chi)/q) / (chi/dof) above
        the 1 - 1e-3/K quantile of F(q, dof), q = 2 + 2P (look-elsewhere: a noise pole
        is the best of ~K candidates); and its fitted peak above 1 % of the local
        FRF level."""
        from scipy.stats import f as fisher_f

        allp = np.concatenate([p, ps])
        res, fitted, r = lsfd(f, Hn, allp, Wt)
        chi = np.sum(np.abs(r) ** 2)
        K, P = Hn.shape
        q = 2 + 2 * P
        dof = 2 * K * P - (2 * allp.size + P * (2 * allp.size + 4))
        if dof <= 0 or chi <= 0:
            return np.ones(p.size, bool)
        crit = fisher_f.isf(1e-3 / K, q, dof)
        F = np.array([((np.sum(np.abs(lsfd(f, Hn, np.delete(allp, k), Wt)[2]) ** 2) - chi)
                       / q) / (chi / dof) for k in range(p.size)])
        lev2 = np.sum(np.abs(Hn) ** 2, axis=1)
        wn_p, z_p = pole_to_modal(p)
        peak = np.sqrt(np.sum(np.abs(res[:, :p.size]) ** 2, axis=0)) / (-p.real)
        win = np.abs(w[None, :] - wn_p[:, None]) <= np.maximum(
            3 * z_p * wn_p, 2 * np.diff(w).max())[:, None]                 # (m, K)
        level = np.sqrt((win * lev2).sum(axis=1) / np.maximum(win.sum(axis=1), 1))
        return (F > crit) & (peak > 0.01 * level)

    def split_pair(p, ps):
        """One mode fitted by two poles closer than a half-power width (and, several
        points, residue MAC > 0.9): drop the weaker unless the F-test (as in
        :func:`significant`, but refitting the poles) says both are needed."""
        from scipy.stats import f as fisher_f

        keep = np.ones(p.size, bool)
        wn_p, z_p = pole_to_modal(p)
        res = lsfd(f, Hn, np.concatenate([p, ps]), Wt)[0][:, :p.size]
        peak = np.sqrt(np.sum(np.abs(res) ** 2, axis=0)) / (-p.real)
        for i, j in zip(*np.triu_indices(p.size, 1)):
            close = abs(wn_p[i] - wn_p[j]) < max(z_p[i] * wn_p[i], z_p[j] * wn_p[j])
            if not close or (Hn.shape[1] > 1 and mac(res[:, i], res[:, j])[0, 0] < LINK_MAC):
                continue
            weak = i if peak[i] < peak[j] else j
            K, P = Hn.shape
            chi = np.sum(np.abs(lsfd(f, Hn, np.concatenate([p, ps]), Wt)[2]) ** 2)
            p1, ps1 = fit(np.delete(p, weak))
            chi1 = np.sum(np.abs(lsfd(f, Hn, np.concatenate([p1, ps1]), Wt)[2]) ** 2)
            n_par = 2 * (p.size + ps.size) + P * (2 * (p.size + ps.size) + 4)
            dof, q = 2 * K * P - n_par, 2 + 2 * P
            if dof > 0 and chi > 0 and ((chi1 - chi) / q) / (chi / dof) < fisher_f.isf(
                    1e-3 / K, q, dof):
                keep[weak] = False
                break
        return keep

    pseudo = np.zeros(0, complex)
    for stage in range(2):
        for _ in range(4):      # refine; drop runaway / insignificant poles; refine again
            if not poles.size:
                break
            poles, pseudo = fit(poles)
            keep = physical(poles)
            if n_modes is None and keep.any():
                keep[keep] = significant(poles[keep], pseudo)
                if keep.all():
                    keep = split_pair(poles, pseudo)
            if keep.all():
                break
            poles, stab = poles[keep], stab[keep]
        if weighting != "auto" or stage == 1 or not poles.size:
            break
        Wt = noise_weights(f, Hn, np.concatenate([poles, pseudo]))
    scale = np.sqrt(np.mean(np.abs(H) ** 2, axis=0))
    corr = float("nan")
    if poles.size:
        allp = np.concatenate([poles, pseudo])
        residues, fitted, wres = lsfd(f, Hn, allp, Wt)
        residues = residues[:, :poles.size]
        fit_error = float(np.linalg.norm(Hn - fitted) / np.linalg.norm(Hn))
        s_w2, s_z = modal_std(poles, pole_covariance(f, Hn, allp, Wt))
        corr = float(np.real(np.sum(np.conj(wres[:-1]) * wres[1:]))
                     / max(np.sum(np.abs(wres) ** 2), 1e-300))
    else:
        residues, fit_error = np.zeros((H.shape[1], 0), complex), float("nan")
    idx = np.argsort(np.abs(poles))
    modes = []
    for r in idx:
        wn, z = pole_to_modal(poles[r])
        modes.append(IdentifiedMode(frequency_hz=float(wn / (2 * np.pi)), omega2=float(wn**2),
                                    zeta=float(z), shape=residues[:, r] * scale,
                                    pole=complex(poles[r]), stability=float(stab[r]),
                                    omega2_std=float(s_w2[r]), zeta_std=float(s_z[r])))
    diagram.selected_hz = np.array([m.frequency_hz for m in modes])
    if n_modes is not None and len(modes) < int(n_modes):
        raise ValueError(f"{n_modes} mode(s) requested, {len(modes)} left after the "
                         f"refinement in {lo:g}-{hi:g} Hz (poles ran out of the band or "
                         "to zero damping)")
    return Identification(modes, diagram, fit_error, (float(lo), float(hi)), corr,
                          np.asarray(pseudo, complex))


def identify_modes(freq_hz, frf, band=None, n_modes=None, **options) -> list[IdentifiedMode]:
    """Modes identified from FRFs (see :func:`identify`); the ARCHITECTURE contract."""
    return identify(freq_hz, frf, band=band, n_modes=n_modes, **options).modes
