"""The base FE fit's parameters and starts (:func:`base_parameters`): the paper's
estimator on the fit levels (:func:`estimator_start`), the further starts of the law's
form (:mod:`feloop.joint_forms`) and a naive start from the damping growth of the fit
levels (:func:`naive_ln_dc1`). Used by the FE model choice (:mod:`feloop.select`)."""
from __future__ import annotations

import math

import numpy as np

from feloop.levels import FELevels
from inverse.estimate import estimate
from inverse.update import Parameter

__all__ = ["ESTIMATE_F0_MAX", "NAIVE_ZETA_SHARE", "estimator_start", "naive_ln_dc1",
           "base_parameters"]

#: Largest stuck frequency of the paper's estimator taken as a start, over the first
#: level's frequency (assumed: a joint that softens a mode by 25 % between zero amplitude
#: and its lowest tested level is past micro-slip there).
ESTIMATE_F0_MAX = 1.25


def estimator_start(data, levels) -> tuple[dict | None, str | None]:
    """The paper's estimator (``exact``, on ``levels``) as a start of the base fit:
    (``chi``, ``ln_dc1``, ``zeta_v``, ``f0_hz``) and None, or None and why it is not
    used (it failed, chi or kappa1 B~ outside the fit's box, or its stuck frequency more
    than :data:`ESTIMATE_F0_MAX` times the first level's: a scatter in damping can throw
    its extrapolation to zero amplitude far off)."""
    try:
        est = estimate(data, fit_levels=levels, method="exact")
    except ValueError as exc:
        return None, f"the paper's estimator failed ({str(exc)[:80]})"
    if not -0.98 < est.chi < -0.005:
        return None, f"the paper's estimator gave chi = {est.chi:.3g}, outside (-0.98, -0.005)"
    if not est.kappa1_B > 0:
        return None, (f"the paper's estimator gave kappa1 B~ = {est.kappa1_B:.3g} <= 0 "
                      "(damping that does not grow with level)")
    f_est = math.sqrt(max(est.omega2_linear, 0.0)) / (2 * math.pi)
    f1 = math.sqrt(float(data.omega2[0])) / (2 * math.pi)
    if not 0 < f_est <= ESTIMATE_F0_MAX * f1:
        return None, (f"the paper's estimator put the stuck frequency at {f_est:.4g} Hz, "
                      f"not within {ESTIMATE_F0_MAX:g} times the first level's {f1:.4g} Hz "
                      "(assumed limit)")
    return {"chi": est.chi, "ln_dc1": math.log(est.kappa1_B),
            "zeta_v": est.c_modal / (2.0 * math.sqrt(est.omega2_linear)), "f0_hz": f_est}, None


#: The joints' share of the level-1 damping ratio the naive start takes when the fit
#: levels show no damping growth (assumed).
NAIVE_ZETA_SHARE = 1e-4


def naive_ln_dc1(data, mask, chi: float) -> float:
    """``ln |kappa1| B~`` at level 1 of a joint of exponent ``chi`` that gives the damping
    growth of the fit levels (paper eq. 30-32: the quadrature stiffness ``2 omega^2
    zeta`` grows as ``dc1 (a / a_1)^(chi+1)``, the slip amplitude ``a`` taken as
    ``excitation / (zeta omega^2)``): ``dc1 = 2 omega_top^2 dzeta / (x^(chi+1) - 1)``;
    without growth, :data:`NAIVE_ZETA_SHARE` of the level-1 damping. A start, not an
    estimate: it keeps the naive start where a joint works the data rather than where
    it slips through at every level (the FE benchmark's draw 6107)."""
    i = np.flatnonzero(mask)
    a, b = i[0], i[-1]
    w2, z, e = (np.asarray(v, float) for v in (data.omega2, data.zeta, data.excitation))
    x = (e[b] / (z[b] * w2[b])) / (e[a] / (z[a] * w2[a]))
    growth = 2.0 * w2[b] * z[b] - 2.0 * w2[a] * z[a]
    if growth > 0 and x > 1.0:
        return math.log(growth / (x ** (chi + 1.0) - 1.0))
    return math.log(2.0 * float(w2[0]) * NAIVE_ZETA_SHARE)


def base_parameters(data, mask, fe: FELevels, estimated=None) -> tuple[dict, list]:
    """Parameters of the base model and their starts; the start list holds the paper's
    estimator (:func:`estimator_start`, the fit levels; ``estimated``: its result when
    already computed: its ``zeta_v`` and ``f0_hz`` for any law), the further starts of
    the law's form (:meth:`feloop.joint_forms.JointForm.starts`: two others of chi for
    Iwan joints) and, when the estimator gave the first, the start from the first level
    alone (the frequency bounds hold both)."""
    lv = [int(v) for v in data.level[mask]]
    w1 = math.sqrt(float(data.omega2[0]))
    naive = {"chi": -0.4, "ln_dc1": naive_ln_dc1(data, mask, -0.4),
             "zeta_v": float(data.zeta[0]), "f0_hz": w1 / (2 * math.pi)}
    est, _ = estimator_start(data, lv) if estimated is None else estimated
    first = est or naive
    zv0, f00 = first["zeta_v"], first["f0_hz"]
    joint = fe.form.parameters(first)
    P = {**{n: joint[n] for n in fe.form.names},
         "zeta_v": Parameter("zeta_v", zv0, 1e-5, 0.2, 1e-5, "1",
                             "viscous modal damping ratio"),
         "f0_hz": Parameter("f0_hz", f00, 0.95 * min(f00, naive["f0_hz"]),
                            1.05 * max(f00, naive["f0_hz"]), 1e-3, "Hz",
                            "stuck-joint natural frequency of the mode"),
         "log10_kt": Parameter("log10_kt", math.log10(fe.default_kt),
                               6.0, 11.0, 0.5, "log10 N/m",
                               "stuck tangential stiffness of all joints together"),
         **{n: v for n, v in joint.items() if n not in fe.form.names}}
    starts = [{}] + fe.form.starts(first)
    if est is not None:                  # a noisy series can mislead the estimator
        starts.append({k: v for k, v in naive.items() if k in P})
    return P, starts
