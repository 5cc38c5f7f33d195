"""Standard uncertainty of identified poles from the refinement's least squares.

The refinement (:mod:`ident.refine`) minimizes the weighted misfit
``r(theta) = W (H - H_fit(theta))`` over the poles ``theta = (sigma_r, omega_d,r)``
(``lambda_r = -sigma_r + i omega_d,r``; near-band poles included, fixed out-of-band
poles held), the residues and
residual terms being solved linearly for every trial (variable projection). Near the
optimum, with independent line noise of equal variance after weighting, the poles'
covariance is the Gauss-Newton one (Golub and Pereyra 2003; Pintelon and Schoukens
2012, eq. 7-41):

    Cov(theta) = s^2 (J^T J)^-1,   s^2 = |r|^2 / (N - n_theta - n_lin),

``J = d r / d theta`` of the *projected* residual (central differences),
``N = 2 K P`` real residuals (K lines, P points), ``n_lin = P (2 (m + n_fixed) + 4)``
real linear parameters (residues and U, L per point), so the linear parameters' uncertainty is
accounted for. The residual variance ``s^2`` makes the result independent of the
weights' scale. Then, by the delta method,

    omega^2 = sigma^2 + omega_d^2:  d omega^2 = 2 sigma d sigma + 2 omega_d d omega_d,
    zeta = sigma / omega_n:         d zeta = (omega_d^2 d sigma - sigma omega_d d omega_d)
                                             / omega_n^3.

Only noise is counted: a model that cannot follow the data (a force-controlled FRF
distorted by the joint, a missed mode) biases the poles by more than this; the band
check of :mod:`ident.fit_quality` looks for that. Checked against a Monte Carlo over
noise realizations in ``tests/test_series_identify.py``.
"""
from __future__ import annotations

import numpy as np

from ident.lsfd import lsfd

__all__ = ["gauss_newton_covariance", "pole_covariance", "modal_std"]


def gauss_newton_covariance(residual, x, steps, n_linear: int) -> np.ndarray:
    """``s^2 (J^T J)^-1`` of a projected residual at ``x`` (module doc): ``J`` by central
    differences with ``steps`` (per parameter), ``s^2 = |r|^2 / (N - n_x - n_linear)``.
    NaN without residual degrees of freedom; columns that move nothing (or are not
    finite) are held fixed, and a pseudo-inverse leaves out what the linear parameters
    can mimic."""
    x = np.asarray(x, float)
    r0 = residual(x)
    J = np.empty((r0.size, x.size))
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = steps[k]
        J[:, k] = (residual(x + e) - residual(x - e)) / (2 * steps[k])
    dof = r0.size - x.size - n_linear
    cov = np.full((x.size, x.size), np.nan)
    if dof <= 0:
        return cov
    s2 = float(r0 @ r0) / dof
    c = np.linalg.norm(J, axis=0)
    use = np.isfinite(c) & (c > 0) & np.all(np.isfinite(J), axis=0)
    Js = J[:, use] / c[use]
    cov[np.ix_(use, use)] = (s2 * np.linalg.pinv(Js.T @ Js, rcond=1e-12, hermitian=True)
                             / np.outer(c[use], c[use]))
    return cov


def pole_covariance(freq_hz, frf, poles, weights=None, fixed=()) -> np.ndarray:
    """Covariance (2m, 2m) of ``(sigma_1..m, omega_d,1..m)`` of the fitted ``poles``
    (rad/s), the ``fixed`` poles (out-of-band terms, :mod:`ident.refine`) held.

    Parameters
    ----------
    freq_hz : (K,) Hz.  frf : (K, P) complex FRFs the poles were fitted to.
    poles : (m,) complex, the fitted poles (modes and near-band poles).
    weights : (K, P) weights of the fit, or None (uniform).
    fixed : poles held in the fit; their residues count as linear parameters.

    Returns NaN entries where the Jacobian is not finite or there are no residual degrees
    of freedom; a singular direction is left out by a pseudo-inverse."""
    poles = np.asarray(poles, complex)
    fixed = np.asarray(fixed, complex)
    frf = np.asarray(frf)
    if frf.ndim == 1:
        frf = frf[:, None]
    m = poles.size
    P = frf.shape[1]

    def resid(x):
        allp = np.concatenate([-x[:m] + 1j * x[m:], fixed])
        r = lsfd(freq_hz, frf, allp, weights)[2]
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    h = 1e-6 * np.maximum(np.abs(poles), 1e-300)
    return gauss_newton_covariance(resid, np.concatenate([-poles.real, poles.imag]),
                                   np.concatenate([h, h]), P * (2 * (m + fixed.size) + 4))


def modal_std(poles, cov) -> tuple[np.ndarray, np.ndarray]:
    """Standard uncertainties of ``omega^2`` (rad^2/s^2) and ``zeta`` of the first
    ``len(poles)`` poles from the covariance of :func:`pole_covariance` (delta method,
    module doc)."""
    poles = np.asarray(poles, complex)
    m = poles.size
    n = cov.shape[0] // 2
    sigma, wd = -poles.real, poles.imag
    wn = np.abs(poles)
    s_w2, s_z = np.empty(m), np.empty(m)
    for i in range(m):
        idx = [i, n + i]
        C = cov[np.ix_(idx, idx)]
        g_w2 = np.array([2 * sigma[i], 2 * wd[i]])
        g_z = np.array([wd[i] ** 2, -sigma[i] * wd[i]]) / wn[i] ** 3
        s_w2[i] = np.sqrt(max(g_w2 @ C @ g_w2, 0.0)) if np.all(np.isfinite(C)) else np.nan
        s_z[i] = np.sqrt(max(g_z @ C @ g_z, 0.0)) if np.all(np.isfinite(C)) else np.nan
    return s_w2, s_z
