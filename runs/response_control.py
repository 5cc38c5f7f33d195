"""Response-controlled stepped sine: each level holds the drive-point response amplitude.

Phase-resonance and response-controlled testing hold the response, not the force: at
every line of a level the force amplitude ``F`` is adjusted until the first harmonic of
the response at the control DOF ``d`` has the held amplitude ``A``. Along the lines of a
level the joints then see (nearly) one amplitude, so each level's FRF is that of the
structure linearized at one amplitude and a linear modal fit of it gives a point of the
backbone (``control = response`` in ``docs/formats/measured-data.md``).

At one line ``w`` the condensed harmonic balance of :mod:`fe.harmonic_balance`
(``S_h = F S_h^lin - R_h G_h(S)``, with ``S^lin`` the linear slips per newton of the
load pattern) gets one more unknown, ``F``, and one more equation,

    |X_d|^2 = A^2,   X_d = F x_d^lin - (D_1^{-1} G^T)_d G_1(S),

solved together by the globalized Newton of :func:`fe.newton_path.damped_newton` with
the exact Jacobian (the joints through either path of :mod:`fe.joint_harmonics`: any
joint law by its describing function, or Jenkins banks by AFT). Lines are followed by
the secant continuation of :func:`fe.harmonic_balance.natural_continuation`.
:class:`ResponseControlProtocol` plugs this into :func:`runs.stepped_sine.run_campaign`
(store, resume, executors): the campaign's ``force`` column holds the held amplitudes
(m), the level's receptance is ``X / F`` per line, and the force of each line is
``A / |receptance at d|`` (:func:`line_forces`).

SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fe.harmonic_balance import HBOperator, HBSettings, HBSolution, natural_continuation
from fe.joint_harmonics import joint_path
from fe.newton_path import SteadyStateError, damped_newton, stall_words
from fe.reduction import JointBank, ReducedModel
from joints.bouc_wen import BoucWenJoints, BoucWenParameters
from joints.describing import IwanJoints
from joints.iwan import IwanParameters
from joints.law import JointLaw

__all__ = ["ControlledSolution", "solve_response_controlled", "ResponseControlProtocol",
           "law_rows", "rows_law", "line_forces"]


@dataclass
class ControlledSolution(HBSolution):
    """:class:`fe.harmonic_balance.HBSolution` plus the force amplitude ``force`` (N) that
    holds the response."""

    force: float = float("nan")


def solve_response_controlled(model: ReducedModel, joints, load, omega: float, control,
                              amplitude: float, guess=None, tol: float = 1e-10,
                              max_iter: int = 60) -> ControlledSolution:
    """Steady state at ``omega`` whose first harmonic ``control @ Q_1`` has modulus
    ``amplitude`` (module docstring).

    Parameters
    ----------
    model : ReducedModel
    joints : fe.joint_harmonics.BankHarmonics or ExactHarmonics
    load : (r,) reduced load pattern per newton.
    omega : float, rad/s.
    control : (r,) row giving the controlled displacement ``control @ q`` (e.g. a row of
        the basis: a physical DOF).
    amplitude : float, held amplitude (m).
    guess : (n_h, n_joints) complex slip harmonics, optional (default: the linear
        response scaled to the held amplitude).
    """
    A = float(amplitude)
    if not A > 0:
        raise ValueError(f"held amplitude must be > 0, got {amplitude!r}")
    h = np.asarray(joints.harmonics)
    op = HBOperator(model, load, omega, None, harmonics=h)
    i1 = int(np.flatnonzero(h == 1)[0])
    x_lin = complex(control @ op.Xp[i1])
    bal = _ControlledBalance(op, joints, i1, x_lin, control @ op.XG[i1], A,
                             max(np.abs(op.y_lin).max() * A / abs(x_lin), 1e-300))
    y, F = bal.start(guess, h.size)
    try:
        z, it, upd, _ = damped_newton(bal.balance, np.append(y, F), tol, max_iter, bal.scale,
                                      relative_update=bal.relative_update)
    except SteadyStateError as exc:
        raise SteadyStateError(f"{omega / (2 * np.pi):.6g} Hz", exc.reason,
                               solver="response-controlled balance") from None
    return bal.solution(omega, h, z, it, upd, tol)


@dataclass
class _ControlledBalance:
    """The condensed balance at one line with the force ``F`` as one more unknown and
    the held amplitude ``A`` of ``X_d`` as one more equation (module docstring);
    ``x_g = (D_1^{-1} G^T)_d``, ``scale`` the slip scale of the Newton steps."""

    op: HBOperator
    joints: object
    i1: int
    x_lin: complex
    x_g: np.ndarray
    A: float
    scale: float
    eye: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        """The identity of the slip block."""
        self.eye = np.eye(self.op.nc * self.op.nj)

    def evaluate(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, complex]:
        """Joint harmonics, their Jacobian, slip amplitudes and the first harmonic."""
        i1 = self.i1
        Gh, Jg, amp = self.joints(y.reshape(self.op.nc, self.op.nj))
        return Gh, Jg, amp, Gh[2 * i1] + 1j * Gh[2 * i1 + 1]

    def start(self, guess, n_h: int) -> tuple[np.ndarray, float]:
        """The first ``(y, F)``: the guess's slips with their least-squares force, or
        the linear response scaled to the held amplitude."""
        op = self.op
        if guess is None:
            F = self.A / abs(self.x_lin)
            return F * op.y_lin, F
        g = np.asarray(guess, dtype=complex).reshape(n_h, op.nj)
        y = np.empty((op.nc, op.nj))
        y[0::2], y[1::2] = g.real, g.imag
        y = y.reshape(-1)
        Gh = self.evaluate(y)[0]
        return y, float(op.y_lin @ (y + op.Rr @ Gh.reshape(-1)) / (op.y_lin @ op.y_lin))

    def balance(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual and exact Jacobian in ``z = [y, F]`` (module docstring)."""
        op, i1, A, x_lin, x_g = self.op, self.i1, self.A, self.x_lin, self.x_g
        n = op.nc * op.nj
        y, F = z[:-1], z[-1]
        Gh, Jg, amp, N1 = self.evaluate(y)
        X = F * x_lin - x_g @ N1
        res = np.empty(n + 1)
        res[:-1] = y - F * op.y_lin + op.Rr @ Gh.reshape(-1)
        res[-1] = 0.5 * (abs(X) ** 2 / A ** 2 - 1.0)
        Jac = np.empty((n + 1, n + 1))
        Jac[:-1, :-1] = self.eye + np.einsum("cjel,led->cjdl", op.Rr4, Jg).reshape(n, n)
        Jac[:-1, -1] = -op.y_lin
        dN1 = Jg[:, 2 * i1, :] + 1j * Jg[:, 2 * i1 + 1, :]           # (nj, nc): dN1_l/dY[d, l]
        dX = -(x_g[:, None] * dN1).T                                   # (nc, nj)
        Jac[-1, :-1] = (np.conj(X) * dX).real.reshape(-1) / A ** 2
        Jac[-1, -1] = (np.conj(X) * x_lin).real / A ** 2
        return res, Jac

    def relative_update(self, z: np.ndarray, d: np.ndarray) -> float:
        """The Newton step's size relative to the slips and to the force."""
        return max(np.abs(d[:-1]).max() / max(np.abs(z[:-1]).max(), self.scale * 1e-12),
                   abs(d[-1]) / max(abs(z[-1]), 1e-300))

    def solution(self, omega: float, h: np.ndarray, z: np.ndarray, it: int, upd: float,
                 tol: float) -> ControlledSolution:
        """The steady state of the converged ``z = [y, F]`` (``F > 0``)."""
        op, i1 = self.op, self.i1
        y, F = z[:-1], float(z[-1])
        if F < 0:              # the mirror solution (odd joints): same receptance, F > 0
            y, F = -y, -F
        Gh, _, amp, _ = self.evaluate(y)
        Y = y.reshape(op.nc, op.nj)
        S, Nh = Y[0::2] + 1j * Y[1::2], Gh[0::2] + 1j * Gh[1::2]
        q = -np.einsum("hrj,hj->hr", op.XG, Nh)
        q[i1] += F * op.Xp[i1]
        return ControlledSolution(omega=float(omega), harmonics=h, slip=S, joint_force=Nh,
                                  q=q, slip_amplitude=amp, iterations=it,
                                  residual=float(upd), fallback=stall_words(upd, tol),
                                  force=float(F))


