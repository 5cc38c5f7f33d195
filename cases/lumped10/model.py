"""The paper's 10-DOF lumped model with two Iwan joints (paper section 3, eq. 38-40).

Topology (the paper's Fig. 3 is missing; this reading is checked by
:func:`mode_topology`, see below)::

    ground -k1- m1 -k2- m2 -k3- m3 -k4- m4 -k5- m5   <- force f at m5
                |       |
           k11 + Iwan1  k12 + Iwan2
                |       |
    ground -k6- m6 -k7- m7 -k8- m8 -k9- m9 -k10- m10

Two fixed-free chains, joined by ``k11`` (m1-m6) and ``k12`` (m2-m7), each in
parallel with a four-parameter Iwan joint (K_T = 1.1e5 N/m, F_S = 400 N,
chi = -0.5, beta = 4). Masses 1 kg; k1 = k6 = 1.5e6 N/m, the other chain springs
1e6 N/m, k11 = 0.3e6 N/m, k12 = 0.5e6 N/m. ``C = a M + b K_J`` with a = 0.5 1/s,
b = 7e-5 s (paper eq. 40). Force levels ``f = 2 * 2**k`` N, k = 0..11; 0.5 Hz lines.

DOF ``i`` (0-based) is the displacement of mass ``m_{i+1}``. Joint slips are
``s1 = u6 - u1`` and ``s2 = u7 - u2``.

Topology check: the two chains are identical (k1 = k6, k2..k5 = k7..k10), so every
mode of ``(K_J, M)`` is either symmetric (``u_i = u_{i+5}``: the couplings and joints
are not stretched) or antisymmetric (joints stretched). Numerically the symmetric
modes are 1, 3, 5, 7, 9 (48.19, 139.90, 218.13, 275.66, 308.49 Hz, independent of the
joints) and the antisymmetric ones 2, 4, 6, 8, 10 (61.71, 173.76, 246.74, 287.63,
338.67 Hz with stuck joints), as the paper states for modes 1-9; the paper does not
mention mode 10, which also moves the joints. The ratio of the two joint slips in
modes 2, 4, 6 (0.315, 0.469, 1.091) matches the paper's Table 1 column ratios.
"""
from __future__ import annotations

import csv as _csv
import io as _io
import math as _math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares as _least_squares

from fe.reduction import (JointBank, JointedSystem, ReducedModel, rayleigh_damping,
                          reduced_basis)
from joints.iwan import IwanParameters

__all__ = [
    "LumpedParameters",
    "ModeTopology",
    "lumped10_system",
    "lumped10_bank",
    "force_vector",
    "force_levels",
    "mode_topology",
    "LumpedStudy",
    "LumpedReport",
    "ModeResult",
    "ImprovedFit",
    "MODE_BANDS",
    "PAPER_CHI",
    "TABLE1_TEXT",
    "TABLE2_TEXT",
    "paper_table",
    "modal_inverse_receptance",
    "fit_improved",
    "run_study",
]


@dataclass(frozen=True)
class LumpedParameters:
    """Parameters of the 10-DOF model (paper eq. 38-40), SI units.

    ``chain_a`` are k1..k5 (ground to m5), ``chain_b`` k6..k10 (ground to m10).
    """

    masses: tuple = (1.0,) * 10
    chain_a: tuple = (1.5e6, 1e6, 1e6, 1e6, 1e6)
    chain_b: tuple = (1.5e6, 1e6, 1e6, 1e6, 1e6)
    k11: float = 0.3e6
    k12: float = 0.5e6
    joint: IwanParameters = field(
        default_factory=lambda: IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0))
    a: float = 0.5
    b: float = 7e-5
    force_dof: int = 4
    base_force: float = 2.0
    level_ratio: float = 2.0
    n_levels: int = 12


#: joint pairs (i, j): slip = u_j - u_i (0-based DOFs): m1-m6 and m2-m7.
JOINT_PAIRS = ((0, 5), (1, 6))


