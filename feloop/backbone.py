"""Untested levels predicted by the FE backbone of an estimated joint, for any case.

:func:`predict_from_backbone` puts the joint of an estimate (chi and ``|kappa1| B~`` from
the damping growth of the fit levels, :func:`inverse.estimate.estimate` with the case's
FE model) into the case's FE-levels model (:class:`feloop.levels.FELevels`: one
Iwan element per joint element, ``beta = 0``, the reduced basis with static joint
modes) with the stuck frequency and the viscous modal damping matched so that the
lowest level has its measured omega^2 and damping ratio (eq. 2 of
:mod:`inverse.estimate`: ``omega_n^2 = Omega_1^2 + (kappa2/|kappa1|) dc1``,
``zeta_v = (zeta_1 - dc1 / (2 Omega_1^2)) Omega_1 / omega_n``, ``dc1 = |kappa1| B~``
at level 1; the stiffness scaled by ``omega_n^2 / omega_k^2``, structure and joints
alike, as ``f0_hz`` of :class:`FELevels` does), computes the nonlinear
mode by EPMC (:mod:`fe.epmc`, exact-DF path: no slider discretization) and reads it at
the resonance of every level's force (eq. 1 of :mod:`fe.backbone`: single nonlinear
mode, drive at the case's drive DOF). Unlike the estimator's closed-form predictions
(paper eq. 43, 46), the backbone keeps the mode's change of shape, the joints'
distributed slip and macro-slip. SI units.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from fe.epmc import epmc_backbone
from fe.joint_harmonics import ExactHarmonics
from ident.errors import InputError
from inverse.iwan_modal import kappa_ratio
from joints.iwan import IwanParameters

__all__ = ["estimated_joint", "predict_from_backbone"]


def estimated_joint(chi: float, dc1: float, omega2_1: float, zeta_1: float) -> dict:
    """The parameter set of :class:`FELevels` for an Iwan joint of exponent ``chi`` and
    ``|kappa1| B~ = dc1`` (rad^2/s^2) at level 1, the stuck frequency and the viscous
    damping matched so that level 1 has ``omega2_1`` (rad^2/s^2) and ``zeta_1`` (module
    docstring)."""
    if not -1.0 < chi < 0.0 or not dc1 > 0:
        raise InputError(f"the estimate (chi = {chi:.4g}, |kappa1| B = {dc1:.4g}) is no "
                         "Iwan joint")
    Om2 = float(omega2_1)
    w2 = Om2 + kappa_ratio(chi, "exact") * dc1
    zeta_v = (float(zeta_1) - dc1 / (2.0 * Om2)) * math.sqrt(Om2 / w2)
    return {"chi": float(chi), "ln_dc1": math.log(dc1), "zeta_v": zeta_v,
            "f0_hz": math.sqrt(w2) / (2.0 * math.pi)}


def predict_from_backbone(data, est, levels, force_scale: float = 1.0, case_name: str = "",
                          n_points: int = 60, max_extensions: int = 4) -> dict:
    """Frequency, damping and slip of every level of ``data`` from the FE backbone.

    Parameters
    ----------
    data : MeasuredData (the estimate's mode is used)
    est : inverse.estimate.Estimate of the fit levels
    levels : callable(data, force_scale=) -> :class:`feloop.levels.FELevels`
        (the case's ``fe_levels`` capability).
    force_scale : float
        N per unit of the excitation column (as given to the estimate).
    case_name : str, in the output.

    Returns
    -------
    dict
        ``chi``, ``R``, ``phi_max``, ``fe_mode``, ``levels`` (per level: excitation,
        force, predicted and measured omega2 and zeta, largest slip over phi_max,
        ``held_out``), ``points`` (backbone size).
    """
    d = data.for_mode(est.mode)
    fe = levels(d, force_scale=float(force_scale))
    if fe.form.law != "iwan4":
        raise InputError(f"--backbone predicts from the paper's estimator, a four-parameter "
                         f"Iwan joint; case {case_name!r} has {fe.form.law} joints: "
                         f"iwanfe update fits them")
    p = estimated_joint(est.chi, est.kappa1_B, d.omega2[0], d.zeta[0])
    j, red, scale, _, _ = fe.setup(p)
    lin, a = j["linear"], float(scale[0])      # the stiffness scale of f0_hz
    red = replace(red, K=a * red.K)
    mode = int(np.sum(lin.red.omega < lin.omega_k)) + 1    # its rank in the reduced model
    params = [IwanParameters(chi=q.chi, K_T=a * q.K_T, F_S=a * q.F_S, beta=q.beta)
              for q in j["params"]]
    joints = ExactHarmonics(params, red.n_joints)
    force = force_scale * np.asarray(d.excitation, dtype=float)
    s_lin = lin.a_ref * force / force[0]
    lo, hi = 0.25 * s_lin.min(), 4.0 * s_lin.max()
    for _ in range(max_extensions + 1):
        bb = epmc_backbone(red, joints, mode, np.geomspace(lo, hi, n_points))
        F = bb.force_at_resonance(lin.drive_dof)
        if F[-1] >= force.max() and F[0] <= force.min() and np.all(np.diff(F) > 0):
            break
        lo, hi = (lo / 4 if F[0] > force.min() else lo), hi * 4
    ok = (force >= F[0]) & (force <= F[-1]) if np.all(np.diff(F) > 0) \
        else np.zeros_like(force, bool)
    n = force.size
    om2, zeta, ratio = (np.full(n, np.nan) for _ in range(3))
    if ok.any():
        pt = bb.at_force(force[ok], lin.drive_dof)
        om2[ok], zeta[ok] = pt["omega2"], pt["zeta"]
        ratio[ok] = pt["slip_amplitude"].max(axis=1) / j["phi_max"]
    rows = [{"level": int(d.level[i]), "excitation": float(d.excitation[i]),
             "force_N": float(force[i]), "held_out": int(d.level[i]) not in est.fit_levels,
             "omega2": None if np.isnan(om2[i]) else float(om2[i]),
             "zeta": None if np.isnan(zeta[i]) else float(zeta[i]),
             "slip_over_phi_max": None if np.isnan(ratio[i]) else float(ratio[i]),
             "measured_omega2": float(d.omega2[i]), "measured_zeta": float(d.zeta[i])}
            for i in range(n)]
    return {"case": case_name, "model": fe.label, "fe_mode": lin.fe_mode, "chi": j["chi"],
            "R": a * j["R"], "phi_max": j["phi_max"], "zeta_viscous": p["zeta_v"],
            "path": "exact", "points": len(bb), "levels": rows}
