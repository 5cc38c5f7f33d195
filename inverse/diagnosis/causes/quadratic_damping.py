"""Cause ``quadratic-damping``: an extra amplitude-dependent damping without softening
(air, viscoelastic glue, material damping).

One-mode model: ``zeta += q s**m / (1 + (u s)**m)``: free exponent ``m`` in [0.3, 3],
saturating above ``s = 1/u`` (``u`` in [0, 5]; ``u = 0``: a pure power), ``q >= 0``.
"""
from __future__ import annotations

import math

import numpy as np

from fe.hb_resonance import QuadraticDamper
from inverse.diagnosis.fe_realization import AIR_DENSITY, Extension, mode_row

ID = "quadratic-damping"
ORDER = 50
WORDS = ("an extra amplitude-dependent damping without softening (air, viscoelastic, "
         "material) makes the damping grow faster than the Iwan tie to the frequency drop "
         "allows")
ADVICE = ("add levels above the top one (the added damping grows faster than the Iwan "
          "power law)")
NONLINEAR = [("m_damping", 0.3, 3.0, np.array([0.35, 0.7, 1.1, 1.7, 2.6])),
             ("u_saturation", 0.0, 5.0, np.array([0.0, 1.2, 3.0]))]
LINEAR = ["q"]
NONNEG = ("q",)
EFFECT = "q"


def columns(obs, col, log_s, p, w2):
    """Column of ``q`` (module doc)."""
    sm = np.exp(col["m_damping"] * log_s)
    return [np.zeros_like(log_s)], [sm / (1.0 + col["u_saturation"] ** col["m_damping"] * sm)]


def parameters(lin, nl, obs, log_s, chi):
    """``q_top`` (damping ratio added at the top level), ``m_damping``, ``u_saturation``."""
    sm = np.exp(nl["m_damping"] * np.max(log_s))
    return {"q_top": lin["q"] * sm / (1.0 + nl["u_saturation"] ** nl["m_damping"] * sm),
            "m_damping": nl["m_damping"], "u_saturation": nl["u_saturation"]}


def signature(obs, base):
    """zeta + s."""
    z = np.zeros(obs.n)
    return z, obs.s, z


def testable(obs):
    """Always testable."""
    return True, None


# --- the FE realization (feloop/: the FE level fits it to the levels) -------------
# Damping that grows with amplitude without softening. Its mechanism here: aerodynamic
# drag on the 50 mm wide strip pair, ``f = -1/2 rho_air C_D b |w'| w'`` per unit length
# (Morison-type drag on a bluff oscillating plate); Baker, Woolam & Young (Int. J. Mech.
# Sci. 9 (1967) 743) measured the air damping of thin cantilever strips and found it
# grows with amplitude, the drag term dominating at larger amplitudes. Galerkin
# projection on the mass-normalized mode ``phi`` gives a modal quadratic damper ``c2
# |q'| q'`` with ``c2 = 1/2 rho_air C_D b int |phi_w|^3 dx`` (a
# :class:`fe.hb_resonance.QuadraticDamper` on the mode's coordinate); ``C_D`` is fitted,
# ``rho_air = 1.204 kg/m^3`` assumed. An amplitude-dependent loss factor of the adhesive
# or of the aluminium (Lazan, Damping of materials and members, 1968: dissipation ``~
# stress^n``, ``n ~ 3`` gives the same first harmonic) acts the same way on one mode:
# one mode cannot tell them apart, so the report gives C_D together with the modal
# damping it adds.
class AirDrag(Extension):
    cause, parameter, unit = "quadratic-damping", "drag_cd", "1"
    fit_order = 20
    description = "drag coefficient C_D of the strip pair (air, rho 1.204 kg/m^3)"
    force_scale_power = -1        # zeta added ~ C_D x amplitude, amplitude ~ s

    @staticmethod
    def c2(p, lin):
        return 0.5 * AIR_DENSITY * float(p["drag_cd"]) * lin.width * lin.lambda3

    def step(self, fe, base, noise, top):
        a = float(base.modal_amplitude[top])
        lin = fe.linear(base.joint["K_T"])
        c2_unit = self.c2({"drag_cd": 1.0}, lin)
        dzeta = 4.0 / (3.0 * math.pi) * c2_unit * a      # zeta added per unit C_D
        return float(noise.sigma_zeta[top] / dzeta)

    def apply(self, p, fe, lin, scale, forces):
        return scale, forces, (QuadraticDamper(mode_row(lin), np.array([self.c2(p, lin)])),)

    def reading(self, p, fe, lin, pred):
        c2 = self.c2(p, lin)
        return {"C_D": float(p[self.parameter]), "modal_c2": c2,
                "zeta_added_top_level": float(4.0 / (3.0 * math.pi) * c2
                                              * pred.modal_amplitude[-1])}


FE_REALIZATION = AirDrag()
