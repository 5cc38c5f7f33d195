"""Harmonics of the joints' slip-induced force for given slip harmonics: the two joint paths.

The solvers of nonlinear modes (:mod:`fe.epmc`) and of response-controlled steady
states (:mod:`runs.response_control`) see the joints only through one call: given the
real Fourier coefficients ``Y`` (n_c, n_joints) of the slips (rows ``[Re S_h, Im S_h]``
per harmonic ``h``, the layout of :mod:`fe.harmonic_balance`: ``s(t) = Re sum_h S_h
e^{i h w t}``), return the coefficients of ``g = F(s) - K_T s`` (the joints' departure
from their stuck stiffness, paper eq. 25), their exact Jacobian per joint and the slip
amplitudes. Two paths, each reusing the project's one implementation:

* :class:`BankHarmonics`: Jenkins banks (:class:`fe.reduction.JointBank`) through the
  AFT march of :func:`fe.aft.aft_joint_force` (exact Jacobian of the sampled force),
  any set of harmonics;
* :class:`ExactHarmonics`: any joint law (:mod:`joints.law`; the exact continuous
  four-parameter Iwan joints for Iwan parameters), first harmonic only, through its
  describing function and its derivative: ``G_1 = (k_in(|S|) - K_T + i k_q(|S|)) S``.

Joints are independent: the Jacobian is block diagonal, one (n_c, n_c) block per joint.
SI units: m, N.
"""
from __future__ import annotations

import numpy as np

from fe.aft import aft_joint_force
from fe.harmonic_balance import harmonic_synthesis
from fe.reduction import JointBank
from joints.describing import as_joint_law
from joints.iwan import IwanParameters
from joints.law import describing_force

__all__ = ["BankHarmonics", "ExactHarmonics", "joint_path"]


class BankHarmonics:
    """Jenkins banks by AFT: ``harmonics`` (odd ones suffice for zero-mean slips),
    ``n_time`` samples per period (:func:`fe.aft.aft_joint_force`)."""

    path = "bank"

    def __init__(self, bank: JointBank, harmonics=(1, 3, 5, 7), n_time: int = 256):
        self.bank = bank
        self.harmonics = np.asarray(harmonics, dtype=int)
        if np.any(self.harmonics < 1):
            raise ValueError("BankHarmonics: harmonics must be >= 1 (no static term)")
        self.E, self.P = harmonic_synthesis(self.harmonics, int(n_time))
        self.nc = self.E.shape[1]
        self.K_T = bank.K_T
        self._eye = np.eye(self.nc)

    def __call__(self, Y: np.ndarray, jacobian: bool = True):
        """``(G, J, A)``: coefficients of ``g`` (n_c, n_joints) (N), ``J[j] = dG[:, j] /
        dY[:, j]`` (n_joints, n_c, n_c) (N/m; None without ``jacobian``), half
        peak-to-peak slips (n_joints,) (m)."""
        s_t = np.ascontiguousarray((self.E @ Y).T)
        F, JF = aft_joint_force(s_t, self.bank, *((self.P, self.E) if jacobian else ()))
        G = self.P @ (F - self.K_T[:, None] * s_t).T
        J = JF - self.K_T[:, None, None] * self._eye if jacobian else None
        return G, J, 0.5 * (s_t.max(axis=1) - s_t.min(axis=1))


class ExactHarmonics:
    """Any joint law (:class:`joints.law.JointLaw`; Iwan parameters, one per joint or one
    shared, give the exact continuous Iwan joints), first harmonic, through its
    describing function and the one Jacobian :func:`joints.law.describing_force`."""

    path = "exact"
    harmonics = np.array([1])
    nc = 2

    def __init__(self, joints, n_joints: int | None = None):
        n = getattr(joints, "n_joints", None) if n_joints is None else n_joints
        self.law = as_joint_law(joints, n)
        self.K_T = self.law.K_T

    @property
    def parameters(self) -> list[IwanParameters]:
        """The Iwan joints' parameters (Iwan laws only)."""
        return list(self.law.params)

    def __call__(self, Y: np.ndarray, jacobian: bool = True):
        """As :meth:`BankHarmonics.__call__`; the amplitude is ``|S_1|``."""
        S = Y[0] + 1j * Y[1]
        A = np.abs(S)
        k_in, k_q, dk_in, dk_q = self.law.describing_derivative(A)
        N, d_re, d_im = describing_force((k_in - self.K_T) + 1j * k_q, dk_in + 1j * dk_q, S,
                                         np.maximum(A, 1e-300))
        G = np.array([N.real, N.imag])
        if not jacobian:
            return G, None, A
        J = np.empty((S.size, 2, 2))
        J[:, 0, 0], J[:, 0, 1] = d_re.real, d_im.real
        J[:, 1, 0], J[:, 1, 1] = d_re.imag, d_im.imag
        return G, J, A


def joint_path(path: str, bank: JointBank | None = None, joints=None, n_joints=None,
               harmonics=(1, 3, 5, 7), n_time: int = 256):
    """The joint harmonics of ``path``: ``"bank"`` (needs ``bank``) or ``"exact"`` (needs
    ``joints``: a joint law, or Iwan parameters and ``n_joints``)."""
    if path == "bank":
        if bank is None:
            raise ValueError("the bank path needs a JointBank")
        return BankHarmonics(bank, harmonics, n_time)
    if path == "exact":
        if joints is None:
            raise ValueError("the exact path needs the Iwan parameters of the joints")
        return ExactHarmonics(joints, n_joints)
    raise ValueError(f"unknown joint path {path!r} (choose bank or exact)")