@dataclass(frozen=True)
class ResponseControlProtocol:
    """Response control at physical DOF ``dof`` for :func:`runs.stepped_sine.run_campaign`
    (the campaign's ``force`` holds the held amplitudes, m).

    ``path``: ``"bank"`` (the campaign's Jenkins banks, harmonics and AFT samples of
    ``settings``) or ``"exact"`` (first harmonic, the joints ``exact_joints``: one
    ``(chi, K_T, F_S, beta)`` per continuous Iwan joint, or rows naming another law,
    ``("bouc-wen", K_T, F_S, alpha, shape)`` or ``("jenkins", stiffnesses, slip limits)``
    per joint: :func:`law_rows`).
    """

    dof: int
    path: str = "bank"
    settings: HBSettings = field(default_factory=HBSettings)
    exact_joints: tuple = ()
    name: str = "response"

    @classmethod
    def exact(cls, dof: int, joints, settings: HBSettings = HBSettings()):
        """The exact path with ``joints`` (sequence of IwanParameters, or a joint law:
        :func:`law_rows`)."""
        return cls(int(dof), "exact", settings, law_rows(joints))

    def joint_harmonics(self, bank):
        if self.path == "exact":
            joints = rows_law(self.exact_joints)
            return joint_path("exact", joints=joints, n_joints=len(self.exact_joints))
        return joint_path(self.path, bank=bank, harmonics=self.settings.harmonics,
                          n_time=self.settings.n_time)

    def run_level(self, model: ReducedModel, bank, campaign, amplitude: float, tick=None):
        """One level at held ``amplitude`` (m) over the campaign's lines: the level runner
        of :func:`runs.stepped_sine.run_level` (receptance, first-harmonic slips, slip
        amplitudes, Newton iterations and fallbacks per line)."""
        joints = self.joint_harmonics(bank)
        load = model.load(campaign.load)
        control = np.asarray(model.basis[int(self.dof)], dtype=float)
        s = self.settings
        sols = natural_continuation(
            lambda w, guess: solve_response_controlled(model, joints, load, w, control,
                                                       amplitude, guess, s.tol, s.max_iter),
            2 * np.pi * campaign.frequency_hz, tick)
        rec = np.array([x.first_harmonic(model)[campaign.outputs] / x.force for x in sols])
        slip = np.array([x.slip[x.harmonics == 1][0] for x in sols])
        amp = np.array([x.slip_amplitude for x in sols])
        work = np.array([x.iterations for x in sols], dtype=float)
        return rec, slip, amp, work, [x.fallback for x in sols]


