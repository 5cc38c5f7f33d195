"""Iwan modal relations of the estimator: kappa ratio, damping ratio with a joint, B~, R~.

Theory (paper Sec. 2.2 and 4, re-derived; equation numbers are the paper's)
-----------------------------------------------------------------------------
A micro-slip Iwan joint under slip amplitude ``A`` loses in-phase stiffness
``kappa2 A^(chi+1)`` and gains quadrature stiffness ``|kappa1| A^(chi+1)`` (eq. 14, 18;
:mod:`joints.iwan`). For a mass-normalized mode ``phi`` and joint elements ``m`` with
slip rows ``g_m`` (``slip = g_m . x``) the modal changes are (eq. 30-32)

    Delta omega^2 = kappa2 B,   Delta c = |kappa1| B,
    B = sum_m w_m (g_m . phi)^2 A_m^(chi+1)                                   (1)

where ``w_m`` is joint element ``m``'s share of the one Iwan joint (``R_m = w_m R``;
kappa1 and kappa2 are linear in R, so the shares weight B; ``w_m = 1`` for identical
independent joints each of parameter R).

Damping ratio. The modal FRF denominator is ``(omega_J^2 - Delta omega^2 - w^2) +
i (2 zeta_n omega_n w + Delta c)`` (eq. 31); at resonance ``w = Omega`` with
``Omega^2 = omega_J^2 - Delta omega^2``, matching it to ``Omega^2 - w^2 + 2 i zeta_J
Omega w`` (eq. 44) gives

    zeta_J = zeta_n omega_n / Omega + Delta c / (2 Omega^2)                   (2)

The paper's eq. 45 prints ``Delta c / omega_J^2``: a factor 2 is missing. Only the
corrected form reproduces the published ``|kappa1| B = 29.431`` from the published
Table 5 (the printed form gives half of it, 14.8); see :data:`EQ45_FACTOR`.

R (eq. 36, 37): ``R~ = |kappa1| B / (|kappa1|/R) / B~`` with ``|kappa1|/R =
4/(pi (chi+2)(chi+3))`` and ``B~`` from eq. 1 with the FE mode and the joint slip
amplitudes at the reference level (:mod:`inverse.fe_reference`).

Predictions (eq. 43, 46) use ``Delta omega^2 = (kappa2/|kappa1|) Delta c``
(:func:`kappa_ratio`), a function of chi alone.
"""
from __future__ import annotations

import numpy as np

from joints.describing import kappa1, kappa2_exact, kappa2_paper

#: Factor of Delta c in eq. 45 as derived (2); the paper prints 1.
EQ45_FACTOR = 2.0


def kappa_ratio(chi, method: str = "paper"):
    """``kappa2 / |kappa1|`` at ``chi`` (paper eq. A15; printed or exact kappa2).

    ``Delta omega^2 = kappa_ratio * Delta c`` (eq. 30, 43). ``paper``: the printed
    three-term Taylor kappa2 (eq. A12, A15); otherwise the exact one,
    ``B(chi+5/2, 1/2) (chi+2)/(chi+1)`` (4 at chi = -1/2). A float for a scalar
    ``chi``, an array for an array (element-wise).
    """
    k2 = kappa2_paper if method == "paper" else kappa2_exact
    ratio = k2(1.0, chi) / np.abs(kappa1(1.0, chi))
    return float(ratio) if np.ndim(ratio) == 0 else np.asarray(ratio, dtype=float)


def kappa1_per_R(chi) -> float:
    """``|kappa1| / R = 4 / (pi (chi+2)(chi+3))`` (paper eq. A15), m^-(chi+2) * m^(chi+2)."""
    return float(abs(kappa1(1.0, chi)))


def zeta_with_joint(delta_c, omega2, c_modal, factor: float = EQ45_FACTOR):
    """Measured damping ratio with a joint, eq. 2 of the module docstring (eq. 45 fixed).

    ``zeta_J = c_modal / (2 Omega) + Delta c / (factor/2 * 2 Omega^2)``; ``factor=2``
    is the derived relation, ``factor=1`` the paper's printed eq. 45.

    Parameters
    ----------
    delta_c : array_like
        Joint quadrature stiffness of the mode, ``|kappa1| B``, rad^2/s^2.
    omega2 : array_like
        ``Omega^2`` at that amplitude, rad^2/s^2.
    c_modal : float
        Viscous modal damping ``2 zeta_n omega_n``, rad/s.
    """
    omega2 = np.asarray(omega2, dtype=float)
    return c_modal / (2.0 * np.sqrt(omega2)) + np.asarray(delta_c) / (factor * omega2)


def delta_c_from_zeta(zeta, omega2, c_modal, factor: float = EQ45_FACTOR):
    """Inverse of :func:`zeta_with_joint`: ``Delta c = factor Omega^2 zeta - factor/2 c Omega``."""
    omega2 = np.asarray(omega2, dtype=float)
    return factor * (omega2 * np.asarray(zeta) - 0.5 * c_modal * np.sqrt(omega2))


def b_tilde(slip_rows, phi, slip_amplitude, chi, shares=None) -> float:
    """``B~ = sum_m w_m (g_m . phi)^2 A_m^(chi+1)`` (paper eq. 32, 37; eq. 1 above).

    Parameters
    ----------
    slip_rows : sparse or ndarray, (n_joints, n_dofs)
        Slip of each joint element from the DOFs (dimensionless / m per m).
    phi : ndarray, (n_dofs,)
        Mass-normalized mode shape, kg^-1/2.
    slip_amplitude : ndarray, (n_joints,)
        Slip amplitude of each joint at the reference level, m.
    chi : float
    shares : ndarray, (n_joints,), optional
        Share ``w_m`` of the Iwan joint carried by each element (``R_m = w_m R``);
        default 1.

    Returns
    -------
    float
        B~ in m^(chi+1)/kg.
    """
    g_phi = np.asarray(slip_rows @ np.asarray(phi, dtype=float)).ravel()
    a = np.asarray(slip_amplitude, dtype=float).ravel()
    w = np.ones_like(a) if shares is None else np.asarray(shares, dtype=float).ravel()
    return float(np.sum(w * g_phi ** 2 * a ** (chi + 1.0)))


def r_tilde(kappa1_B, chi, b) -> float:
    """``R~ = |kappa1| B / ((|kappa1|/R) B~)`` (paper eq. 36, 37), N m^-(chi+2)."""
    return float(kappa1_B / (kappa1_per_R(chi) * b))
