"""Newmark / HHT-alpha time integration of a reduced jointed structure.

Equation of motion in the reduced basis (:mod:`fe.reduction`, paper eq. 23-25)::

    M q'' + C q' + K_J q + G^T g(s) = p(t),   s = G q,   g(s) = F(s) - K_T s,

where ``F`` is the Jenkins-bank force of each joint (:mod:`joints.jenkins`) and
``K_J`` already holds the stuck stiffness ``K_T``; ``g`` is the slip-induced force.

Scheme: HHT-alpha (Hilber, Hughes, Taylor 1977) with ``alpha`` in [-1/3, 0],
``beta = (1 - alpha)^2/4``, ``gamma = 1/2 - alpha``; ``alpha = 0`` is the Newmark
average-acceleration rule (Newmark 1959, paper ref. 18), unconditionally stable and
non-dissipative. The balance at ``t_{n+1}``::

    M a1 + (1+alpha)(C v1 + K q1 + G^T g1) - alpha (C v0 + K q0 + G^T g0)
        = (1+alpha) p1 - alpha p0

is linear in ``a1`` except for ``g1 = g(G q1)``. Writing
``a1 = a_lin - (1+alpha) S^{-1} G^T g1`` with ``S = M + (1+alpha)(gamma dt C + beta
dt^2 K)`` reduces each step to ``n_joints`` nonlinear equations in the slips::

    h(s) = s - s_lin + (1+alpha) beta dt^2 Z g(s) = 0,   Z = G S^{-1} G^T,

solved by Newton with the consistent tangent ``dg/ds = k_t - K_T`` from the return
mapping. The joints' slider states are committed once the step has converged. The
step loops (compiled, and the reference Python loop) are in :mod:`fe.newmark_march`;
:class:`NewmarkIntegrator` builds the step operators once for repeated runs.

Energy balance (reported by :func:`integrate`): with ``Dq = q1 - q0``,
``input = sum Dq . (p0 + p1)/2``, ``viscous = sum Dq . C (v0 + v1)/2``,
``joint dissipation = sum_i k_i phi_i |D x_i|`` (friction work of the sliders),
kinetic ``v.M v/2``, structural strain energy ``q.K_J q/2 - sum K_T s^2/2`` and joint
stored energy ``sum_i k_i (s - x_i)^2/2``. For ``alpha = 0`` the scheme conserves this
balance exactly except for the trapezoidal joint work over a step in which a slider
starts to slip (``O(dt^2)``); ``alpha < 0`` adds numerical dissipation, which then
shows in the residual. SI units: s, m, N, J.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fe.newmark_march import march, reference_loop
from fe.reduction import JointBank, ReducedModel
from joints.law import JointLaw

__all__ = ["NewmarkSettings", "NewmarkState", "EnergyBalance", "NewmarkRun", "NewmarkIntegrator",
           "integrate"]


@dataclass(frozen=True)
class NewmarkSettings:
    """Time step ``dt`` (s), HHT ``alpha`` in [-1/3, 0], Newton tolerance on the slip
    residual (relative to the slip scale, dimensionless) and iteration cap."""

    dt: float
    alpha: float = 0.0
    tol: float = 1e-12
    max_iter: int = 40

    def __post_init__(self):
        if not self.dt > 0:
            raise ValueError(f"time step dt must be > 0, got {self.dt!r}")
        if not -1.0 / 3.0 <= self.alpha <= 0.0:
            raise ValueError(f"HHT alpha must lie in [-1/3, 0], got {self.alpha!r}")

    @property
    def beta(self) -> float:
        return 0.25 * (1.0 - self.alpha) ** 2

    @property
    def gamma(self) -> float:
        return 0.5 - self.alpha


@dataclass
class NewmarkState:
    """Committed state at time ``t``: reduced displacement ``q`` (m), velocity ``v``,
    acceleration ``a``, the joint law's state ``anchor`` (a Jenkins bank's slider
    anchors, m, shape (n_joints, n_sliders)), slip-induced
    joint force ``g`` (N) and the scalar excitation value ``e`` at ``t``."""

    t: float
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    anchor: np.ndarray
    g: np.ndarray
    e: float = 0.0

    @classmethod
    def rest(cls, model: ReducedModel, bank: JointLaw, t: float = 0.0) -> "NewmarkState":
        """Structure at rest, joints virgin (``anchor``: the law's initial state)."""
        r = model.n_reduced
        return cls(t=t, q=np.zeros(r), v=np.zeros(r), a=np.zeros(r),
                   anchor=bank.initial_state(), g=np.zeros(bank.n_joints), e=0.0)

    @classmethod
    def periodic(cls, model: ReducedModel, bank: JointBank, harmonics, q_harmonics,
                 omega: float, load, n_time: int = 256,
                 dt: float | None = None) -> "NewmarkState":
        """State at phase 0 (``t = 0``, excitation ``e = cos 0 = 1``) of the periodic
        orbit ``q(t) = Re sum_h Q_h e^{i h omega t}`` (e.g. a harmonic-balance solution,
        :attr:`fe.harmonic_balance.HBSolution.q`): ``q``, ``v`` from the harmonics
        (``V_h = i h omega Q_h``, or with ``dt`` the trapezoidal rule's own steady-state
        relation ``V_h = (2i/dt) tan(h omega dt/2) Q_h``), the
        slider anchors of the periodic loop at phase 0 (:func:`fe.aft.aft_slider_state`
        on ``n_time`` samples), ``g`` from them and ``a`` from the equation of motion
        with the real reduced ``load``. Integration from it starts on (near) the orbit:
        the transient is only the difference between the orbit and the integrator's own
        steady state."""
        from fe.aft import aft_slider_state

        h = np.asarray(harmonics, dtype=float)
        Q = np.asarray(q_harmonics, dtype=complex)                      # (n_h, r)
        theta = 2.0 * np.pi * np.arange(int(n_time)) / int(n_time)
        s_t = model.G @ np.real(Q.T @ np.exp(1j * np.outer(h, theta)))  # (nj, N)
        anchor = aft_slider_state(s_t, bank, 0)
        q = np.real(Q.sum(axis=0))
        rate = h * omega if dt is None else (2.0 / dt) * np.tan(0.5 * h * omega * dt)
        v = np.real((1j * rate[:, None] * Q).sum(axis=0))
        s = model.G @ q
        g = np.sum(bank.stiffness * (s[:, None] - anchor), axis=1) - model.K_T * s
        f = np.asarray(load, dtype=float) - model.C @ v - model.K @ q - model.G.T @ g
        return cls(t=0.0, q=q, v=v, a=np.linalg.solve(model.M, f), anchor=anchor, g=g, e=1.0)

    def copy(self) -> "NewmarkState":
        anchor = self.anchor.copy() if hasattr(self.anchor, "copy") else self.anchor
        return NewmarkState(self.t, self.q.copy(), self.v.copy(), self.a.copy(),
                            anchor, self.g.copy(), self.e)


@dataclass
class EnergyBalance:
    """Energies over a run (J). ``residual = input - (viscous + joint_dissipation +
    kinetic + strain + joint_stored)`` where the last three are changes."""

    input: float = 0.0
    viscous: float = 0.0
    joint_dissipation: float = 0.0
    kinetic: float = 0.0
    strain: float = 0.0
    joint_stored: float = 0.0

    @property
    def residual(self) -> float:
        return self.input - (self.viscous + self.joint_dissipation + self.kinetic
                             + self.strain + self.joint_stored)

    @property
    def relative_residual(self) -> float:
        """``|residual| / max(|input|, sum of |terms|)``."""
        scale = max(abs(self.input), abs(self.viscous) + abs(self.joint_dissipation)
                    + abs(self.kinetic) + abs(self.strain) + abs(self.joint_stored))
        return abs(self.residual) / scale if scale > 0 else 0.0


@dataclass
class NewmarkRun:
    """Result of :func:`integrate`: times ``t`` (n_steps+1,), reduced displacements
    ``q`` and velocities ``v`` (n_steps+1, r), slips (n_steps+1, n_joints), the final
    state, the energy balance (None if not asked for, or for a joint law other than a
    Jenkins bank: only the bank states its stored energy and friction work) and the
    total number of Newton iterations."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    slip: np.ndarray
    state: NewmarkState
    energy: EnergyBalance | None
    newton_iterations: int = 0
    joint_force: np.ndarray = field(default=None)


def _energies(model: ReducedModel, bank: JointBank, q, v, anchor):
    s = model.G @ q
    kin = 0.5 * v @ (model.M @ v)
    strain = 0.5 * q @ (model.K @ q) - 0.5 * np.sum(model.K_T * s * s)
    return kin, strain, bank.stored_energy(s, anchor)


class NewmarkIntegrator:
    """Step operators of the HHT/Newmark scheme for one model, joint bank and time
    step, built once and reused by every :meth:`run` (a stepped-sine line integrates
    period after period with the same operators).

    Parameters
    ----------
    model : ReducedModel
    bank : joints.law.JointLaw
        The joints; ``bank.K_T`` must equal ``model.K_T``. A Jenkins bank
        (:class:`joints.bank.JointBank`) runs the compiled step loop; any other law the
        plain Python loop over its ``step`` (300-600x slower per step for one joint,
        ``benchmarks/bench_joint_laws.py``; ``compiled`` is then ignored).
    settings : NewmarkSettings
    """

    def __init__(self, model: ReducedModel, bank: JointLaw, settings: NewmarkSettings):
        K_T_bank = bank.K_T
        if K_T_bank.shape != model.K_T.shape or np.any(
                np.abs(K_T_bank - model.K_T) > 1e-9 * np.abs(model.K_T) + 1e-300):
            raise ValueError("joint bank stiffness does not match the model's K_T")
        self.model, self.bank, self.settings = model, bank, settings
        dt, al = settings.dt, settings.alpha
        be, ga = settings.beta, settings.gamma
        M, C, K, G = model.M, model.C, model.K, model.G
        S = M + (1.0 + al) * (ga * dt * C + be * dt * dt * K)
        self.Sinv = Sinv = np.linalg.inv(S)
        self.Y = Y = Sinv @ G.T                                   # (r, nj)
        self.Z = G @ Y                                            # (nj, nj)
        self.cz = (1.0 + al) * be * dt * dt
        # a_lin = B @ [q; v; a] + Sinv load ((1+al) e1 - al e0) + al Y g0
        A_q = -K
        A_v = -C - (1.0 + al) * dt * K
        A_a = -(1.0 + al) * (dt * (1.0 - ga) * C + dt * dt * (0.5 - be) * K)
        self.B = np.ascontiguousarray(Sinv @ np.hstack([A_q, A_v, A_a]))   # (r, 3r)
        c = np.ascontiguousarray
        self._BT, self._YT, self._Zc = c(self.B.T), c(Y.T), c(self.Z)
        self._G = c(G, dtype=float)
        self._K_T = c(model.K_T, dtype=float)
        self.is_bank = isinstance(bank, JointBank)
        if self.is_bank:
            self._k, self._phi = c(bank.stiffness), c(bank.slip_limit)
            self._fric = c(bank.friction_force)
        self.slip_scale = float(np.min(bank.slip_scale)) * 1e-3
        self.bdt2, self.ga_dt = be * dt * dt, ga * dt
        self._reference_ops = None

    def _reference_operators(self):
        if self._reference_ops is None:
            r = self.model.n_reduced
            dt, be, ga = self.settings.dt, self.settings.beta, self.settings.gamma
            eye = np.eye(r)
            P = np.hstack([eye, dt * eye, dt * dt * (0.5 - be) * eye])      # q~ = P x
            Vp = np.hstack([np.zeros((r, r)), eye, dt * (1.0 - ga) * eye])  # v~ = Vp x
            self._reference_ops = (P, Vp, self.model.G @ P, self.model.G @ self.B)
        return self._reference_ops

    def run(self, load, excitation, state: NewmarkState | None = None,
            record_force: bool = False, compiled: bool = True,
            energy: bool = True) -> NewmarkRun:
        """Integrate ``len(excitation) - 1`` steps; see :func:`integrate`.

        ``energy=False`` skips the energy balance (``NewmarkRun.energy`` is then None):
        it costs ``O(n_steps r^2)``, as much as the steps themselves for a large
        unreduced model."""
        model, bank, settings = self.model, self.bank, self.settings
        load = np.ascontiguousarray(load, dtype=float)
        e = np.ascontiguousarray(excitation, dtype=float)
        n_steps = e.size - 1
        if n_steps < 1:
            raise ValueError("need at least two excitation samples")
        st = NewmarkState.rest(model, bank) if state is None else state.copy()
        dt, al = settings.dt, settings.alpha
        be, ga = settings.beta, settings.gamma
        G, K_T = model.G, model.K_T
        r = model.n_reduced
        sl = self.Sinv @ load
        energy = energy and self.is_bank
        if energy:
            kin0, strain0, stored0 = _energies(model, bank, st.q, st.v, st.anchor)
        if compiled and not record_force and self.is_bank:
            x0 = np.concatenate([st.q, st.v, st.a])
            c = np.ascontiguousarray
            qh, vh, sh, x, g_end, anchor, dissip, iters, status = march(
                self._BT, sl, self._G, self._YT, self._Zc, self.cz, self.bdt2, al, dt,
                dt * dt * (0.5 - be), dt * (1.0 - ga), self.ga_dt, e, x0,
                c(st.g, dtype=float), c(st.anchor, dtype=float), self._k, self._phi,
                self._fric, self._K_T, settings.tol, settings.max_iter, self.slip_scale)
            if status >= 0:
                raise RuntimeError(f"Newton did not converge at step {status}")
            sh[0] = G @ st.q
            fh = None
        else:
            P, Vp, GP, GB = self._reference_operators()
            qh, vh, sh, fh, x, g_end, anchor, dissip, iters = reference_loop(
                st, e, self.B, sl, GP, GB, G @ sl, P, Vp, self.Y, self.Z, self.cz,
                self.bdt2, al, self.ga_dt, G, K_T, bank.step, settings.tol,
                settings.max_iter, self.slip_scale, record_force,
                bank.dissipated if self.is_bank else None)
        q1, v1 = x[:r], x[r:2 * r]
        balance = None
        if energy:   # vectorized over the history (matrix products, O(n r^2))
            dq = np.diff(qh, axis=0)
            vbar = 0.5 * (vh[1:] + vh[:-1])
            ebar = 0.5 * (e[1:] + e[:-1])
            w_in = float(np.dot(dq @ load, ebar))
            w_visc = float(np.sum((dq @ model.C) * vbar))
            kin1, strain1, stored1 = _energies(model, bank, q1, v1, anchor)
            balance = EnergyBalance(input=w_in, viscous=w_visc,
                                    joint_dissipation=float(dissip),
                                    kinetic=float(kin1 - kin0),
                                    strain=float(strain1 - strain0),
                                    joint_stored=stored1 - stored0)
        final = NewmarkState(t=st.t + n_steps * dt, q=q1.copy(), v=v1.copy(),
                             a=x[2 * r:].copy(), anchor=anchor, g=np.array(g_end, dtype=float),
                             e=float(e[-1]))
        t = st.t + dt * np.arange(n_steps + 1)
        return NewmarkRun(t=t, q=qh, v=vh, slip=sh, state=final, energy=balance,
                          newton_iterations=int(iters), joint_force=fh)


def integrate(model: ReducedModel, bank: JointBank, load, excitation, settings: NewmarkSettings,
              state: NewmarkState | None = None, record_force: bool = False,
              compiled: bool = True) -> NewmarkRun:
    """Integrate ``len(excitation) - 1`` steps of the HHT/Newmark scheme.

    Builds a :class:`NewmarkIntegrator` (step operators) and runs it; to integrate
    several stretches with the same model, bank and step, build the integrator once.

    Parameters
    ----------
    model : ReducedModel
    bank : joints.law.JointLaw
        The joints (a :class:`joints.bank.JointBank`, or any law: then the plain step
        loop, :class:`NewmarkIntegrator`); ``bank.K_T`` must equal ``model.K_T``.
    load : ndarray, shape (r,)
        Reduced load pattern ``Phi^T f`` (N).
    excitation : ndarray, shape (n_steps + 1,)
        Scalar multiplier of ``load`` at ``t0 + k dt``; ``excitation[0]`` must be the
        value at the initial state's time.
    settings : NewmarkSettings
    state : NewmarkState, optional
        Initial state (default: rest, virgin joints). Not modified.
    record_force : bool
        Also return the joint forces ``F`` (n_steps+1, n_joints) (reference loop).
    compiled : bool
        Compiled step loop (default; joints through
        :func:`joints.kernel.bank_update_kernel`) or the reference Python loop over
        :func:`joints.jenkins.jenkins_update` (same algebra; for tests).

    Returns
    -------
    NewmarkRun
    """
    return NewmarkIntegrator(model, bank, settings).run(load, excitation, state,
                                                        record_force, compiled)
