"""A case file as a :class:`cases.case.Case`: the FE model (calibrated, or at the file's
values), the measured data it names, its nonlinear model when every joint parameter is
given (any joint law, :mod:`casefile.laws`), its summary, and (joint interfaces of one
law with their ``kt``, a drive and a measured-data table) its FE-levels model and
``update`` and ``fe_uncertainty`` (:mod:`feloop.case_file`), for every joint law
(:mod:`feloop.joint_forms`)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

from cases.case import Case
from casefile.build import build_model
from feloop import case_file as fe_loop
from casefile.calibrate import calibrate
from casefile.nonlinear import missing_joint_parameters, nonlinear_case
from casefile.schema import read_case_file
from casefile.spec import is_base_drive
from casefile.summary import case_summary


class CaseFileCase(Case):
    """A case file as a case (module docstring); ``cf`` the checked file."""

    def __init__(self, cf):
        super().__init__(cf.name, cf.description, str(cf.path), cf)

    def offers(self) -> tuple:
        cf, out = self.file, ["fe_model", "summary", "calibrated_file"]
        if cf.measured is not None and cf.measured.files:
            out.append("measured_data")
        joints = any(i.tangential == "joint" for i in cf.interfaces)
        if joints and cf.drive is not None and not missing_joint_parameters(cf):
            out.append("nonlinear_model")
        if fe_loop.qualifies(cf):
            out += ["fe_levels", "update", "update_modes", "fe_uncertainty"]
        return tuple(out)

    @property
    def refused(self) -> dict:
        """A base drive (``[drive] kind = "base"``): the FE loop knows a point force only."""
        cf = self.file
        if not (is_base_drive(cf.drive) and cf.measured is not None and cf.measured.files):
            return {}
        why = (f"{cf.path}: base drive not supported by the FE loop (update, loop, diagnose "
               f"--case, uncertainty) yet: it fits levels driven at a point")
        return dict.fromkeys(("fe_levels", "fe_check", "update", "fe_uncertainty"), why)

    def _calibrated_file(self, element_size=None, calibrated=True):
        """(the file at ``element_size``, calibrated unless told not to; its report)."""
        f = self.file if element_size is None else dataclasses.replace(
            self.file, element_size=float(element_size))
        return calibrate(f) if calibrated else (f, None)

    def _fe_model(self, element_size=None, calibrated=True):
        return build_model(self._calibrated_file(element_size, calibrated)[0]).model

    def _summary(self):
        f, report = self._calibrated_file()
        return case_summary(f, build_model(f), report)

    def _measured_data(self):
        return self.file.measured.file

    def _nonlinear_model(self, mode=None):
        return nonlinear_case(self._calibrated_file()[0], self._fe_model(), mode=mode)

    def _fe_levels(self, data, force_scale: float = 1.0):
        return fe_loop.levels_builder(self.file)(data, force_scale=force_scale)

    def _update(self, **options):
        return fe_loop.update_builder(self.file)(**options)

    def _update_modes(self, **options):
        return fe_loop.modes_builder(self.file)(**options)

    def _fe_uncertainty(self, *args, **options):
        return fe_loop.uncertainty_builder(self.file)(*args, **options)


def case_from_file(path, model=None) -> CaseFileCase:
    """Read and check the case file at ``path`` (CaseFileError on a fault); ``model``: an
    ``updated_model.json`` of ``iwanfe update`` whose fitted joints and structure replace
    the file's (:func:`feloop.updated_model.updated_file`)."""
    cf = read_case_file(Path(path))
    if model is not None:
        from feloop.updated_model import updated_file

        cf = updated_file(cf, model)
    return CaseFileCase(cf)
