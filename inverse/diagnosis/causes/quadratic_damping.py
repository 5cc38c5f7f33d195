"""Cause ``quadratic-damping``: an extra amplitude-dependent damping without softening
(air, viscoelastic glue, material damping).

One-mode model: ``zeta += q s**m / (1 + (u s)**m)``: free exponent ``m`` in [0.3, 3],
saturating above ``s = 1/u`` (``u`` in [0, 5]; ``u = 0``: a pure power), ``q >= 0``.
"""
from __future__ import annotations

import numpy as np

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
#: Slot for the FE realization (filled by the FE level).
FE_REALIZATION = None


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
