"""How each joint law of a case file enters the FE-levels model (:mod:`feloop.levels`).

A *joint form* names the joint parameters the base FE model fits for one law, their
bounds and starts, and the joints one parameter set makes on the joint elements (the
objects the first-harmonic balance takes: :mod:`joints.law`). Every element ``m`` takes
the share ``w_m = k_m / K_T`` of the stuck stiffness and of the slip force, so the slip
scale is one for all (:mod:`casefile.laws`). ``a_ref`` is the largest level-1
linear-inverse joint slip (:attr:`feloop.levels.LinearPart.a_ref`): a slip scale is
fitted as ``ln(scale / a_ref)``, the variable in which the onset level barely moves when
the strength changes. SI units.

* ``iwan4`` (:class:`IwanForm`): ``chi``, ``ln_dc1`` = ln ``|kappa1| B~`` at level 1
  (paper eq. 30-32, 37) and, with the macro-slip cause, ``ln_phimax``
  (:class:`feloop.levels.FELevels` documents them).
* ``jenkins`` (:class:`JenkinsForm`): ``ln_slip`` = ``ln((F_S / K_T) / a_ref)``, one
  elastic-perfectly-plastic slider per element (stiffness ``w_m K_T``, slip force
  ``w_m F_S``): stuck below the slip ``F_S / K_T``, a damping that starts at it.
* ``bouc-wen`` (:class:`BoucWenForm`): ``ln_slip`` = ``ln(z_u / a_ref)``, ``z_u = F_S /
  ((1 - alpha) K_T)`` and ``alpha`` (the stiffness left in gross slip); the loop
  shape ``gamma/beta`` is the file's (assumed 0.5 when the file leaves it).

A law's form is one class here and its entry in :data:`FORMS`
(:func:`feloop.case_levels.form_of` picks a case file's).
"""
from __future__ import annotations

import math

import numpy as np

from inverse.iwan_modal import kappa_ratio, r_tilde
from inverse.update import Parameter
from joints.bank import JointBank
from joints.bouc_wen import BoucWenJoints, BoucWenParameters
from joints.iwan import IwanParameters

__all__ = ["JointForm", "IwanForm", "JenkinsForm", "BoucWenForm", "FORMS",
           "phi_max_of", "BOUC_WEN_SHAPE", "MICRO_LIMIT"]

#: ``ln_phimax`` this large means ``beta = 0`` (the micro-slip limit) for any model here.
MICRO_LIMIT = 50.0

#: ``gamma/beta`` of a Bouc-Wen joint when the case file leaves it (assumed: the
#: middle of the softening range (-1, 1], a loop between the sharp and the round one)
BOUC_WEN_SHAPE = 0.5


def phi_max_of(K_T, R, chi, beta) -> float:
    """Eq. (1): ``(K_T (chi+1) / ((1+beta) R))^(1/(chi+1))`` (m; Segalman 2005, eq. 12);
    ValueError (one line) if that is not a positive normal double."""
    try:
        pm = (K_T * (chi + 1.0) / ((1.0 + beta) * R)) ** (1.0 / (chi + 1.0))
    except (OverflowError, ZeroDivisionError):
        pm = math.inf
    if not (math.isfinite(pm) and pm >= 2.3e-308):
        raise ValueError(f"the glue joint's phi_max = (K_T (chi+1)/((1+beta) R))^(1/(chi+1)) "
                         f"with K_T = {K_T:g} N/m, R = {R:g}, chi = {chi:g}, beta = {beta:g} is "
                         f"outside double precision (check --R, --chi, --force-scale)")
    return pm


