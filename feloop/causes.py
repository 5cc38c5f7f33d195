"""The causes of the diagnosis catalogue as FE physics of any jointed FE model.

Each cause of ``docs/formats/diagnosis.md`` with a physical mechanism becomes one
:class:`Extension` of the FE-levels model (:mod:`feloop.levels`): one extra
parameter (nested: its ``none`` value gives back the base model), a realization in the
first-harmonic balance (:mod:`fe.hb_resonance`: an element, a per-level stiffness scale
or a per-level force) and the physical reading of the fitted value. SI units. Each
extension is found by the id of its plug-in cause (``inverse/diagnosis/causes/<id>.py``,
checked at import; the plug-in's ``FE_REALIZATION`` slot stays empty: ``inverse`` cannot
import ``cases``); adding a cause with an FE realization means its plug-in file and one
class here.

``macro-slip`` (:class:`MacroSlip`). The four-parameter Iwan joint leaves micro-slip at
``phi_max`` (Segalman 2005, J. Appl. Mech. 72, 752: beyond it the joint slides as a
whole at ``F_S``). The base model has ``beta = 0``, the largest ``phi_max`` the stuck
stiffness allows (:func:`feloop.levels.phi_max_of`, eq. 1); the extension frees
``ln(1+beta)``: a Dirac share of the density that lowers ``phi_max`` and ``F_S`` and
brings macro-slip into the tested levels.

``quadratic-damping`` (:class:`AirDrag`). Damping that grows with amplitude without
softening. Its mechanism here: aerodynamic drag on the 50 mm wide strip pair, ``f =
-1/2 rho_air C_D b |w'| w'`` per unit length (Morison-type drag on a bluff oscillating
plate); Baker, Woolam & Young (Int. J. Mech. Sci. 9 (1967) 743) measured the air
damping of thin cantilever strips and found it grows with amplitude, the drag term
dominating at larger amplitudes. Galerkin projection on the mass-normalized mode
``phi`` gives a modal quadratic damper ``c2 |q'| q'`` with ``c2 = 1/2 rho_air C_D b
int |phi_w|^3 dx`` (a :class:`fe.hb_resonance.QuadraticDamper` on the mode's
coordinate); ``C_D`` is fitted, ``rho_air = 1.204 kg/m^3`` assumed. An
amplitude-dependent loss factor of the adhesive or of the aluminium (Lazan, Damping of
materials and members, 1968: dissipation ``~ stress^n``, ``n ~ 3`` gives the same first
harmonic) acts the same way on one mode: one mode cannot tell them apart, so the
report gives C_D together with the modal damping it adds.

``geometric-hardening`` (:class:`CubicHardening`). A stiffness growing with amplitude
squared: the cubic term of a large-deflection beam (nonlinear curvature and the axial
stretching a glued tip forces on the strips; Crespo da Silva & Glynn, J. Struct. Mech.
6 (1978) 437; Nayfeh & Pai, Linear and Nonlinear Structural Mechanics, 2004),
Galerkin-projected on the mode: a modal cubic spring ``k3 q^3``
(:class:`fe.hb_resonance.CubicSpring`), ``k3 >= 0``.

``thermal-drift`` (:class:`ThermalDrift`). The modulus drifts with time (exciter coil
and room heating the strips): every stiffness (strips and glue) scales by ``1 + d
(run - run_1)``; for aluminium ``(1/E) dE/dT ~ -4e-4 /K`` (a handbook value, assumed),
so ``d`` reads as a temperature change per run.

``nonproportional-amplitude`` (:class:`ForceCompression`). A voltage-driven
electrodynamic exciter does not deliver a force proportional to the drive near a
resonance and at high drive (force drop-out: Olsen, Sound and Vibration 20(6) (1986)
18; Varoto & de Oliveira, Shock and Vibration 9 (2002) 165). The FRF is measured
against the force gauge and stays the structure's own, but the joint amplitude of a
level no longer scales with the drive voltage. Realization: the force of level ``v`` is
``force_scale e_v / sqrt(1 + (e_v / e_sat)^2)`` with ``g = 1/e_sat >= 0`` fitted
(amplifier/armature compression).
"""
from __future__ import annotations

import math

import numpy as np

from fe.hb_resonance import CubicSpring, QuadraticDamper
from inverse.diagnosis.causes import CATALOGUE
from inverse.update import Parameter

__all__ = ["AIR_DENSITY", "ALUMINIUM_DLNE_DT", "Extension", "MacroSlip", "AirDrag",
           "CubicHardening", "ThermalDrift", "ForceCompression", "Combined", "EXTENSIONS"]

AIR_DENSITY = 1.204          # kg/m^3 at 20 C (assumed)
ALUMINIUM_DLNE_DT = -4.0e-4  # 1/K, (1/E) dE/dT of wrought aluminium alloys (assumed)


def _mode_row(lin) -> np.ndarray:
    row = np.zeros((1, lin.red.n_reduced))
    row[0, lin.k] = 1.0
    return row


