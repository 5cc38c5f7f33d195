"""Model families of the diagnosis: the base Iwan modal model and one extension per cause.

Base model (paper Sec. 2.2 and 4, with its algebra corrected): one equivalent
micro-slip four-parameter Iwan joint acting on the mode, joint amplitude proportional
to the excitation, ``s_v = a_v / a_max`` with ``a_v = excitation_v / excitation_1``:

    omega2_v = W - K2 s_v**(chi+1)                                   (paper eq. 43)
    zeta_v   = (c/2) / sqrt(omega2_v) + K1 s_v**(chi+1) / (2 omega2_v)   (eq. 45)

``K1`` is the hysteretic (quadrature) modal stiffness at the top level, ``c`` the
constant viscous modal damping (``zeta_0 = c / (2 sqrt(W))``; the factor
``omega_n/omega_J`` of eq. 45 is kept, the factor 2 the paper drops is restored).
Frequency drop and damping growth are tied by the exact first-harmonic coefficients
(paper eq. 14, A15; :func:`tie_ratio`):

    K2 / K1 = kappa2_exact / |kappa1| = B(chi+5/2, 1/2) (chi+2) / (chi+1),

a function of chi alone. The base model has four parameters ``W, c, chi, K1`` fitted
jointly to ``omega2`` and ``zeta`` (and, when the file has ``response_amplitude``,
the response predicted proportional to the excitation, one more offset parameter).

Each cause of the spec (``shared/spec/diagnosis.md``) is an extension of the base:

=============================  ==========================================================
cause                          extension (extra parameters)
=============================  ==========================================================
``macro-slip``                 exact describing function past ``phi_max`` (continuous
                               density + Dirac at ``phi_max``): joint amplitude
                               ``x_v = x_top s_v`` in units of ``phi_max`` and the Dirac
                               weight ``beta`` (2: ``x_top``, ``beta``)
``nonproportional-amplitude``  joint amplitude ``log s_v + gamma (s_v**kappa - 1)``
                               instead of ``log s_v`` (2: ``gamma``, ``kappa``); needs
                               ``response_amplitude``, which every model predicts as
                               ``alpha + log(joint amplitude)``
``geometric-hardening``        ``omega2 += h s_v**2`` (1: ``h >= 0``)
``thermal-drift``              ``omega2 += d (run_v - run_min) / (run_max - run_min)``
                               (1: ``d``)
``quadratic-damping``          ``zeta += q s_v`` (1: ``q >= 0``)
=============================  ==========================================================

The fits (:mod:`inverse.diagnosis_fit`) evaluate these models on :class:`Observations`
through the design columns of :func:`design_matrices`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special


# --------------------------------------------------------------------------- physics


def tie_ratio(chi):
    """``K2/K1 = kappa2_exact/|kappa1| = B(chi+5/2, 1/2) (chi+2)/(chi+1)``.

    From paper eq. (A15) ``|kappa1| = 4R/(pi (chi+2)(chi+3))`` and the exact
    ``kappa2 = 4R B(chi+5/2, 1/2)/(pi (chi+1)(chi+3))`` (the paper's Taylor series A12
    replaced by the Beta function). Dimensionless; 4 at chi = -1/2.
    """
    chi = np.asarray(chi, dtype=float)
    return special.beta(chi + 2.5, 0.5) * (chi + 2.0) / (chi + 1.0)


def _slider_in_phase(t):
    """In-phase describing function of a unit Jenkins element, ``t = phi/A`` in [0, 1].

    ``(psi - sin psi cos psi)/pi`` with ``cos psi = 1 - 2 t`` (elastic-perfectly-
    plastic element; 1 when stuck, t >= 1)."""
    c = np.clip(1.0 - 2.0 * t, -1.0, 1.0)
    psi = np.arccos(c)
    return (psi - np.sin(psi) * c) / np.pi


def slip_shapes(x, chi):
    """Loss of in-phase stiffness and quadrature stiffness of an Iwan joint, normalized.

    For slip amplitude ``A = x phi_max`` and ``U = R phi_max**(chi+1)``, the joint's
    first-harmonic stiffnesses are ``k_in = K_T - U P2 - S Q2`` and
    ``k_q = U P1 + S Q1`` (``S`` the Dirac weight), with ``rho = min(1, 1/x)``,
    ``m = min(x, 1)``, ``g`` the slider in-phase function:

        P2 = [1 - g(rho) + (8/pi) x**(chi+1) B(rho; chi+5/2, 3/2)] / (chi+1)
        P1 = (4/pi) [x m**(chi+2)/(chi+2) - m**(chi+3)/(chi+3)] / x**2
        Q2 = 1 - g(rho),  Q1 = 4 (x-1)/(pi x**2) for x > 1, else 0.

    (Sum of each slider's describing function over the density, integrating by parts
    with ``dg/dt = (8/pi) sqrt(t(1-t))``; dissipation per cycle ``pi A^2 k_q``.) For
    ``x <= 1``: ``P1 = |kappa1|/R x**(chi+1)``, ``P2 = kappa2_exact/R x**(chi+1)``.

    Broadcasts ``x`` against ``chi``; returns ``(P1, P2, Q1, Q2)``.
    """
    x, chi = np.broadcast_arrays(np.asarray(x, float), np.asarray(chi, float))
    p = chi + 1.0
    rho = np.minimum(1.0, 1.0 / x)
    g = np.where(x > 1.0, _slider_in_phase(rho), 1.0)
    a, b = chi + 2.5, 1.5
    inc = special.betainc(a, b, rho) * special.beta(a, b)
    P2 = (1.0 - g + 8.0 / np.pi * x**p * inc) / p
    m = np.minimum(x, 1.0)
    P1 = 4.0 / np.pi * (x * m ** (chi + 2.0) / (chi + 2.0) - m ** (chi + 3.0) / (chi + 3.0)) / x**2
    Q2 = 1.0 - g
    Q1 = np.where(x > 1.0, 4.0 * (x - 1.0) / (np.pi * x**2), 0.0)
    return P1, P2, Q1, Q2


# --------------------------------------------------------------------------- data


@dataclass
class Observations:
    """One mode's data as the fits use them (sorted by level).

    ``s_exc = excitation / max(excitation)``, ``s_resp = response / max(response)`` or
    None, ``t_run = (run - min)/(max - min)`` in [0, 1]."""

    level: np.ndarray
    excitation: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    run_order: np.ndarray
    response: np.ndarray | None
    mode: int = 1

    @property
    def n(self) -> int:
        return int(self.level.size)

    @property
    def s_exc(self) -> np.ndarray:
        return self.excitation / self.excitation.max()

    @property
    def s_resp(self) -> np.ndarray | None:
        return None if self.response is None else self.response / self.response.max()

    @property
    def t_run(self) -> np.ndarray:
        r = self.run_order.astype(float)
        span = r.max() - r.min()
        return (r - r.min()) / span if span > 0 else np.zeros_like(r)

    @property
    def a_max(self) -> float:
        """Excitation ratio of the top level to level 1 (``a_max``)."""
        return float(self.excitation.max() / self.excitation.min())


# --------------------------------------------------------------------------- design


def log_amplitude(model, s, theta):
    """log of the relative joint amplitude s_eff (G, n) for parameters theta (G, m)."""
    logs = np.log(s)[None, :]
    if model == "nonproportional-amplitude":
        kappa, gamma = np.exp(theta[:, 1:2]), theta[:, 2:3]
        return logs + gamma * (s[None, :] ** kappa - 1.0)
    return np.broadcast_to(logs, (theta.shape[0], s.size))


def design_matrices(model, s, t_run, omega2_meas, theta):
    """Columns of the linear parameters for every parameter point ``theta`` (G, m).

    Returns (A_omega, A_zeta, nonneg, log_s_eff): design stacks (G, n, k), the
    indices of the columns constrained >= 0, and the log relative amplitude (G, n)."""
    G, n = theta.shape[0], s.size
    p = theta[:, :1]
    chi = p - 1.0
    inv_w = 0.5 / np.sqrt(omega2_meas)[None, :] * np.ones((G, 1))
    half_inv_w2 = 0.5 / omega2_meas[None, :]
    one, zero = np.ones((G, n)), np.zeros((G, n))
    log_s = log_amplitude(model, s, theta)
    if model == "macro-slip":
        x = np.exp(theta[:, 1:2] + log_s)
        P1, P2, Q1, Q2 = slip_shapes(x, chi)
        A_om = np.stack([one, zero, -P2, -Q2], axis=-1)
        A_ze = np.stack([zero, inv_w, P1 * half_inv_w2, Q1 * half_inv_w2], -1)
        return A_om, A_ze, [2, 3], log_s
    sp = np.exp(p * log_s)
    cols_om = [one, zero, -tie_ratio(chi) * sp]
    cols_ze = [zero, inv_w, sp * half_inv_w2]
    nonneg = [2]
    if model == "geometric-hardening":
        cols_om.append(np.exp(2.0 * log_s))
        cols_ze.append(zero)
        nonneg.append(3)
    elif model == "thermal-drift":
        cols_om.append(np.broadcast_to(t_run, (G, n)))
        cols_ze.append(zero)
    elif model == "quadratic-damping":
        cols_om.append(zero)
        cols_ze.append(np.exp(log_s))
        nonneg.append(3)
    return np.stack(cols_om, -1), np.stack(cols_ze, -1), nonneg, log_s
