"""Cause ``thermal-drift``: the natural frequency drifts with time (``run_order``), not
with amplitude; the damping is unaffected.

One-mode model: ``omega2 += d f(t_v)``, ``t_v`` the run order scaled to [0, 1],
``f = 0`` before the onset ``t_0`` and ``(1 - e^(-b u))/(1 - e^(-b))`` after it,
``u = (t - t_0)/(1 - t_0)``: an exponential approach to a new temperature (Newton's law
of cooling) from the start of the test or from a change of the surroundings during it
(``t_0`` > 0; a large ``b`` makes it a step), linear at ``b = 0``, accelerating for
``b < 0``. Not testable on a run order monotone in amplitude, a repeat run next to
its level counting with it (time and amplitude are then one variable:
:func:`inverse.judge.time_separable`).
"""
from __future__ import annotations

import math

import numpy as np

from inverse.diagnosis.fe_realization import ALUMINIUM_DLNE_DT, Extension

ID = "thermal-drift"
ORDER = 40
WORDS = ("the natural frequency drifts with the order in which the levels were run, not "
         "with amplitude; the damping is unaffected")
ADVICE = ("repeat the lowest level at the end of the test (or shuffle the run order): "
          "drift follows time, not amplitude")
NONLINEAR = [("b_drift", -4.0, 40.0, np.array([-2.0, 0.0, 2.0, 5.0, 20.0])),
             ("t_onset", 0.0, 0.9, np.array([0.0, 0.3, 0.6]))]
LINEAR = ["d"]
NONNEG = ()
EFFECT = None


def drift_shape(t, b):
    """``(1 - exp(-b t)) / (1 - exp(-b))`` (``t`` at ``b = 0``), broadcast; ``t`` in [0, 1]."""
    small = np.abs(b) < 1e-6
    bb = np.where(small, 1.0, b)
    return np.where(small, t * (1 + 0.5 * b * (1 - t)), np.expm1(-bb * t) / np.expm1(-bb))


def onset_shape(t, b, t0):
    """:func:`drift_shape` started at ``t0`` (0 before it), broadcast."""
    u = np.clip((t - t0) / (1.0 - t0), 0.0, 1.0)
    return drift_shape(u, b)


def columns(obs, col, log_s, p, w2):
    """Column of ``d`` (module doc)."""
    f = onset_shape(obs.t_run[None, :], col["b_drift"], col["t_onset"])
    return [f], [np.zeros_like(log_s)]


def parameters(lin, nl, obs, log_s, chi):
    """``d_total`` (omega2 drift over the run, rad^2/s^2), ``d`` per run (average), the
    shape ``b_drift`` and the onset ``t_onset`` (run order scaled to [0, 1]); all
    fitted."""
    span = obs.run_span
    return {"d_total": lin["d"], "d": lin["d"] / span if span > 0 else 0.0,
            "b_drift": nl["b_drift"], "t_onset": nl["t_onset"]}


def signature(obs, base):
    """omega2 + t_run."""
    z = np.zeros(obs.n)
    return np.asarray(obs.t_run, float), z, z


def testable(obs):
    """Not on a run order monotone in amplitude (:func:`inverse.judge.time_separable`)."""
    if obs.run_monotone:
        return False, ("the levels were run in order of amplitude: a drift with time "
                       "cannot be told from an amplitude effect")
    return True, None


# --- the FE realization (feloop/: the FE level fits it to the levels) -------------
# The modulus drifts with time (exciter coil and room heating the strips): every
# stiffness (strips and glue) scales by ``1 + d (run - run_1)``; for aluminium ``(1/E)
# dE/dT ~ -4e-4 /K`` (a handbook value, assumed), so ``d`` reads as a temperature change
# per run.
class ThermalDrift(Extension):
    cause, parameter, unit = "thermal-drift", "drift", "1/run"
    fit_order = 40
    description = "relative stiffness change per run (every stiffness alike)"
    lower, stiffens = -math.inf, True

    def step(self, fe, base, noise, top):
        span = max(float(np.ptp(fe.run_order)), 1.0)
        return float(noise.sigma_omega2[0] / base.omega2[0] / span)

    def starts(self, spec):
        return [0.0, 3.0 * spec.step, -3.0 * spec.step]

    def apply(self, p, fe, lin, scale, forces):
        run = fe.run_order - fe.run_order.min()
        return scale * (1.0 + float(p["drift"]) * run), forces, ()

    def reading(self, p, fe, lin, pred):
        d = float(p[self.parameter])
        return {"drift_per_run": d, "temperature_change_per_run_K": d / ALUMINIUM_DLNE_DT}


FE_REALIZATION = ThermalDrift()
