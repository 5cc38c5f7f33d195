"""The reproduction of paper section 3 on the 10-DOF model: stepped-sine campaign
(Fig. 4), modal identification per level, joint amplitudes at the identified
resonances (Table 1), the chi fit of eq. 35 (Fig. 5) and the R errors of eq. 37
(Table 2); then the improved method (:mod:`cases.lumped10.improved_fit`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from cases.lumped10.improved_fit import fit_improved
from cases.lumped10.model import (LumpedParameters, ModeTopology, force_levels, force_vector,
                                  lumped10_bank, lumped10_system, mode_topology)
from cases.lumped10.report import LumpedReport, ModeResult
from fe.reduction import JointBank, JointedSystem, ReducedModel, reduced_basis

if TYPE_CHECKING:
    from ident.measured import MeasuredData
    from runs.campaign import CampaignResult

__all__ = [
    "LumpedStudy",
    "LumpedSetup",
    "MODE_BANDS",
    "lumped10_setup",
    "run_study",
]

#: Identification bands (Hz) around the joint-moving modes studied by the paper.
MODE_BANDS = {2: (55.0, 68.0), 4: (160.0, 190.0), 6: (225.0, 268.0)}


@dataclass(frozen=True)
class LumpedStudy:
    """Settings of the reproduction: model, Jenkins discretization, lines (Hz) and the
    studied modes with their identification bands."""

    params: LumpedParameters = field(default_factory=LumpedParameters)
    n_sliders: int = 100
    f_lo: float = 40.0
    f_hi: float = 320.0
    df: float = 0.5
    modes: tuple = (2, 4, 6)
    bands_only: bool = False

    @property
    def lines(self) -> np.ndarray:
        f = np.round(np.arange(self.f_lo, self.f_hi + 0.5 * self.df, self.df), 9)
        if self.bands_only:
            keep = np.zeros(f.size, bool)
            for m in self.modes:
                lo, hi = MODE_BANDS[m]
                keep |= (f >= lo) & (f <= hi)
            f = f[keep]
        return f


@dataclass(frozen=True)
class LumpedSetup:
    """The study's solver inputs: jointed system, Jenkins banks, reduced model, unit load
    pattern (N) and force levels (N)."""

    system: JointedSystem
    bank: JointBank
    model: ReducedModel
    load: np.ndarray
    levels: np.ndarray


def lumped10_setup(study: "LumpedStudy") -> LumpedSetup:
    """Build everything a campaign on the 10-DOF model needs (paper eq. 38-40)."""
    p = study.params
    system = lumped10_system(p)
    return LumpedSetup(system, lumped10_bank(p, study.n_sliders), reduced_basis(system),
                       force_vector(p), force_levels(p))


def _identify_level(freq, rec, band, target_hz):
    """Frequency (Hz) and damping ratio of the identified mode nearest ``target_hz`` in
    ``band``; NaN when none is found."""
    from ident.identify import identify_modes

    sel = (freq >= band[0]) & (freq <= band[1])
    try:
        modes = identify_modes(freq[sel], rec[sel], band=band)
    except ValueError:
        return np.nan, np.nan
    if not modes:
        return np.nan, np.nan
    m = min(modes, key=lambda m: abs(m.frequency_hz - target_hz))
    return m.frequency_hz, m.zeta


def _protocol(protocol: str):
    """The campaign protocol named ``protocol`` (ValueError if unknown)."""
    from runs.campaign import HBProtocol, NewmarkProtocol, PaperProtocol

    protocols = {"default": HBProtocol(), "hb": HBProtocol(), "newmark": NewmarkProtocol(),
                 "paper": PaperProtocol()}
    if protocol not in protocols:
        raise ValueError(f"unknown protocol {protocol!r} (choose default, newmark or paper)")
    return protocols[protocol]


@dataclass(frozen=True)
class _Run:
    """What every studied mode shares: the study's lines (Hz), setup and protocol, the
    campaign's result and the normal modes of the stuck system."""

    setup: LumpedSetup
    proto: object
    freq: np.ndarray
    res: CampaignResult
    omega_n: np.ndarray
    shapes: np.ndarray
    topo: ModeTopology


