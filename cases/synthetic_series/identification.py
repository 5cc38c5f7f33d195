"""Identification of a simulated level: LSCF + refinement (:func:`ident.identify.identify`)
and the standard uncertainty of the identified ``omega2`` and ``zeta``.

Uncertainty (delta method on the pole): the pole ``lambda = -sigma + i w_d`` is the
nonlinear parameter of the modal model whose residues and residual terms are solved
linearly (:func:`ident.lsfd.lsfd`, variable projection). With ``J`` the Jacobian of the
weighted residual vector with respect to ``(sigma, w_d)`` (central differences) and
``s^2 = RSS / (2 K P - n_par)`` the residual variance (``n_par = 2 + 6 P``: the pole,
a complex residue and complex U, L per point), ``cov = s^2 (J^T J)^-1`` (Golub &
Pereyra 2003: the projected Jacobian gives the marginal covariance of the nonlinear
parameters). Then ``omega2 = sigma^2 + w_d^2`` and ``zeta = sigma / |lambda|``. The
residual variance includes any misfit of the linear modal model to a nonlinear FRF,
so a distorted FRF reads as a less certain level.

The row of the measured-data table (``shared/spec/measured-data.md``): force control
``excitation`` = the held level, ``response_amplitude`` = |fitted FRF| at the natural
frequency times the measured force there; response control ``response_amplitude`` =
the held amplitude, ``excitation`` = the force there.
"""
from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from ident.identify import identify
from ident.lsfd import lsfd

__all__ = ["pole_std", "identify_level"]


def pole_std(freq_hz, frf, pole):
    """Standard uncertainties (omega2 in rad^2/s^2, zeta) of a one-mode pole (module
    doc), weights ``1/|H_fit|``."""
    f = np.asarray(freq_hz, float)
    H = np.asarray(frf).reshape(f.size, -1)
    fitted = lsfd(f, H, [pole])[1]
    wgt = 1.0 / np.maximum(np.abs(fitted), 1e-300)

    def res(sig, wd):
        r = lsfd(f, H, [complex(-sig, wd)], wgt)[2]
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    sig, wd = -pole.real, pole.imag
    h = 1e-6 * abs(pole)
    r0 = res(sig, wd)
    J = np.stack([(res(sig + h, wd) - res(sig - h, wd)) / (2 * h),
                  (res(sig, wd + h) - res(sig, wd - h)) / (2 * h)], axis=1)
    K, P = H.shape
    dof = max(2 * K * P - (2 + 6 * P), 1)
    cov = float(r0 @ r0) / dof * np.linalg.inv(J.T @ J)
    wn2 = sig**2 + wd**2
    wn = np.sqrt(wn2)
    g_w2 = np.array([2 * sig, 2 * wd])
    g_z = np.array([wd**2, -sig * wd]) / wn**3
    return float(np.sqrt(g_w2 @ cov @ g_w2)), float(np.sqrt(g_z @ cov @ g_z))


def identify_level(freq_hz, frf, force, control: str, held: float) -> dict:
    """One row of the measured-data table from one level's FRF (module doc).

    ``frf`` receptance ``q/F`` (m/N) at the drive point, ``force`` the force amplitude
    per line (N). Returns omega2, zeta, their stds, excitation, response_amplitude,
    fit_error."""
    ident = identify(freq_hz, frf, n_modes=1)
    mode = ident.modes[0]
    s_w2, s_z = pole_std(freq_hz, frf, mode.pole)
    fitted = lsfd(freq_hz, np.asarray(frf).reshape(-1, 1), [mode.pole])[1][:, 0]
    fn = mode.frequency_hz
    h_n = float(np.abs(CubicSpline(freq_hz, fitted)(fn)))
    f_n = float(CubicSpline(freq_hz, force)(fn))
    if control == "response":
        excitation, response = f_n, float(held)
    else:
        excitation, response = float(held), h_n * f_n
    return {"omega2": mode.omega2, "zeta": mode.zeta, "omega2_std": s_w2, "zeta_std": s_z,
            "excitation": excitation, "response_amplitude": response,
            "fit_error": ident.fit_error}
