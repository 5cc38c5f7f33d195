"""Cause ``nonproportional-amplitude``: the joint amplitude does not grow in proportion to
the excitation (exciter force drop-out, a held level that is not the force reaching the
structure).

One-mode model: ``log s -> log s + gamma (s**kappa - 1)/kappa`` (Box-Cox):
``kappa -> 0`` a steady per-step shortfall ``(1 + gamma) log s``, ``kappa > 0`` a
shortfall growing toward the top (saturation); the response channel follows. No linear
parameter of its own. Needs the ``response_amplitude`` column and force control.
"""
from __future__ import annotations

import math

import numpy as np

from inverse.diagnosis.fe_realization import Extension
from inverse.iwan_modal import kappa_ratio

ID = "nonproportional-amplitude"
ORDER = 20
WORDS = ("the joint amplitude does not grow in proportion to the excitation (the force "
         "reaching the structure falls short of the held level)")
ADVICE = ("measure the force reaching the structure (force transducer) or run under "
          "response control")
NONLINEAR = [("gamma", -0.95, 0.6, np.linspace(-0.8, 0.4, 9)),
             ("kappa", 0.0, 5.0, np.array([0.0, 0.7, 1.8, 4.0]))]
LINEAR = []
NONNEG = ()
EFFECT = None


def box_cox(log_s, gamma, kappa):
    """Nonproportional correction ``gamma (s**kappa - 1)/kappa`` (``gamma log s`` at
    ``kappa = 0``), broadcast; ``log_s <= 0`` (top level at 0)."""
    kl = kappa * log_s
    safe = np.where(np.abs(kappa) > 1e-9, kappa, 1.0)
    return gamma * np.where(np.abs(kl) > 1e-9, np.expm1(kl) / safe, log_s * (1 + 0.5 * kl))


def transform_log_s(log_s, col):
    """The effective log amplitude (module doc)."""
    return log_s + box_cox(log_s, col["gamma"], col["kappa"])


def columns(obs, col, log_s, p, w2):
    """No columns of its own: it acts through :func:`transform_log_s`."""
    return [], []


def parameters(lin, nl, obs, log_s, chi):
    """``gamma``, ``kappa`` and ``amplitude_shortfall_top`` (1 - joint amplitude ratio
    top/level 1 over the base abscissa's ratio)."""
    log_base = np.log(obs.s)
    shortfall = 1.0 - np.exp((np.max(log_s) - log_s[0]) - (log_base.max() - log_base[0]))
    return {"gamma": nl["gamma"], "kappa": nl["kappa"], "amplitude_shortfall_top": shortfall}


def signature(obs, base):
    """A steady shortfall of 20 % per decade of excitation (log s -> 0.8 log s)."""
    s, w2, p = obs.s, obs.omega2, base["chi"] + 1.0
    K1 = max(base["kappa1_B"] * s[0] ** -p,
             2.0 * base["omega2_0"] * float(np.ptp(obs.zeta)), 1e-300)
    ds = s ** (0.8 * p) - s**p
    return (-kappa_ratio(p - 1.0, "exact") * K1 * ds, 0.5 * K1 * ds / w2,
            -0.2 * np.log(s))


def testable(obs):
    """Needs force control and the response channel."""
    if obs.response_controlled:
        return False, "under response control the response amplitude is the abscissa"
    if obs.log_r is None:
        return False, "needs the response_amplitude column"
    return True, None


# --- the FE realization (feloop/: the FE level fits it to the levels) -------------
# A voltage-driven electrodynamic exciter does not deliver a force proportional to the
# drive near a resonance and at high drive (force drop-out: Olsen, Sound and Vibration
# 20(6) (1986) 18; Varoto & de Oliveira, Shock and Vibration 9 (2002) 165). The FRF is
# measured against the force gauge and stays the structure's own, but the joint
# amplitude of a level no longer scales with the drive voltage. Realization: the force
# of level ``v`` is ``force_scale e_v / sqrt(1 + (e_v / e_sat)^2)`` with ``g = 1/e_sat
# >= 0`` fitted (amplifier/armature compression).
class ForceCompression(Extension):
    cause, parameter, unit = "nonproportional-amplitude", "inv_e_sat", "1/excitation unit"
    fit_order = 50
    description = "1/e_sat: force = force_scale e / sqrt(1 + (e/e_sat)^2)"

    def step(self, fe, base, noise, top):
        return 0.1 / float(fe.excitation[top])

    def apply(self, p, fe, lin, scale, forces):
        g = float(p["inv_e_sat"])
        return scale, forces / np.sqrt(1.0 + (g * fe.excitation) ** 2), ()

    def reading(self, p, fe, lin, pred):
        g = float(p[self.parameter])
        top = float(fe.excitation[-1])
        return {"e_sat": (1.0 / g) if g > 0 else math.inf,
                "force_lost_top_level": 1.0 - 1.0 / math.sqrt(1.0 + (g * top) ** 2)}


FE_REALIZATION = ForceCompression()
