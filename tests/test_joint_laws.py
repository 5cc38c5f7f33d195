"""The joint-law interface (joints.law) held by every law: the Iwan joint (exact), the
Jenkins bank and Bouc-Wen. Each law against independent truth of its own: the step's
tangent against a finite difference of its force, the virgin tangent against K_T, the
describing function's derivative against a finite difference, and the describing function
against the Fourier coefficients of the law's own steady loop (its step marched around
a sinusoid until the loop closes). A new law is added to LAWS."""
from __future__ import annotations

import numpy as np
import pytest

from fe.aft import aft_joint_force
from fe.harmonic_balance import harmonic_synthesis
from fe.reduction import JointBank
from joints.bouc_wen import BoucWenJoints, BoucWenParameters
from joints.describing import IwanJoints
from joints.iwan import IwanParameters, force_history
from joints.jenkins import discretize
from joints.law import JointLaw

IWAN = [IwanParameters(chi=-0.4, K_T=5e4, F_S=30.0, beta=0.8),
        IwanParameters(chi=-0.7, K_T=2e5, F_S=90.0, beta=0.0)]
LAWS = {
    "iwan": lambda: IwanJoints(IWAN),
    "jenkins": lambda: JointBank.from_discretizations([discretize(p, 40) for p in IWAN]),
    "bouc-wen": lambda: BoucWenJoints([BoucWenParameters(5e4, 30.0, 0.1, 0.5),
                                       BoucWenParameters(2e5, 90.0, 0.0, 1.0)]),
}


@pytest.fixture(params=sorted(LAWS))
def law(request) -> JointLaw:
    return LAWS[request.param]()


def test_virgin_tangent_is_the_stuck_stiffness(law):
    s = 1e-40 * law.slip_scale          # the Iwan tangent departs as s**(chi+1)
    F, kt, _ = law.step(s, law.initial_state())
    assert np.allclose(kt, law.K_T, rtol=1e-9) and np.allclose(F, s * law.K_T, rtol=1e-9)
    assert np.array_equal(law.stuck_stiffness, law.K_T) and law.n_joints == 2


def _committed_slip(law, state):
    """The slip of the committed state (each law keeps it its own way)."""
    if isinstance(law, BoucWenJoints):
        return state[:, 0]
    if isinstance(law, IwanJoints):
        return np.array([st[0] for st in state])
    return np.full(law.n_joints, -np.inf)   # bank: tangent is one-sided either way


def test_step_tangent_is_the_derivative_and_state_is_not_modified(law):
    rng = np.random.default_rng(3)
    state = law.initial_state()
    for s in np.cumsum(rng.normal(size=(40, 2)), axis=0) * 0.5 * law.slip_scale:
        before = repr(state)
        F, kt, new = law.step(s, state)
        assert repr(state) == before
        # a small continuation of the step in its own direction (a bank's sliders may
        # change state inside a finite difference: tolerance 1e-3 K_T)
        h = 1e-7 * law.slip_scale * np.where(s >= _committed_slip(law, state), 1.0, -1.0)
        F2 = law.step(s + h, state)[0]
        assert np.allclose((F2 - F) / h, kt, rtol=1e-3, atol=1e-3 * law.K_T)
        state = new


def test_describing_derivative_is_the_derivative(law):
    A = np.geomspace(0.05, 5.0, 7)[:, None] * law.slip_scale
    k_in, k_q, dk_in, dk_q = law.describing_derivative(A)
    h = 1e-4 * A
    (ip, qp), (im, qm) = law.describing(A + h), law.describing(A - h)
    assert np.allclose(dk_in, (ip - im) / (2 * h), rtol=1e-4, atol=1e-6 * law.K_T / law.slip_scale)
    assert np.allclose(dk_q, (qp - qm) / (2 * h), rtol=1e-4, atol=1e-6 * law.K_T / law.slip_scale)
    assert np.all(k_q >= 0) and np.all(k_in <= law.K_T * (1 + 1e-12))


def test_describing_function_is_the_loop_of_the_step(law):
    """March the law's own step around s = A sin(theta) (1024 samples a period) until the
    force of a period repeats, then take the first Fourier coefficients (trapezoid)."""
    n = 1024
    theta = 2 * np.pi * np.arange(n) / n
    for ratio in (0.3, 2.0):
        A = ratio * law.slip_scale
        state = law.initial_state()
        prev = None
        for _ in range(200):
            F = np.empty((n, 2))
            for i, t in enumerate(theta):
                F[i], _, state = law.step(A * np.sin(t), state)
            if prev is not None and np.abs(F - prev).max() < 1e-12 * np.abs(F).max():
                break
            prev = F
        else:
            pytest.fail("the loop did not close")
        ki = 2 * np.mean(F * np.sin(theta)[:, None], axis=0) / A
        kq = 2 * np.mean(F * np.cos(theta)[:, None], axis=0) / A
        k_in, k_q = law.describing(A)
        # trapezoid on 1024 samples of a loop with kinks: 1e-5 of K_T
        assert np.allclose(ki, k_in, atol=1e-5 * law.K_T.max())
        assert np.allclose(kq, k_q, atol=1e-5 * law.K_T.max())