def _chain_stiffness(springs, offset: int, K: np.ndarray) -> None:
    """Add a fixed-free chain ground-k[0]-m0-k[1]-m1-... to ``K`` at ``offset``."""
    k = np.asarray(springs, dtype=float)
    n = k.size
    idx = offset + np.arange(n)
    diag = k.copy()
    diag[:-1] += k[1:]
    K[idx, idx] += diag
    K[idx[:-1], idx[1:]] -= k[1:]
    K[idx[1:], idx[:-1]] -= k[1:]


def lumped10_system(p: LumpedParameters = LumpedParameters()) -> JointedSystem:
    """Mass, stiffness (couplings k11, k12 included, joints excluded), damping
    ``C = a M + b K_J`` (paper eq. 40) and slip operator of the 10-DOF model."""
    n = len(p.masses)
    if n != 10 or len(p.chain_a) != 5 or len(p.chain_b) != 5:
        raise ValueError("the lumped model has 10 masses and two chains of 5 springs")
    M = np.diag(np.asarray(p.masses, dtype=float))
    K = np.zeros((n, n))
    _chain_stiffness(p.chain_a, 0, K)
    _chain_stiffness(p.chain_b, 5, K)
    G = np.zeros((len(JOINT_PAIRS), n))
    for row, (i, j) in enumerate(JOINT_PAIRS):
        G[row, i], G[row, j] = -1.0, 1.0
    couplings = np.array([p.k11, p.k12])
    K += G.T @ (couplings[:, None] * G)
    K_T = np.full(len(JOINT_PAIRS), p.joint.K_T)
    K_J = K + G.T @ (K_T[:, None] * G)
    C = rayleigh_damping(M, K_J, p.a, p.b)
    return JointedSystem(M=M, K=K, C=C, G=G, K_T=K_T)


def lumped10_bank(p: LumpedParameters = LumpedParameters(), n_sliders: int = 100) -> JointBank:
    """The two identical Iwan joints as Jenkins banks of ``n_sliders`` each."""
    return JointBank.from_iwan(p.joint, n_sliders, n_joints=len(JOINT_PAIRS))


def force_vector(p: LumpedParameters = LumpedParameters()) -> np.ndarray:
    """Unit load pattern: 1 N at ``m5`` (paper section 3)."""
    f = np.zeros(len(p.masses))
    f[p.force_dof] = 1.0
    return f


def force_levels(p: LumpedParameters = LumpedParameters()) -> np.ndarray:
    """Force amplitudes ``2 * 2**k`` N, k = 0..11 (paper eq. 38)."""
    return p.base_force * p.level_ratio ** np.arange(p.n_levels)


@dataclass(frozen=True)
class ModeTopology:
    """Stuck-joint modes and how much they move the joints.

    Attributes
    ----------
    frequency_hz : (10,) natural frequencies with stuck joints (Hz).
    frequency_free_hz : (10,) natural frequencies without joints (K only).
    joint_slip : (10, 2) joint slips ``G phi`` of each mass-normalized mode.
    symmetry : (10,) +1 symmetric (in phase at the interface), -1 antisymmetric.
    moves_joints : (10,) bool, joint slip larger than 1e-8 of the mode's norm.
    """

    frequency_hz: np.ndarray
    frequency_free_hz: np.ndarray
    joint_slip: np.ndarray
    symmetry: np.ndarray
    moves_joints: np.ndarray

    def joint_modes(self) -> np.ndarray:
        """1-based numbers of the modes that stretch the joints."""
        return np.flatnonzero(self.moves_joints) + 1


def mode_topology(system: JointedSystem) -> ModeTopology:
    """Check which modes move the joints (paper section 3, discussion of Fig. 4).

    A mode is symmetric when ``phi[0:5] = phi[5:10]`` (masses of both chains in
    phase): then ``G phi = 0`` and the joints cannot slip in that mode.
    """
    from fe.modal import normal_modes

    omega, phi = normal_modes(system.K_J, system.M, system.n_dof)
    omega0, _ = normal_modes(system.K, system.M, system.n_dof)
    slip = (system.G @ phi).T
    top, bottom = phi[:5], phi[5:]
    sym = np.where(np.linalg.norm(top - bottom, axis=0) < np.linalg.norm(top + bottom, axis=0),
                   1, -1)
    moves = np.linalg.norm(slip, axis=1) > 1e-8 * np.linalg.norm(phi, axis=0)
    return ModeTopology(frequency_hz=omega / (2 * np.pi), frequency_free_hz=omega0 / (2 * np.pi),
                        joint_slip=slip, symmetry=sym, moves_joints=moves)


