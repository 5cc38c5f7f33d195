"""The period-map Newton step of fe.newmark_period against the integrator itself."""
from __future__ import annotations

import numpy as np
import scipy.linalg as la

from fe.newmark import NewmarkIntegrator, NewmarkSettings, NewmarkState
from fe.newmark_period import PeriodNewton, joint_equivalent, linear_monodromy, period_step
from fe.reduction import JointBank, ReducedModel


def two_dof(K_T=2e4):
    """Two masses, a spring to ground and a joint between them (K includes K_T)."""
    M = np.diag([1.0, 0.5])
    k1 = 1e5
    G = np.array([[-1.0, 1.0]])
    K = np.array([[k1, 0.0], [0.0, 0.0]]) + K_T * G.T @ G
    C = 2e-3 * K + 0.5 * M
    lam = la.eigh(K, M, eigvals_only=True)
    return ReducedModel(basis=np.eye(2), omega=np.sqrt(lam), M=M, K=K, C=C, G=G,
                        K_T=np.array([K_T]))


def stuck_bank(K_T):
    """One slider per joint with a slip limit no motion here reaches: a linear joint."""
    return JointBank(np.array([[K_T]]), np.array([[1.0]]))


def test_monodromy_equals_the_integrators_map():
    model = two_dof()
    bank = stuck_bank(model.K_T[0])
    dt, n = 2e-4, 37
    A = linear_monodromy(model, dt, n)
    integ = NewmarkIntegrator(model, bank, NewmarkSettings(dt=dt))
    cols = []
    for j in range(4):
        st = NewmarkState.rest(model, bank)
        x = np.zeros(4)
        x[j] = 1e-4
        st.q, st.v = x[:2].copy(), x[2:].copy()
        st.a = -np.linalg.solve(model.M, model.K @ st.q + model.C @ st.v)
        run = integ.run(np.zeros(2), np.zeros(n + 1), st, energy=False)
        cols.append(np.concatenate([run.state.q, run.state.v]) / 1e-4)
    np.testing.assert_allclose(A, np.array(cols).T, rtol=1e-9, atol=1e-9 * np.abs(A).max())


def test_one_step_lands_on_the_orbit_of_a_linear_structure():
    model = two_dof()
    bank = stuck_bank(model.K_T[0])
    w = 0.97 * model.omega[0]
    N = 128
    dt = 2 * np.pi / (w * N)
    load = np.array([0.0, 1.0])
    e = np.cos(w * dt * np.arange(N + 1))
    integ = NewmarkIntegrator(model, bank, NewmarkSettings(dt=dt))
    A = linear_monodromy(model, dt, N)
    st = NewmarkState.rest(model, bank)
    st.a, st.e = np.linalg.solve(model.M, load), 1.0
    end = integ.run(load, e, st, energy=False).state
    drift_plain = np.abs(end.q - st.q).max()
    nxt = period_step(model, bank, st, end, PeriodNewton(A), load)
    after = integ.run(load, e, nxt, energy=False).state
    drift = np.abs(after.q - nxt.q).max()
    assert drift_plain > 1e-6
    assert drift < 1e-12 * np.abs(nxt.q).max() + 1e-16
    # and it is the discrete scheme's steady state: the harmonic solution of the
    # trapezoidal rule (s -> (2/dt) tanh) at the drive
    s = 2j / dt * np.tan(w * dt / 2)
    X = np.linalg.solve(model.K + s * model.C + s * s * model.M, load)
    np.testing.assert_allclose(nxt.q, X.real, rtol=1e-9, atol=1e-12 * np.abs(X).max())


def test_joint_equivalent_of_a_spring_and_dashpot():
    w = 300.0
    S = np.array([[2e-6 + 1e-6j, 0.0]])
    k, c = np.array([5e3, 1e3]), np.array([2.0, 3.0])
    Gh = (k + 1j * w * c) * S
    kk, cc = joint_equivalent(S, Gh, [1], w)
    np.testing.assert_allclose(kk, [5e3, 0.0])
    np.testing.assert_allclose(cc, [2.0, 0.0])


def test_campaign_with_the_period_newton_step_reaches_the_same_steady_state_sooner():
    """A jointed SDOF driven through its resonance (micro-slip, lightly damped) by the
    Newmark protocol from the harmonic-balance orbits, with and without the step."""
    import dataclasses

    from cases.random_series import sdof_iwan
    from fe.harmonic_balance import HBSettings
    from joints.iwan import IwanParameters
    from runs.campaign import Campaign, NewmarkProtocol
    from runs.stepped_sine import run_level

    joint = IwanParameters(chi=-0.5, K_T=1e5, F_S=100.0, beta=0.5)
    model, bank = sdof_iwan(joint, 9e5, 1.0, 0.002)
    f0 = model.omega[0] / (2 * np.pi)
    lines = f0 * np.array([0.99, 0.995, 0.998, 1.0, 1.002])
    F = 0.1 * joint.phi_max * 2 * 0.003 * model.K[0, 0]
    plain = NewmarkProtocol(steps_per_period=128, tol=1e-8, hb_start=HBSettings())
    runs = {}
    for on in (False, True):
        camp = Campaign(lines, [F], np.ones(1), [0],
                        dataclasses.replace(plain, period_newton=on))
        runs[on] = run_level(model, bank, camp, 0)
    np.testing.assert_allclose(runs[True].receptance, runs[False].receptance, rtol=1e-6)
    assert runs[True].work.sum() < 0.3 * runs[False].work.sum()
