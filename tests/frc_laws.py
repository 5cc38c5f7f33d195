"""Small joint laws and one-DOF models for the forced-response tests
(``tests/test_continuation.py``, ``tests/test_hill.py``): a cubic spring (the Duffing
oscillator as a joint law) and a one-sided elastic stop. Both are memoryless, their step
is exact, and their describing functions are closed forms."""
from __future__ import annotations

import numpy as np

from fe.reduction import ReducedModel
from joints.law import JointLaw


class CubicSpring(JointLaw):
    """``F = k3 s^3`` (N), stuck stiffness 0; first harmonic ``k_in = 3 k3 A^2 / 4``."""

    name = "cubic"

    def __init__(self, k3: float):
        self.k3 = float(k3)
        self.K_T = np.zeros(1)

    @property
    def slip_scale(self):
        return np.ones(1)

    def initial_state(self):
        return None

    def step(self, slip, state):
        s = np.asarray(slip, dtype=float)
        return self.k3 * s ** 3, 3.0 * self.k3 * s ** 2, state

    def describing_derivative(self, amplitude):
        A = np.asarray(amplitude, dtype=float)
        return 0.75 * self.k3 * A ** 2, 0.0 * A, 1.5 * self.k3 * A, 0.0 * A


class OneSidedStop(JointLaw):
    """An elastic stop of stiffness ``k_s`` (N/m) engaged beyond the gap ``g`` (m):
    ``F = k_s max(s - g, 0)`` (piecewise linear, stuck stiffness 0)."""

    name = "stop"

    def __init__(self, k_s: float, gap: float):
        self.k_s, self.gap = float(k_s), float(gap)
        self.K_T = np.zeros(1)

    @property
    def slip_scale(self):
        return np.array([self.gap])

    def initial_state(self):
        return None

    def step(self, slip, state):
        s = np.asarray(slip, dtype=float)
        on = s > self.gap
        return self.k_s * np.where(on, s - self.gap, 0.0), np.where(on, self.k_s, 0.0), state

    def describing_derivative(self, amplitude):
        raise NotImplementedError("not needed by the multi-harmonic tests")


def sdof(omega0: float, zeta: float, k_joint: float = 0.0, mass: float = 1.0) -> ReducedModel:
    """``m q'' + 2 zeta omega0 m q' + m omega0^2 q`` with one joint on ``s = q`` of stuck
    stiffness ``k_joint`` already inside ``K`` (``K = m omega0^2``)."""
    return ReducedModel(basis=np.eye(1), omega=np.array([omega0]), M=np.array([[mass]]),
                        K=np.array([[mass * omega0 ** 2]]),
                        C=np.array([[2.0 * zeta * omega0 * mass]]), G=np.eye(1),
                        K_T=np.array([float(k_joint)]), n_modes=1)


class HardenedIwan(JointLaw):
    """Four-parameter Iwan joints (:class:`joints.describing.IwanJoints`) in parallel with
    a cubic spring ``k3 s^3``: hysteresis with memory, and a hardening that folds."""

    name = "iwan+cubic"

    def __init__(self, iwan, k3: float):
        self.iwan, self.k3 = iwan, float(k3)
        self.K_T = iwan.K_T

    @property
    def slip_scale(self):
        return self.iwan.slip_scale

    def initial_state(self):
        return self.iwan.initial_state()

    def step(self, slip, state):
        F, kt, new = self.iwan.step(slip, state)
        s = np.asarray(slip, dtype=float)
        return F + self.k3 * s ** 3, kt + 3.0 * self.k3 * s ** 2, new

    def describing_derivative(self, amplitude):
        k_in, k_q, dk_in, dk_q = self.iwan.describing_derivative(amplitude)
        A = np.asarray(amplitude, dtype=float)
        return k_in + 0.75 * self.k3 * A ** 2, k_q, dk_in + 1.5 * self.k3 * A, dk_q
