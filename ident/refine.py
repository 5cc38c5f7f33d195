"""Refinement of selected poles: variable-projection nonlinear least squares of the
modal model, pseudo-modes outside the band, noise-model weights.

The selected poles are refined by variable-projection nonlinear least squares of the
modal model (receptance form)
``H_o(w) = sum_r A_ro/(i w - lambda_r) + conj(A_ro)/(i w - conj(lambda_r))
+ U_o - L_o / w^2`` with relative weights ``1 / |H_o(w)|`` (maximum likelihood for
noise proportional to |H|) or those of a noise model fitted to the residuals
(:func:`noise_weights`); residues ``A_ro`` and the residual terms U, L (complex)
are solved linearly for each trial set of poles (LSFD with residual correction,
:func:`ident.lsfd.lsfd`). Two *pseudo-modes*, constrained below and above the band,
join the model when an F-test on the nested fits says they explain the misfit (a mode
just outside the band, whose tail U - L/w^2 cannot follow).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from ident.lsfd import lsfd
from ident.poles import modal_to_pole

def _pseudo_unpack(a, b, w_edge, below):
    """Pseudo-mode pole outside the band: ``w_n = w_edge exp(-+exp(a))`` (strictly
    below / above the edge), ``zeta = 0.5 / (1 + exp(-b))`` in (0, 0.5)."""
    a, b = np.clip(a, -12.0, 2.5), np.clip(b, -30.0, 30.0)
    wn = w_edge * np.exp(-np.exp(a) if below else np.exp(a))
    return modal_to_pole(wn, 0.5 / (1.0 + np.exp(-b)))


def refine_poles(freq_hz, frf, poles, weights=None, pseudo_band=None, max_nfev=None):
    """Variable-projection nonlinear least squares of the poles (module doc).

    Parameters ``theta = [ln(sigma/sigma0), (w_d - w_d0)/sigma0]`` per pole keep the
    damping positive. With ``pseudo_band = (w_lo, w_hi)`` (rad/s) two pseudo-modes, one
    constrained below w_lo and one above w_hi, join the fit: they stand for modes just
    outside the band whose tails U - L/w^2 cannot follow.

    Returns
    -------
    poles : refined poles (same order), pseudo : (0 or 2,) pseudo-mode poles.
    """
    poles = np.asarray(poles, complex)
    m = poles.size
    sigma0, wd0 = -poles.real, poles.imag
    n_ps = 0 if pseudo_band is None else 2
    b0 = np.log(0.1 / 0.4)                                     # zeta 0.1 at the start

    def unpack(theta):
        p = -sigma0 * np.exp(theta[:m]) + 1j * (wd0 + sigma0 * theta[m:2 * m])
        if n_ps:
            q = theta[2 * m:]
            ps = np.array([_pseudo_unpack(q[0], q[1], pseudo_band[0], True),
                           _pseudo_unpack(q[2], q[3], pseudo_band[1], False)])
            return p, ps
        return p, np.zeros(0, complex)

    big = None

    def residual(theta):
        nonlocal big
        p, ps = unpack(theta)
        allp = np.concatenate([p, ps])
        if np.all(np.isfinite(allp)) and np.all(allp.real < 0):
            try:
                r = lsfd(freq_hz, frf, allp, weights)[2]
                out = np.concatenate([r.real.ravel(), r.imag.ravel()])
                if np.all(np.isfinite(out)):
                    if big is None:
                        big = 1e3 * np.abs(out).max() + 1.0
                    return out
            except np.linalg.LinAlgError:
                pass
        return np.full(2 * np.size(frf), big if big is not None else 1e6)

    theta0 = np.concatenate([np.zeros(2 * m), [-2.0, b0, -2.0, b0][:2 * n_ps]])
    if theta0.size == 0:
        return poles, np.zeros(0, complex)
    sol = least_squares(residual, theta0, method="lm", x_scale=1.0,
                        max_nfev=max_nfev or 100 * (theta0.size + 1))
    return unpack(sol.x)


PSEUDO_F_QUANTILE = 0.999
PSEUDO_MAX_NFEV = 40   # iterations of the optional pseudo-mode fit (flat when not needed)


def noise_weights(freq_hz, frf, poles):
    """Weights 1/sigma_k of a noise model fitted to the residuals of the modal model.

    ``sigma_k^2 = a^2 |H_fit,k|^2 + b^2`` (noise proportional to the FRF plus a floor),
    a^2, b^2 >= 0 by non-negative least squares of the squared residuals |H - H_fit|^2
    on (|H_fit|^2, 1), all points pooled (each point scaled to unit rms). For noise
    proportional to |H| this is the maximum-likelihood weighting with the fitted rather
    than the noisy |H|; an additive floor stops noisy low-level lines (anti-resonances,
    far from the modes) from dominating the fit."""
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
        return 1.0 / np.maximum(np.abs(frf), 1e-300)
    return 1.0 / np.sqrt(sigma2)


def refine_selected(freq_hz, frf, poles, weights, pseudo_band):
    """Refine ``poles``; keep the two pseudo-modes only if they pass an F-test.

    Nested least-squares models: without (chi0) and with (chi1) the pseudo-modes, which
    add q = 4 + 4 P parameters to p = 2 m + P (2 m + 4) in N = 2 K P real residuals;
    kept when ``((chi0 - chi1)/q) / (chi1/(N - p - q))`` exceeds the 0.999 quantile of
    F(q, N - p - q). A narrow band gives them room to bend the mode's own skirts, so
    they must earn their place."""
    from scipy.stats import f as fisher_f

    p0, _ = refine_poles(freq_hz, frf, poles, weights)
    if pseudo_band is None:
        return p0, np.zeros(0, complex)
    p1, ps = refine_poles(freq_hz, frf, p0, weights, pseudo_band, max_nfev=PSEUDO_MAX_NFEV)
    chi0 = np.sum(np.abs(lsfd(freq_hz, frf, p0, weights)[2]) ** 2)
    chi1 = np.sum(np.abs(lsfd(freq_hz, frf, np.concatenate([p1, ps]), weights)[2]) ** 2)
    K, P = np.shape(frf)
    n = 2 * K * P
    p = 2 * poles.size + P * (2 * poles.size + 4)
    q = 4 + 4 * P
    dof = n - p - q
    if dof <= 0 or chi1 <= 0:
        return p0, np.zeros(0, complex)
    F = ((chi0 - chi1) / q) / (chi1 / dof)
    if F > fisher_f.ppf(PSEUDO_F_QUANTILE, q, dof):
        return p1, ps
    return p0, np.zeros(0, complex)