class JointForm:
    """One law in the FE-levels model (module docstring). ``names``: the joint
    parameters of the base model (fitted, before ``zeta_v`` and ``f0_hz``);
    ``scale_name``: what the slip scale of the law is called in reports."""

    law = ""
    names: tuple = ()
    scale_name = "slip scale"
    #: the joint element, in reports
    element = ""
    #: how the joint's figures scale with the assumed force scale s, in reports
    scaling = "the slip scale and F_S scale as its first power"
    #: parameters whose likelihood is not near-quadratic at the optimum (profiled by
    #: update whether or not on a bound, :mod:`inverse.profile`)
    profiled: tuple = ()

    def key(self, p: dict) -> tuple:
        """What the joints of parameter set ``p`` depend on (their cache key)."""
        return tuple(float(p[n]) for n in self.names)

    def parameters(self, first: dict) -> dict:
        """name -> :class:`inverse.update.Parameter` of the joint parameters, from the
        start ``first`` of the base fit (its joint values, when it holds them)."""
        raise NotImplementedError

    def starts(self, first: dict) -> list:
        """Further starts of the base fit (dicts of joint parameters) besides ``first``."""
        return []

    def restarts(self, values: dict) -> list:
        """The joint starts of a cause's fit from the base optimum ``values``."""
        return [{}]

    def engaged_starts(self, P: dict) -> list:
        """Starts of the base fit where the joints work the data at the lowest levels,
        tried when its optimum's joint has no effect (``P``: the base parameters)."""
        return []

    def joint(self, p: dict, lin) -> dict:
        """The joints of ``p`` on ``lin`` (:class:`feloop.levels.LinearPart`): ``law``,
        ``K_T`` (N/m), ``F_S`` (N), ``slip_scale`` (m), ``params`` (the joints for
        :mod:`fe.hb_resonance`) and the law's own figures."""
        raise NotImplementedError

    def derived(self, j: dict, values: dict) -> dict:
        """The joint's figures in the update's report (SI units)."""
        return {"F_S_N": j["F_S"], "slip_scale_m": j["slip_scale"]}

    def words(self, d: dict) -> str:
        """One line of the joint of :meth:`derived` ``d``."""
        return (f"{self.law}: {self.scale_name} = {d['slip_scale_m']:.4g} m, F_S = "
                f"{d['F_S_N']:.4g} N")

    def interface(self, joint: dict, values: dict) -> dict:
        """The case-file keys of the fitted joint besides ``kt`` and ``fs``."""
        return {}


class IwanForm(JointForm):
    """The four-parameter Iwan joint (Segalman 2005) in the paper's modal variables."""

    law, names, scale_name = "iwan4", ("chi", "ln_dc1"), "phi_max"
    element = "one continuous four-parameter Iwan element per joint node"
    scaling = "R~ scales as its -(chi+1) power, phi_max and F_S as its first power"

    def key(self, p):
        return (float(p["chi"]), float(p["ln_dc1"]),
                float(p["ln_phimax"]) if "ln_phimax" in p else "absent")

    def parameters(self, first):
        # ln(exp(x)) as the start always was (the fits' starts bitwise unchanged)
        return {"chi": Parameter("chi", first["chi"], -0.98, -0.005, 0.05, "1",
                                 "Iwan exponent"),
                "ln_dc1": Parameter("ln_dc1", math.log(math.exp(first["ln_dc1"])), -15.0,
                                    15.0, 0.2, "ln(rad^2/s^2)",
                                    "ln |kappa1| B~ at level 1: the joints' modal damping there"),
                "ln_phimax": Parameter("ln_phimax", MICRO_LIMIT, math.log(1e-3), MICRO_LIMIT,
                                       0.35, "1", "ln(phi_max / a_ref): macro-slip onset in "
                                       "units of the level-1 joint slip (beta = 0 above its "
                                       "limit)")}

    def starts(self, first):
        return [{"chi": c} for c in (-0.2, -0.6) if abs(c - first["chi"]) > 0.05]

    def engaged_starts(self, P):
        # a weaker joint at level 1 than the start's (whose damping growth can carry
        # the fit to joints slipped through at every level): 1/e^2 .. 1/e^6 of it
        return [{"ln_dc1": P["ln_dc1"].start - d} for d in (2.0, 4.0, 6.0)]

    def restarts(self, values):
        # chi from the base optimum and from -0.5 (an extension can move chi far: a slip
        # onset or a hardening bends the top levels, which chi then need not do)
        return [{"chi": c} for c in sorted({values["chi"], -0.5})]

    def joint(self, p, lin):
        K_T = lin.K_T                   # the model's own (log10 K_T rounded to 1e-9)
        chi = float(p["chi"])
        if not -1.0 < chi < 0.0:
            raise ValueError(f"chi must lie in (-1, 0), got {chi:.4g}")
        R = r_tilde(math.exp(float(p["ln_dc1"])), chi, lin.B(chi))
        pm = phi_max_of(K_T, R, chi, 0.0)            # beta = 0: the largest phi_max
        beta = 0.0
        if "ln_phimax" in p:                           # phi_max / a_ref given: beta >= 0
            target = math.exp(float(p["ln_phimax"])) * lin.a_ref
            if target < pm:
                beta = (pm / target) ** (chi + 1.0) - 1.0
                pm = target
        params = [IwanParameters.from_density(R * w, chi, pm, K_T * w * beta / (1.0 + beta))
                  for w in lin.shares]
        return {"law": self.law, "chi": chi, "R": R, "K_T": K_T, "beta": beta, "phi_max": pm,
                "F_S": float(sum(q.F_S for q in params)), "slip_scale": pm, "params": params}

    def derived(self, j, values):
        return {"R_tilde": j["R"], "phi_max_m": j["phi_max"], "F_S_N": j["F_S"],
                "beta": j["beta"]}

    def modal(self, values) -> dict:
        """The modal figures behind the joint (paper eq. 30-32, 37)."""
        return {"kappa1_B_level1": math.exp(values["ln_dc1"]),
                "kappa2_over_kappa1": kappa_ratio(values["chi"], "exact")}

    def words(self, d):
        return (f"R~ = {d['R_tilde']:.4g} N/m^(chi+2), phi_max = {d['phi_max_m']:.4g} m, "
                f"F_S = {d['F_S_N']:.4g} N, beta = {d['beta']:.4g}")

    def interface(self, joint, values):
        return {"chi": float(values["chi"]), "beta": float(joint["beta"])}


