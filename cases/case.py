"""One face per case: its model, measured data, nonlinear model and what it can do.

A command asks a :class:`Case` for a capability (:meth:`Case.require`); a case that lacks
it is a one-line :class:`ident.errors.InputError` naming the case and what it offers, or
the case's own reason when it refuses the capability (:attr:`Case.refused`: a case file
whose joint law the FE loop does not fit).
Cases come from :mod:`cases.registry` (a shipped name or a case file).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ident.errors import InputError

#: capability -> what it means (the wording of the error when a case lacks it)
CAPABILITIES = {
    "fe_model": "FE strip model (modes, convergence, render, export)",
    "summary": "model summary (case check)",
    "measured_data": "measured data",
    "nonlinear_model": "nonlinear model with every joint parameter given (backbone)",
    "update": "FE model updating against its measured levels (update, loop)",
    "fe_levels": "FE-levels model of measured levels (diagnose DATA --case)",
    "fe_check": "FE-level check of a one-mode diagnosis (diagnose DATA --case)",
    "uncertainty": "Monte Carlo of its own stepped-sine study (uncertainty)",
    "fe_uncertainty": "Monte Carlo of its FE-levels predictions over update's model "
                      "(uncertainty)",
}


@dataclass
class Case:
    """A case: ``name`` (used in outputs), ``source`` (its file or module), and one
    builder per capability (:data:`CAPABILITIES`)."""

    name: str
    description: str
    source: str
    builders: dict = field(default_factory=dict)
    file: object = None          # the checked case file, when the case is one
    refused: dict = field(default_factory=dict)   # capability -> why not (one line)

    @property
    def capabilities(self) -> tuple:
        return tuple(c for c in CAPABILITIES if c in self.builders)

    def require(self, capability: str) -> Callable:
        """The builder of ``capability``, or InputError (one line)."""
        if capability in self.refused:
            raise InputError(self.refused[capability])
        if capability not in self.builders:
            offers = ", ".join(self.capabilities) or "nothing"
            raise InputError(f"case {self.name!r} has no {CAPABILITIES[capability]} "
                             f"(it offers: {offers})")
        return self.builders[capability]

    def fe_model(self, **options):
        """The linear FE model (``options``: e.g. ``element_size``, ``calibrated``)."""
        return self.require("fe_model")(**options)

    def measured_data(self):
        """Path of the measured-data table."""
        return self.require("measured_data")()

    def nonlinear_model(self, mode: int | None = None):
        """The jointed model (:class:`cases.nonlinear_case.NonlinearCase`)."""
        return self.require("nonlinear_model")(mode=mode)

    def summary(self) -> dict:
        return self.require("summary")()
