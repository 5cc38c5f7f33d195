"""Untested levels predicted by the FE backbone of an estimated joint.

:func:`predict_from_backbone` puts the joint of an estimate (chi and R~ from the damping
growth of the fit levels, :func:`inverse.estimate.estimate` with the case's FE model)
into the case's FE model as the case study does (:func:`cases.double_beam.joint_setup.joint_setup`:
one Iwan element per glue node, ``beta = 0``, viscous damping matched to the lowest
level), computes the nonlinear mode by EPMC (:mod:`fe.epmc`, exact-DF path: no slider
discretization) and reads it at the resonance of every level's force (eq. 1 of
:mod:`fe.backbone`: single nonlinear mode, drive at the case's drive DOF). Unlike the
estimator's closed-form predictions (paper eq. 43, 46), the backbone keeps the mode's
change of shape, the glue's distributed slip and macro-slip.
"""
from __future__ import annotations

import numpy as np

from fe.epmc import epmc_backbone
from fe.joint_harmonics import ExactHarmonics
from ident.errors import InputError

__all__ = ["predict_from_backbone"]


def predict_from_backbone(data, est, case_name: str = "double-beam",
                          force_scale: float = 1.0, n_points: int = 60,
                          max_extensions: int = 4) -> dict:
    """Frequency, damping and slip of every level of ``data`` from the FE backbone.

    Parameters
    ----------
    data : MeasuredData (the estimate's mode is used)
    est : inverse.estimate.Estimate
        Computed with the case's FE model (``est.case``), so that chi and R~ exist.
    case_name : str
        Only ``double-beam`` has a joint setup (the FE model of :mod:`cases.registry`).
    force_scale : float
        N per unit of the excitation column (as given to the estimate).

    Returns
    -------
    dict
        ``chi``, ``R``, ``phi_max``, ``fe_mode``, ``levels`` (per level: excitation,
        force, predicted and measured omega2 and zeta, largest slip over phi_max,
        ``held_out``), ``points`` (backbone size).
    """
    if case_name != "double-beam":
        raise InputError(f"--backbone: no joint setup for case {case_name!r} (double-beam)")
    if est.case is None or est.R is None:
        raise InputError("--backbone needs an estimate with the case's FE model (--case)")
    from cases.double_beam.joint_setup import joint_setup, nonlinear_model
    from cases.double_beam.model import build_double_beam
    from cases.double_beam.settings import DoubleBeamStudy

    d = data.for_mode(est.mode)
    study = DoubleBeamStudy(force_scale=float(force_scale))
    fe = build_double_beam()
    setup = joint_setup(fe, d, study, source=est)
    red, _ = nonlinear_model(fe, setup, study)
    joints = ExactHarmonics(setup.params, red.n_joints)
    force = force_scale * np.asarray(d.excitation, dtype=float)
    s_lin = float(np.max(setup.slip_level1_linear)) * force / force[0]
    lo, hi = 0.25 * s_lin.min(), 4.0 * s_lin.max()
    for _ in range(max_extensions + 1):
        bb = epmc_backbone(red, joints, setup.fe_mode, np.geomspace(lo, hi, n_points))
        F = bb.force_at_resonance(int(fe.drive_dof))
        if F[-1] >= force.max() and F[0] <= force.min() and np.all(np.diff(F) > 0):
            break
        lo, hi = (lo / 4 if F[0] > force.min() else lo), hi * 4
    ok = (force >= F[0]) & (force <= F[-1]) if np.all(np.diff(F) > 0) else np.zeros_like(force, bool)
    n = force.size
    om2, zeta, ratio = (np.full(n, np.nan) for _ in range(3))
    if ok.any():
        p = bb.at_force(force[ok], int(fe.drive_dof))
        om2[ok], zeta[ok] = p["omega2"], p["zeta"]
        ratio[ok] = p["slip_amplitude"].max(axis=1) / setup.phi_max
    levels = [{"level": int(d.level[i]), "excitation": float(d.excitation[i]),
               "force_N": float(force[i]), "held_out": int(d.level[i]) not in est.fit_levels,
               "omega2": None if np.isnan(om2[i]) else float(om2[i]),
               "zeta": None if np.isnan(zeta[i]) else float(zeta[i]),
               "slip_over_phi_max": None if np.isnan(ratio[i]) else float(ratio[i]),
               "measured_omega2": float(d.omega2[i]), "measured_zeta": float(d.zeta[i])}
              for i in range(n)]
    return {"case": case_name, "fe_mode": setup.fe_mode, "chi": setup.chi, "R": setup.R,
            "phi_max": setup.phi_max, "zeta_viscous": setup.zeta_viscous,
            "path": "exact", "points": len(bb), "levels": levels}
