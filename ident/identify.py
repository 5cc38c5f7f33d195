"""Modal parameters from FRFs: the automatic identification (LSCF, pole selection,
refinement) and its results.

Pipeline of :func:`identify` (single reference, one or more response points):

1. **LSCF** poles for model orders 1..max_order on the band only
   (:func:`ident.lscf.lscf_poles`; basis and equations in :mod:`ident.lscf`).
2. **Stabilization**: stability status of every pole and chains of linked poles
   across orders (:mod:`ident.lscf`); the candidates are chosen from the chains
   (:func:`ident.pole_selection.candidates`: long chains, shorter ones near a peak of
   the mode indicator ``sum_o |H_o|^2``; ``n_modes`` given: the n longest).
3. **Refinement** (:mod:`ident.refine`): the candidates are refined by
   variable-projection nonlinear least squares of the modal model (receptance form,
   residual-corrected LSFD) with relative weights ``1 / |H_o(w)|``, fixed out-of-band
   poles joining as linear terms when an F-test says they explain the misfit. Poles
   that are not physical, whose removal does not raise the misfit significantly or
   that double a resonance are dropped and the rest refitted
   (:mod:`ident.pole_selection`); then the weights are replaced by those of a noise
   model fitted to the residuals (:func:`ident.refine.noise_weights`) and the
   selection repeated. Near-band poles (modes just outside the band whose skirt it
   holds) are refined with the modes and returned among the pseudo-poles.
4. **Settling** (:func:`_settle`): the chosen model is refitted until the poles are an
   optimum (Newton decrement below :data:`ident.refine.DECREMENT_TOL`) of the fit
   weighted by the noise model of their own residuals (a fixed point). Round-off in the
   LSCF start then moves the result by far less than its standard deviation
   (``benchmarks/blas_repro.py``); a fit that does not settle says so in ``notes``, as
   does a selection test that decided within 10 % of its threshold. The returned shape
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

from ident.lscf import StabilizationDiagram, chain_representatives, lscf_poles, stabilization
from ident.lsfd import lsfd
from ident.pole_selection import (candidates, near_threshold, one_resonance_pair, physical,
                                  roles, runaway, significant)
from ident.pole_uncertainty import modal_std, pole_covariance
from ident.poles import pole_to_modal, to_receptance
from ident.refine import (DECREMENT_TOL, OUT_OF_BAND_ROOM, noise_variance, noise_weights,
                          refine_poles, refine_selected)


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


def _check_options(n_modes: int | None, weighting: str) -> None:
    """Refuse a number of modes below 1 and an unknown weighting."""
    if n_modes is not None and int(n_modes) < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes}")
    if weighting not in ("auto", "relative", "uniform"):
        raise ValueError(f"weighting must be 'auto', 'relative' or 'uniform', "
                         f"got {weighting!r}")


def _resolved_order(max_order: int | None, n_lines: int, n_peaks: int) -> int:
    """The highest LSCF order: the one given (>= 1) or the default of the lines and peaks."""
    if max_order is None:
        max_order = _default_max_order(n_lines, n_peaks)
    max_order = int(max_order)
    if max_order < 1:
        raise ValueError(f"max_order must be >= 1, got {max_order}")
    return max_order


def _stabilization(f: np.ndarray, Hn: np.ndarray, mif: np.ndarray, max_order: int
                   ) -> tuple[list, StabilizationDiagram]:
    """LSCF poles of orders 1..max_order on the band, their chains across orders
    (:func:`ident.lscf.chain_representatives`) and the stabilization diagram."""
    w = 2 * np.pi * f
    pole_sets = lscf_poles(f, Hn, max_order)
    order, lam, status, link, label = stabilization(f, Hn, pole_sets, (w[0], w[-1]))
    chains = chain_representatives(lam, link, label, order)
    wn_d, z_d = pole_to_modal(lam)
    diagram = StabilizationDiagram(order=order, frequency_hz=wn_d / (2 * np.pi), zeta=z_d,
                                   status=status, indicator_hz=f, indicator=mif)
    return chains, diagram


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


#: Fixed-point iterations of the noise-model weights at most (:func:`_settle`), and the
#: move of every pole, in half-power half-widths, below which they have settled (the
#: iteration contracts by about 0.4 per pass on a distorted level; a pole's standard
#: deviation is 1e-3 to 1e-1 half-widths, so 1e-7 is below 1e-4 of it).
WEIGHT_PASSES = 40
WEIGHT_TOL = 1e-7


def _settle(f, Hn, poles, pseudo, Wt, noise_model):
    """The chosen model refitted to convergence: the poles refined with the
    out-of-band terms held (:func:`ident.refine.refine_poles`), and, with
    ``noise_model``, the noise variance recomputed from each fit until the poles move
    by less than :data:`WEIGHT_TOL` of their half-power half-width (a fixed point of
    the weighted fit; the weights then belong to the poles they weight). A pass that
    does not shrink the move by 0.7 halves the relaxation of the variance (a noise
    model of a deterministic misfit can flip between two states, a two-cycle).
    Returns (poles, weights, the last refinement, a note or None)."""
    ref = refine_poles(f, Hn, poles, Wt, pseudo)
    moved, before, relax, var = 0.0, np.inf, 1.0, None
    for _ in range(WEIGHT_PASSES if noise_model else 0):
        new_var = noise_variance(f, Hn, np.concatenate([ref.poles, pseudo]))
        var = new_var if var is None else (1 - relax) * var + relax * new_var
        Wt = 1.0 / np.sqrt(var)
        new = refine_poles(f, Hn, ref.poles, Wt, pseudo)
        moved = float(np.max(np.abs(new.poles - ref.poles) / np.abs(ref.poles.real)))
        ref = new
        if moved < WEIGHT_TOL:
            break
        if moved > 0.7 * before:
            relax = max(relax / 2, 1 / 16)
        before = moved
    note = None
    if not ref.converged:
        note = (f"the refinement did not converge (Newton decrement {ref.decrement:.2g} "
                f"s^2 against {DECREMENT_TOL:g}): its poles may move with round-off")
    elif moved >= WEIGHT_TOL:
        note = (f"the noise-model weights did not settle in {WEIGHT_PASSES} passes (the "
                f"poles still moved {moved:.2g} half-widths): they may move with round-off")
    return ref.poles, Wt, ref, note


def _fit(f, Hn, Wt, p, ob_band):
    """Refined poles, out-of-band poles and near-threshold notes of
    :func:`ident.refine.refine_selected`."""
    sel = refine_selected(f, Hn, p, Wt, ob_band)
    notes = [near_threshold("F-test of the out-of-band terms", sel.f_stat, sel.f_crit)]
    notes += [near_threshold(f"room {side} the modes for out-of-band terms (decay rates)",
                             room, OUT_OF_BAND_ROOM)
              for side, room in zip(("below", "above"), sel.room)]
    return sel.poles, sel.pseudo, [n for n in notes if n]


def _select(f, Hn, Wt, poles, stab, n_modes, ob_band, band_w, peak_w, dw):
    """Refine the candidates and drop what :mod:`ident.pole_selection` rejects, one
    step at a time, until every pole stays: a runaway pole (the one that moved the
    most) is dropped and the rest refined again from their starts; non-physical,
    insignificant or doubled poles are dropped and the rest refined from where they
    are. Returns (poles, stability, nuisance, out-of-band poles, notes)."""
    pseudo, notes = np.zeros(0, complex), []
    nuisance = np.zeros(poles.size, bool)
    for _ in range(4 + poles.size):
        if not poles.size:
            break
        new, pseudo, notes = _fit(f, Hn, Wt, poles, ob_band)
        moved = runaway(poles, new)
        if moved.any():
            keep = np.ones(poles.size, bool)
            keep[np.argmax(np.abs(new - poles) / np.abs(poles.real))] = False
            poles, stab = poles[keep], stab[keep]
            continue
        poles = new
        keep, _ = physical(poles, band_w, peak_w, dw)
        nuisance = np.zeros(poles.size, bool)
        if n_modes is not None and keep.any():
            ok = keep.copy()
            keep[ok], nuisance[ok] = roles(f, Hn, poles[ok], pseudo, Wt, n_modes, band_w,
                                           peak_w)
        if n_modes is None and keep.any():
            sig, F, crit = significant(f, Hn, poles[keep], pseudo, Wt)
            notes += [near_threshold(f"F-test of the pole at {abs(pk) / (2 * np.pi):.6g} Hz",
                                     Fk, crit) for pk, Fk in zip(poles[keep], F)]
            keep[keep] = sig
            if keep.all():
                keep, tests = one_resonance_pair(f, Hn, poles, pseudo, Wt,
                                                 lambda p: _fit(f, Hn, Wt, p, ob_band)[:2])
                notes += [near_threshold(
                    f"F-test of two poles on one resonance ({abs(poles[i]) / (2 * np.pi):.6g}, "
                    f"{abs(poles[j]) / (2 * np.pi):.6g} Hz)", Fk, crit)
                    for (i, j), Fk, crit in tests]
        if keep.all():
            break
        poles, stab, nuisance = poles[keep], stab[keep], nuisance[keep]
    return poles, stab, nuisance, pseudo, [n for n in notes if n]


def _modes(f, H, Hn, poles, pseudo, near, stab, Wt):
    """The identified modes (poles not ``near``, sorted by frequency; residues in the
    units of ``H``, standard uncertainties of :mod:`ident.pole_uncertainty`), the
    relative misfit and the lag-1 correlation of the weighted residuals."""
    if not poles.size:
        return [], float("nan"), float("nan")
    scale = np.sqrt(np.mean(np.abs(H) ** 2, axis=0))
    residues, fitted, wres = lsfd(f, Hn, np.concatenate([poles, pseudo]), Wt)
    fit_error = float(np.linalg.norm(Hn - fitted) / np.linalg.norm(Hn))
    s_w2, s_z = modal_std(poles, pole_covariance(f, Hn, poles, Wt, pseudo))
    corr = float(np.real(np.sum(np.conj(wres[:-1]) * wres[1:]))
                 / max(np.sum(np.abs(wres) ** 2), 1e-300))
    modes = []
    for r in (r for r in np.argsort(np.abs(poles)) if not near[r]):
        wn, z = pole_to_modal(poles[r])
        modes.append(IdentifiedMode(frequency_hz=float(wn / (2 * np.pi)), omega2=float(wn**2),
                                    zeta=float(z), shape=residues[:, r] * scale,
                                    pole=complex(poles[r]), stability=float(stab[r]),
                                    omega2_std=float(s_w2[r]), zeta_std=float(s_z[r])))
    return modes, fit_error, corr


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
    pseudo_modes : offer fixed out-of-band poles to the refinement (F-tested linear
        terms, :func:`ident.refine.refine_selected`); they are not returned.

    Returns
    -------
    Identification (modes sorted by frequency, stabilization diagram, fit error).
    """
    f, H, (lo, hi) = _prepare(freq_hz, frf, band)
    _check_options(n_modes, weighting)
    H = to_receptance(f, H, quantity)
    w = 2 * np.pi * f
    Hn = H / np.sqrt(np.mean(np.abs(H) ** 2, axis=0))
    mif = np.sum(np.abs(Hn) ** 2, axis=1)
    peaks, _ = find_peaks(np.log(mif), prominence=0.1)
    max_order = _resolved_order(max_order, f.size, peaks.size)
    chains, diagram = _stabilization(f, Hn, mif, max_order)
    if not chains:
        if n_modes is None and peaks.size == 0:
            return Identification([], diagram, float("nan"))
        raise ValueError(f"no stable pole in {lo:g}-{hi:g} Hz up to model order "
                         f"{max_order}: widen the band or raise the order")
    rep = np.array([c[0] for c in chains])
    orders = [c[1] for c in chains]
    dw = float(np.diff(w).max())
    band_w = (w[0], w[-1])
    poles, stab = candidates(rep, orders, max_order, n_modes, w[peaks], dw, band_w)

    Wt = None if weighting == "uniform" else 1.0 / np.maximum(np.abs(Hn), 1e-300)
    ob_band = band_w if pseudo_modes else None
    notes = []
    for stage in range(2):
        poles, stab, nuisance, pseudo, stage_notes = _select(
            f, Hn, Wt, poles, stab, n_modes, ob_band, band_w, w[peaks], dw)
        if weighting != "auto" or stage == 1 or not poles.size:
            break
        Wt = noise_weights(f, Hn, np.concatenate([poles, pseudo]))
    notes += stage_notes
    near = np.zeros(poles.size, bool)
    if poles.size:
        poles, Wt, ref, note = _settle(f, Hn, poles, pseudo, Wt, weighting == "auto")
        notes += [note] if note else []
        near = physical(poles, band_w, w[peaks], dw)[1] | nuisance
        notes += [f"a resonance at {abs(pk) / (2 * np.pi):.6g} Hz fitted beside the "
                  f"{n_modes} mode(s) asked for (not returned)" for pk in poles[nuisance]]
    modes, fit_error, corr = _modes(f, H, Hn, poles, pseudo, near, stab, Wt)
    pseudo = np.concatenate([poles[near], pseudo])
    diagram.selected_hz = np.array([m.frequency_hz for m in modes])
    if n_modes is not None and len(modes) < int(n_modes):
        raise ValueError(f"{n_modes} mode(s) requested, {len(modes)} left after the "
                         f"refinement in {lo:g}-{hi:g} Hz (poles ran out of the band or "
                         "to zero damping)")
    return Identification(modes, diagram, fit_error, (float(lo), float(hi)), corr,
                          np.asarray(pseudo, complex), notes)


def identify_modes(freq_hz, frf, band=None, n_modes=None, **options) -> list[IdentifiedMode]:
    """Modes identified from FRFs (see :func:`identify`); the ARCHITECTURE contract."""
    return identify(freq_hz, frf, band=band, n_modes=n_modes, **options).modes
