"""Jenkins banks of all joints, one row per joint: the discretized Iwan joint as a
:class:`joints.law.JointLaw` (compiled step :func:`joints.jenkins.jenkins_update`,
exact first harmonic of the discretized bank). SI units: m, N, N/m, J.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from joints.describing import slider_in_phase
from joints.iwan import IwanParameters
from joints.jenkins import discretize, discretize_log, jenkins_update
from joints.law import JointLaw

__all__ = ["JointBank"]


@dataclass(frozen=True)
class JointBank(JointLaw):
    """Jenkins banks of all joints (one row per joint).

    Parameters
    ----------
    stiffness, slip_limit : ndarray, shape (n_joints, n_sliders)
        Slider spring stiffnesses (N/m) and slip limits (m) (:mod:`joints.jenkins`).
    """

    stiffness: np.ndarray
    slip_limit: np.ndarray
    name = "jenkins"

    def __post_init__(self):
        k = np.atleast_2d(np.asarray(self.stiffness, dtype=float))
        phi = np.atleast_2d(np.asarray(self.slip_limit, dtype=float))
        if k.shape != phi.shape:
            raise ValueError("stiffness and slip_limit must have the same shape")
        if np.any(k < 0) or np.any(phi <= 0):
            raise ValueError("slider stiffnesses must be >= 0 and slip limits > 0")
        object.__setattr__(self, "stiffness", k)
        object.__setattr__(self, "slip_limit", phi)

    @classmethod
    def from_iwan(cls, params: IwanParameters | Sequence[IwanParameters], n_sliders: int,
                  n_joints: int | None = None) -> "JointBank":
        """Discretize Iwan joints (:func:`joints.jenkins.discretize`).

        ``params`` is one :class:`IwanParameters` shared by ``n_joints`` joints, or one
        per joint.
        """
        if isinstance(params, IwanParameters):
            if n_joints is None:
                raise ValueError("n_joints is required with a single IwanParameters")
            params = [params] * int(n_joints)
        return cls.from_discretizations([discretize(p, n_sliders) for p in params])

    @classmethod
    def from_discretizations(cls, discretizations) -> "JointBank":
        """Bank from one :class:`joints.jenkins.JenkinsDiscretization` per joint (e.g.
        :func:`joints.jenkins.discretize_log`); all must have the same number of sliders.
        """
        discs = list(discretizations)
        sizes = {d.n_sliders for d in discs}
        if len(sizes) != 1:
            raise ValueError(f"every joint's discretization needs the same number of "
                             f"sliders, got {sorted(sizes)}")
        return cls(np.array([d.stiffness for d in discs]), np.array([d.slip_limit for d in discs]))

    @classmethod
    def log_spaced(cls, params, a_low: float, sliders_per_octave: int = 16) -> "JointBank":
        """Jenkins banks with slip limits spaced geometrically, one row per joint.

        :func:`joints.jenkins.discretize_log` of every joint (``sliders_per_octave``
        sliders per octave of slip limit from ``phi_max`` down to ``a_low``, exact cell
        moments, stiffnesses summing to ``K_T``; its docstring states the accuracy). The
        joints share one slider grid, so they need the same ``phi_max`` and ``chi``.

        Parameters
        ----------
        params : sequence of IwanParameters
            One per joint, equal ``phi_max`` and ``chi``.
        a_low : float
            Lowest resolved slip limit (m), ``0 < a_low < phi_max``.
        sliders_per_octave : int
        """
        params = list(params)
        pm, chi = params[0].phi_max, params[0].chi
        if any(not np.isclose(p.phi_max, pm, rtol=1e-12, atol=0.0) or p.chi != chi
               for p in params):
            raise ValueError("JointBank.log_spaced: all joints need the same phi_max and chi")
        return cls.from_discretizations(
            discretize_log(p, a_low, sliders_per_octave) for p in params)

    @property
    def n_joints(self) -> int:
        return self.stiffness.shape[0]

    @property
    def n_sliders(self) -> int:
        return self.stiffness.shape[1]

    @property
    def K_T(self) -> np.ndarray:
        """Stuck stiffness of each joint, ``sum_i k_i`` (N/m)."""
        return self.stiffness.sum(axis=1)

    @property
    def friction_force(self) -> np.ndarray:
        """Slider friction forces ``k_i phi_i`` (N), shape (n_joints, n_sliders)."""
        return self.stiffness * self.slip_limit

    def initial_anchor(self) -> np.ndarray:
        """Virgin state: every slider at zero (m), shape (n_joints, n_sliders)."""
        return np.zeros_like(self.stiffness)

    def update(self, slip, anchor):
        """Trial ``(force, tangent, anchor_new)`` (:func:`joints.jenkins.jenkins_update`)."""
        return jenkins_update(slip, anchor, self.stiffness, self.slip_limit)

    def stored_energy(self, slip, anchor) -> float:
        """Elastic energy of the slider springs ``sum 0.5 k_i (s - x_i)^2`` (J)."""
        stretch = np.asarray(slip, dtype=float)[:, None] - anchor
        return float(0.5 * np.sum(self.stiffness * stretch * stretch))

    def dissipated(self, anchor_old, anchor_new) -> float:
        """Friction work of a slider increment ``sum k_i phi_i |x_new - x_old|`` (J)."""
        return float(np.sum(self.friction_force * np.abs(anchor_new - anchor_old)))

    # ---- the joint-law interface (joints.law)

    @property
    def slip_scale(self) -> np.ndarray:
        """Weakest slip limit of each joint (m)."""
        return self.slip_limit.min(axis=1)

    def initial_state(self) -> np.ndarray:
        return self.initial_anchor()

    def step(self, slip, state):
        """``(force, tangent, anchor_new)``: :func:`joints.jenkins.jenkins_update`."""
        return jenkins_update(slip, state, self.stiffness, self.slip_limit)

    def describing_derivative(self, amplitude):
        """Exact first harmonic of the bank: the sum over its sliders of the Jenkins
        element's describing function (:func:`joints.describing.slider_in_phase`). A
        slider ``(k, phi)`` with ``r = phi/A < 1`` gives ``k_in = k I_r(3/2, 3/2)`` and
        ``k_q = 4 k phi (A - phi)/(pi A^2)``, a stuck one ``k`` and 0; derivatives with
        ``dI_r/dr = (8/pi) sqrt(r (1-r))``, ``dr/dA = -r/A``."""
        A = np.maximum(np.asarray(amplitude, dtype=float), 1e-300)[..., None]
        k, phi = self.stiffness, self.slip_limit
        r = np.minimum(phi / A, 1.0)
        slips = phi < A
        g = slider_in_phase(r)
        dg = (8.0 / np.pi) * np.sqrt(r * (1.0 - r)) * (-r / A)
        q = np.where(slips, 4.0 * k * phi * (A - phi) / (np.pi * A * A), 0.0)
        dq = np.where(slips, 4.0 * k * phi * (2.0 * phi - A) / (np.pi * A ** 3), 0.0)
        return ((k * g).sum(-1), q.sum(-1), (k * dg).sum(-1), dq.sum(-1))