def _campaign(setup: LumpedSetup, proto, freq: np.ndarray, store, progress: bool,
              workers: int, executor) -> tuple[CampaignResult, object]:
    """Run (or resume) the stepped-sine campaign: (result, store directory or None)."""
    from runs.campaign import Campaign
    from runs.stepped_sine import run_campaign

    system, bank, model = setup.system, setup.bank, setup.model
    camp = Campaign(freq, setup.levels, setup.load, np.arange(system.n_dof), proto)
    if store is not None:
        from pathlib import Path

        from runs.stepped_sine import campaign_hash
        store = Path(store) / f"campaign-{proto.name}-{campaign_hash(model, bank, camp)[:12]}"
    res = run_campaign(model, bank, camp, store=store, progress=progress,
                       workers=None if executor is not None else workers, executor=executor)
    return res, store


def _identify_mode(run: _Run, m: int, bar) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mode ``m`` level by level: identified frequency (Hz), damping ratio, and the joint
    slip amplitudes at the identified resonance (Table 1)."""
    from runs.campaign import Campaign
    from runs.stepped_sine import run_level

    system, F, load = run.setup.system, run.setup.levels, run.setup.load
    band = MODE_BANDS[m]
    f_id = np.full(F.size, np.nan)
    z_id = np.full(F.size, np.nan)
    t1 = np.full((F.size, system.n_joints), np.nan)
    for lv in range(F.size):
        f_id[lv], z_id[lv] = _identify_level(run.freq, run.res.receptance[lv], band,
                                             run.omega_n[m - 1] / (2 * np.pi))
        f_drive = f_id[lv] if np.isfinite(f_id[lv]) else run.omega_n[m - 1] / (2 * np.pi)
        one = Campaign([f_drive], [F[lv]], load, np.arange(system.n_dof), run.proto)
        t1[lv] = run_level(run.setup.model, run.setup.bank, one, 0).slip_amplitude[0]
        if bar is not None:
            bar.update(1)
    return f_id, z_id, t1


def _mode_data(m: int, F: np.ndarray, f_id: np.ndarray, z_id: np.ndarray, t1: np.ndarray,
               phi_max: float) -> tuple[MeasuredData, list[int], np.ndarray]:
    """The identified levels of mode ``m`` as a measured-data table, the fit levels
    (micro-slip levels, else the first three) and the mask of identified levels."""
    from ident.measured import MeasuredData

    micro = [lv + 1 for lv in range(F.size)
             if np.all(t1[lv] < phi_max) and np.isfinite(z_id[lv])]
    fit_levels = micro if len(micro) >= 3 else [lv + 1 for lv in range(min(3, F.size))]
    ok = np.isfinite(z_id)
    data = MeasuredData(level=np.arange(1, F.size + 1)[ok], excitation=F[ok],
                        omega2=(2 * np.pi * f_id[ok]) ** 2, zeta=z_id[ok],
                        mode=np.full(ok.sum(), m), run_order=np.arange(1, F.size + 1)[ok])
    fit_levels = [lv for lv in fit_levels if ok[lv - 1]]
    return data, fit_levels, ok


def _r_per_difference(differences: list[dict], chi: float, z: float, B_inv: float,
                      B_sim: float) -> tuple[np.ndarray, np.ndarray]:
    """eq. 37 for each successive difference (Table 2): Delta d_v (eq. 46, as fitted)
    with B~ from the linear inverse and from the simulation."""
    from inverse.iwan_modal import kappa1_per_R

    pch = chi + 1.0
    dd = np.array([d["delta_d"] for d in differences])
    v = np.arange(dd.size)
    denom = kappa1_per_R(chi) * z ** (v * pch) * (z ** pch - 1.0)
    return dd / (denom * B_inv), dd / (denom * B_sim)


def _mode_result(run: _Run, study: LumpedStudy, m: int, bar) -> ModeResult:
    """Identification, Table 1, the paper's and the amplitude estimates, B~ and R~ (eq. 37,
    Table 2) and the improved fit of mode ``m``."""
    from inverse.estimate import estimate
    from inverse.iwan_modal import b_tilde, r_tilde

    p, system, load, F = study.params, run.setup.system, run.setup.load, run.setup.levels
    phi_max = p.joint.phi_max
    band = MODE_BANDS[m]
    f_id, z_id, t1 = _identify_mode(run, m, bar)
    data, fit_levels, ok = _mode_data(m, F, f_id, z_id, t1, phi_max)
    est_paper = estimate(data, fit_levels=fit_levels, method="paper")
    dominant = int(np.argmax(np.abs(run.topo.joint_slip[m - 1])))
    est_amp = estimate(data, fit_levels=fit_levels, method="amplitude",
                       amplitude=t1[ok, dominant])
    chi = est_paper.chi
    phi = run.shapes[:, m - 1]
    # B~ (eq. 37) from the linear model at the identified level-1 resonance
    # ("inverse matrix") and from the simulated level-1 amplitudes ("Newmark")
    w1 = 2 * np.pi * f_id[0]
    x = np.linalg.solve(system.K_J - w1 ** 2 * system.M + 1j * w1 * system.C, load * F[0])
    A_inv = np.abs(system.G @ x)
    B_inv = b_tilde(system.G, phi, A_inv, chi)
    B_sim = b_tilde(system.G, phi, t1[0], chi)
    R_paper = r_tilde(est_paper.kappa1_B, chi, B_sim)
    R_inv, R_sim = _r_per_difference(est_paper.differences, chi, p.level_ratio, B_inv, B_sim)
    imp = fit_improved(system, phi, load, run.freq, run.res.receptance, run.res.slip_amplitude,
                       m, phi_max, band=band, R0=1e5, chi0=-0.4)
    return ModeResult(mode=m, band=band, frequency_hz=f_id, zeta=z_id, table1=t1,
                      fit_levels=fit_levels, paper_estimate=est_paper,
                      amplitude_estimate=est_amp, B_inverse=B_inv, B_simulated=B_sim,
                      R_paper=R_paper, R_per_difference_inverse=R_inv,
                      R_per_difference_simulated=R_sim, improved=imp)


def run_study(study: LumpedStudy = LumpedStudy(), protocol: str = "default", store=None,
              progress: bool = True, workers: int = 1, executor=None) -> LumpedReport:
    """Reproduce paper section 3 (Fig. 4, 5, Tables 1, 2) and the improved method.

    Parameters
    ----------
    study : LumpedStudy
    protocol : {"default", "newmark", "paper"}
        ``default``: harmonic balance with continuation (fast); ``newmark``: time
        integration to a periodic state, state carried from line to line; ``paper``:
        Newmark, 9 s + 1 s per line from rest (the paper's protocol; hours at full
        resolution).
    store : path, optional
        Parent directory of the campaign store ``campaign-<protocol>-<hash12>``
        (resumable; see :func:`runs.stepped_sine.run_campaign`).
    progress : bool
        tqdm bars on stderr.
    workers : int
        Without ``executor``: levels computed in that many local processes.
    executor : str or runs.executor.ExecutorSpec, optional
        Where the levels run (:func:`runs.stepped_sine.run_campaign`; e.g.
        :func:`cli.executor_options.executor_from_args`); results are bitwise the same.
    """
    import time as _time

    from fe.modal import normal_modes

    proto = _protocol(protocol)
    p = study.params
    setup = lumped10_setup(study)
    system = setup.system
    freq = study.lines
    topo = mode_topology(system)
    timings = {}
    t0 = _time.perf_counter()
    res, store = _campaign(setup, proto, freq, store, progress, workers, executor)
    timings["campaign"] = _time.perf_counter() - t0
    timings["campaign_levels_computed"] = int(res.computed.sum())
    timings["campaign_store"] = None if store is None else str(store)
    omega_n, shapes = normal_modes(system.K_J, system.M, system.n_dof)
    run = _Run(setup, proto, freq, res, omega_n, shapes, topo)
    t0 = _time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(study.modes) * setup.levels.size, desc="identify + Table 1",
                   unit="level", leave=False)
    modes = {m: _mode_result(run, study, m, bar) for m in study.modes}
    if bar is not None:
        bar.close()
    timings["identification_and_fits"] = _time.perf_counter() - t0
    return LumpedReport(study=study, protocol=protocol, topology=topo, campaign=res,
                        modes=modes, R_true=p.joint.R, chi_true=p.joint.chi, timings=timings)
