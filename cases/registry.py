"""The shipped cases by name: the one registry every ``--case`` option resolves through.

``CASES`` names the FE models of the shipped cases. :func:`build_case` builds one (the
estimator takes it as a duck-typed model, see :mod:`inverse.fe_reference`),
:func:`case_modes` gives its lowest modes (render, export), :func:`mode_table` the
``iwanfe modes`` report, :data:`MEASURED_DATA` the measured data shipped with a case,
and :func:`fe_check` the FE-level check of a diagnosis on the case's model. The case
modules are imported only when a case is built (the command line starts quickly).
"""
from __future__ import annotations

import numpy as np

from cases.paper_data import DATA_FILE
from ident.errors import InputError

CASES = ("double-beam",)
#: Cases with a nonlinear (jointed) model: ``iwanfe backbone --case``
#: (:func:`nonlinear_case`).
NONLINEAR_CASES = ("double-beam", "lumped")
#: Measured-data CSV shipped with each case (``iwanfe diagnose --case NAME``).
MEASURED_DATA = {"double-beam": DATA_FILE}


def _check_known(name: str) -> None:
    """InputError (one line) unless ``name`` is a shipped case."""
    if name not in CASES:
        raise InputError(f"unknown case {name!r}; known: {', '.join(CASES)}")


def build_case(name: str):
    """The FE model of the shipped case ``name`` (its default configuration)."""
    _check_known(name)
    from cases.double_beam.model import DoubleBeamConfig, build_double_beam

    return build_double_beam(DoubleBeamConfig())


def case_modes(model, n_modes: int):
    """Lowest ``n_modes`` modes of ``model``: (frequencies in Hz, shapes (n_free, n))."""
    if n_modes < 1:
        raise ValueError(f"number of modes must be >= 1, got {n_modes}")
    n_free = getattr(model, "n_free", None)
    if n_free is not None and n_modes > n_free:
        raise ValueError(f"the model has only {n_free} degrees of freedom, asked for {n_modes} modes")
    omega, shapes = model.modes(n_modes)
    omega = np.asarray(omega, dtype=float)
    shapes = np.asarray(shapes)
    if omega.size < n_modes or shapes.ndim != 2 or shapes.shape[1] < n_modes:
        raise ValueError(f"the model has only {omega.size} modes, asked for {n_modes}")
    return omega[:n_modes] / (2 * np.pi), shapes[:, :n_modes]


def mode_table(name: str, **options) -> dict:
    """The ``iwanfe modes`` report of case ``name``: modes in a band with kind and glue
    slip, and the calibration statement (``options``: see
    :func:`cases.double_beam.mode_table.double_beam_report`)."""
    _check_known(name)
    from cases.double_beam.mode_table import double_beam_report

    return double_beam_report(**options)


def fe_check(name: str, measured_omega2: float) -> dict:
    """FE-level check of a diagnosis on the model of case ``name``
    (:func:`cases.double_beam.fe_check.double_beam_fe_check`)."""
    _check_known(name)
    from cases.double_beam.fe_check import double_beam_fe_check

    return double_beam_fe_check(measured_omega2=measured_omega2)


def nonlinear_case(name: str, **options):
    """The jointed model of case ``name`` in :data:`NONLINEAR_CASES`
    (:func:`cases.nonlinear_case.build_nonlinear_case`)."""
    if name not in NONLINEAR_CASES:
        raise InputError(f"unknown case {name!r}; known: {', '.join(NONLINEAR_CASES)}")
    from cases.nonlinear_case import build_nonlinear_case

    return build_nonlinear_case(name, **options)
