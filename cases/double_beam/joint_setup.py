"""The simulation's Iwan glue joints, damping, reduced model and stepped-sine campaign.

From the measured levels and the FE double beam (:mod:`cases.double_beam.model`) to
what the solver runs; the other choices of the study are in
:mod:`cases.double_beam.settings`.

Joints. The FE model carries one tangential joint per glue node with a share ``w_m =
k_m / K_T`` of the stuck glue stiffness ``K_T`` (1e8 N/m assumed, or ``--glue-kt`` with
the grip re-calibrated: :func:`cases.double_beam.calibration.calibrated_model`). Each becomes a
four-parameter Iwan element with the same ``chi`` and the same share of ``R`` and ``S``
(``R_m = w_m R``), hence the same ``phi_max``: this is exactly the model
:func:`inverse.estimate.b_tilde` assumes (eq. 1 of :mod:`inverse.estimate`), so the
simulation is the model the method identifies from the measurements. ``chi`` and ``R =
R~`` come from the ``exact`` estimate of measured levels 1-7 (:func:`source_estimate`:
exact kappa2, eq. 45 with its factor 2, B~ from the linear inverse at the stated force
scale).

phi_max and beta are *not* free once ``K_T``, ``R`` and ``chi`` are fixed: the stuck
stiffness of a four-parameter joint is ``K_T = R phi_max^(chi+1)/(chi+1) + S`` with
``S = K_T beta/(1+beta)`` (Segalman 2005), so

    phi_max = (K_T (chi+1) / ((1+beta) R))^(1/(chi+1)),                     (1)

largest at ``beta = 0``. The default is therefore ``beta = 0`` (no Dirac term; ``F_S =
R phi_max^(chi+2)/(chi+2)``), the choice that keeps the joint longest in micro-slip;
any ``beta > 0`` moves macro-slip to lower levels.

Force scale. The paper gives drive voltages (5 mV .. 2.56 V), never newtons; the
force is ``force_scale * voltage`` with ``force_scale`` = 1 N/V (the estimator's
:data:`inverse.estimate.DEFAULT_FORCE_SCALE`), a stated assumption. It cannot be
calibrated from the data and it does not matter: B~ scales as ``s^(chi+1)`` so R~ as
``s^-(chi+1)``, and by (1) ``phi_max`` as ``s``; the Iwan density ``R phi^chi`` on
``(0, phi_max)`` under ``phi -> s phi``, ``R -> s^-(chi+1) R`` maps the joint force of a
slip history ``s u(t)`` to ``s`` times that of ``u(t)`` (the log-spaced Jenkins bank
scales the same way), so every simulated FRF, omega2 and zeta is invariant and only the
slip amplitudes (and R~, phi_max, F_S) scale. :func:`force_scale_dependence` lists R~
and phi_max for several scales; the ratio of the top-level slip to ``phi_max`` is the
same for all of them.

Viscous damping. Modal damping ``C_r = diag(2 zeta_v omega_r)`` on the reduced basis
(:func:`fe.reduction.ritz_basis`) with ``zeta_v`` such that the simulated level 1 has
the measured ``zeta_1`` = 1.2780 %: ``zeta_v = (zeta_1 - Delta c_1 / (2 Omega_1^2))
Omega_1 / omega_n`` (eq. 2 of :mod:`inverse.estimate`; ``Delta c_1 = |kappa1| B`` of the
estimate, ``Omega_1^2 = omega_n^2 - (kappa2/|kappa1|) Delta c_1``, ``omega_n`` the FE
mode).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from cases.double_beam.settings import SOURCE_METHOD, DoubleBeamStudy
from feloop.levels import phi_max_of
from fe.reduction import JointBank, JointedSystem, ritz_basis
from ident.measured import MeasuredData
from inverse.estimate import estimate
from inverse.iwan_modal import kappa_ratio, r_tilde
from joints.describing import kappa1
from joints.iwan import IwanParameters

__all__ = [
    "JointSetup",
    "phi_max_of",
    "source_estimate",
    "joint_setup",
    "nonlinear_model",
    "level_campaign",
    "mode_weights",
    "force_scale_dependence",
]


@dataclass
class JointSetup:
    """The Iwan joints and damping of the simulation, and where they came from.

    Attributes
    ----------
    chi, R : float
        Exponent and total density coefficient (N m^-(chi+2)) of the glue.
    beta : float
    K_T : float
        Total stuck glue stiffness (N/m), the FE model's.
    phi_max : float
        Eq. (1) of the module docstring (m).
    F_S : float
        Macro-slip force of the whole glue (N), ``sum_m F_S,m``.
    shares : (n_joints,) ``w_m = k_m / K_T``.
    params : list of IwanParameters, one per joint element.
    force_scale : float (N/V); force : (n_levels,) force amplitudes (N).
    zeta_viscous : float
        Modal damping ratio of every basis vector.
    fe_mode : int
        1-based FE mode of the measured mode; ``omega_n`` its frequency (rad/s).
    source : inverse.estimate.Estimate
        The estimate chi and R come from (unless the study gives them).
    slip_level1_linear : (n_joints,) linear-inverse slip amplitudes at level 1 (m).
    """

    chi: float
    R: float
    beta: float
    K_T: float
    phi_max: float
    F_S: float
    shares: np.ndarray
    params: list
    force_scale: float
    force: np.ndarray
    zeta_viscous: float
    fe_mode: int
    omega_n: float
    source: object
    slip_level1_linear: np.ndarray

    def to_dict(self) -> dict:
        return {
            "chi": self.chi, "R": self.R, "beta": self.beta, "K_T": self.K_T,
            "phi_max": self.phi_max, "F_S": self.F_S, "S": self.K_T * self.beta / (1 + self.beta),
            "shares": self.shares, "force_scale_N_per_V": self.force_scale,
            "force_N": self.force, "zeta_viscous": self.zeta_viscous,
            "fe_mode": self.fe_mode, "fe_frequency_hz": self.omega_n / (2 * math.pi),
            "source_method": self.source.method, "source_fit_levels": self.source.fit_levels,
            "source_chi": self.source.chi, "source_R": self.source.R,
            "source_kappa1_B": self.source.kappa1_B,
            "slip_level1_linear": self.slip_level1_linear,
        }


def source_estimate(model, data: MeasuredData, study: DoubleBeamStudy, **options):
    """The :data:`SOURCE_METHOD` estimate of the ``study.fit`` levels of ``data`` with
    the FE ``model`` (paper eq. 33-37): the chi and R~ that drive the simulation.
    ``options`` go to :func:`inverse.estimate.estimate` (e.g. ``confidence``)."""
    return estimate(data, fit_levels=study.fit, method=SOURCE_METHOD, model=model,
                    force_scale=study.force_scale, **options)


def joint_setup(model, data: MeasuredData, study: DoubleBeamStudy, source=None) -> JointSetup:
    """Iwan parameters and viscous damping of the simulation (module docstring).

    ``data`` holds one mode, levels sorted. The :data:`SOURCE_METHOD` estimate of
    ``study.fit`` levels with the FE ``model`` (:func:`source_estimate`, or ``source``
    if given) gives chi and R~ (unless overridden).
    """
    src = source_estimate(model, data, study) if source is None else source
    chi = src.chi if study.chi is None else float(study.chi)
    if study.R is not None:
        R = float(study.R)
    elif study.chi is not None:   # R~ for the overriding chi, same |kappa1| B and B~(chi)
        R = r_tilde(src.kappa1_B, chi, src.case.B_of_chi(chi))
    else:
        R = float(src.R)
    if not -1.0 < chi < 0.0:
        raise ValueError(f"the estimated chi = {chi:.4g} is outside (-1, 0): cannot build an "
                         f"Iwan joint (give --chi)")
    kj = np.asarray(model.joint_stiffness, dtype=float)
    K_T = float(kj.sum())
    shares = kj / K_T
    beta = float(study.beta)
    pm = phi_max_of(K_T, R, chi, beta)
    params = [IwanParameters.from_density(R * w, chi, pm, K_T * w * beta / (1.0 + beta))
              for w in shares]
    F_S = float(sum(p.F_S for p in params))
    # viscous damping: level 1 gets the measured zeta (eq. 2 of inverse.estimate)
    fe_mode = src.case.fe_mode
    omega_n = 2 * math.pi * src.case.fe_frequency_hz
    dc1 = src.kappa1_B if study.chi is None and study.R is None else (
        abs(kappa1(R, chi)) * src.case.B_of_chi(chi))          # |kappa1| B at level 1
    Om2 = omega_n ** 2 - kappa_ratio(chi, "exact") * dc1
    zeta_v = (float(data.zeta[0]) - dc1 / (2.0 * Om2)) * math.sqrt(Om2) / omega_n
    return JointSetup(chi=float(chi), R=float(R), beta=beta, K_T=K_T, phi_max=float(pm),
                      F_S=F_S, shares=shares, params=params, force_scale=study.force_scale,
                      force=study.force_scale * np.asarray(data.excitation, dtype=float),
                      zeta_viscous=float(zeta_v), fe_mode=int(fe_mode), omega_n=float(omega_n),
                      source=src, slip_level1_linear=np.asarray(src.case.slip_amplitudes))


def nonlinear_model(model, setup: JointSetup, study: DoubleBeamStudy):
    """Reduced jointed double beam (:func:`fe.reduction.ritz_basis` of ``model`` with the
    glue springs as joints, ``zeta_v``) and its Jenkins banks
    (:meth:`fe.reduction.JointBank.log_spaced` down to ``2^-octaves_below`` of the
    smallest linear level-1 slip amplitude).

    Returns
    -------
    (fe.reduction.ReducedModel, fe.reduction.JointBank)
    """
    n = model.M.shape[0]
    system = JointedSystem(M=model.M, K=model.K_without_joints, C=sp.csr_matrix((n, n)),
                           G=model.slip_matrix, K_T=model.joint_stiffness)
    red = ritz_basis(system, study.n_modes, setup.zeta_viscous)
    a_low = float(setup.slip_level1_linear.min()) * 2.0 ** (-study.octaves_below)
    a_low = min(a_low, 0.5 * setup.phi_max)
    bank = JointBank.log_spaced(setup.params, a_low, study.sliders_per_octave)
    return red, bank


def level_campaign(model, setup: JointSetup, study: DoubleBeamStudy, protocol: str = "hb"):
    """The stepped-sine campaign of the study: ``study.lines`` (Hz, upward) at the
    forces ``setup.force`` (N) on the drive DOF, every DOF recorded, harmonic balance
    with ``study.hb`` (``protocol="hb"``) or time integration (``"newmark"``;
    :func:`cases.double_beam.protocols.campaign_protocol`).

    Returns
    -------
    runs.stepped_sine.Campaign
    """
    from cases.double_beam.protocols import campaign_protocol
    from runs.campaign import Campaign

    n = model.M.shape[0]
    load = np.zeros(n)
    load[int(model.drive_dof)] = 1.0
    return Campaign(study.lines, setup.force, load, np.arange(n),
                    campaign_protocol(protocol, study.hb))


def mode_weights(model, setup: JointSetup):
    """The FE mode ``phi`` (mass-normalized, kg^-1/2) of ``setup.fe_mode`` and the B
    weights ``q_m = w_m (g_m . phi)^2`` of its joints (eq. 1 of :mod:`inverse.estimate`).

    Returns
    -------
    (phi (n,), weights (n_joints,))
    """
    _, shapes = model.modes(setup.fe_mode)
    phi = shapes[:, setup.fe_mode - 1]
    gphi = np.asarray(model.slip_matrix @ phi).ravel()
    return phi, setup.shares * gphi ** 2


def force_scale_dependence(model, data, study: DoubleBeamStudy, scales=(0.1, 1.0, 10.0),
                           top_slip=None) -> list[dict]:
    """R~ (linear-inverse B~, :data:`SOURCE_METHOD`) and phi_max (eq. 1) per force scale.

    ``scales`` are multiples of ``study.force_scale``. ``top_slip``: the simulated
    top-level maximum slip at ``study.force_scale`` (m), scaled to each force scale.
    """
    rows = []
    for k in scales:
        s = study.force_scale * k
        e = estimate(data, fit_levels=study.fit, method=SOURCE_METHOD, model=model,
                     force_scale=s)
        chi, R = e.chi, e.R
        K_T = float(np.sum(model.joint_stiffness))
        pm = phi_max_of(K_T, R, chi, study.beta)
        F_S = IwanParameters.from_density(R, chi, pm, K_T * study.beta / (1 + study.beta)).F_S
        row = {"force_scale_N_per_V": s, "chi": chi, "R": R, "phi_max": pm, "F_S": F_S,
               "level1_force_N": s * float(data.excitation[0]),
               "top_linear_slip_over_phi_max": float(e.case.slip_amplitudes.max()) / pm
               * float(data.excitation[-1] / data.excitation[0])}
        if top_slip is not None:
            row["top_simulated_slip_over_phi_max"] = top_slip * k / pm
        rows.append(row)
    return rows