# =========================================================================== the study
#
# Paper section 3 reproduced: stepped-sine campaign (Fig. 4), modal identification
# per level, joint amplitudes at the identified resonances (Table 1), the chi fit of
# eq. 35 (Fig. 5) and the R errors of eq. 37 (Table 2); then the improved method.

#: Paper Table 1 (half peak-to-peak joint slips, m), transcribed (identical to
#: shared/data/paper/table1_lumped_relative_displacement.csv; checked by the tests).
TABLE1_TEXT = """experiment,mode2_iwan1,mode2_iwan2,mode4_iwan1,mode4_iwan2,mode6_iwan1,mode6_iwan2
1,0.00005,0.00016,0.00001,0.00003,0.00001,0.00001
2,0.00010,0.00030,0.00003,0.00006,0.00002,0.00002
3,0.00018,0.00057,0.00005,0.00011,0.00004,0.00004
4,0.00034,0.00106,0.00010,0.00021,0.00007,0.00007
5,0.00061,0.00191,0.00019,0.00041,0.00015,0.00013
6,0.00107,0.00337,0.00037,0.00078,0.00028,0.00025
7,0.00149,0.00471,0.00069,0.00146,0.00053,0.00048
8,0.00193,0.00592,0.00127,0.00268,0.00098,0.00089
9,0.00275,0.00855,0.00214,0.00451,0.00179,0.00162
10,0.00439,0.01372,0.00284,0.00601,0.00322,0.00291
11,0.00791,0.02345,0.00447,0.00935,0.00486,0.00455
12,0.01467,0.04335,0.00720,0.01493,0.00691,0.00658
"""

#: Paper Table 2 (R errors, percent), transcribed (shared/data/paper/table2_*.csv).
TABLE2_TEXT = """nu_minus_1,mode2_inverse_matrix,mode2_newmark,mode4_inverse_matrix,mode4_newmark,mode6_inverse_matrix,mode6_newmark
0,13.199,10.574,31.887,15.272,100.000,100.000
1,9.937,7.214,28.839,12.608,135.950,37.369
2,8.675,5.913,28.704,12.490,67.009,2.768
3,10.367,7.656,22.844,7.368,67.679,2.379
4,18.818,16.363,22.321,6.911,68.544,1.875
5,117.323,123.895,21.789,6.446,64.167,4.423
6,217.785,227.395,20.967,5.727,61.796,5.804
7,169.117,177.255,59.959,39.806,58.587,7.672
8,63.680,68.630,295.122,245.344,54.384,10.119
9,69.430,68.505,306.771,255.524,239.717,97.781
10,132.867,133.861,292.655,243.187,385.652,182.743
"""

#: The paper's chi from Fig. 5 (modes 2, 4, 6).
PAPER_CHI = {2: -0.528, 4: -0.526, 6: -0.531}

#: Identification bands (Hz) around the joint-moving modes studied by the paper.
MODE_BANDS = {2: (55.0, 68.0), 4: (160.0, 190.0), 6: (225.0, 268.0)}


def paper_table(text: str) -> dict[str, np.ndarray]:
    """Columns of a transcribed paper table as float arrays."""
    rows = list(_csv.DictReader(_io.StringIO(text)))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


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


def modal_inverse_receptance(receptance, shape, M, load) -> np.ndarray:
    """Inverse modal receptance by modal filtering, ``D = (phi.f)/(phi.M x)``.

    For a linear structure with proportional damping ``D(w) = w_n^2 - w^2 + i w c_n``
    exactly (the other modes are filtered out by mass orthogonality); with joints,
    ``D`` carries the joints' describing-function stiffness and damping as seen by
    the mode (paper eq. 26 projected on ``phi``). ``receptance`` (..., n_dof) complex
    per newton; returns (...,) complex (rad^2/s^2).
    """
    return (shape @ load) / (np.asarray(receptance) @ (M @ shape))


