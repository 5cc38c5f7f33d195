"""Model families of the diagnosis: the base Iwan modal model, one extension per cause,
and every combination of two.

Abscissa (the joint amplitude, relative). Under response control the held response
amplitude ``R_v`` is the measure of the joint amplitude (linear mode shape), so
``s_v = R_v / max R``. Under force control the paper takes ``s_v`` proportional to the
excitation, which holds only while the damping ratio stays put: at resonance a mode
of damping ratio ``zeta`` under force ``E`` reaches ``X = E / (2 zeta omega^2)`` (unit
modal mass), so the base model takes

    s_v = (E_v / (zeta_v omega2_v)) / max(...)                                    (1)

from the identified ``zeta_v`` and ``omega2_v``: proportional to the excitation at fixed
damping (the paper's assumption), and the resonant amplitude of a mode whose damping
grows. A shortfall beyond (1) (exciter force drop-out, a held level that is not the
force reaching the structure) is the ``nonproportional-amplitude`` cause. With the
``response_amplitude`` column the response channel ``y_v = log R_v - log s_v`` is fitted
too: a constant (the offset ``alpha``) in every model but that cause.

Base model (paper Sec. 2.2 and 4, eq. 43 and 45 with its factor 2), micro-slip, one
equivalent joint, ``p = chi + 1``:

    omega2_v = W - K2 s_v**p,                  K2 = kappa_ratio(chi) K1           (2)
    zeta_v   = c / (2 sqrt(omega2_v)) + K1 s_v**p / (2 omega2_v)                  (3)

with ``kappa_ratio = kappa2_exact / |kappa1| = B(chi+5/2, 1/2) (chi+2)/(chi+1)``
(:func:`inverse.iwan_modal.kappa_ratio`), a function of chi alone: the tie between the
frequency drop and the damping growth. ``K1 >= 0`` is the hysteretic modal stiffness at
the top level (rad^2/s^2), ``c`` the viscous modal damping (rad/s); the measured
``omega2_v`` stands in the factors of (3), as in the paper.

Extensions (``s`` below is the effective amplitude: ``s_v`` of (1), times the
nonproportional correction when that cause is in the model):

=============================  ==========================================================
cause                          extension (nonlinear; linear parameters)
=============================  ==========================================================
``macro-slip``                 exact describing function past ``phi_max``
                               (:func:`slip_shapes`): joint amplitude ``x_top s`` in units
                               of ``phi_max``; ``U P(x)`` replaces ``K1 s**p`` and a Dirac
                               weight ``S Q(x)`` joins (``log x_top``; ``U, S >= 0``)
``nonproportional-amplitude``  ``log s -> log s + gamma (s**kappa - 1)/kappa`` (Box-Cox):
                               ``kappa -> 0`` a steady per-step shortfall
                               ``(1 + gamma) log s`` (``gamma = -e``), ``kappa > 0`` a
                               shortfall growing toward the top (saturation); the response
                               channel follows (``gamma, kappa``); needs the response
``geometric-hardening``        ``omega2 += h s**n C(s_c / s)``: a power ``n`` (smooth
                               hardening springs: ``n = 2``) times the contact shape
                               ``C(r) = 1 - (2/pi)(asin r + r sqrt(1 - r^2))`` of a
                               stiffness that engages past ``s_c`` in [0, 0.9] (a gap
                               closing; ``C = 1`` at ``s_c = 0``); ``n = nu + 1.5 w``,
                               ``nu`` in [0, 3], ``w`` = 1 for an onset at or below the
                               second-lowest level, 0 at or above the third-lowest
                               (log-linear between): a term without an onset that two
                               levels below it show must grow at least as ``s**1.5``,
                               since ``s**n`` with ``n < 1`` would only re-tie the Iwan
                               terms (``s**p``) (``nu, s_c``; ``h >= 0``)
``thermal-drift``              ``omega2 += d f(t_v)``, ``t_v`` the run order scaled to
                               [0, 1], ``f = (1 - e^(-b t))/(1 - e^(-b))``: an exponential
                               approach to a new temperature (Newton), linear at ``b = 0``,
                               accelerating for ``b < 0`` (``b``; ``d``)
``quadratic-damping``          ``zeta += q s**m / (1 + (u s)**m)``: free exponent ``m``
                               in [0.3, 3], saturating above ``s = 1/u`` (``u`` in [0, 5];
                               ``u = 0``: a pure power) (``m, u``; ``q >= 0``)
=============================  ==========================================================

A pair of causes applies both extensions. :func:`design` builds the weighted linear
columns of a model for a batch of nonlinear parameter points.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from scipy import special

from inverse.iwan_modal import kappa_ratio

__all__ = ["CAUSES", "Model", "Observations", "MODELS", "slip_shapes", "box_cox", "drift_shape",
           "contact_shape", "hardening_power", "design"]

#: The catalogue of causes (spec ids), in a fixed order.
CAUSES = ("macro-slip", "nonproportional-amplitude", "geometric-hardening",
          "thermal-drift", "quadratic-damping")

# nonlinear parameters: name, lower bound, upper bound, grid of the global search
_NONLINEAR = {
    None: [("p", 0.01, 0.99, np.linspace(0.04, 0.96, 13))],
    "macro-slip": [("log_x_top", np.log(1.02), np.log(6.0),
                    np.log(np.geomspace(1.05, 4.5, 8)))],
    "nonproportional-amplitude": [("gamma", -0.95, 0.6, np.linspace(-0.8, 0.4, 9)),
                                  ("kappa", 0.0, 5.0, np.array([0.0, 0.7, 1.8, 4.0]))],
    "geometric-hardening": [("nu_hardening", 0.0, 3.0, np.array([0.0, 0.6, 1.4, 2.5])),
                            ("s_contact", 0.0, 0.9, np.array([0.0, 0.25, 0.5, 0.75]))],
    "thermal-drift": [("b_drift", -4.0, 8.0, np.array([-2.0, 0.0, 2.0, 5.0]))],
    "quadratic-damping": [("m_damping", 0.3, 3.0, np.array([0.35, 0.7, 1.1, 1.7, 2.6])),
                          ("u_saturation", 0.0, 5.0, np.array([0.0, 1.2, 3.0]))],
}
_BASE_P_FINE = np.linspace(0.02, 0.98, 33)   # the base model alone: a finer chi grid


@dataclass(frozen=True)
class Model:
    """The base model with a set of causes (empty: the base model, cause ``none``)."""

    causes: tuple = ()

    @property
    def name(self) -> str:
        return "+".join(self.causes) if self.causes else "none"

    def has(self, cause: str) -> bool:
        return cause in self.causes

    @property
    def nonlinear(self) -> list:
        out = list(_NONLINEAR[None])
        if not self.causes:
            out[0] = ("p", 0.01, 0.99, _BASE_P_FINE)
        for c in self.causes:
            out += _NONLINEAR[c]
        return out

    def linear_names(self, response: bool) -> list:
        names = ["W", "c"] + (["U", "S"] if self.has("macro-slip") else ["K1"])
        names += [n for c, n in (("geometric-hardening", "h"), ("thermal-drift", "d"),
                                 ("quadratic-damping", "q")) if self.has(c)]
        return names + (["alpha"] if response else [])

    def nonneg(self, response: bool) -> list:
        names = self.linear_names(response)
        return [i for i, n in enumerate(names) if n in ("K1", "U", "S", "h", "q")]

    def n_params(self, response: bool) -> int:
        return len(self.linear_names(response)) + len(self.nonlinear)


#: Every candidate: the base, each cause alone, every pair (catalogue order).
MODELS = [Model()] + [Model((c,)) for c in CAUSES] + [Model(p) for p in combinations(CAUSES, 2)]


@dataclass
class Observations:
    """One mode's data as the fits use them, sorted by level.

    ``s`` is the base abscissa of eq. (1), ``log_r`` the response channel
    ``log R_v - log s_v`` (None without one), ``t_run`` the run order scaled to [0, 1]
    (``run_monotone``: the levels were run in order of amplitude), ``sigma`` the noise
    level per channel and level (set by the diagnosis)."""

    level: np.ndarray
    s: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    t_run: np.ndarray
    log_r: np.ndarray | None
    response_controlled: bool
    sigma: dict
    run_monotone: bool = False

    @property
    def n(self) -> int:
        return int(self.level.size)

    @property
    def channels(self) -> list:
        return ["omega2", "zeta"] + (["response"] if self.log_r is not None else [])


# --------------------------------------------------------------------------- shapes


def _slider_in_phase(t):
    """In-phase describing function of a unit Jenkins element, ``t = phi/A`` in [0, 1]:
    ``I_t(3/2, 3/2)`` (1 when stuck)."""
    return special.betainc(1.5, 1.5, np.clip(t, 0.0, 1.0))


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


def box_cox(log_s, gamma, kappa):
    """Nonproportional correction ``gamma (s**kappa - 1)/kappa`` (``gamma log s`` at
    ``kappa = 0``), broadcast; ``log_s <= 0`` (top level at 0)."""
    kl = kappa * log_s
    safe = np.where(np.abs(kappa) > 1e-9, kappa, 1.0)
    return gamma * np.where(np.abs(kl) > 1e-9, np.expm1(kl) / safe, log_s * (1 + 0.5 * kl))


def hardening_power(nu, s_contact, s_levels):
    """Power ``n = nu + 1.5 w`` of the hardening term: ``w`` = 1 for a contact onset
    ``s_contact`` at or below the second-lowest level of ``s_levels``, 0 at or above
    the third-lowest, log-linear between (an onset is seen when at least two levels lie
    below it, showing no hardening)."""
    lv = np.sort(np.asarray(s_levels, float))
    lo, hi = lv[min(1, lv.size - 1)], lv[min(2, lv.size - 1)]
    with np.errstate(divide="ignore"):
        w = np.log(hi / np.maximum(s_contact, 1e-300)) / max(np.log(hi / lo), 1e-12)
    return nu + 1.5 * np.clip(w, 0.0, 1.0)


def contact_shape(r):
    """Describing function of a spring engaging past a gap, relative to the spring:
    ``1 - (2/pi)(asin r + r sqrt(1 - r^2))`` with ``r = gap / amplitude`` clipped to
    [0, 1] (1 at no gap, 0 before contact)."""
    r = np.clip(r, 0.0, 1.0)
    return 1.0 - 2.0 / np.pi * (np.arcsin(r) + r * np.sqrt(1.0 - r * r))


def drift_shape(t, b):
    """``(1 - exp(-b t)) / (1 - exp(-b))`` (``t`` at ``b = 0``), broadcast; ``t`` in [0, 1]."""
    small = np.abs(b) < 1e-6
    bb = np.where(small, 1.0, b)
    return np.where(small, t * (1 + 0.5 * b * (1 - t)), np.expm1(-bb * t) / np.expm1(-bb))


# --------------------------------------------------------------------------- design


def design(model: Model, obs: Observations, theta):
    """Weighted design of ``model`` for every parameter point of ``theta`` (G, d).

    Rows: the omega2 channel (target ``omega2 - omega2[0]``), the zeta channel, the
    response channel (when present), each divided by its noise level. Returns
    ``(A (G, N, k), b (G, N), log_s_eff (G, n))``; columns in the order of
    :meth:`Model.linear_names`.
    """
    theta = np.atleast_2d(theta)
    G, n = theta.shape[0], obs.n
    names = [a[0] for a in model.nonlinear]
    col = {name: theta[:, i:i + 1] for i, name in enumerate(names)}
    p = col["p"]
    log_s = np.broadcast_to(np.log(obs.s)[None, :], (G, n))
    if model.has("nonproportional-amplitude"):
        log_s = log_s + box_cox(log_s, col["gamma"], col["kappa"])
    w2 = obs.omega2[None, :]
    one, zero = np.ones((G, n)), np.zeros((G, n))
    inv_w = np.broadcast_to(0.5 / np.sqrt(w2), (G, n))
    om, ze = [one, zero], [zero, inv_w]
    if model.has("macro-slip"):
        P1, P2, Q1, Q2 = slip_shapes(np.exp(col["log_x_top"] + log_s), p - 1.0)
        om += [-P2, -Q2]
        ze += [0.5 * P1 / w2, 0.5 * Q1 / w2]
    else:
        sp = np.exp(p * log_s)
        om.append(-kappa_ratio(p - 1.0, "exact") * sp)
        ze.append(0.5 * sp / w2)
    if model.has("geometric-hardening"):
        n_h = hardening_power(col["nu_hardening"], col["s_contact"], obs.s)
        om.append(np.exp(n_h * log_s) * contact_shape(col["s_contact"] * np.exp(-log_s)))
        ze.append(zero)
    if model.has("thermal-drift"):
        om.append(drift_shape(obs.t_run[None, :], col["b_drift"]))
        ze.append(zero)
    if model.has("quadratic-damping"):
        om.append(zero)
        sm = np.exp(col["m_damping"] * log_s)
        ze.append(sm / (1.0 + col["u_saturation"] ** col["m_damping"] * sm))
    sw, sz = obs.sigma["omega2"][None, :, None], obs.sigma["zeta"][None, :, None]
    blocks = [np.stack(om, -1) / sw, np.stack(ze, -1) / sz]
    targets = [np.broadcast_to((obs.omega2 - obs.omega2[0]) / obs.sigma["omega2"], (G, n)),
               np.broadcast_to(obs.zeta / obs.sigma["zeta"], (G, n))]
    if obs.log_r is not None:
        k = blocks[0].shape[-1]
        blocks = [np.concatenate([b, np.zeros((G, n, 1))], -1) for b in blocks]
        sr = obs.sigma["response"][None, :]
        resp = np.zeros((G, n, k + 1))
        resp[..., k] = 1.0 / sr
        blocks.append(resp)
        shift = log_s - np.log(obs.s)[None, :]
        targets.append((obs.log_r[None, :] - shift) / sr)
    return np.concatenate(blocks, axis=1), np.concatenate(targets, axis=1), log_s
