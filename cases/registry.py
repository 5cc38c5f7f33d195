"""The shipped cases, and ``--case NAME|FILE``: every ``--case`` resolves here.

:func:`resolve_case` gives a :class:`cases.case.Case` for a shipped name
(:data:`SHIPPED`: each a case file, or a Python case such as the lumped 10-DOF model) or
for a path to a ``.toml`` case file; a case file with iwan4 joints and measured data
gets the generic FE loop (:mod:`feloop.case_file` on :mod:`feloop`); the double beam
is :class:`cases.double_beam.case.DoubleBeamCase` (its Python FE-levels model for
``update``, ``fe_levels``, and its own ``fe_check`` and ``uncertainty``). The older helpers
below serve ``estimate --case``:
:func:`build_case` builds the double beam's Python model (equal to its case file's to
~2e-8 in frequency, the calibrated clamp grip's last digits), :data:`MEASURED_DATA`,
:func:`fe_check`. The case modules are imported only when a case is built.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cases.paper_data import DATA_FILE
from ident.errors import InputError

_HERE = Path(__file__).resolve().parent
#: shipped case files by name
CASE_FILES = {"double-beam": _HERE / "double_beam" / "double-beam.toml",
              "brb": _HERE / "brb" / "brb.toml"}
#: every shipped name: the case files and the Python cases
SHIPPED = (*CASE_FILES, "lumped")

#: the case a command studies when ``--case`` is not given
DEFAULT_CASE = "double-beam"
CASES = ("double-beam",)
#: Measured-data CSV shipped with each case (``iwanfe diagnose --case NAME``).
MEASURED_DATA = {"double-beam": DATA_FILE}


def resolve_case(name_or_file: str, model=None):
    """The :class:`cases.case.Case` of a shipped name or of a case file path; ``model``:
    an ``updated_model.json`` of ``iwanfe update`` on that case, whose fitted model the
    case then is (case files and the shipped case files; not the lumped case)."""
    from cases.case_file import case_from_file

    key = str(name_or_file)
    if key == "double-beam" and model is None:     # its case file and its Python study
        from cases.double_beam.case import DoubleBeamCase
        from casefile.schema import read_case_file

        return DoubleBeamCase(read_case_file(CASE_FILES[key]))
    if key in CASE_FILES:
        return case_from_file(CASE_FILES[key], model=model)
    if key == "lumped":
        if model is not None:
            raise InputError("case 'lumped' has no FE model to update (--model)")
        from cases.lumped10.case import LumpedCase

        return LumpedCase()
    if key.endswith(".toml") or Path(key).is_file():
        return case_from_file(key, model=model)
    raise InputError(f"unknown case {key!r}: give a shipped name ({', '.join(SHIPPED)}) "
                     f"or a case file (.toml)")


def _check_known(name: str) -> None:
    """InputError (one line) unless ``name`` is a case of the older helpers."""
    if name not in CASES:
        raise InputError(f"unknown case {name!r}; known: {', '.join(CASES)}")


def build_case(name: str):
    """The FE model of a case of :data:`CASES` (the double beam's Python model)."""
    _check_known(name)
    from cases.double_beam.model import DoubleBeamConfig, build_double_beam

    return build_double_beam(DoubleBeamConfig())


def case_modes(model, n_modes: int):
    """Lowest ``n_modes`` modes of ``model``: (frequencies in Hz, shapes (n_free, n))."""
    if n_modes < 1:
        raise ValueError(f"number of modes must be >= 1, got {n_modes}")
    n_free = getattr(model, "n_free", None)
    if n_free is not None and n_modes > n_free:
        raise ValueError(f"the model has only {n_free} degrees of freedom, "
                         f"asked for {n_modes} modes")
    omega, shapes = model.modes(n_modes)
    omega = np.asarray(omega, dtype=float)
    shapes = np.asarray(shapes)
    if omega.size < n_modes or shapes.ndim != 2 or shapes.shape[1] < n_modes:
        raise ValueError(f"the model has only {omega.size} modes, asked for {n_modes}")
    return omega[:n_modes] / (2 * np.pi), shapes[:, :n_modes]


def fe_check(name: str, measured_omega2: float) -> dict:
    """FE-level check of a diagnosis on the model of case ``name``
    (:func:`cases.double_beam.fe_check.double_beam_fe_check`)."""
    _check_known(name)
    from cases.double_beam.fe_check import double_beam_fe_check

    return double_beam_fe_check(measured_omega2=measured_omega2)