def _model_inverse_receptance(system, shape, load, omega, slip_amplitude, R, chi):
    """``D`` of paper eq. 26 without the decoupling of eq. 29-30: each joint ``m`` adds
    the complex stiffness ``(-kappa2 + i |kappa1|) A_m^(chi+1)`` (exact micro-slip
    kappas of eq. 14/A15) on its slip, at the joint amplitudes ``A`` of each line."""
    from joints.iwan import kappa1, kappa2_exact

    w = np.asarray(omega, dtype=float)
    G = np.asarray(system.G)
    Z = (system.K_J[None] - (w ** 2)[:, None, None] * system.M[None]
         + 1j * w[:, None, None] * system.C[None])
    if R is not None:
        dk = (-kappa2_exact(R, chi) + 1j * abs(kappa1(R, chi))) * slip_amplitude ** (chi + 1.0)
        Z = Z + np.einsum("jm,nj,jk->nmk", G, dk, G)
    X = np.linalg.solve(Z, np.broadcast_to(load, (w.size, load.size))[..., None])[..., 0]
    return (shape @ load) / (X @ (system.M @ shape))


@dataclass
class ImprovedFit:
    """Result of :func:`fit_improved` for one mode (SI units)."""

    mode: int
    chi: float
    R: float
    chi_with_frequency: float
    R_with_frequency: float
    levels: list
    n_lines: int
    level_amplitude: np.ndarray      # (n_levels, 2) joint amplitudes at the peak line
    level_delta_c: np.ndarray        # (n_levels,) measured Delta c at the peak line
    level_delta_c_model: np.ndarray  # (n_levels,) fitted model at the same lines


