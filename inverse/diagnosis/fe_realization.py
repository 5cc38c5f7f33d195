"""The FE realization of a cause: the face every cause's ``FE_REALIZATION`` has.

A cause of the catalogue (``inverse/diagnosis/causes/<id>.py``) with a physical mechanism
holds, beside its one-mode model, one :class:`Extension` of the FE-levels model
(:mod:`feloop.levels`): one extra parameter (nested: its ``none`` value gives back the
base model), a realization in the first-harmonic balance (:mod:`fe.hb_resonance`: an
element, a per-level stiffness scale or a per-level force) and the physical reading of
the fitted value. SI units. :class:`Combined` puts two of them together (the
diagnosis's ``also``). The FE level (:mod:`feloop.causes`) tests every cause whose
``FE_REALIZATION`` is set and lists the others as not tested at the FE level.
"""
from __future__ import annotations

import math

import numpy as np

from inverse.update import Parameter

__all__ = ["AIR_DENSITY", "ALUMINIUM_DLNE_DT", "mode_row", "Extension", "Combined"]

AIR_DENSITY = 1.204          # kg/m^3 at 20 C (assumed)
ALUMINIUM_DLNE_DT = -4.0e-4  # 1/K, (1/E) dE/dT of wrought aluminium alloys (assumed)


def mode_row(lin) -> np.ndarray:
    """(1, n) row picking the measured mode's coordinate of the reduced model ``lin``."""
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
    #: the order in which the FE level fits the realizations (each fit warm-starts the
    #: next simulation, so the order is part of the result)
    fit_order = 100
    #: the joint laws whose FE-levels model it extends (:mod:`feloop.joint_forms`;
    #: empty: every law)
    laws: tuple = ()
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
