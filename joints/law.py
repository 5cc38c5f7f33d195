"""The one interface every joint law offers the solvers, vectorized over joints.

A joint law acts on the relative slips ``s`` (m) of ``n_joints`` independent joints and
gives the solvers three things (``fe`` knows a joint only through them):

* ``step(slip, state) -> (force, tangent, new_state)``: the force ``F`` (N) and the
  consistent tangent ``dF/ds`` (N/m) at the end of a time step that carries the joints
  from their committed ``state`` to ``slip``; ``state`` is not modified (Newmark
  iterates on ``slip`` and commits ``new_state`` once a step has converged).
  ``initial_state()`` is the virgin joint at ``s = 0``.
* ``describing_derivative(A) -> (k_in, k_q, dk_in/dA, dk_q/dA)``: the first-harmonic
  (describing-function) stiffnesses of the steady loop of ``s = A sin(wt)``,
  ``F_1 = A (k_in sin wt + k_q cos wt)`` (dissipation per cycle ``pi A^2 k_q``), and
  their derivatives in ``A`` for Newton Jacobians; ``A`` broadcasts against
  ``(n_joints,)``. ``describing(A)`` is its first two.
* ``K_T`` (``stuck_stiffness``): ``dF/ds`` of the virgin joint (N/m, ``(n_joints,)``).
  Every solver writes ``F = K_T s + g(s)`` and keeps ``K_T`` in the linear part
  (paper eq. 25).

Laws: :class:`joints.describing.IwanJoints` (four-parameter Iwan, exact),
:class:`joints.bank.JointBank` (Jenkins banks, compiled step) and
:class:`joints.bouc_wen.BoucWenJoints` (Bouc 1967 / Wen 1976). A new law is one file
with a class that derives from :class:`JointLaw` (docs/joint-laws.md).

:func:`describing_force` is the one first-harmonic joint force and Jacobian every
describing-function balance uses. SI units: m, N, N/m.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

__all__ = ["JointLaw", "describing_force"]


class JointLaw(ABC):
    """Base of the joint laws (module docstring). Subclasses set ``K_T`` (n_joints,)
    and implement :meth:`step`, :meth:`initial_state` and :meth:`describing_derivative`.
    """

    #: stuck stiffness of each joint (N/m), shape (n_joints,)
    K_T: np.ndarray
    #: short name of the law (reports, results)
    name: str = "joint law"

    @property
    def n_joints(self) -> int:
        return int(np.size(self.K_T))

    @property
    def slip_scale(self) -> np.ndarray:
        """Slip (m) per joint at which the joint is clearly nonlinear (a Jenkins bank's
        weakest slip limit, an Iwan joint's ``phi_max``): solvers set their slip
        tolerances relative to it."""
        raise NotImplementedError

    @property
    def stuck_stiffness(self) -> np.ndarray:
        """``dF/ds`` of the virgin joint (N/m), shape (n_joints,)."""
        return self.K_T

    @abstractmethod
    def initial_state(self) -> np.ndarray:
        """State of the virgin joints at zero slip."""

    @abstractmethod
    def step(self, slip, state):
        """``(force (N), tangent dF/ds (N/m), new_state)`` at ``slip`` (n_joints,) (m)
        after a step from the committed ``state`` (module docstring)."""

    @abstractmethod
    def describing_derivative(self, amplitude):
        """``(k_in, k_q, dk_in/dA, dk_q/dA)`` at slip amplitudes ``amplitude`` (m)
        (N/m, N/m, N/m^2, N/m^2)."""

    def describing(self, amplitude):
        """First-harmonic stiffnesses ``(k_in, k_q)`` (N/m) of the steady loop of
        ``s = A sin(wt)``."""
        return self.describing_derivative(amplitude)[:2]


def describing_force(kap, dkap, S, A):
    """First harmonic of a describing-function force and its exact Jacobian.

    ``N = kap(|S|) S`` with ``kap = k_in - K_T + i k_q`` (the joints' departure from
    their stuck stiffness, complex, N/m) and ``S`` the complex first-harmonic slip (m);
    with ``A = |S|`` (floored away from 0 by the caller) and ``kap' = dkap/dA``,

        dN/dRe S = kap + S kap' Re S / A,     dN/dIm S = i kap + S kap' Im S / A.

    Returns ``(N, dN/dRe S, dN/dIm S)``, complex, all broadcast like ``S``.
    """
    g = dkap / A
    return kap * S, kap + S * g * S.real, 1j * kap + S * g * S.imag