def fit_improved(system, shape, load, freq_hz, receptance, slip_amplitude, mode: int,
                 phi_max: float, band=None, R0: float = 1e5, chi0: float = -0.4) -> ImprovedFit:
    """The improved estimate of ``(chi, R)`` from one mode's damping growth.

    Differences from the paper's eq. 33-37: (i) the joint amplitudes are the
    simulated ones, line by line, instead of ``z^v A_0``; (ii) the joints enter the
    structure's dynamic stiffness as in eq. 26 with the exact ``kappa2`` (A15 with the
    exact Beta-function integral) instead of being decoupled per mode (eq. 29-30,
    which misses the coupling through the joints' in-phase stiffness loss, 4x larger
    than the damping term for chi = -0.5); (iii) no differencing: the linear part is
    the model's. The measured quantity is the modal-filtered inverse receptance
    ``D`` (:func:`modal_inverse_receptance`) on the half-power lines of the mode at
    every level whose joint amplitudes stay below ``phi_max`` (micro-slip); ``(ln R,
    chi)`` minimize ``sum (Im D_meas - Im D_model)^2`` (damping only, as the paper);
    ``*_with_frequency`` also fits ``Re D`` (the frequency drop).

    Parameters
    ----------
    system : JointedSystem
    shape : (n,) mass-normalized stuck mode.
    load : (n,) unit load pattern.
    freq_hz : (n_lines,) line frequencies.
    receptance : (n_levels, n_lines, n) complex first-harmonic receptance.
    slip_amplitude : (n_levels, n_lines, n_joints) simulated joint amplitudes (m).
    mode : mode number (label).
    phi_max : micro-slip limit (m).
    band : (lo, hi) Hz, optional
        Lines considered (default all).
    """
    freq_hz = np.asarray(freq_hz, dtype=float)
    inband = np.ones(freq_hz.size, bool) if band is None else (
        (freq_hz >= band[0]) & (freq_hz <= band[1]))
    if inband.sum() < 3:
        raise ValueError(f"mode {mode}: fewer than 3 lines in the band {band}")
    freq_hz = freq_hz[inband]
    receptance = np.asarray(receptance)[:, inband]
    slip_amplitude = np.asarray(slip_amplitude)[:, inband]
    w_all = 2 * np.pi * freq_hz
    D_all = modal_inverse_receptance(receptance, shape, system.M, load)
    q = 1.0 / np.abs(D_all)
    W, Dm, A, levels = [], [], [], []
    peak_idx = np.argmax(q, axis=1)
    for lv in range(receptance.shape[0]):
        sel = q[lv] >= q[lv].max() / np.sqrt(2.0)
        if slip_amplitude[lv, sel].max() >= phi_max:
            continue
        levels.append(lv + 1)
        W.append(w_all[sel]), Dm.append(D_all[lv, sel]), A.append(slip_amplitude[lv, sel])
    if len(levels) < 2:
        raise ValueError(f"mode {mode}: fewer than 2 micro-slip levels to fit")
    W, Dm, A = np.concatenate(W), np.concatenate(Dm), np.concatenate(A)
    D_lin = _model_inverse_receptance(system, shape, load, W, A, None, None)
    scale = np.mean(np.abs(Dm.imag - D_lin.imag))

    def residual(x, with_freq):
        Dmod = _model_inverse_receptance(system, shape, load, W, A, _math.exp(x[0]), x[1])
        r = (Dmod.imag - Dm.imag) / scale
        return np.concatenate([r, (Dmod.real - Dm.real) / scale]) if with_freq else r

    bounds = ([_math.log(R0) - 30, -0.999], [_math.log(R0) + 30, -0.001])
    out = []
    for with_freq in (False, True):
        sol = _least_squares(residual, [_math.log(R0), chi0], args=(with_freq,),
                             x_scale=[1.0, 0.1], bounds=bounds, xtol=1e-14, ftol=1e-14)
        out.append((float(sol.x[1]), float(_math.exp(sol.x[0]))))
    chi, R = out[0]
    # per-level view (peak line of each level) for Fig. 5
    pk = peak_idx
    lv_all = np.arange(receptance.shape[0])
    wp = w_all[pk]
    Ap = slip_amplitude[lv_all, pk]
    Dp = D_all[lv_all, pk]
    Dl = _model_inverse_receptance(system, shape, load, wp, Ap, None, None)
    Dmod = _model_inverse_receptance(system, shape, load, wp, Ap, R, chi)
    return ImprovedFit(mode=mode, chi=chi, R=R, chi_with_frequency=out[1][0],
                       R_with_frequency=out[1][1], levels=levels, n_lines=int(W.size),
                       level_amplitude=Ap, level_delta_c=Dp.imag - Dl.imag,
                       level_delta_c_model=Dmod.imag - Dl.imag)


@dataclass
class ModeResult:
    """Everything computed for one studied mode (SI units, zeta as fractions)."""

    mode: int
    band: tuple
    frequency_hz: np.ndarray          # (12,) identified (LSCF) natural frequency
    zeta: np.ndarray                  # (12,) identified damping ratio
    table1: np.ndarray                # (12, 2) joint amplitudes at the identified resonance
    fit_levels: list
    paper_estimate: object            # inverse.estimate.Estimate (method "paper")
    amplitude_estimate: object        # inverse.estimate.Estimate (method "amplitude")
    B_inverse: float
    B_simulated: float
    R_paper: float
    R_per_difference_inverse: np.ndarray   # (11,) eq. 37 per successive difference
    R_per_difference_simulated: np.ndarray
    improved: ImprovedFit