def test_iwan_step_is_the_masing_force_history():
    law = IwanJoints(IWAN[0], 1)
    rng = np.random.default_rng(5)
    path = np.cumsum(rng.normal(size=300)) * 0.3 * IWAN[0].phi_max
    state, F = law.initial_state(), []
    for s in path:
        f, _, state = law.step(np.array([s]), state)
        F.append(f[0])
    assert np.allclose(F, force_history(IWAN[0], path), rtol=1e-14, atol=1e-14 * IWAN[0].F_S)


def test_bank_describing_function_is_its_aft_loop():
    """The bank's closed-form first harmonic against the AFT march of the same bank."""
    bank = LAWS["jenkins"]()
    E, P = harmonic_synthesis([1], 8192)
    for A in np.array([0.1, 0.7, 3.0]) * bank.slip_limit.max():
        s = np.ascontiguousarray(np.tile(E @ np.array([0.0, -A]), (2, 1)))   # A sin
        F, _ = aft_joint_force(s, bank)
        c = F @ P.T
        k_in, k_q = bank.describing(A)
        assert np.allclose(-c[:, 1] / A, k_in, rtol=1e-6)
        assert np.allclose(c[:, 0] / A, k_q, rtol=1e-6, atol=1e-9 * bank.K_T.max())


def sdof(K_T, m, c):
    from fe.reduction import ReducedModel
    return ReducedModel(basis=np.eye(1), omega=np.array([np.sqrt(K_T / m)]),
                        M=np.array([[m]]), K=np.array([[K_T]]), C=np.array([[c]]),
                        G=np.eye(1), K_T=np.array([K_T]), n_modes=1)


def test_newmark_with_the_exact_iwan_step_converges_to_the_bank():
    """A free-then-forced mass on an Iwan joint: Newmark through the exact continuous step
    (plain loop) against Newmark through Jenkins banks of 50 and 400 sliders (compiled):
    the bank's error falls with the sliders toward the exact step's response."""
    from fe.newmark import NewmarkSettings, integrate
    p = IWAN[0]
    model = sdof(p.K_T, 1.0, 5.0)
    w = 0.95 * np.sqrt(p.K_T)
    dt = 2 * np.pi / w / 64
    t = np.arange(64 * 15 + 1) * dt
    exc = np.cos(w * t)
    load = np.array([0.8 * p.F_S])
    exact = integrate(model, IwanJoints(p, 1), load, exc, NewmarkSettings(dt=dt)).q[:, 0]
    errs = [np.abs(integrate(model, JointBank.from_discretizations([discretize(p, n)]), load,
                             exc, NewmarkSettings(dt=dt)).q[:, 0] - exact).max() for n in (50, 400)]
    assert errs[1] < errs[0] / 8 and errs[1] < 1e-3 * np.abs(exact).max()


def test_bank_through_its_describing_function_is_the_one_harmonic_aft_balance():
    """A Jenkins bank on the describing-function path (ExactHarmonics of the law) and on the
    AFT path with one harmonic (BankHarmonics) give the same EPMC backbone."""
    from fe.epmc import epmc_backbone
    from fe.joint_harmonics import BankHarmonics, ExactHarmonics
    bank = JointBank.from_discretizations([discretize(IWAN[0], 40)])
    model = sdof(IWAN[0].K_T, 2.0, 0.0)
    A = np.geomspace(0.05, 3.0, 6) * IWAN[0].phi_max
    df = epmc_backbone(model, ExactHarmonics(bank), 1, A)
    aft = epmc_backbone(model, BankHarmonics(bank, (1,), 4096), 1, A)
    assert np.allclose(df.omega, aft.omega, rtol=1e-7)
    assert np.allclose(df.zeta, aft.zeta, rtol=1e-5)


def test_response_control_holds_the_amplitude_with_bouc_wen_joints():
    """Response control through a Bouc-Wen law over a stepped-sine sweep (secant
    continuation): at the force it finds, the force-controlled describing-function balance
    (fe.hb_exact) gives the held amplitude at every line."""
    from fe.hb_exact import solve_hb_exact
    from fe.joint_harmonics import ExactHarmonics
    from fe.newton_path import natural_continuation
    from runs.response_control import solve_response_controlled
    law = BoucWenJoints(BoucWenParameters(5e4, 30.0, 0.1, 0.5), 1)
    model = sdof(5e4, 1.0, 3.0)
    A = 2.0 * law.slip_scale[0]
    sols = natural_continuation(lambda w, guess: solve_response_controlled(
        model, ExactHarmonics(law), np.array([1.0]), w, np.array([1.0]), A, guess),
        np.linspace(150.0, 230.0, 9), None)
    for sol in sols:
        ref = solve_hb_exact(model, law, np.array([sol.force + 0j]), sol.omega)
        assert abs(ref.q[0, 0]) == pytest.approx(A, rel=1e-9)


def test_log_spaced_bank_refuses_joints_whose_slip_limits_differ_by_a_percent():
    """``phi_max`` is micrometres: an absolute tolerance would let 1 % differences through."""
    from joints.bank import JointBank
    from joints.iwan import IwanParameters

    p = IwanParameters(chi=-0.5, K_T=1e6, F_S=1.0, beta=0.1)
    q = IwanParameters(chi=-0.5, K_T=1e6, F_S=1.01, beta=0.1)
    assert abs(q.phi_max / p.phi_max - 1) > 5e-3 and p.phi_max < 1e-5
    with pytest.raises(ValueError, match="same phi_max"):
        JointBank.log_spaced([p, q], 1e-3 * p.phi_max)
    assert JointBank.log_spaced([p, p], 1e-3 * p.phi_max).n_joints == 2
