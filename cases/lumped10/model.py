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

from dataclasses import dataclass, field

import numpy as np

from fe.reduction import JointBank, JointedSystem, rayleigh_damping
from joints.iwan import IwanParameters

__all__ = [
    "LumpedParameters",
    "ModeTopology",
    "lumped10_system",
    "lumped10_bank",
    "force_vector",
    "force_levels",
    "mode_topology",
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