@dataclass
class LumpedReport:
    """The reproduction of paper section 3 and the improved method."""

    study: LumpedStudy
    protocol: str
    topology: ModeTopology
    campaign: object                  # runs.stepped_sine.CampaignResult
    modes: dict                       # mode -> ModeResult
    R_true: float
    chi_true: float
    timings: dict

    def to_dict(self) -> dict:
        """Plain JSON form (``iwanfe reproduce lumped --json``)."""
        t1p = paper_table(TABLE1_TEXT)
        t2p = paper_table(TABLE2_TEXT)
        keys = [str(m) for m in self.modes]

        def err(R):
            return 100.0 * (R / self.R_true - 1.0)

        out = {
            "chi_true": self.chi_true,
            "R_true": self.R_true,
            "protocol": self.protocol,
            "chi_paper_method": {k: self.modes[int(k)].paper_estimate.chi for k in keys},
            "chi_improved": {k: self.modes[int(k)].improved.chi for k in keys},
            "chi_amplitude_regression": {k: self.modes[int(k)].amplitude_estimate.chi
                                         for k in keys},
            "chi_improved_with_frequency": {k: self.modes[int(k)].improved.chi_with_frequency
                                            for k in keys},
            "chi_paper_published": {str(m): PAPER_CHI[m] for m in self.modes},
            "R_error_percent": {k: {"paper_method": err(self.modes[int(k)].R_paper),
                                    "improved": err(self.modes[int(k)].improved.R)}
                                for k in keys},
            "fit_levels": {k: self.modes[int(k)].fit_levels for k in keys},
            "improved_levels": {k: self.modes[int(k)].improved.levels for k in keys},
            "table1": {}, "table2": {}, "identified": {},
            "topology": {
                "frequency_hz": self.topology.frequency_hz,
                "joint_modes": self.topology.joint_modes(),
                "in_phase_modes": np.flatnonzero(~self.topology.moves_joints) + 1,
                "joint_slip_ratio": {str(m): float(abs(self.topology.joint_slip[m - 1, 0]
                                                       / self.topology.joint_slip[m - 1, 1]))
                                     for m in self.modes},
            },
            "timings_s": self.timings,
        }
        for k in keys:
            mr = self.modes[int(k)]
            out["table1"][k] = {
                "level": list(range(1, 13)), "force_N": self.campaign.force,
                "frequency_hz": mr.frequency_hz,
                "iwan1": mr.table1[:, 0], "iwan2": mr.table1[:, 1],
                "paper_iwan1": t1p[f"mode{k}_iwan1"], "paper_iwan2": t1p[f"mode{k}_iwan2"],
            }
            out["table2"][k] = {
                "nu_minus_1": list(range(mr.R_per_difference_inverse.size)),
                "inverse_matrix": err(mr.R_per_difference_inverse),
                "simulated": err(mr.R_per_difference_simulated),
                "paper_inverse_matrix": t2p[f"mode{k}_inverse_matrix"],
                "paper_newmark": t2p[f"mode{k}_newmark"],
            }
            out["identified"][k] = {"frequency_hz": mr.frequency_hz, "zeta": mr.zeta}
        return out


