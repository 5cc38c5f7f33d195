"""Cause ``macro-slip``: the joint amplitude passes phi_max, the four-parameter Iwan
leaves the power law (Segalman 2005, eq. 12-14; exact describing function past phi_max).

One-mode model: the joint amplitude at the top is ``x_top`` phi_max; ``U P2(x) + S Q2(x)``
replaces the power-law frequency drop ``K2 s**p`` and ``U P1(x) + S Q1(x)`` the damping
term, ``x = x_top s`` (:func:`slip_shapes`; ``U, S >= 0``, ``S`` the Dirac weight).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

from inverse.diagnosis.fe_realization import Extension
from inverse.iwan_modal import kappa1_per_R, kappa_ratio
from inverse.update import Parameter
from joints.describing import slider_in_phase

ID = "macro-slip"
ORDER = 10
WORDS = ("the joint leaves micro-slip at the top levels (slip past phi_max): the frequency "
         "drop and the damping growth bend away from the power law")
ADVICE = "add levels above the top one (macro-slip grows fast past phi_max)"
NONLINEAR = [("log_x_top", np.log(1.02), np.log(6.0), np.log(np.geomspace(1.05, 4.5, 8)))]
LINEAR = ["U", "S"]
NONNEG = ("U", "S")
EFFECT = None
REPLACES_JOINT = True


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
    g = np.where(x > 1.0, slider_in_phase(rho), 1.0)
    a, b = chi + 2.5, 1.5
    inc = special.betainc(a, b, rho) * special.beta(a, b)
    P2 = (1.0 - g + 8.0 / np.pi * x**p * inc) / p
    m = np.minimum(x, 1.0)
    P1 = 4.0 / np.pi * (x * m ** (chi + 2.0) / (chi + 2.0) - m ** (chi + 3.0) / (chi + 3.0)) / x**2
    Q2 = 1.0 - g
    Q1 = np.where(x > 1.0, 4.0 * (x - 1.0) / (np.pi * x**2), 0.0)
    return P1, P2, Q1, Q2


def columns(obs, col, log_s, p, w2):
    """Columns of ``U`` and ``S`` (module doc)."""
    P1, P2, Q1, Q2 = slip_shapes(np.exp(col["log_x_top"] + log_s), p - 1.0)
    return [-P2, -Q2], [0.5 * P1 / w2, 0.5 * Q1 / w2]


def parameters(lin, nl, obs, log_s, chi):
    """``x_top`` (top slip amplitude / phi_max), ``beta`` (Dirac weight
    ``S (chi+1) / (R phi_max^(chi+1))``) and ``K1_top`` (the power law continued to
    the top level, rad^2/s^2)."""
    p = chi + 1.0
    U, S = lin["U"], lin["S"]
    x_top = float(np.exp(nl["log_x_top"] + np.max(log_s)))
    return {"x_top": x_top, "beta": S * p / U if U > 0 else float("inf"),
            "K1_top": U * kappa1_per_R(chi) * x_top**p}


def signature(obs, base):
    """Top slip 2 phi_max with Dirac weight beta = 1, on the base fit's chi and
    hysteretic stiffness."""
    s, w2, p = obs.s, obs.omega2, base["chi"] + 1.0
    chi = p - 1.0
    K1 = max(base["kappa1_B"] * s[0] ** -p,
             2.0 * base["omega2_0"] * float(np.ptp(obs.zeta)), 1e-300)
    x_top, beta = 2.0, 1.0
    U = K1 / (kappa1_per_R(chi) * x_top**p)
    x = x_top * s
    P1, P2, Q1, Q2 = slip_shapes(x, chi)
    P1m = kappa1_per_R(chi) * x**p
    S = beta * U / p
    d_om = -(U * (P2 - kappa_ratio(chi, "exact") * P1m) + S * Q2)
    return d_om, 0.5 * (U * (P1 - P1m) + S * Q1) / w2, np.zeros(obs.n)


def testable(obs):
    """Always testable."""
    return True, None


# --- the FE realization (feloop/: the FE level fits it to the levels) -------------
# The four-parameter Iwan joint leaves micro-slip at ``phi_max`` (Segalman 2005, J.
# Appl. Mech. 72, 752: beyond it the joint slides as a whole at ``F_S``). The base model
# has ``beta = 0``, the largest ``phi_max`` the stuck stiffness allows
# (:func:`feloop.levels.phi_max_of`, eq. 1); the extension frees ``ln(1+beta)``: a Dirac
# share of the density that lowers ``phi_max`` and ``F_S`` and brings macro-slip into
# the tested levels.
class MacroSlip(Extension):
    cause, parameter = "macro-slip", "ln_phimax"
    fit_order = 10
    laws = ("iwan4",)       # a Jenkins or Bouc-Wen joint slides as a whole already
    description = "ln(phi_max / a_ref): macro-slip onset in units of the level-1 slip"
    lower, upper = math.log(1e-3), math.inf

    @staticmethod
    def micro_limit(fe, values) -> float:
        """``ln(phi_max(beta = 0) / a_ref)`` of a parameter set: the value at and above
        which the extension is the base model."""
        j = fe.joint({k: v for k, v in values.items() if k != "ln_phimax"})
        return math.log(j["phi_max"] / j["linear"].a_ref)

    def step(self, fe, base, noise, top):
        return 0.35

    def spec(self, fe, base, noise, top):
        p = super().spec(fe, base, noise, top)
        lin = fe.linear(base.joint["K_T"])
        start = math.log(base.joint["phi_max"] / lin.a_ref)
        # the base joint may already slip past 1e-3 a_ref (e.g. a weak glue zone): the
        # lower bound then moves with the start, so the bounds always enclose it
        return Parameter(p.name, start, min(self.lower, start - 6.0), start + 2.0, p.step,
                         p.unit, p.description)

    def starts(self, spec):
        return [spec.start - d for d in (0.0, 2.0, 4.0)]

    def reading(self, p, fe, lin, pred):
        return {"beta": pred.joint["beta"], "phi_max_m": pred.joint["phi_max"],
                "F_S_N": pred.joint["F_S"],
                "top_slip_over_phi_max": float(pred.slip_over_phi_max[-1])}


FE_REALIZATION = MacroSlip()