#: further starts of a slip scale's ln(scale / a_ref) besides the parameter's own 0.7:
#: the onset below, at and well above level 1's slip (assumed grid; a slider stuck at
#: every level has no gradient, so one start must slip)
SLIP_STARTS = (-0.7, 2.1)


def _scale_parameter(law: str, what: str) -> Parameter:
    return Parameter("ln_slip", 0.7, math.log(1e-3), math.log(1e3), 0.2, "1",
                     f"ln({what} / a_ref): where the {law} joints slip, in units of the "
                     "level-1 joint slip")


class JenkinsForm(JointForm):
    """One elastic-perfectly-plastic slider per joint element (module docstring)."""

    law, names, scale_name = "jenkins", ("ln_slip",), "fs/kt"
    element = "one Jenkins slider (elastic-perfectly-plastic) per joint node"
    # the slider is linear below its slip: levels that do not reach it bound the slip
    # from below only, and its damping has a kink at the onset (a linearized interval
    # there misled: 3.87 .. 4.45 "determined" around a truth of 4.85)
    profiled = ("ln_slip",)

    def parameters(self, first):
        return {"ln_slip": _scale_parameter(self.law, "F_S/K_T")}

    def starts(self, first):
        return [{"ln_slip": v} for v in SLIP_STARTS]

    def joint(self, p, lin):
        u = math.exp(float(p["ln_slip"])) * lin.a_ref
        k = lin.K_T * np.asarray(lin.shares, float)
        bank = JointBank(k[:, None], np.full((k.size, 1), u))
        return {"law": self.law, "K_T": lin.K_T, "F_S": lin.K_T * u, "slip_scale": u,
                "params": bank}


class BoucWenForm(JointForm):
    """Bouc-Wen joints (Bouc 1967, Wen 1976, ``n = 1``; module docstring); ``shape``:
    ``gamma/beta`` (the file's, or :data:`BOUC_WEN_SHAPE` assumed)."""

    law, names, scale_name = "bouc-wen", ("ln_slip", "alpha"), "z_u"
    element = "one Bouc-Wen element (n = 1) per joint node"

    def __init__(self, shape: float | None = None):
        self.shape = BOUC_WEN_SHAPE if shape is None else float(shape)
        self.shape_kind = "assumed" if shape is None else "given"

    def parameters(self, first):
        return {"ln_slip": _scale_parameter(self.law, "z_u"),
                "alpha": Parameter("alpha", 0.1, 0.0, 0.95, 0.02, "1",
                                   "stiffness left in gross slip, a fraction of K_T")}

    def starts(self, first):
        return [{"ln_slip": v} for v in SLIP_STARTS]

    def joint(self, p, lin):
        u, alpha = math.exp(float(p["ln_slip"])) * lin.a_ref, float(p["alpha"])
        F_S = (1.0 - alpha) * lin.K_T * u
        law = BoucWenJoints([BoucWenParameters(K_T=lin.K_T * w, F_S=F_S * w, alpha=alpha,
                                               shape=self.shape) for w in lin.shares])
        return {"law": self.law, "K_T": lin.K_T, "F_S": F_S, "slip_scale": u,
                "alpha": alpha, "shape": self.shape, "params": law}

    def derived(self, j, values):
        return {**super().derived(j, values), "alpha": j["alpha"], "shape": j["shape"]}

    def words(self, d):
        return (f"{super().words(d)}, alpha = {d['alpha']:.4g}, shape gamma/beta = "
                f"{d['shape']:g} ({self.shape_kind})")

    def interface(self, joint, values):
        return {"alpha": float(joint["alpha"]), "shape": float(joint["shape"])}


#: law -> its form's class
FORMS = {"iwan4": IwanForm, "jenkins": JenkinsForm, "bouc-wen": BoucWenForm}