class Extension:
    """One cause as FE physics: its parameter and how it enters the simulation."""

    cause = ""
    parameter = ""
    unit = ""
    description = ""
    lower, upper = 0.0, math.inf
    #: whether the effect can raise the stiffness: then a level's frequency may pass
    #: the stuck-joint one and its damping ratio fall below the viscous one
    stiffens = False
    #: the fitted value scales as ``s ** force_scale_power`` with the assumed force scale
    #: ``s`` (N per excitation unit; omega^2 and zeta are invariant to it): 0 = it does not
    force_scale_power = 0

    def step(self, fe, base, noise, top) -> float:
        """A parameter change that moves the top fit level by about one noise unit."""
        raise NotImplementedError

    def spec(self, fe, base, noise, top: int) -> Parameter:
        """The parameter, its step from the base fit ``base`` (a LevelPrediction) at
        level index ``top`` (the highest fit level)."""
        return Parameter(self.parameter, 0.0, self.lower, self.upper,
                         self.step(fe, base, noise, top), self.unit, self.description)

    def starts(self, spec: Parameter) -> list:
        """Start values of the multi-start fit (the effect may be invisible at 0; two
        starts: on the shipped data a third one, 30 steps, found nothing better)."""
        return [0.0, 10.0 * spec.step]

    @property
    def parameter_names(self) -> tuple:
        return (self.parameter,)

    def start_sets(self, specs) -> list:
        """Start dicts of the multi-start fit, one per start value."""
        return [{self.parameter: v} for v in self.starts(specs[0])]

    def apply(self, p, fe, lin, scale, forces):
        """(scale, forces, elements) of the first-harmonic balance with the effect."""
        return scale, forces, ()

    def reading(self, p, fe, lin, pred) -> dict:
        """Physical reading of the fitted value."""
        return {}


class MacroSlip(Extension):
    cause, parameter = "macro-slip", "ln_phimax"
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


class AirDrag(Extension):
    cause, parameter, unit = "quadratic-damping", "drag_cd", "1"
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
        return scale, forces, (QuadraticDamper(_mode_row(lin), np.array([self.c2(p, lin)])),)

    def reading(self, p, fe, lin, pred):
        c2 = self.c2(p, lin)
        return {"C_D": float(p[self.parameter]), "modal_c2": c2,
                "zeta_added_top_level": float(4.0 / (3.0 * math.pi) * c2
                                              * pred.modal_amplitude[-1])}


class CubicHardening(Extension):
    cause, parameter, unit = "geometric-hardening", "k3", "1/(kg s^2 m^2)"
    description = "modal cubic stiffness k3 (mass-normalized mode)"
    stiffens = True
    force_scale_power = -2        # omega^2 rise ~ k3 x amplitude^2, amplitude ~ s

    def step(self, fe, base, noise, top):
        a = float(base.modal_amplitude[top])
        return float(noise.sigma_omega2[top] / (0.75 * a * a))

    def apply(self, p, fe, lin, scale, forces):
        return scale, forces, (CubicSpring(_mode_row(lin), np.array([float(p["k3"])])),)

    def reading(self, p, fe, lin, pred):
        a = float(pred.modal_amplitude[-1])
        return {"k3": float(p[self.parameter]),
                "omega2_rise_top_level": 0.75 * float(p[self.parameter]) * a * a}


class ThermalDrift(Extension):
    cause, parameter, unit = "thermal-drift", "drift", "1/run"
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


class ForceCompression(Extension):
    cause, parameter, unit = "nonproportional-amplitude", "inv_e_sat", "1/excitation unit"
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


class Combined(Extension):
    """Two causes at once (the diagnosis's ``also``): ``first`` already fitted (its
    value is kept as the start), ``second`` from its own starts."""

    def __init__(self, first: Extension, second: Extension):
        self.first, self.second = first, second
        self.cause = f"{first.cause}+{second.cause}"
        self.stiffens = first.stiffens or second.stiffens

    @property
    def parameter_names(self):
        return self.first.parameter_names + self.second.parameter_names

    def spec(self, fe, base, noise, top):
        return [self.first.spec(fe, base, noise, top), self.second.spec(fe, base, noise, top)]

    def start_sets(self, specs):
        return self.second.start_sets(specs[len(self.first.parameter_names):])

    def apply(self, p, fe, lin, scale, forces):
        scale, forces, e1 = self.first.apply(p, fe, lin, scale, forces)
        scale, forces, e2 = self.second.apply(p, fe, lin, scale, forces)
        return scale, forces, tuple(e1) + tuple(e2)

    def reading(self, p, fe, lin, pred):
        return {**self.first.reading(p, fe, lin, pred), **self.second.reading(p, fe, lin, pred)}


EXTENSIONS = {e.cause: e for e in (MacroSlip(), AirDrag(), CubicHardening(), ThermalDrift(),
                                   ForceCompression())}


def force_scale_power(parameter: str) -> int:
    """How the fitted ``parameter`` scales with the assumed force scale s: s^power
    (:attr:`Extension.force_scale_power`; 0 for the base parameters and any other)."""
    return next((e.force_scale_power for e in EXTENSIONS.values()
                 if e.parameter == parameter), 0)

# every FE realization is a cause of the plug-in catalogue (inverse/diagnosis/causes/)
_unknown = sorted(set(EXTENSIONS) - set(CATALOGUE))
if _unknown:
    raise ImportError(f"FE realizations of causes not in the catalogue: {_unknown}")