def law_rows(joints) -> tuple:
    """The joints as plain rows (hashable into a campaign's hash): Iwan parameters as
    ``(chi, K_T, F_S, beta)``, a Bouc-Wen law as ``("bouc-wen", K_T, F_S, alpha, shape)``
    and a Jenkins bank as ``("jenkins", stiffnesses, slip limits)`` per joint."""
    if isinstance(joints, BoucWenJoints):
        return tuple(("bouc-wen", p.K_T, p.F_S, p.alpha, p.shape) for p in joints.params)
    if isinstance(joints, JointBank):
        return tuple(("jenkins", tuple(map(float, k)), tuple(map(float, phi)))
                     for k, phi in zip(joints.stiffness, joints.slip_limit))
    if isinstance(joints, IwanJoints):
        joints = joints.params
    if isinstance(joints, JointLaw):
        raise ValueError(f"response control: no rows for the joint law {joints.name!r}")
    return tuple((p.chi, p.K_T, p.F_S, p.beta) for p in joints)


def rows_law(rows):
    """The joints of :func:`law_rows`' ``rows`` (Iwan parameters, or the law)."""
    tag = rows[0][0] if rows else None
    if tag == "bouc-wen":
        return BoucWenJoints([BoucWenParameters(*r[1:]) for r in rows])
    if tag == "jenkins":
        return JointBank(np.array([r[1] for r in rows]), np.array([r[2] for r in rows]))
    return [IwanParameters(*row) for row in rows]


def line_forces(result, campaign) -> np.ndarray:
    """Force amplitude of every line (n_levels, n_lines) (N) of a response-controlled
    campaign result: held amplitude over the receptance modulus at the control DOF."""
    dof = campaign.protocol.dof
    idx = np.flatnonzero(np.asarray(campaign.outputs) == dof)
    if idx.size == 0:
        raise ValueError(f"the control DOF {dof} is not among the campaign's outputs")
    return campaign.force[:, None] / np.abs(result.receptance[:, :, idx[0]])
