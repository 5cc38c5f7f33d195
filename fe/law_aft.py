"""Alternating frequency-time (AFT) harmonics of any joint law through its time step.

For multi-harmonic balance with a law known only by its step ``step(slip, state) ->
(force, tangent, state)`` (:mod:`joints.law`), the slips ``s(t) = sum_c E_c(t) Y_c``
(real coefficients ``Y``, the layout of :func:`fe.harmonic_balance.harmonic_synthesis`)
are sampled at ``n_time`` instants of the period and the law is marched through the
samples from its virgin state, starting at the slip maximum of the first joint, period
after period until the force over a period repeats (``|F_p - F_{p-1}| <= rtol
max |F_p|``; at least two periods: a Masing law or a Jenkins bank repeats after the
first), and the last period is the periodic steady force ``F_n``. Its harmonics are

    G = P (F - K_T s),                                                             (1)

the joints' departure from their stuck stiffness (paper eq. 25). Jacobian ``dG/dY``
(block per joint, joints are independent), by ``jacobian``:

* ``"bank"`` (automatic for :class:`joints.bank.JointBank`): the exact Jacobian of the
  compiled periodic Jenkins march, :func:`fe.aft.aft_joint_force` (no second march
  here);
* ``"fd"`` (automatic otherwise): finite differences of the whole periodic march, one
  march per real coefficient (all joints at once, since they are independent), central
  (``fd_central``) or forward, step ``fd_step`` times each joint's slip amplitude, each
  march as many periods as the unperturbed one (one when its first period already
  repeated: a Masing law, a Jenkins bank, a law without memory).
  This is the consistent tangent of the marched path, memory of past reversals
  included;
* ``"tangent"``: ``P diag(k_t) E - K_T I`` from the step's tangent along the period:
  exact for a law without memory (an elastic spring), a quasi-Newton matrix otherwise.

SI units: m, N, N/m.
"""
from __future__ import annotations

import numpy as np

from fe.aft import aft_joint_force
from fe.harmonic_balance import harmonic_synthesis
from joints.bank import JointBank
from joints.law import JointLaw

__all__ = ["periodic_law_force", "LawHarmonics"]


def periodic_law_force(law: JointLaw, slip_t: np.ndarray, max_periods: int = 50,
                       rtol: float = 1e-12, n_periods: int | None = None):
    """Periodic force of ``law`` for slips sampled over one period (module docstring).

    Parameters
    ----------
    law : joints.law.JointLaw
    slip_t : ndarray, shape (n_joints, n_time)
        Slip samples (m) at ``t_n = n T / n_time``.
    max_periods, rtol : the repetition test (module docstring).
    n_periods : int, optional
        March exactly this many periods (no test): the finite-difference marches use
        the count of the unperturbed one.

    Returns
    -------
    force, tangent : ndarray, shape (n_joints, n_time)
        ``F`` (N) and ``dF/ds`` of the step (N/m) on the last period.
    periods : int
        Periods marched.
    """
    slip_t = np.asarray(slip_t, dtype=float)
    nj, N = slip_t.shape
    start = int(np.argmax(slip_t[0]))
    order = (start + np.arange(N)) % N
    state = law.initial_state()
    force, tangent = np.empty((nj, N)), np.empty((nj, N))
    previous = None
    limit = max_periods if n_periods is None else n_periods
    for period in range(1, limit + 1):
        for n in order:
            F, kt, state = law.step(slip_t[:, n], state)
            force[:, n], tangent[:, n] = F, kt
        if n_periods is None and previous is not None and np.max(
                np.abs(force - previous)) <= rtol * max(np.abs(force).max(), 1e-300):
            return force, tangent, period
        previous = force.copy()
    if n_periods is None:
        raise RuntimeError(f"the joint force did not repeat within {max_periods} periods")
    return force, tangent, limit


