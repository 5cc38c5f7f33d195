"""Cause ``geometric-hardening``: a hardening stiffness grows with amplitude against the
Iwan softening; the damping is unaffected.

One-mode model: ``omega2 += h s**n C(s_c / s)``: a power ``n`` (smooth hardening
springs: ``n = 2``) times the contact shape ``C(r) = 1 - (2/pi)(asin r + r sqrt(1 -
r^2))`` of a stiffness that engages past ``s_c`` in [0, 0.9] (a gap closing; ``C = 1``
at ``s_c = 0``); ``n = nu + 1.5 w``, ``nu`` in [0, 3], ``w`` = 1 for an onset at or
below the second-lowest level, 0 at or above the third-lowest (log-linear between): a
term without an onset that two levels below it show must grow at least as ``s**1.5``,
since ``s**n`` with ``n < 1`` would only re-tie the Iwan terms (``h >= 0``).
"""
from __future__ import annotations

import numpy as np

from fe.hb_resonance import CubicSpring
from inverse.diagnosis.fe_realization import Extension, mode_row

ID = "geometric-hardening"
ORDER = 30
WORDS = ("a hardening stiffness lifts the natural frequency with amplitude against the "
         "Iwan softening; the damping is unaffected")
ADVICE = "add levels above the top one (hardening grows with amplitude squared or faster)"
NONLINEAR = [("nu_hardening", 0.0, 3.0, np.array([0.0, 0.6, 1.4, 2.5])),
             ("s_contact", 0.0, 0.9, np.array([0.0, 0.25, 0.5, 0.75]))]
LINEAR = ["h"]
NONNEG = ("h",)
EFFECT = "h"


def hardening_power(nu, s_contact, s_levels):
    """Power ``n = nu + 1.5 w`` of the hardening term (module doc)."""
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


def columns(obs, col, log_s, p, w2):
    """Column of ``h`` (module doc)."""
    n_h = hardening_power(col["nu_hardening"], col["s_contact"], obs.s)
    return ([np.exp(n_h * log_s) * contact_shape(col["s_contact"] * np.exp(-log_s))],
            [np.zeros_like(log_s)])


def parameters(lin, nl, obs, log_s, chi):
    """``h_top`` (omega2 added at the top level), ``n_hardening`` and ``s_contact``."""
    top = np.exp(np.max(log_s))
    n_h = float(hardening_power(nl["nu_hardening"], nl["s_contact"], obs.s))
    return {"h_top": lin["h"] * top**n_h * contact_shape(nl["s_contact"] / top),
            "n_hardening": n_h, "s_contact": nl["s_contact"]}


def signature(obs, base):
    """omega2 + s^2."""
    z = np.zeros(obs.n)
    return obs.s**2, z, z


def testable(obs):
    """Always testable."""
    return True, None


# --- the FE realization (feloop/: the FE level fits it to the levels) -------------
# A stiffness growing with amplitude squared: the cubic term of a large-deflection beam
# (nonlinear curvature and the axial stretching a glued tip forces on the strips; Crespo
# da Silva & Glynn, J. Struct. Mech. 6 (1978) 437; Nayfeh & Pai, Linear and Nonlinear
# Structural Mechanics, 2004), Galerkin-projected on the mode: a modal cubic spring ``k3
# q^3`` (:class:`fe.hb_resonance.CubicSpring`), ``k3 >= 0``.
class CubicHardening(Extension):
    cause, parameter, unit = "geometric-hardening", "k3", "1/(kg s^2 m^2)"
    fit_order = 30
    description = "modal cubic stiffness k3 (mass-normalized mode)"
    stiffens = True
    force_scale_power = -2        # omega^2 rise ~ k3 x amplitude^2, amplitude ~ s

    def step(self, fe, base, noise, top):
        a = float(base.modal_amplitude[top])
        return float(noise.sigma_omega2[top] / (0.75 * a * a))

    def apply(self, p, fe, lin, scale, forces):
        return scale, forces, (CubicSpring(mode_row(lin), np.array([float(p["k3"])])),)

    def reading(self, p, fe, lin, pred):
        a = float(pred.modal_amplitude[-1])
        return {"k3": float(p[self.parameter]),
                "omega2_rise_top_level": 0.75 * float(p[self.parameter]) * a * a}


FE_REALIZATION = CubicHardening()
