"""Weak-joint reruns of the double-beam simulation: the estimator against a planted chi.

The simulation's joint (:mod:`cases.double_beam.joint_setup`) softens the glue by up to
a fifth of its stiffness, past the decoupling the estimator assumes. Rerunning with the
same ``chi`` and a smaller ``R`` (:func:`weak_joint_recovery`) keeps the glue nearly
stuck, so the recovered chi shows how the estimator's error depends on the softening.
"""
from __future__ import annotations

import dataclasses

from cases.double_beam.joint_setup import JointSetup
from cases.double_beam.pipeline import simulate_study
from cases.double_beam.settings import DoubleBeamStudy

__all__ = ["weak_joint_recovery"]


def weak_joint_recovery(study: DoubleBeamStudy, setup: JointSetup, store=None,
                        progress: bool = True, workers: int = 1, model=None,
                        executor=None, protocol: str = "hb") -> list[dict]:
    """Rerun the simulation with ``R`` times each of ``study.weak_joint_scales``.

    The joint's relative softening at a given level scales with ``R`` (``kappa2
    A^(chi+1) / K_T`` at fixed slip), so these runs show how close the estimator gets to
    the input chi when the glue stays nearly stuck: the decoupling of eq. 29-30 and the
    proportional amplitudes of eq. 33 then hold. One row per scale: top-level slip,
    loss ratio and modal-filter ratio at the last fit level, and per method the chi and
    R~ recovered from the LSCF and the modal-filter data.
    """
    rows = []
    for k in study.weak_joint_scales:
        sub = dataclasses.replace(study, chi=setup.chi, R=setup.R * k, weak_joint_scales=())
        rep = simulate_study(sub, store=store, progress=progress, workers=workers,
                             model=model, executor=executor, protocol=protocol)
        c = rep.comparison()
        i7 = max(i for i, r in enumerate(c) if r["level"] in study.fit)
        mf = rep.modal_filter
        row = {"R_scale": float(k), "R": rep.setup.R, "phi_max": rep.setup.phi_max,
               "top_slip_over_phi_max": float(rep.slip_over_phi_max[-1]),
               "last_fit_level": c[i7]["level"],
               "loss_ratio_last_fit_level": c[i7]["loss_ratio"],
               "slip_per_force_relative_last_fit_level": c[i7]["slip_per_force_relative"],
               "modal_filter_ratio_last_fit_level": float(mf.delta_c[i7]
                                                          / mf.delta_c_decoupled[i7]),
               "recovery": {"lscf": rep.recovery("lscf"),
                            "modal_filter": rep.recovery("modal_filter")}}
        if rep.protocol_comparison is not None:
            row["protocol_comparison"] = rep.protocol_comparison
        rows.append(row)
    return rows