class LawHarmonics:
    """Harmonics of ``g = F - K_T s`` of any joint law by AFT (module docstring), with
    the call of :class:`fe.joint_harmonics.BankHarmonics`.

    Parameters
    ----------
    law : joints.law.JointLaw
    harmonics : sequence of int
        Harmonic numbers (``0``: the static term).
    n_time : int
        Samples per period.
    jacobian : ``"auto"``, ``"bank"``, ``"fd"`` or ``"tangent"``
    fd_step : float
        Finite-difference step relative to each joint's largest slip.
    fd_central : bool
    """

    path = "law"

    def __init__(self, law: JointLaw, harmonics=(1, 3, 5, 7), n_time: int = 256,
                 jacobian: str = "auto", fd_step: float = 1e-6, fd_central: bool = False,
                 max_periods: int = 50, rtol: float = 1e-12):
        if jacobian == "auto":
            jacobian = "bank" if isinstance(law, JointBank) else "fd"
        if jacobian not in ("bank", "fd", "tangent"):
            raise ValueError(f"unknown jacobian {jacobian!r} (bank, fd or tangent)")
        if jacobian == "bank" and not isinstance(law, JointBank):
            raise ValueError("the bank Jacobian needs a JointBank")
        self.law, self.jacobian = law, jacobian
        self.harmonics = np.asarray(harmonics, dtype=int)
        self.E, self.P = harmonic_synthesis(self.harmonics, int(n_time))
        self.nc = self.E.shape[1]
        self.K_T = np.asarray(law.K_T, dtype=float)
        self.fd_step, self.fd_central = float(fd_step), bool(fd_central)
        self.max_periods, self.rtol = int(max_periods), float(rtol)
        self._eye = np.eye(self.nc)

    def _force(self, s_t, n_periods=None):
        return periodic_law_force(self.law, s_t, self.max_periods, self.rtol, n_periods)

    def __call__(self, Y: np.ndarray, jacobian: bool = True):
        """``(G, J, A)``: coefficients of ``g`` (n_c, n_joints) (N), ``J[j] =
        dG[:, j]/dY[:, j]`` (n_joints, n_c, n_c) (N/m; None without ``jacobian``),
        half peak-to-peak slips (n_joints,) (m)."""
        Y = np.asarray(Y, dtype=float)
        s_t = np.ascontiguousarray((self.E @ Y).T)
        amp = 0.5 * (s_t.max(axis=1) - s_t.min(axis=1))
        if self.jacobian == "bank":
            F, JF = aft_joint_force(s_t, self.law, *((self.P, self.E) if jacobian else ()))
            J = JF - self.K_T[:, None, None] * self._eye if jacobian else None
            return self.P @ (F - self.K_T[:, None] * s_t).T, J, amp
        F, kt, periods = self._force(s_t)
        G = self.P @ (F - self.K_T[:, None] * s_t).T
        if not jacobian:
            return G, None, amp
        if self.jacobian == "tangent":
            JF = np.einsum("cn,jn,nd->jcd", self.P, kt, self.E)
        else:
            JF = self._fd(s_t, F, 1 if periods == 2 else periods)
        return G, JF - self.K_T[:, None, None] * self._eye, amp

    def _fd(self, s_t, F, periods):
        """``P dF/dY`` (n_joints, n_c, n_c) by differences of the periodic march."""
        scale = np.maximum(np.abs(s_t).max(axis=1), 1e-300)            # (nj,)
        h = self.fd_step * scale
        JF = np.empty((s_t.shape[0], self.nc, self.nc))
        for d in range(self.nc):
            ds = h[:, None] * self.E[:, d][None, :]
            Fp = self._force(s_t + ds, periods)[0]
            if self.fd_central:
                Fm = self._force(s_t - ds, periods)[0]
                dF = (Fp - Fm) / (2.0 * h[:, None])
            else:
                dF = (Fp - F) / h[:, None]
            JF[:, :, d] = dF @ self.P.T
        return JF
