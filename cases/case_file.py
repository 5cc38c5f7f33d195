"""A case file as a :class:`cases.case.Case`: the FE model (calibrated, or at the file's
values), the measured data it names, its nonlinear model when every joint parameter is
given (any joint law, :mod:`casefile.laws`), its summary, and (joint interfaces with law
``iwan4`` and their ``kt``, a drive and a measured-data table) its FE-levels model and
``update`` (:mod:`feloop.case_file`). A file of another law refuses ``update``,
``fe_levels`` and ``fe_uncertainty`` in one line that says which commands take its law
(:func:`feloop.case_file.refusal`)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

from cases.case import Case
from casefile.build import build_model
from feloop import case_file as fe_loop
from casefile.calibrate import calibrate
from casefile.nonlinear import missing_joint_parameters, nonlinear_case
from casefile.schema import read_case_file
from casefile.summary import case_summary


def case_from_file(path, model=None) -> Case:
    """Read and check the case file at ``path`` (CaseFileError on a fault); ``model``: an
    ``updated_model.json`` of ``iwanfe update`` whose fitted joints and structure replace
    the file's (:func:`feloop.updated_model.updated_file`)."""
    cf = read_case_file(Path(path))
    if model is not None:
        from feloop.updated_model import updated_file

        cf = updated_file(cf, model)

    def file_at(element_size=None, calibrated=True):
        f = cf if element_size is None else dataclasses.replace(
            cf, element_size=float(element_size))
        return calibrate(f) if calibrated else (f, None)

    def fe_model(element_size=None, calibrated=True):
        return build_model(file_at(element_size, calibrated)[0]).model

    def summary():
        f, report = file_at()
        return case_summary(f, build_model(f), report)

    builders = {"fe_model": fe_model, "summary": summary, "calibrated_file": file_at}
    if cf.measured is not None and cf.measured.files:
        builders["measured_data"] = lambda: cf.measured.file
    joints = any(i.tangential == "joint" for i in cf.interfaces)
    if joints and cf.drive is not None and not missing_joint_parameters(cf):
        builders["nonlinear_model"] = lambda mode=None: nonlinear_case(
            file_at()[0], fe_model(), mode=mode)
    if fe_loop.qualifies(cf):
        builders["fe_levels"] = fe_loop.levels_builder(cf)
        builders["update"] = fe_loop.update_builder(cf)
        builders["fe_uncertainty"] = fe_loop.uncertainty_builder(cf)
    why = fe_loop.refusal(cf)
    refused = {c: why for c in ("update", "fe_levels", "fe_uncertainty")} if why else {}
    return Case(name=cf.name, description=cf.description, source=str(cf.path),
                builders=builders, file=cf, refused=refused)
