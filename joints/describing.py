"""First-harmonic (describing-function) stiffnesses of the four-parameter Iwan joint.

Exact in-phase and quadrature stiffnesses for a sinusoidal slip at any amplitude
(micro- and macro-slip), and the paper's micro-slip coefficients kappa1, kappa2 (exact
and as printed, paper eqs. 14, A12, A15). The joint model itself (parameters, density,
backbone, dissipation per cycle) is :mod:`joints.iwan`.

Sign convention (paper eqs. 5, 14): for slip ``u = A sin(wt)`` the force is
``F = K_T u - dF_s`` with first harmonic
``F1 = A (k_in_phase sin wt + k_quadrature cos wt)``; in micro-slip
``k_in_phase = K_T - kappa2 A**(chi+1)`` and ``k_quadrature = -kappa1 A**(chi+1)``.
SI units: m, N, N/m.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

from joints.iwan import IwanParameters, dissipation_per_cycle

__all__ = ["describing_function", "kappa1", "kappa2_exact", "kappa2_paper"]


def _slider_in_phase(r):
    """In-phase describing function of one unit Jenkins element, ``r = phi/A``.

    ``g = (psi - sin(psi) cos(psi))/pi`` with ``cos(psi) = 1 - 2r`` for ``r < 1`` and
    ``g = 1`` otherwise (elastic-perfectly-plastic element). Since
    ``dg/dr = (8/pi) sqrt(r (1-r))``, ``g`` is the regularized incomplete Beta function
    ``I_r(3/2, 3/2)``, evaluated that way to keep full precision as ``r -> 0``.
    """
    r = np.clip(np.asarray(r, dtype=float), 0.0, 1.0)
    return special.betainc(1.5, 1.5, r)


def describing_function(p: IwanParameters, amplitude):
    """Exact first-harmonic stiffnesses for slip ``u = A sin(wt)``, any ``A > 0``.

    ``k_in_phase = (1/(pi A)) int F sin`` and ``k_quadrature = (1/(pi A)) int F cos``
    over one steady cycle, so the dissipation per cycle is ``pi A^2 k_quadrature``.

    Summing the describing function ``g(phi/A)`` of each slider over the density and
    integrating by parts (``dg/dr = (8/pi) sqrt(r (1-r))``, so ``g = I_r(3/2, 3/2)``)
    gives, with ``rho = min(1, phi_max/A)`` and ``B(x; a, b)`` the incomplete Beta
    function (derived here; not in the paper),

        k_in_phase = K_T I_rho(3/2, 3/2)
                     - 8 R A**(chi+1) B(rho; chi+5/2, 3/2) / (pi (chi+1)),

    which in micro-slip (``rho = 1``) is ``K_T - kappa2_exact A**(chi+1)`` (paper
    eq. 14, A15 with the exact kappa2), and
    ``k_quadrature = dissipation_per_cycle / (pi A^2)`` (``= -kappa1 A**(chi+1)`` in
    micro-slip). Limits: ``k_in_phase -> K_T`` as ``A -> 0``;
    ``k_quadrature -> 4 F_S / (pi A)`` and
    ``k_in_phase -> (8/pi) (phi_max/A)**1.5 (2 K_T/3 - (K_T - S)/(chi + 5/2))``
    as ``A -> inf``. Agrees with quadrature of the Fourier integrals of the Masing loop
    to 1e-10 relative (tests).

    Parameters
    ----------
    p : IwanParameters
    amplitude : float or array_like
        Slip amplitude ``A`` (m), > 0.

    Returns
    -------
    k_in_phase, k_quadrature : float or ndarray (N/m)
    """
    A = np.asarray(amplitude, dtype=float)
    if np.any(~(A > 0.0)) or np.any(~np.isfinite(A)):
        raise ValueError("slip amplitude must be finite and > 0")
    chi, R = p.chi, p.R
    rho = np.minimum(1.0, p.phi_max / A)
    a, b = chi + 2.5, 1.5
    inc_beta = special.betainc(a, b, rho) * special.beta(a, b)
    k_in = (p.K_T * _slider_in_phase(rho)
            - 8.0 * R * A ** (chi + 1.0) * inc_beta / (np.pi * (chi + 1.0)))
    D = dissipation_per_cycle(p, A)
    with np.errstate(over="ignore"):  # A*A overflows above 1.3e154 m: divide twice there
        k_quad = np.where(A < 1e150, D / (np.pi * A * A), D / (np.pi * A) / A)
    if k_in.ndim == 0:
        return float(k_in), float(k_quad)
    return k_in, k_quad


def kappa1(R: float, chi: float) -> float:
    """Paper eq. (A15): ``kappa1 = -4 R / (pi (chi+2)(chi+3))`` (exact, N m^-(chi+2))."""
    return -4.0 * R / (np.pi * (chi + 2.0) * (chi + 3.0))


def kappa2_exact(R: float, chi: float) -> float:
    """Exact micro-slip coefficient of the in-phase force, paper eq. (14).

    ``kappa2 = 4 R B(chi+5/2, 1/2) / (pi (chi+1)(chi+3))`` with ``B`` the Euler Beta
    function: from paper eq. (11), ``b1 = (2 gamma1/pi) I(n)``, ``n = chi+2``,
    ``I(n) = int_{-pi/2}^{pi/2} (1+sin t)^n sin t dt = 2^n B(n+1/2, 1/2) n/(n+1)``.
    ``kappa2 -> R/2`` as ``chi -> 0``.
    """
    return 4.0 * R * special.beta(chi + 2.5, 0.5) / (np.pi * (chi + 1.0) * (chi + 3.0))


def _Q_b(chi: float) -> float:
    """Paper eq. (A12), constants 1.7071 and 0.2929 as printed."""
    n = chi + 2.0
    hi, lo = 1.7071, 0.2929
    s2 = math.sqrt(2.0)
    c3 = n * np.pi ** 3 / 384.0
    return ((hi ** n - lo ** n) * (1.0 / (2.0 * s2) - np.pi ** 2 / (192.0 * s2)) * np.pi
            + c3 * (hi ** (n - 1.0) - lo ** (n - 1.0))
            + c3 * (chi + 1.0) * (hi ** chi - lo ** chi))


def kappa2_paper(R: float, chi: float) -> float:
    """The paper's kappa2, eq. (A15) with ``Q_b`` exactly as printed in (A12).

    ``kappa2 = R 2**(-chi) Q_b(chi) / (pi (chi+1)(chi+2))``. Kept to reproduce the
    paper; use :func:`kappa2_exact` otherwise. It is 7.55 % below the exact value at
    chi = -0.5 (3.0 % at chi -> 0, 9.9 % at chi = -0.9). Of that, about 0.9 % is the
    three-term Taylor series itself; the rest are two slips in the printed ``Q_b``:
    its second term should read ``(1.7071**(chi+1) + 0.2929**(chi+1))`` and its third
    term lacks a factor ``1/sqrt(2)`` (checked against a numerical re-derivation in
    ``tests/test_iwan.py``).
    """
    return R * 2.0 ** (-chi) * _Q_b(chi) / (np.pi * (chi + 1.0) * (chi + 2.0))
