"""One face per case: its model, measured data, nonlinear model and what it can do.

A :class:`Case` is a typed object; each capability (:data:`CAPABILITIES`) is one of its
methods (``_<capability>`` in a subclass), offered when the case qualifies for it
(:meth:`Case.offers`). A command asks
for a capability (:meth:`Case.require`); a case that lacks it is a one-line
:class:`ident.errors.InputError` naming the case and what it offers, or the case's own
reason when it declines a capability it could offer (:attr:`Case.refused`). The kinds of case: a case file
(:class:`cases.case_file.CaseFileCase`, built from its TOML alone), the double beam
(:class:`cases.double_beam.case.DoubleBeamCase`: its case file with the Python model of
the paper's study beside it) and the lumped 10-DOF model
(:class:`cases.lumped10.case.LumpedCase`). They come from :mod:`cases.registry` (a
shipped name or a case file).
"""
from __future__ import annotations

from typing import Callable

from ident.errors import InputError

__all__ = ["CAPABILITIES", "Case"]

#: capability -> what it means (the wording of the error when a case lacks it)
CAPABILITIES = {
    "fe_model": "FE strip model (modes, convergence, render, export)",
    "summary": "model summary (case check)",
    "calibrated_file": "case file with its calibration (modes, case check)",
    "measured_data": "measured data",
    "nonlinear_model": "nonlinear model with every joint parameter given (backbone)",
    "update": "FE model updating against its measured levels (update, loop)",
    "update_modes": "one joint fitted to several measured modes (update --modes, loop "
                    "--fit-modes)",
    "fe_levels": "FE-levels model of measured levels (diagnose DATA --case)",
    "fe_check": "FE-level check of a one-mode diagnosis (diagnose DATA --case)",
    "uncertainty": "Monte Carlo of its own stepped-sine study (uncertainty)",
    "fe_uncertainty": "Monte Carlo of its FE-levels predictions over update's model "
                      "(uncertainty)",
}


class Case:
    """A case: ``name`` (used in outputs), ``description``, ``source`` (its file or
    module), ``file`` (the checked case file, or None); a subclass defines a method
    ``_<capability>`` per capability it can have and says in :meth:`offers` which it has."""

    def __init__(self, name: str, description: str, source: str, file=None):
        self.name, self.description, self.source, self.file = name, description, source, file

    def offers(self) -> tuple:
        """The capabilities this case has (a subclass's)."""
        return ()

    @property
    def refused(self) -> dict:
        """capability -> why this case refuses it (one line)."""
        return {}

    @property
    def capabilities(self) -> tuple:
        offered = set(self.offers())
        return tuple(c for c in CAPABILITIES if c in offered)

    @property
    def builders(self) -> dict:
        """capability -> its bound method, for every capability offered."""
        return {c: getattr(self, f"_{c}") for c in self.capabilities}

    def require(self, capability: str) -> Callable:
        """The method of ``capability``, or InputError (one line)."""
        why = self.refused.get(capability)
        if why:
            raise InputError(why)
        if capability not in self.capabilities:
            offers = ", ".join(self.capabilities) or "nothing"
            raise InputError(f"case {self.name!r} has no {CAPABILITIES[capability]} "
                             f"(it offers: {offers})")
        return getattr(self, f"_{capability}")

    def fe_model(self, **options):
        """The linear FE model (``options``: e.g. ``element_size``, ``calibrated``)."""
        return self.require("fe_model")(**options)

    def measured_data(self):
        """Path of the measured-data table."""
        return self.require("measured_data")()

    def nonlinear_model(self, mode: int | None = None):
        """The jointed model (:class:`casefile.jointed.NonlinearCase`)."""
        return self.require("nonlinear_model")(mode=mode)

    def summary(self) -> dict:
        """The model summary of ``case check``."""
        return self.require("summary")()