def _identify_level(freq, rec, band, target_hz):
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

    from inverse.estimate import estimate
    from inverse.iwan_modal import b_tilde, kappa1_per_R, r_tilde
    from ident.measured import MeasuredData
    from runs.stepped_sine import (Campaign, HBProtocol, NewmarkProtocol, PaperProtocol,
                                 run_campaign, run_level)

    protocols = {"default": HBProtocol(), "hb": HBProtocol(), "newmark": NewmarkProtocol(),
                 "paper": PaperProtocol()}
    if protocol not in protocols:
        raise ValueError(f"unknown protocol {protocol!r} (choose default, newmark or paper)")
    proto = protocols[protocol]
    p = study.params
    setup = lumped10_setup(study)
    system, bank, model, load, F = (setup.system, setup.bank, setup.model, setup.load,
                                    setup.levels)
    freq = study.lines
    topo = mode_topology(system)
    timings = {}
    t0 = _time.perf_counter()
    camp = Campaign(freq, F, load, np.arange(system.n_dof), proto)
    if store is not None:
        from pathlib import Path

        from runs.stepped_sine import campaign_hash
        store = Path(store) / f"campaign-{proto.name}-{campaign_hash(model, bank, camp)[:12]}"
    res = run_campaign(model, bank, camp, store=store, progress=progress,
                       workers=None if executor is not None else workers, executor=executor)
    timings["campaign"] = _time.perf_counter() - t0
    timings["campaign_levels_computed"] = int(res.computed.sum())
    timings["campaign_store"] = None if store is None else str(store)
    from fe.modal import normal_modes

    omega_n, shapes = normal_modes(system.K_J, system.M, system.n_dof)
    phi_max = p.joint.phi_max
    modes = {}
    t0 = _time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(study.modes) * F.size, desc="identify + Table 1", unit="level",
                   leave=False)
    for m in study.modes:
        band = MODE_BANDS[m]
        f_id = np.full(F.size, np.nan)
        z_id = np.full(F.size, np.nan)
        t1 = np.full((F.size, system.n_joints), np.nan)
        for lv in range(F.size):
            f_id[lv], z_id[lv] = _identify_level(freq, res.receptance[lv], band,
                                                 omega_n[m - 1] / (2 * np.pi))
            f_drive = f_id[lv] if np.isfinite(f_id[lv]) else omega_n[m - 1] / (2 * np.pi)
            one = Campaign([f_drive], [F[lv]], load, np.arange(system.n_dof), proto)
            t1[lv] = run_level(model, bank, one, 0).slip_amplitude[0]
            if bar is not None:
                bar.update(1)
        micro = [lv + 1 for lv in range(F.size)
                 if np.all(t1[lv] < phi_max) and np.isfinite(z_id[lv])]
        fit_levels = micro if len(micro) >= 3 else [lv + 1 for lv in range(min(3, F.size))]
        ok = np.isfinite(z_id)
        data = MeasuredData(level=np.arange(1, F.size + 1)[ok], excitation=F[ok],
                            omega2=(2 * np.pi * f_id[ok]) ** 2, zeta=z_id[ok],
                            mode=np.full(ok.sum(), m), run_order=np.arange(1, F.size + 1)[ok])
        fit_levels = [lv for lv in fit_levels if ok[lv - 1]]
        est_paper = estimate(data, fit_levels=fit_levels, method="paper")
        dominant = int(np.argmax(np.abs(topo.joint_slip[m - 1])))
        est_amp = estimate(data, fit_levels=fit_levels, method="amplitude",
                           amplitude=t1[ok, dominant])
        chi = est_paper.chi
        phi = shapes[:, m - 1]
        # B~ (eq. 37) from the linear model at the identified level-1 resonance
        # ("inverse matrix") and from the simulated level-1 amplitudes ("Newmark")
        w1 = 2 * np.pi * f_id[0]
        x = np.linalg.solve(system.K_J - w1 ** 2 * system.M + 1j * w1 * system.C, load * F[0])
        A_inv = np.abs(system.G @ x)
        B_inv = b_tilde(system.G, phi, A_inv, chi)
        B_sim = b_tilde(system.G, phi, t1[0], chi)
        R_paper = r_tilde(est_paper.kappa1_B, chi, B_sim)
        # eq. 37 for each successive difference (Table 2): Delta d_v (eq. 46, as fitted)
        z = p.level_ratio
        pch = chi + 1.0
        dd = np.array([d["delta_d"] for d in est_paper.differences])
        v = np.arange(dd.size)
        denom = kappa1_per_R(chi) * z ** (v * pch) * (z ** pch - 1.0)
        R_inv = dd / (denom * B_inv)
        R_sim = dd / (denom * B_sim)
        imp = fit_improved(system, phi, load, freq, res.receptance, res.slip_amplitude, m,
                           phi_max, band=band, R0=1e5, chi0=-0.4)
        modes[m] = ModeResult(mode=m, band=band, frequency_hz=f_id, zeta=z_id, table1=t1,
                              fit_levels=fit_levels, paper_estimate=est_paper,
                              amplitude_estimate=est_amp, B_inverse=B_inv, B_simulated=B_sim,
                              R_paper=R_paper, R_per_difference_inverse=R_inv,
                              R_per_difference_simulated=R_sim, improved=imp)
    if bar is not None:
        bar.close()
    timings["identification_and_fits"] = _time.perf_counter() - t0
    return LumpedReport(study=study, protocol=protocol, topology=topo, campaign=res,
                        modes=modes, R_true=p.joint.R, chi_true=p.joint.chi, timings=timings)
