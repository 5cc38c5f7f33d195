"""Virtual stepped-sine tests of the double beam made independently of the FE diagnosis.

:func:`draw_case` draws, from a seed, one measured-data table of the double beam's
measured mode, made by a different simulation than the one the diagnosis fits. It
imports nothing from ``inverse/`` (a test checks) and shares no functional form with
the diagnosis's cause realizations (:mod:`feloop.causes`):

=====================  ==========================================  ==============================
family (answer)        this generator                              the diagnosis fits
=====================  ==========================================  ==============================
structure              ``n_joints`` in {3, 4, 7, 9} glue nodes,    5 nodes, ``K_T = 1e8`` assumed
                       ``K_T`` log-uniform 10^7.4 .. 10^8.6 N/m
joint / solver         Jenkins bank (8 sliders per octave),        exact Iwan describing
                       multi-harmonic balance (harmonics 1, 3,     function, one harmonic,
                       5; 64 AFT samples), stepped sine over       phase resonance
                       lines, LSCF identification
``none``               micro-slip Iwan bank, top slip 0.1-0.6      base model
                       phi_max
``macro-slip``         bank with a Dirac share beta 0.1-0.6,       ln phi_max (beta from it)
                       top slip 1.5-4 phi_max
``quadratic-damping``  viscous modal damping growing with the      modal drag ``c2 |q'| q'``
                       force, ``zeta_v (1 + g (F/F_top)^p)``,
                       p 1.0-2.0
``geometric-hardening`` strip stiffness ``(1 + h (F/F_top)^p)``,   modal cubic spring ``k3 q^3``
                       p 1.5-2.5 (per level)
``thermal-drift``      warm-up ``1 - d (1 - exp(-n/tau))`` of the  linear in run number
                       strip stiffness over run ``n``, tau 2-6
out-of-catalogue       damping that *falls* with force,            (nothing: ``unexplained``)
(``unexplained``)      ``zeta_v exp(-g (F/F_top)^p)``
=====================  ==========================================  ==============================

Effect sizes: log-uniform :data:`EFFECT_SIGMA` noise units at the top level. Noise:
repeatability, Gaussian, drawn per series: relative ``omega2`` sd log-uniform
:data:`SIGMA_OMEGA2` (frequency 0.005-0.05 %), relative ``zeta`` sd :data:`SIGMA_ZETA`
(0.5-3 %): assumed, the range the project's brief gives for real rigs (about 0.05 % in
frequency, a few % in damping), not measured here (the earlier 4e-6 .. 1.5e-5 and 2e-4 ..
1e-3 lie below any rig's repeatability, where the fitted model's own form shows:
docs/judge.md, "Limits"); half the series carry ``omega2_std`` /
``zeta_std`` columns holding only the identification's part (0.3 of the repeatability),
the other half none (the paper's data path). Run order shuffled. 10 levels, 5 mV ..
2.56 V at 1 N/V, 31 lines of 0.5 Hz upward around the stuck frequency.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from cases.double_beam.calibration import calibrate_clamp_length
from cases.double_beam.model import DoubleBeamConfig, build_double_beam
from fe.harmonic_balance import HBSettings
from fe.reduction import JointBank, JointedSystem, ritz_basis
from ident.identify import identify_modes
from ident.modal_data import MeasuredData
from joints.iwan import IwanParameters
from runs.campaign import Campaign, HBProtocol
from runs.stepped_sine import run_campaign

__all__ = ["FAMILIES", "ANSWER", "EFFECT_SIGMA", "SyntheticFECase", "draw_case"]

FAMILIES = ("none", "macro-slip", "quadratic-damping", "geometric-hardening",
            "thermal-drift", "out-of-catalogue")
#: What the diagnosis should answer for each family.
ANSWER = {f: f for f in FAMILIES} | {"out-of-catalogue": "unexplained"}
EFFECT_SIGMA = (15.0, 80.0)
SIGMA_OMEGA2 = (1e-4, 1e-3)
SIGMA_ZETA = (5e-3, 3e-2)
EXCITATION = 0.005 * 2.0 ** np.arange(10)
LINES_HZ = np.arange(-9.0, 6.001, 0.5)
HB = HBSettings(n_harmonics=5, n_time=64, odd_only=True)
N_MODES = 12


@dataclass
class SyntheticFECase:
    """A generated series (``data``), its ``family`` and the drawn ``truth``."""

    data: MeasuredData
    family: str
    seed: int
    truth: dict = field(default_factory=dict)

    @property
    def answer(self) -> str:
        return ANSWER[self.family]


def _structure(rng):
    cfg = DoubleBeamConfig(n_joints=int(rng.choice([3, 4, 7, 9])),
                           glue_tangential_stiffness=10.0 ** rng.uniform(7.4, 8.6))
    cfg = replace(cfg, clamp_length=calibrate_clamp_length(cfg, xtol=1e-9))
    model = build_double_beam(cfg)
    omega, shapes = model.modes(4)
    k = int(np.argmin(np.abs(omega / (2 * np.pi) - 252.0)))
    return cfg, model, float(omega[k]), shapes[:, k]


def _joints(model, omega, phi, zeta, top_force, chi, beta, top_ratio):
    """Per-node Iwan joints with one phi_max: the top level's linear slip is
    ``top_ratio`` phi_max (linear modal estimate at resonance)."""
    gphi = np.abs(np.asarray(model.slip_matrix @ phi).ravel())
    q = top_force * abs(phi[int(model.drive_dof)]) / (2.0 * zeta * omega ** 2)
    pm = float(gphi.max() * q) / top_ratio
    kj = np.asarray(model.joint_stiffness, dtype=float)
    c = (chi + 1.0) / (chi + 2.0)
    return [IwanParameters(F_S=pm * k * (beta + c) / (1.0 + beta), K_T=float(k), chi=chi,
                           beta=beta) for k in kj], pm


def _level(model, red, bank, force, lines_hz, k_scale, zeta_scale, label):
    """Level ``label``: its receptance at the response DOF (m/N) over ``lines_hz`` and
    how its steady states were reached when not by plain Newton
    (:meth:`runs.campaign.CampaignResult.fallback_lines`, empty without)."""
    red_l = replace(red, K=red.K * k_scale, C=red.C * zeta_scale * math.sqrt(k_scale))
    load = np.zeros(model.M.shape[0])
    load[int(model.drive_dof)] = 1.0
    camp = Campaign(lines_hz, np.array([force]), load, np.array([int(model.response_dof)]),
                    HBProtocol(HB))
    res = run_campaign(red_l, bank, camp, progress=False)
    return res.receptance[0, :, 0], res.fallback_lines([label])


def draw_case(seed: int, family: str | None = None) -> SyntheticFECase:
    """One synthetic series (module docstring); ``family`` drawn from :data:`FAMILIES`
    unless given."""
    rng = np.random.default_rng(seed)
    shape_rng = np.random.default_rng([seed, 1])   # the effect's shape: its own stream,
    family = str(FAMILIES[rng.integers(len(FAMILIES))]) if family is None else family
    if family not in FAMILIES:
        raise ValueError(f"unknown family {family!r}; choose from {', '.join(FAMILIES)}")
    cfg, model, omega, phi = _structure(rng)
    zeta = rng.uniform(0.010, 0.014)
    chi = rng.uniform(-0.7, -0.25)
    L = EXCITATION.size
    force = EXCITATION.copy()                                   # 1 N/V
    s_w = math.exp(rng.uniform(*np.log(SIGMA_OMEGA2)))
    s_z = math.exp(rng.uniform(*np.log(SIGMA_ZETA)))
    size = math.exp(rng.uniform(*np.log(EFFECT_SIGMA)))
    run_order = rng.permutation(L) + 1
    beta, ratio = 0.0, rng.uniform(0.1, 0.6)
    if family == "macro-slip":
        beta, ratio = shape_rng.uniform(0.1, 0.6), shape_rng.uniform(1.5, 4.0)
    params, pm = _joints(model, omega, phi, zeta, force[-1], chi, beta, ratio)
    n = model.M.shape[0]
    system = JointedSystem(M=model.M, K=model.K_without_joints, C=sp.csr_matrix((n, n)),
                           G=model.slip_matrix, K_T=model.joint_stiffness)
    red = ritz_basis(system, N_MODES, zeta)
    bank = JointBank.log_spaced(params, 1e-3 * pm, 8)
    x = force / force[-1]
    k_scale, z_scale = np.ones(L), np.ones(L)
    p = None
    if family == "quadratic-damping":       # (so one seed gives every family the same
        p = shape_rng.uniform(1.0, 2.0)     # structure and noise)
        z_scale = 1.0 + size * s_z * x ** p
    elif family == "out-of-catalogue":
        p = shape_rng.uniform(1.0, 2.0)
        z_scale = np.exp(-size * s_z * x ** p)
    elif family == "geometric-hardening":
        p = shape_rng.uniform(1.5, 2.5)
        k_scale = 1.0 + size * s_w * x ** p
    elif family == "thermal-drift":
        tau = shape_rng.uniform(2.0, 6.0)
        sign = 1.0 if shape_rng.random() < 0.5 else -1.0
        t = run_order - 1.0
        warm = (1.0 - np.exp(-t / tau)) / (1.0 - math.exp(-(L - 1) / tau))
        k_scale = 1.0 - sign * size * s_w * warm
        p = tau
    f0 = omega / (2 * np.pi)
    lines = f0 + LINES_HZ
    om2, ze, fallbacks = np.empty(L), np.empty(L), []
    for lv in range(L):
        rec, how = _level(model, red, bank, force[lv], lines * math.sqrt(k_scale[lv]),
                          k_scale[lv], z_scale[lv], lv + 1)
        fallbacks += how
        fl = lines * math.sqrt(k_scale[lv])
        # one mode in the band: a top level deep in macro-slip is otherwise fitted with
        # two poles on its distorted resonance (a converged refinement keeps both)
        modes = identify_modes(fl, rec, band=(fl[0], fl[-1]), n_modes=1, weighting="uniform",
                               pseudo_modes=False)
        if not modes:
            raise RuntimeError(f"no mode identified at synthetic level {lv + 1}")
        m = min(modes, key=lambda m: abs(m.frequency_hz - f0 * math.sqrt(k_scale[lv])))
        om2[lv], ze[lv] = m.omega2, m.zeta
    with_std = bool(rng.random() < 0.5)
    om2_obs = om2 * (1.0 + s_w * rng.standard_normal(L))
    ze_obs = ze * (1.0 + s_z * rng.standard_normal(L))
    data = MeasuredData(level=np.arange(1, L + 1), excitation=EXCITATION.copy(),
                        omega2=om2_obs, zeta=ze_obs, mode=np.ones(L, dtype=int),
                        run_order=run_order,
                        omega2_std=0.3 * s_w * om2_obs if with_std else None,
                        zeta_std=0.3 * s_z * ze_obs if with_std else None,
                        source="independent synthetic FE double beam")
    truth = {"n_joints": cfg.n_joints, "K_T": cfg.glue_tangential_stiffness, "chi": chi,
             "beta": beta, "top_slip_ratio": ratio, "zeta_v": zeta, "size_sigma": size,
             "shape": p, "sigma_omega2_rel": s_w, "sigma_zeta_rel": s_z,
             "std_columns": with_std, "fallbacks": fallbacks}
    return SyntheticFECase(data=data, family=family, seed=int(seed), truth=truth)
