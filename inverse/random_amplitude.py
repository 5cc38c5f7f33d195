"""The Iwan joint under random excitation: stiffnesses expected over Rayleigh amplitudes.

Which expectation, and why
--------------------------
A lightly damped mode driven by broadband Gaussian force responds narrow-band: the
slip is ``u(t) = A(t) sin(omega t + phi(t))`` with a slowly varying envelope ``A`` that
is Rayleigh distributed, ``p(A) = (A / sigma^2) exp(-A^2 / (2 sigma^2))``, ``sigma``
the RMS of ``u`` (``E[A^2] = 2 sigma^2``; Crandall & Mark 1963). The H1 FRF of such a
test is the FRF of the equivalent linear system of statistical linearization
(Caughey 1963; Roberts & Spanos 1990, Ch. 6), whose stiffness and damping minimize the
mean-square difference between the joint force and a linear force. With the joint
force's first harmonic at each envelope, ``F1 = A (k_in(A) sin + k_q(A) cos)``
(:func:`joints.describing.describing_function`), and the phase uniform, this gives

    k_in_eq = E[A^2 k_in(A)] / E[A^2],   k_q_eq = E[A^2 k_q(A)] / E[A^2]          (1)

the ``A^2``-weighted (energy) expectation: for the quadrature part (1) is the mean
power balance (the dissipation per cycle ``pi A^2 k_q(A)`` averaged over the envelope
equals that of the equivalent damper, ``pi E[A^2] k_q_eq``), so the damping an H1 fit
reads off is (1). The plain mean ``E[k(A)]`` would weigh the small amplitudes, which
carry little energy, as much as the large ones; it is not what H1 measures.

Micro-slip closed form (derived here). With ``k_q(A) = |kappa1| A^(chi+1)`` and
``K_T - k_in(A) = kappa2 A^(chi+1)`` (paper eq. 14) and the Rayleigh moments
``E[A^n] = (2 sigma^2)^(n/2) Gamma(1 + n/2)``:

    E[A^(chi+3)] / E[A^2] = (sqrt(2) sigma)^(chi+1) Gamma((chi+5)/2)
                          = c(chi) sigma^(chi+1),
    c(chi) = 2^((chi+1)/2) Gamma((chi+5)/2)                                        (2)

so the random test shows the stepped-sine law at the RMS amplitude times ``c(chi)``
(1.347 at chi = -0.5, -> 1 as chi -> -1, sqrt(2) Gamma(5/2)= 1.880 at chi = 0), or the
sine law at the equivalent amplitude ``A_eq = sqrt(2) Gamma((chi+5)/2)^(1/(chi+1))
sigma`` (1.815 sigma at chi = -0.5). For the estimator the factor is a constant on
amplitude: the damping growth is a power of ``r = sigma_v / sigma_ref``, a ratio in
which ``c`` cancels, so chi from a random series regressed on the response RMS is the
chi of a stepped-sine series of the same joint; ``|kappa1| B`` (and with it R) read on
the RMS abscissa is ``c(chi)`` times the sine value at amplitude ``sigma_ref``.
Outside micro slip (``A > phi_max`` has probability ``exp(-phi_max^2/(2 sigma^2))``)
(1) is evaluated by quadrature, :func:`rayleigh_describing_function`.
SI units: m, N/m.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import integrate, special

from joints.describing import describing_function, kappa1, kappa2_exact
from joints.iwan import IwanParameters

__all__ = ["rayleigh_nodes", "rayleigh_factor", "equivalent_sine_amplitude",
           "rayleigh_micro_slip", "rayleigh_describing_function", "sine_equivalent_kappa1_B"]


def rayleigh_nodes(n: int = 8, min_weight: float = 0.0):
    """Quadrature of the energy-weighted expectation (eq. 1) over a Rayleigh envelope:
    amplitudes ``A_j = x_j rms`` and weights ``w_j`` (sum 1) with
    ``E[A^2 g(A)] / E[A^2] ~ sum_j w_j g(x_j rms)``. With ``u = A^2 / (2 rms^2)`` the
    weight is ``u e^-u du`` (:func:`rayleigh_describing_function`): Gauss-Laguerre
    nodes ``u_j`` of ``alpha = 1``, ``x_j = sqrt(2 u_j)``. Micro slip (``g = u^s``,
    ``0 < s < 1/2``): relative error 8e-4 at n = 8, 2e-4 at n = 16 (the power is not a
    polynomial at 0). Nodes of weight below ``min_weight`` are dropped and the rest
    renormalized (an error below the dropped weight: the far tail, deep in macro slip,
    costs most to simulate and weighs least).

    Returns
    -------
    x : (n,) amplitude over RMS; w : (n,) weights.
    """
    u, w = special.roots_genlaguerre(int(n), 1.0)
    w = w / w.sum()
    keep = w >= min_weight
    return np.sqrt(2.0 * u[keep]), w[keep] / w[keep].sum()


def rayleigh_factor(chi):
    """``c(chi) = 2^((chi+1)/2) Gamma((chi+5)/2)`` (module eq. 2): the random test's
    micro-slip stiffness change over the sine law at the RMS amplitude."""
    chi = np.asarray(chi, float)
    c = 2.0 ** ((chi + 1.0) / 2.0) * special.gamma((chi + 5.0) / 2.0)
    return float(c) if c.ndim == 0 else c


def equivalent_sine_amplitude(rms, chi):
    """Sine amplitude with the random test's micro-slip stiffnesses (module eq. 2):
    ``A_eq = sqrt(2) Gamma((chi+5)/2)^(1/(chi+1)) rms`` (m for a slip RMS in m)."""
    chi = float(chi)
    if not -1.0 < chi <= 0.0:
        raise ValueError(f"chi must be in (-1, 0], got {chi!r}")
    return math.sqrt(2.0) * special.gamma((chi + 5.0) / 2.0) ** (1.0 / (chi + 1.0)) \
        * np.asarray(rms, float)


def rayleigh_micro_slip(p: IwanParameters, rms):
    """Expected (eq. 1) in-phase and quadrature stiffnesses in micro-slip, closed form
    (eq. 2): ``K_T - c kappa2 rms^(chi+1)``, ``c |kappa1| rms^(chi+1)``, N/m.

    Exact while ``P(A > phi_max) = exp(-phi_max^2 / (2 rms^2))`` is negligible."""
    s = np.asarray(rms, float) ** (p.chi + 1.0) * rayleigh_factor(p.chi)
    return p.K_T - kappa2_exact(p.R, p.chi) * s, -kappa1(p.R, p.chi) * s


def rayleigh_describing_function(p: IwanParameters, rms, rtol: float = 1e-10):
    """Expected stiffnesses (eq. 1) at slip RMS ``rms`` (m), any amplitude, by quadrature.

    With ``u = A^2 / (2 rms^2)`` the weight ``A^2 p(A) dA / E[A^2]`` is ``u e^-u du``;
    the integral is split at the micro/macro-slip kink ``A = phi_max``.

    Returns
    -------
    k_in_eq, k_quad_eq : float or ndarray (N/m), shaped like ``rms``.
    """
    rms = np.asarray(rms, float)
    if np.any(~(rms > 0)) or np.any(~np.isfinite(rms)):
        raise ValueError("slip RMS must be finite and > 0")

    def expected(s, j):
        def f(u):
            return u * math.exp(-u) * describing_function(p, s * math.sqrt(2.0 * u))[j]
        kink = p.phi_max ** 2 / (2.0 * s * s)
        parts = [(1e-300, min(kink, 60.0))] + ([(kink, 60.0)] if kink < 60.0 else [])
        return sum(integrate.quad(f, a, b, epsrel=rtol, epsabs=0.0, limit=200)[0]
                   for a, b in parts)                     # e^-60: beyond double precision

    out = np.array([[expected(s, j) for j in (0, 1)] for s in rms.ravel()])
    k_in, k_q = out[:, 0].reshape(rms.shape), out[:, 1].reshape(rms.shape)
    return (float(k_in), float(k_q)) if rms.ndim == 0 else (k_in, k_q)


def sine_equivalent_kappa1_B(kappa1_B_random: float, chi: float) -> float:
    """``|kappa1| B`` of a stepped sine at amplitude ``sigma_ref`` from the value a random
    series gives on its RMS abscissa: divided by ``c(chi)`` (module doc), rad^2/s^2."""
    return float(kappa1_B_random) / rayleigh_factor(chi)
