"""Refinement of selected poles: variable-projection nonlinear least squares of the
modal model, fixed out-of-band poles, noise-model weights, convergence.

The selected poles are refined by variable-projection nonlinear least squares of the
modal model (receptance form)
``H_o(w) = sum_r A_ro/(i w - lambda_r) + conj(A_ro)/(i w - conj(lambda_r))
+ U_o - L_o / w^2`` with relative weights ``1 / |H_o(w)|`` (maximum likelihood for
noise proportional to |H|) or those of a noise model fitted to the residuals
(:func:`noise_weights`); residues ``A_ro`` and the residual terms U, L (complex)
are solved linearly for each trial set of poles (LSFD with residual correction,
:func:`ident.lsfd.lsfd`). The only nonlinear parameters are the modes' poles, two per
mode in units of the mode's own half-power half-width (:func:`refine_poles`), so the
optimum is well posed wherever the modes are resolved.

**Out-of-band poles.** A mode outside the band has a tail that U - L/w^2 cannot
follow. One whose skirt the band holds is found by LSCF and refined like a mode
(a near-band pole, :mod:`ident.pole_selection`). For the others, fixed poles below and
above the band (:func:`out_of_band_poles`: at :data:`OUT_OF_BAND_OFFSETS` of the log
band width beyond each edge, each as wide as its distance to the edge) join the model
with free residues, that is as *linear* terms, when an F-test on the nested fits says
they explain the misfit (:func:`refine_selected`), on each side whose lines clear of
the modes reach :data:`OUT_OF_BAND_ROOM` decay rates (:func:`band_room`): in a band a
few half-power widths wide any smooth term trades with the mode's own skirt and, on a
force-controlled FRF, takes the joint's distortion (on a 41-line level the damping's
standard deviation grew 5-fold and the band check lost its signal). Free out-of-band
poles (two nonlinear parameters each, up to session 18) are not identifiable there:
their fits stopped anywhere along a flat valley (chi2 from 35 to 43 over 30 starts on
one 41-line level, the mode's frequency over 1.4 of its standard deviations) and the
answer moved with the BLAS kernel.

**Convergence** (:func:`refine_poles`). After Levenberg-Marquardt, Gauss-Newton steps
polish the optimum until the Newton decrement ``g^T (J^T J)^-1 g`` (``J`` the central-
difference Jacobian of the projected residual, ``g = J^T r``), in units of the residual
variance ``s^2 = |r|^2 / dof``, is below :data:`DECREMENT_TOL`: the distance to the
optimum in standard deviations of the parameters is its square root (1e-3 here), so
round-off in the start moves the result by far less than its uncertainty. On noise-free
data ``s^2`` is at least (:data:`PRECISION` x the data's rms)^2. A fit that does not get
there says so (``Refinement.converged``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from ident.lsfd import lsfd
from ident.poles import modal_to_pole

__all__ = ["Refinement", "Selected", "polish", "refine_poles", "refine_selected", "out_of_band_poles",
           "band_room", "noise_variance", "noise_weights", "OUT_OF_BAND_OFFSETS", "OUT_OF_BAND_F_QUANTILE",
           "OUT_OF_BAND_ROOM",
           "DECREMENT_TOL"]

#: Distances of the fixed out-of-band poles beyond each band edge, as fractions of the
#: log band width ``ln(w_hi / w_lo)``.
OUT_OF_BAND_OFFSETS = (0.1, 0.5)
#: Room (band_room: edge to the nearest mode, in its decay rates) a side of the band
#: needs for out-of-band poles on that side.
OUT_OF_BAND_ROOM = 4.0
#: Quantile of F(q, dof) the out-of-band poles must pass to join the model.
OUT_OF_BAND_F_QUANTILE = 0.999
#: Newton decrement (in units of the residual variance) below which a fit is converged:
#: the optimum lies within sqrt(DECREMENT_TOL) = 1e-3 standard deviations.
DECREMENT_TOL = 1e-6
#: Relative precision of the data below which a misfit is round-off: the residual
#: variance of a fit is taken as at least (PRECISION x the data's rms)^2.
PRECISION = 1e-10
#: Gauss-Newton polishing steps at most after Levenberg-Marquardt.
POLISH_STEPS = 30


@dataclass
class Refinement:
    """A refined set of poles.

    ``poles`` (m,) rad/s; ``chi2`` the weighted misfit ``|r|^2``; ``decrement`` the
    Newton decrement in units of ``s^2`` (module doc); ``converged`` whether it is
    below :data:`DECREMENT_TOL`; ``n_eval`` residual evaluations."""

    poles: np.ndarray
    chi2: float
    decrement: float
    converged: bool
    n_eval: int


def out_of_band_poles(band_w, side=(True, True)) -> np.ndarray:
    """Fixed poles (rad/s) below and above the band ``(w_lo, w_hi)``: natural frequency
    ``w_lo exp(-c L)`` and ``w_hi exp(c L)`` for ``c`` in :data:`OUT_OF_BAND_OFFSETS`
    (``L = ln(w_hi / w_lo)``), decay rate equal to the distance to the edge (a
    half-power width as wide as the gap: a tail, not a resonance, over the band).
    ``side``: (below, above) wanted."""
    lo, hi = map(float, band_w)
    L = np.log(hi / lo)
    c = np.asarray(OUT_OF_BAND_OFFSETS, float)
    below, above = lo * np.exp(-c * L), hi * np.exp(c * L)
    wn = np.concatenate([below if side[0] else [], above if side[1] else []])
    gap = np.abs(np.where(wn < lo, lo, hi) - wn)
    return modal_to_pole(wn, np.minimum(gap / wn, 0.5))


def band_room(band_w, poles) -> np.ndarray:
    """(below, above): the lines free of the modes on each side of the band, as the
    distance from the edge to the nearest mode in that mode's decay rates
    (``(w_n - w_lo) / sigma``, ``(w_hi - w_n) / sigma``)."""
    poles = np.asarray(poles, complex)
    wn, sigma = np.abs(poles), -poles.real
    i, j = np.argmin(wn), np.argmax(wn)
    with np.errstate(over="ignore", divide="ignore"):
        return np.array([(wn[i] - band_w[0]) / sigma[i], (band_w[1] - wn[j]) / sigma[j]])


def _projected_residual(freq_hz, frf, weights, fixed, sigma0, wd0):
    """The residual of the modal model (real, stacked) as a function of
    ``theta = [ln(sigma/sigma0), (w_d - w_d0)/sigma0]``; a large constant where the
    poles are not stable or the solve fails."""
    m = sigma0.size
    big = [None]

    def poles(theta):
        with np.errstate(over="ignore", invalid="ignore"):
            return -sigma0 * np.exp(theta[:m]) + 1j * (wd0 + sigma0 * theta[m:])

    def residual(theta):
        allp = np.concatenate([poles(theta), fixed])
        if np.all(np.isfinite(allp)) and np.all(allp.real < 0):
            try:
                r = lsfd(freq_hz, frf, allp, weights)[2]
                out = np.concatenate([r.real.ravel(), r.imag.ravel()])
                if np.all(np.isfinite(out)):
                    if big[0] is None:
                        big[0] = 1e3 * np.abs(out).max() + 1.0
                    return out
            except np.linalg.LinAlgError:
                pass
        return np.full(2 * np.size(frf), big[0] if big[0] is not None else 1e6)

    return residual, poles


def _decrement(residual, theta, n_linear, s2_floor=0.0):
    """(Newton decrement / s^2, Gauss-Newton step, chi2) at ``theta``: central-
    difference Jacobian (step 1e-5 of a half-power half-width); ``s^2`` at least
    ``s2_floor`` (a fit to noise-free data has no residual variance to measure by)."""
    r0 = residual(theta)
    h = 1e-5
    J = np.empty((r0.size, theta.size))
    for k in range(theta.size):
        e = np.zeros(theta.size)
        e[k] = h
        J[:, k] = (residual(theta + e) - residual(theta - e)) / (2 * h)
    chi2 = float(r0 @ r0)
    dof = r0.size - theta.size - n_linear
    g = J.T @ r0
    step = -np.linalg.lstsq(J, r0, rcond=1e-12)[0]
    s2 = max(chi2 / dof if dof > 0 else chi2, s2_floor)
    dec = float(-g @ step) / s2 if s2 > 0 else 0.0
    return dec, step, chi2


def polish(residual, theta, n_linear: int, s2_floor: float = 0.0):
    """Gauss-Newton steps with step halving from ``theta`` until the Newton decrement
    is below :data:`DECREMENT_TOL` (or :data:`POLISH_STEPS` are spent, or no step
    descends); ``s2_floor``: the least residual variance per real residual (the data's
    mean square times :data:`PRECISION` squared: noise-free data). Returns (theta,
    decrement, chi2, residual evaluations)."""
    dec, step, chi2 = _decrement(residual, theta, n_linear, s2_floor)
    n_eval = 1 + 2 * theta.size
    for _ in range(POLISH_STEPS):
        if dec < DECREMENT_TOL:
            break
        t = 1.0
        while t > 1e-4:
            trial = theta + t * step
            r = residual(trial)
            n_eval += 1
            if float(r @ r) < chi2:
                break
            t *= 0.5
        else:
            break                      # no descent along the Gauss-Newton step
        theta = trial
        dec, step, chi2 = _decrement(residual, theta, n_linear, s2_floor)
        n_eval += 1 + 2 * theta.size
    return theta, dec, chi2, n_eval


def refine_poles(freq_hz, frf, poles, weights=None, fixed=()) -> Refinement:
    """Variable-projection nonlinear least squares of ``poles`` (module doc), the
    ``fixed`` poles (out-of-band terms) held.

    Parameters ``theta = [ln(sigma/sigma0), (w_d - w_d0)/sigma0]`` per pole (units of
    the start's half-power half-width ``sigma0``; the damping stays positive).
    Levenberg-Marquardt, then Gauss-Newton steps with step halving until the Newton
    decrement is below :data:`DECREMENT_TOL` or :data:`POLISH_STEPS` are spent.
    """
    poles = np.asarray(poles, complex)
    fixed = np.asarray(fixed, complex)
    m = poles.size
    if m == 0:
        return Refinement(poles, float("nan"), 0.0, True, 0)
    K, P = np.shape(frf)
    n_linear = P * (2 * (m + fixed.size) + 4)
    residual, unpack = _projected_residual(freq_hz, frf, weights, fixed,
                                           -poles.real, poles.imag)
    sol = least_squares(residual, np.zeros(2 * m), method="lm", x_scale=1.0,
                        ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200 * (2 * m + 1))
    w = 1.0 if weights is None else np.asarray(weights)
    floor = PRECISION ** 2 * float(np.mean(np.abs(w * np.asarray(frf)) ** 2)) / 2
    theta, dec, chi2, n_eval = polish(residual, sol.x, n_linear, floor)
    return Refinement(unpack(theta), chi2, dec, bool(dec < DECREMENT_TOL),
                      n_eval + int(sol.nfev))


def noise_variance(freq_hz, frf, poles) -> np.ndarray:
    """Variance sigma_k^2 (K, P) of a noise model fitted to the residuals of the modal
    model with ``poles``.

    ``sigma_k^2 = a^2 |H_fit,k|^2 + b^2`` (noise proportional to the FRF plus a floor),
    a^2, b^2 >= 0 by non-negative least squares of the squared residuals |H - H_fit|^2
    on (|H_fit|^2, 1), all points pooled (each point scaled to unit rms). For noise
    proportional to |H| this is the maximum-likelihood weighting with the fitted rather
    than the noisy |H|; an additive floor stops noisy low-level lines (anti-resonances,
    far from the modes) from dominating the fit. ``|H|^2`` where the fit fails."""
    from scipy.optimize import nnls

    _, fitted, _ = lsfd(freq_hz, frf, poles, 1.0 / np.maximum(np.abs(frf), 1e-300))
    r2 = np.abs(frf - fitted).ravel() ** 2
    g2 = np.abs(fitted).ravel() ** 2
    X = np.stack([g2, np.ones_like(g2)], axis=1)
    cs = np.linalg.norm(X, axis=0)
    (a2, b2), _ = nnls(X / cs, r2)
    a2, b2 = a2 / cs[0], b2 / cs[1]
    floor = 1e-12 * np.mean(g2)
    sigma2 = a2 * np.abs(fitted) ** 2 + max(b2, floor)
    if not np.all(np.isfinite(sigma2)) or a2 + b2 <= 0:
        return np.maximum(np.abs(frf), 1e-300) ** 2
    return sigma2


def noise_weights(freq_hz, frf, poles) -> np.ndarray:
    """Weights ``1 / sigma_k`` of :func:`noise_variance`."""
    return 1.0 / np.sqrt(noise_variance(freq_hz, frf, poles))


@dataclass
class Selected:
    """What :func:`refine_selected` chose: the refined mode poles, the out-of-band poles
    kept (empty or :func:`out_of_band_poles`), the F statistic of the out-of-band terms
    and its critical value (NaN when not tested), the refinement that was kept and the
    :func:`band_room` of the band (NaN without out-of-band terms)."""

    poles: np.ndarray
    pseudo: np.ndarray
    f_stat: float
    f_crit: float
    refinement: Refinement
    room: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))


def refine_selected(freq_hz, frf, poles, weights, band_w) -> Selected:
    """Refine ``poles``; keep the out-of-band poles only if they pass an F-test.

    Nested least-squares models: without (chi0) and with (chi1) the out-of-band terms,
    which add q = 2 n_ob P linear parameters (a complex residue per pole and point) to
    p = 2 m + P (2 m + 4) in N = 2 K P real residuals; kept when
    ``((chi0 - chi1)/q) / (chi1/(N - p - q))`` exceeds the :data:`OUT_OF_BAND_F_QUANTILE`
    quantile of F(q, N - p - q). ``band_w`` None: no out-of-band terms."""
    from scipy.stats import f as fisher_f

    none = np.zeros(0, complex)
    r0 = refine_poles(freq_hz, frf, poles, weights)
    if band_w is None:
        return Selected(r0.poles, none, float("nan"), float("nan"), r0)
    room = band_room(band_w, r0.poles)
    ob = out_of_band_poles(band_w, tuple(bool(x) for x in room >= OUT_OF_BAND_ROOM))
    if not ob.size:
        return Selected(r0.poles, none, float("nan"), float("nan"), r0, room)
    r1 = refine_poles(freq_hz, frf, r0.poles, weights, ob)
    K, P = np.shape(frf)
    p = 2 * poles.size + P * (2 * poles.size + 4)
    q = 2 * ob.size * P
    dof = 2 * K * P - p - q
    if dof <= 0 or not r1.chi2 > 0:
        return Selected(r0.poles, none, float("nan"), float("nan"), r0, room)
    F = ((r0.chi2 - r1.chi2) / q) / (r1.chi2 / dof)
    crit = float(fisher_f.ppf(OUT_OF_BAND_F_QUANTILE, q, dof))
    if F > crit:
        return Selected(r1.poles, ob, float(F), crit, r1, room)
    return Selected(r0.poles, none, float(F), crit, r0, room)
