"""Free decay (ring-down) of a reduced jointed model by Newmark integration.

A ring-down test switches the drive off at resonance (or hits the structure) and records
the decaying response: one record sweeps every amplitude the joints pass through. Here
the reduced model (:mod:`fe.reduction`, ``M q'' + C q' + K_J q + G^T g(G q) = 0``) is
integrated from one of two starts:

* :func:`orbit_start`: on a periodic orbit of the mode (a point of its EPMC backbone,
  :func:`fe.epmc.solve_epmc`, Krack 2015): displacement and velocity from the orbit's
  harmonics at phase 0 and the slider anchors of the orbit's steady hysteresis loop
  (:meth:`fe.newmark.NewmarkState.periodic`), i.e. the state of a shaker switched off
  at phase resonance;
* :func:`impulse_start`: at rest, virgin joints, with the velocity ``M^-1 Phi^T I e_d``
  of an impulse ``I`` (N s) at DOF ``d`` (an impact hammer).

Integration (:func:`ring_down`): the average-acceleration rule (HHT ``alpha = 0``, no
numerical damping) with ``n`` steps per period of the mode's stuck-joint frequency
``w0``. The rule's frequency error is removed by pre-warping the time axis, as in the
stepped-sine protocol (:class:`runs.campaign.NewmarkProtocol`): the step integrated is
``dt = dt_rec tan(pi/n)/(pi/n)`` while the samples are written ``dt_rec = 2 pi/(n w0)``
apart, so that a linear mode at ``w0`` rings at exactly ``w0`` in the record (the
trapezoidal rule is the bilinear transform ``s = (2/dt) tanh(s_d dt/2)``: a mode ringing
at ``w`` near ``w0`` appears at ``w0 + (w - w0) sin(2 pi/n)/(2 pi/n)``, a relative
frequency error ``|w/w0 - 1| (2 pi/n)^2/6``, and its damping ratio is multiplied by
``sin(2 pi/n)/(2 pi/n)``, a relative error ``(2 pi/n)^2/6``: 1.6e-3 at ``n = 64``).
The joints (Jenkins banks) are rate independent, so the warped time axis changes
nothing in them. An impulse excites every mode, the higher ones resolved by few steps:
its energy residual is larger (2e-2 on the double beam at 64 steps per period of mode 4).

Energy balance (:class:`fe.newmark.EnergyBalance`, summed over the chunks of the
integration): with no load, ``0 = viscous + joint dissipation + change of kinetic,
strain and joint stored energy`` up to the scheme's ``O(dt^2)`` joint work in the
steps where a slider starts to slip; its relative residual is reported with the record.

SI units: s, m, N, J.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fe.newmark import EnergyBalance, NewmarkIntegrator, NewmarkSettings, NewmarkState
from fe.reduction import JointBank, ReducedModel
from joints.law import JointLaw

__all__ = ["FreeDecayRecord", "orbit_start", "law_orbit_state", "impulse_start",
           "warped_step", "ring_down"]


@dataclass
class FreeDecayRecord:
    """A simulated free decay.

    Attributes
    ----------
    time_s : (n,) sample times (s), pre-warped (module docstring), from 0.
    response : (n, n_points) displacements at the output points (m).
    points : names of the output points (columns of the record).
    slip : (n, n_joints) joint slips (m).
    energy : the energy balance over the whole record (None for a joint law other than
        a Jenkins bank: only the bank states its stored energy and friction work).
    dt_integration : the step integrated (s); ``steps_per_period``: per period of ``w0``.
    omega0 : the stuck-joint frequency (rad/s) the time axis is warped for.
    start : how the decay started (``orbit`` or ``impulse``).
    newton_iterations : total Newton iterations of the joints.
    """

    time_s: np.ndarray
    response: np.ndarray
    points: tuple
    slip: np.ndarray
    energy: EnergyBalance | None
    dt_integration: float
    steps_per_period: int
    omega0: float
    start: str
    newton_iterations: int = 0


def orbit_start(model: ReducedModel, bank: JointLaw, harmonics, q_harmonics, omega: float,
                dt: float, n_time: int = 256) -> NewmarkState:
    """State at phase 0 of the orbit ``q(t) = Re sum_h Q_h e^{i h omega t}`` (e.g. one
    point of :class:`fe.backbone.Backbone`: ``harmonics``, ``q[i]``, ``omega[i]``) with no
    load: :meth:`fe.newmark.NewmarkState.periodic`, the velocity consistent with the
    integrator's step ``dt`` (s) and the slider anchors of the loop on ``n_time``
    samples. Another joint law than a Jenkins bank (a first-harmonic orbit of the exact
    path): :func:`law_orbit_state`."""
    if not isinstance(bank, JointBank):
        return law_orbit_state(model, bank, harmonics, q_harmonics, omega, dt)
    return NewmarkState.periodic(model, bank, harmonics, q_harmonics, omega,
                                 np.zeros(model.n_reduced), n_time, dt)


#: cycles of slip between the loop's turning points at most, to reach the steady loop
LOOP_CYCLES = 10_000


def law_orbit_state(model: ReducedModel, law: JointLaw, harmonics, q_harmonics,
                    omega: float, dt: float) -> NewmarkState:
    """:func:`orbit_start` for any joint law on a first-harmonic orbit (the exact path):
    each joint's slip ``Re(S e^{i omega t})`` swings between ``-|S|`` and ``|S|``, so the
    law's own step is marched between those turning points (exact steps along monotone
    slip) from its virgin state until the force at ``-|S|`` repeats to 1e-12 relative
    (at most :data:`LOOP_CYCLES` cycles: the loop's state is the fixed point of one
    cycle), then to the slip at phase 0 along the branch the orbit is on there
    (loading when ``ds/dt > 0``)."""
    h = np.asarray(harmonics, dtype=float)
    Q = np.asarray(q_harmonics, dtype=complex)
    if not np.array_equal(h, [1.0]):
        raise ValueError(f"law {getattr(law, 'name', '?')}: an orbit start needs a "
                         "first-harmonic orbit (the exact path)")
    S = model.G @ Q[0]
    A, s0 = np.abs(S), S.real
    loading = S.imag < 0.0                      # ds/dt = -omega Im S at t = 0
    state, last = law.initial_state(), None
    for _ in range(LOOP_CYCLES):
        _, _, state = law.step(A, state)
        F, _, state = law.step(-A, state)
        if last is not None and np.all(np.abs(F - last) <= 1e-12 * np.abs(F).max()):
            break
        last = F
    _, _, state = law.step(np.where(loading, -A, A), state)
    F, _, state = law.step(s0, state)
    q = np.real(Q[0])
    v = np.real(1j * (2.0 / dt) * np.tan(0.5 * omega * dt) * Q[0])
    g = F - model.K_T * s0
    a = np.linalg.solve(model.M, -model.C @ v - model.K @ q - model.G.T @ g)
    return NewmarkState(t=0.0, q=q, v=v, a=a, anchor=state, g=g, e=1.0)


def impulse_start(model: ReducedModel, bank: JointBank, load, impulse: float) -> NewmarkState:
    """At rest with virgin joints and the velocity ``M^-1 load * impulse`` left by an
    impulse ``impulse`` (N s) in the reduced load pattern ``load`` (``Phi^T e_d``)."""
    st = NewmarkState.rest(model, bank)
    st.v = np.linalg.solve(model.M, np.asarray(load, dtype=float) * float(impulse))
    st.a = -np.linalg.solve(model.M, model.C @ st.v)
    return st


def warped_step(omega0: float, steps_per_period: int) -> tuple[float, float]:
    """``(dt_integration, dt_record)`` (s) of the pre-warped time axis (module
    docstring) for ``steps_per_period`` samples per period of ``omega0`` (rad/s)."""
    n = int(steps_per_period)
    if n < 8:
        raise ValueError(f"steps per period must be >= 8, got {steps_per_period}")
    if not omega0 > 0:
        raise ValueError(f"the reference frequency must be > 0 rad/s, got {omega0!r}")
    dt_rec = 2.0 * np.pi / (omega0 * n)
    return dt_rec * np.tan(np.pi / n) / (np.pi / n), dt_rec


def ring_down(model: ReducedModel, bank: JointBank, state: NewmarkState, omega0: float,
              cycles: float, outputs, points=None, steps_per_period: int = 64,
              chunk_cycles: float = 50.0, progress=None, on_chunk=None,
              start: str = "orbit") -> FreeDecayRecord:
    """Integrate the free decay from ``state`` over ``cycles`` periods of ``omega0``.

    Parameters
    ----------
    model, bank : the reduced model and its joints (``bank.K_T == model.K_T``): Jenkins
        banks (compiled, energy balance) or any :class:`joints.law.JointLaw` (its own
        step in the plain loop, no energy balance).
    state : NewmarkState, the start (:func:`orbit_start`, :func:`impulse_start`; its
        velocity should be consistent with :func:`warped_step`'s ``dt_integration``).
    omega0 : float, rad/s, the frequency the time axis is warped for (the mode's
        stuck-joint frequency).
    cycles : float, length of the record in periods of ``omega0``.
    outputs : (n_points, r) rows giving the recorded displacements ``outputs @ q``
        (rows of the reduced basis: physical DOFs).
    points : names of the outputs (default ``p1, p2, ...``).
    steps_per_period : int, samples (and steps) per period of ``omega0``.
    chunk_cycles : float, periods integrated per call (one progress tick each).
    progress : tqdm-like bar or None (ticks in periods).
    on_chunk : callable ``(time_s, response, slip)`` of each new chunk (e.g. appending to
        a file), or None.

    Returns
    -------
    FreeDecayRecord
    """
    outputs = np.atleast_2d(np.asarray(outputs, dtype=float))
    if outputs.shape[1] != model.n_reduced:
        raise ValueError(f"outputs must have {model.n_reduced} columns, got {outputs.shape[1]}")
    if not cycles > 0:
        raise ValueError(f"cycles must be > 0, got {cycles!r}")
    names = tuple(points) if points is not None else tuple(
        f"p{i + 1}" for i in range(outputs.shape[0]))
    dt, dt_rec = warped_step(omega0, steps_per_period)
    n_total = int(np.ceil(cycles * steps_per_period))
    n_chunk = max(1, int(round(chunk_cycles * steps_per_period)))
    integ = NewmarkIntegrator(model, bank, NewmarkSettings(dt=dt))
    zero = np.zeros(model.n_reduced)
    st = state.copy()
    st.e = 0.0
    resp = [st.q @ outputs.T]
    slips = [model.G @ st.q]
    total = EnergyBalance() if isinstance(bank, JointBank) else None   # a bank's only
    iters, done = 0, 0
    if on_chunk is not None:
        on_chunk(np.zeros(1), resp[0][None, :], slips[0][None, :])
    while done < n_total:
        n = min(n_chunk, n_total - done)
        run = integ.run(zero, np.zeros(n + 1), st)
        st = run.state
        for name in ("viscous", "joint_dissipation", "kinetic", "strain", "joint_stored"):
            if total is not None:
                setattr(total, name, getattr(total, name) + getattr(run.energy, name))
        iters += run.newton_iterations
        y, s = run.q[1:] @ outputs.T, run.slip[1:]
        resp.append(y)
        slips.append(s)
        if on_chunk is not None:
            on_chunk(dt_rec * np.arange(done + 1, done + n + 1), y, s)
        done += n
        if progress is not None:
            progress.update(n / steps_per_period)
    response = np.vstack([np.atleast_2d(r) for r in resp])
    return FreeDecayRecord(time_s=dt_rec * np.arange(n_total + 1), response=response,
                           points=names, slip=np.vstack([np.atleast_2d(s) for s in slips]),
                           energy=total, dt_integration=dt, steps_per_period=int(steps_per_period),
                           omega0=float(omega0), start=start, newton_iterations=iters)
