"""The shipped cases, and ``--case NAME|FILE``: every ``--case`` resolves here.

:func:`resolve_case` gives a :class:`cases.case.Case` for a shipped name
(:data:`SHIPPED`: each a case file, or a Python case such as the lumped 10-DOF model) or
for a path to a ``.toml`` case file; a case file with iwan4 joints and measured data
gets the generic FE loop (:mod:`feloop.case_file` on :mod:`feloop`), the
double beam puts its Python FE-levels model in (``update``, ``fe_levels``) and adds its
own ``fe_check`` and ``uncertainty`` (a stepped sine per sample). The older helpers
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
    key = str(name_or_file)
    if key in CASE_FILES:
        from cases.case_file import case_from_file

        case = case_from_file(CASE_FILES[key], model=model)
        if key == "double-beam" and model is None:   # its joints: chi, R~ from its levels
            from cases.nonlinear_case import build_nonlinear_case

            case.builders["nonlinear_model"] = lambda mode=None: build_nonlinear_case(
                "double-beam", mode=mode)
            case.builders["update"] = _double_beam_update
            case.builders["fe_levels"] = _double_beam_levels
            case.builders["fe_check"] = lambda measured_omega2: fe_check(
                "double-beam", measured_omega2)
            case.builders["uncertainty"] = _double_beam_uncertainty
        return case
    if key == "lumped":
        if model is not None:
            raise InputError("case 'lumped' has no FE model to update (--model)")
        return _lumped_case()
    if key.endswith(".toml") or Path(key).is_file():
        from cases.case_file import case_from_file

        return case_from_file(key, model=model)
    raise InputError(f"unknown case {key!r}: give a shipped name ({', '.join(SHIPPED)}) "
                     f"or a case file (.toml)")


def _double_beam_update(executor="serial", progress=False, store=None, **settings):
    """``run_update`` of the double beam's Python model on its shipped data, mode label 2,
    fit levels 1-7 (``settings``: fields of :class:`feloop.update.UpdateSettings`)."""
    from cases.double_beam.fe_levels import DoubleBeamLevels, assumption_variants
    from cases.double_beam.model import DoubleBeamConfig
    from cases.double_beam.settings import DEFAULT_DATA
    from feloop.update import UpdateSettings, run_update

    settings = {"data_path": str(DEFAULT_DATA), "mode_label": 2, "fit_levels": "1-7",
                **{k: v for k, v in settings.items() if v is not None}}
    variants = assumption_variants() if settings.get("assumptions") else None
    from casefile.schema import read_case_file
    from feloop.case_file import fitted_plausibility

    r = run_update(UpdateSettings(**settings), DoubleBeamLevels.from_data, executor=executor,
                   progress=progress, store=store, case_name="double-beam",
                   model_key=repr(DoubleBeamConfig()), assumptions=variants)
    # the same glue interface as its case file describes
    r["plausibility"] = fitted_plausibility(read_case_file(CASE_FILES["double-beam"]), r)
    return r


def _double_beam_uncertainty(settings, **options):
    """The double beam's Monte Carlo (:func:`cases.double_beam.uncertainty_report.
    run_uncertainty`: a stepped sine per sample)."""
    from cases.double_beam.uncertainty_report import run_uncertainty

    return run_uncertainty(settings, **options)


def _double_beam_levels(data, force_scale: float = 1.0):
    """The double beam's FE-levels model (its Python model) of ``data``."""
    from cases.double_beam.fe_levels import DoubleBeamLevels

    return DoubleBeamLevels.from_data(data, force_scale=force_scale)


def _lumped_case():
    from cases.case import Case
    from cases.nonlinear_case import lumped_case

    def nonlinear(mode=None):
        case = lumped_case() if mode is None else lumped_case(mode=int(mode))
        if mode is not None:
            if not 1 <= int(mode) <= case.model.n_reduced:
                raise ValueError(f"mode must be in 1..{case.model.n_reduced}, got {mode}")
            case.mode = int(mode)
        return case

    return Case(name="lumped", description="the paper's lumped 10-DOF model (eq. 38-40) "
                "with two Iwan joints", source="cases.lumped10",
                builders={"nonlinear_model": nonlinear})


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

