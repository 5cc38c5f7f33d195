"""One simulation of the double-beam reproduction, from the measured levels to estimates.

:func:`simulate_study`::

    measured levels 1-7 --estimate (exact)--> chi, R~      (paper eq. 33-37)
    FE double beam + one Iwan element per glue node (chi, R~ shares, beta = 0)
    --HB stepped sine, 10 levels--> FRFs --LSCF--> simulated omega2, zeta per level
    --estimate (paper, exact, amplitude)--> on the measured AND on the simulated data

(settings and their reasons: :mod:`cases.double_beam.settings`; the joint:
:mod:`cases.double_beam.joint_setup`). :func:`cases.double_beam.study.run_study` adds the
weak-joint reruns.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cases.double_beam.joint_setup import (
    JointSetup,
    force_scale_dependence,
    joint_setup,
    level_campaign,
    mode_weights,
    nonlinear_model,
)
from cases.double_beam.model import DoubleBeamModel, build_double_beam
from cases.double_beam.protocols import protocol_comparison
from cases.double_beam.report import DoubleBeamReport
from cases.double_beam.settings import DoubleBeamStudy, measured_levels
from fe.reduction import JointBank, ReducedModel
from ident.levels import LevelIdentification, identify_levels
from ident.measured import MeasuredData
from ident.modal_filter import ModalFilterLevels, modal_filter_levels
from inverse.estimate import METHODS, estimate
from inverse.iwan_modal import b_tilde, r_tilde

if TYPE_CHECKING:
    from runs.campaign import CampaignResult

__all__ = ["identify_campaign", "simulate_study"]


def identify_campaign(model, setup: JointSetup, study: DoubleBeamStudy, res, phi, weights,
                      progress=None):
    """Per-level modal data of a finished campaign ``res``: LSCF at the response DOF
    (:func:`ident.levels.identify_levels`, the study's options) and the modal filter of
    every DOF (:func:`ident.modal_filter.modal_filter_levels`). ``phi``, ``weights``:
    :func:`cases.double_beam.joint_setup.mode_weights`;
    ``progress``: tqdm bar or None (one tick per identified level).

    Returns
    -------
    (LevelIdentification, ModalFilterLevels)
    """
    ident = identify_levels(study.lines, res.receptance[:, :, int(model.response_dof)],
                            res.slip_amplitude, setup.force, study.band_hz,
                            setup.omega_n / (2 * math.pi), weights,
                            options=study.identify_options, progress=progress)
    mf = modal_filter_levels(study.lines, res.receptance, model.M, phi, model.drive_dof,
                             setup.omega_n, 2 * setup.zeta_viscous * setup.omega_n,
                             res.slip_amplitude, model.slip_matrix, setup.shares, setup.R,
                             setup.chi)
    return ident, mf


def _estimate_all(data, study, model, amplitude, slip_level1, phi, shares) -> dict:
    """Estimates of every method on ``data``; B~ and R~ from the linear inverse (the
    estimator's) and from the simulated level-1 slips at resonance."""
    out = {}
    for method in METHODS:
        kw = {"amplitude": amplitude} if method == "amplitude" else {}
        try:
            e = estimate(data, fit_levels=study.fit, method=method, model=model,
                         force_scale=study.force_scale, **kw)
        except ValueError as exc:
            out[method] = str(exc)
            continue
        B_sim = b_tilde(model.slip_matrix, phi, slip_level1, e.chi, shares)
        out[method] = (e, B_sim, r_tilde(e.kappa1_B, e.chi, B_sim))
    return out


def _campaign(red, bank, camp, store, progress, workers, executor):
    """Run (or resume) ``camp`` in ``store/campaign-<protocol>-<hash12>``."""
    from runs.stepped_sine import campaign_hash, run_campaign

    store_dir = None
    if store is not None:
        store_dir = (Path(store) / f"campaign-{camp.protocol.name}-"
                     f"{campaign_hash(red, bank, camp)[:12]}")
    res = run_campaign(red, bank, camp, store=store_dir, progress=progress,
                       workers=None if executor is not None else workers, executor=executor)
    return res, store_dir


@dataclass(frozen=True)
class _Simulation:
    """What the steps of one simulation share: the study, the case, its joint and nonlinear
    model, and where and how the campaigns run."""

    study: DoubleBeamStudy
    model: DoubleBeamModel
    data: MeasuredData
    setup: JointSetup
    red: ReducedModel
    bank: JointBank
    store: object
    progress: bool
    workers: int
    executor: object

    def campaign(self, protocol: str) -> tuple:
        """Run (or resume) the study's campaign under ``protocol``: (result, store dir)."""
        return _campaign(self.red, self.bank,
                         level_campaign(self.model, self.setup, self.study, protocol),
                         self.store, self.progress, self.workers, self.executor)


def _identify(sim: _Simulation, res: CampaignResult, phi: np.ndarray,
              weights: np.ndarray) -> tuple[LevelIdentification, ModalFilterLevels]:
    """:func:`identify_campaign` on ``res`` under a progress bar when asked for."""
    bar = None
    if sim.progress:
        from tqdm import tqdm
        bar = tqdm(total=sim.study.n_levels, desc="identify", unit="level", leave=False)
    try:
        return identify_campaign(sim.model, sim.setup, sim.study, res, phi, weights,
                                 progress=bar)
    finally:
        if bar is not None:
            bar.close()


def _hb_comparison(sim: _Simulation, protocol: str, ids: tuple, res: CampaignResult,
                   phi: np.ndarray, weights: np.ndarray) -> dict:
    """The harmonic-balance campaign of the same lines, identified, beside ``res`` (the
    ``protocol`` campaign) and its identification ``ids``."""
    hb_res, _ = sim.campaign("hb")
    hb_ids = identify_campaign(sim.model, sim.setup, sim.study, hb_res, phi, weights)
    proto = level_campaign(sim.model, sim.setup, sim.study, protocol).protocol
    steps = [proto.steps_for(float(a.max()), float(sim.bank.slip_limit.max()))
             for a in hb_res.slip_amplitude]
    return protocol_comparison(sim.data.level, ids, hb_ids, res, hb_res, steps)


def _check_identified(sim: _Simulation, ident: LevelIdentification) -> None:
    """Raise RuntimeError naming the simulated levels where no mode was identified."""
    if not np.all(np.isfinite(ident.omega2)):
        bad = sim.data.level[~np.isfinite(ident.omega2)]
        raise RuntimeError(f"no mode identified near "
                           f"{sim.setup.omega_n / (2 * math.pi):.1f} Hz at "
                           f"simulated level(s) {', '.join(map(str, bad))}")


def _as_data(sim: _Simulation, ident: LevelIdentification, weights: np.ndarray,
             om2: np.ndarray, ze: np.ndarray, slip: np.ndarray, source: str) -> MeasuredData:
    """Simulated modal data per level as a measured-data table (``source``: its route)."""
    data, setup = sim.data, sim.setup
    return MeasuredData(
        level=data.level, excitation=data.excitation, omega2=om2, zeta=ze,
        mode=data.mode, run_order=data.run_order,
        response_amplitude=ident.response if source == "lscf" else None,
        extra={"x_force_N": setup.force, "x_joint_slip_eff_m": slip @ weights / weights.sum(),
               "x_slip_over_phi_max": np.nanmax(slip, axis=1) / setup.phi_max},
        source=f"simulated double beam ({source})")


def _estimates(sim: _Simulation, ident: LevelIdentification, mf: ModalFilterLevels,
               simulated: MeasuredData, filtered: MeasuredData, phi: np.ndarray,
               weights: np.ndarray) -> tuple:
    """Estimates on the measured, simulated (LSCF) and modal-filter data, and the
    force-scale rows: ``(est_m, est_s, est_f, fs_rows)``."""
    study, model, setup = sim.study, sim.model, sim.setup
    est_m = _estimate_all(sim.data, study, model, ident.slip_eff, ident.slip[0], phi,
                          setup.shares)
    est_s = _estimate_all(simulated, study, model, ident.slip_eff, ident.slip[0], phi,
                          setup.shares)
    eff_mf = mf.slip @ weights / weights.sum()
    est_f = (_estimate_all(filtered, study, model, eff_mf, mf.slip[0], phi, setup.shares)
             if np.all(np.isfinite(mf.zeta)) else {})
    top = float(np.nanmax(ident.slip[-1]))
    fs_rows = force_scale_dependence(model, sim.data, study, top_slip=top)
    return est_m, est_s, est_f, fs_rows


def simulate_study(study: DoubleBeamStudy, store=None, progress: bool = True,
                   workers: int = 1, model=None, executor=None, protocol: str = "hb",
                   calibration=None) -> DoubleBeamReport:
    """One simulation of the study (module docstring), without the weak-joint reruns.

    Parameters
    ----------
    study : DoubleBeamStudy
    store : path, optional
        Parent directory of the resumable campaign store ``campaign-hb-<hash12>``
        (:func:`runs.stepped_sine.run_campaign`): finished levels are loaded, not recomputed.
    progress : bool
        tqdm bars on stderr.
    workers : int
        Without ``executor``: levels computed in that many local processes.
    model : cases.double_beam.model.DoubleBeamModel, optional
        Default: :func:`cases.double_beam.model.build_double_beam` (the shipped case).
    executor : str or runs.executor.ExecutorSpec, optional
        Where the levels run (:func:`runs.stepped_sine.run_campaign`); results are bitwise
        the same. A local cluster or pool is started per campaign.
    protocol : {"hb", "newmark"}
        The campaign's solver (:mod:`cases.double_beam.protocols`). With ``"newmark"``
        the harmonic-balance campaign of the same lines is run (or loaded from the
        store) and identified too, and the report holds both side by side
        (``protocol_comparison``).
    calibration : cases.double_beam.calibration.GripCalibration, optional
        How ``model``'s glue stiffness and grip were set, for the report.

    Returns
    -------
    DoubleBeamReport
    """
    timings = {}
    t0 = time.perf_counter()
    model = build_double_beam() if model is None else model
    data = measured_levels(study)
    setup = joint_setup(model, data, study)
    red, bank = nonlinear_model(model, setup, study)
    sim = _Simulation(study, model, data, setup, red, bank, store, progress, workers, executor)
    timings["setup"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    res, store_dir = sim.campaign(protocol)
    timings["campaign"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    phi, weights = mode_weights(model, setup)
    ident, mf = _identify(sim, res, phi, weights)
    comparison = None
    if protocol != "hb":
        t1 = time.perf_counter()
        comparison = _hb_comparison(sim, protocol, (ident, mf), res, phi, weights)
        timings["campaign_hb_check"] = time.perf_counter() - t1
    _check_identified(sim, ident)
    simulated = _as_data(sim, ident, weights, ident.omega2, ident.zeta, ident.slip, "lscf")
    filtered = _as_data(sim, ident, weights, mf.omega2, mf.zeta, mf.slip, "modal filter")
    timings["identification"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    est_m, est_s, est_f, fs_rows = _estimates(sim, ident, mf, simulated, filtered, phi, weights)
    timings["estimation"] = time.perf_counter() - t0
    return DoubleBeamReport(study=study, setup=setup, measured=data, simulated=simulated,
                            campaign=res, identification=ident, modal_filter=mf,
                            estimates_measured=est_m, estimates_simulated=est_s,
                            estimates_filtered=est_f, force_scale_rows=fs_rows,
                            weak_joint_rows=[],
                            store=None if store_dir is None else str(store_dir),
                            timings=timings, sliders_per_joint=int(bank.n_sliders),
                            response_dof=int(model.response_dof), protocol=protocol,
                            protocol_comparison=comparison,
                            calibration=None if calibration is None else calibration.to_dict())
