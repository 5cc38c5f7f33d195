"""The second joint law, Bouc-Wen (joints.bouc_wen), against independent truth, and through
every solver: the describing function against the steady loop of the evolution equation
integrated in time by scipy (solve_ivp, shooting for the closed loop) and by the law's own
step; the step against solve_ivp; harmonic balance against Newmark; EPMC against the
describing function."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp
from scipy.optimize import brentq

from fe.epmc import epmc_backbone
from fe.hb_exact import continuation_exact, solve_hb_exact
from fe.joint_harmonics import ExactHarmonics
from fe.newmark import NewmarkSettings, integrate
from fe.reduction import ReducedModel
from joints.bouc_wen import BoucWenJoints, BoucWenParameters

CASES = [BoucWenParameters(K_T=1e5, F_S=50.0, alpha=0.0, shape=0.5),
         BoucWenParameters(K_T=2e4, F_S=3.0, alpha=0.1, shape=1.0),
         BoucWenParameters(K_T=1e6, F_S=400.0, alpha=0.3, shape=-0.5),
         BoucWenParameters(K_T=5e5, F_S=80.0, alpha=0.05, shape=0.0)]


def z_u(p):
    return p.F_S / ((1.0 - p.alpha) * p.K_T)


def ivp_loop(p, A, n=20001):
    """Steady loop of eq. (2) for ``s = A sin t`` by solve_ivp (DOP853, rtol 1e-12): the
    state at ``t = -pi/2`` that comes back after one period (shooting, brentq)."""
    be, ga = p.beta, p.gamma

    def rhs(t, y):
        sd = A * np.cos(t)
        return [sd * (1.0 - be * np.sign(sd) * y[0] - ga * abs(y[0]))]

    def period(z0, dense=False):
        return solve_ivp(rhs, (-0.5 * np.pi, 1.5 * np.pi), [z0], method="DOP853",
                         rtol=1e-12, atol=1e-15 * z_u(p), max_step=0.05,
                         dense_output=dense)

    zu = z_u(p)
    z0 = brentq(lambda z: period(z).y[0, -1] - z, -zu, 0.0, xtol=1e-15 * zu)
    t = np.linspace(-0.5 * np.pi, 1.5 * np.pi, n)
    return t, period(z0, True).sol(t)[0]


@pytest.mark.parametrize("p", CASES)
@pytest.mark.parametrize("ratio", [0.02, 0.5, 3.0, 30.0])
def test_describing_function_is_the_time_domain_loop_to_1e6(p, ratio):
    """Acceptance (1e-6): k_in, k_q of the law (closed-form branches + Gauss-Legendre) agree
    with the Fourier coefficients of the solve_ivp loop (Simpson on 20001 points) within
    1e-9 of k_in (measured: at most 5e-11), and the loop closes where the law says (z at
    the slip minimum)."""
    law = BoucWenJoints(p, 1)
    A = ratio * z_u(p)
    k_in, k_q = law.describing(np.array([A]))
    t, z = ivp_loop(p, A)
    F = p.K_T * (p.alpha * A * np.sin(t) + (1.0 - p.alpha) * z)
    ki = simpson(F * np.sin(t), x=t) / (np.pi * A)
    kq = simpson(F * np.cos(t), x=t) / (np.pi * A)
    assert abs(ki - k_in[0]) < 1e-9 * k_in[0]
    assert abs(kq - k_q[0]) < 1e-9 * k_in[0]
    assert z[0] == pytest.approx(-law.loop_amplitude(A)[0], rel=1e-8, abs=1e-12 * z_u(p))


@pytest.mark.parametrize("p", CASES[:2])
def test_own_step_traces_the_loop_of_the_describing_function(p):
    """The law's exact step over 4096 samples of a period, started on the loop, comes back
    to its start (the loop closes) and its Fourier coefficients (trapezoid) are the DF."""
    law = BoucWenJoints(p, 1)
    for A in (0.3 * z_u(p), 4.0 * z_u(p)):
        n = 4096
        t = -0.5 * np.pi + 2 * np.pi * np.arange(n + 1) / n
        state = np.array([[-A, -law.loop_amplitude(A)[0]]])
        F = np.empty(n + 1)
        for i, s in enumerate(A * np.sin(t)):
            f, _, state = law.step(np.array([s]), state)
            F[i] = f[0]
        assert state[0, 1] == pytest.approx(-law.loop_amplitude(A)[0], rel=1e-12)
        ki = 2 * np.mean(F[:-1] * np.sin(t[:-1])) / A
        kq = 2 * np.mean(F[:-1] * np.cos(t[:-1])) / A
        k_in, k_q = law.describing(np.array([A]))
        assert abs(ki - k_in[0]) < 1e-6 * k_in[0] and abs(kq - k_q[0]) < 1e-6 * k_in[0]


def test_step_is_the_ode_along_any_path_and_its_tangent_is_the_derivative():
    """Random slip path: the closed-form step equals solve_ivp of eq. (2) in the slip (rtol
    1e-12) sample by sample; the tangent equals a one-sided finite difference."""
    p = CASES[0]
    law = BoucWenJoints([p, CASES[2]])
    rng = np.random.default_rng(7)
    path = np.cumsum(rng.normal(size=(60, 2)) * 0.4 * law.slip_scale, axis=0)
    state = law.initial_state()
    for s in path:
        F, kt, new = law.step(s, state)
        for j, q in enumerate((p, CASES[2])):
            ds = s[j] - state[j, 0]
            if ds == 0:
                continue
            sg = np.sign(ds)
            sol = solve_ivp(lambda x, z: [1 - q.beta * sg * z[0] - q.gamma * abs(z[0])],
                            (state[j, 0], s[j]), [state[j, 1]], rtol=1e-12,
                            atol=1e-16, method="DOP853")
            assert new[j, 1] == pytest.approx(sol.y[0, -1], rel=1e-9, abs=1e-13)
            h = 1e-7 * law.slip_scale[j] * sg
            F2 = law.step(s + h * (np.arange(2) == j), state)[0][j]
            assert (F2 - F[j]) / h == pytest.approx(kt[j], rel=1e-5)
        state = new
    assert np.allclose(law.step(np.zeros(2), law.initial_state())[1], law.K_T)


def test_describing_derivative_and_limits():
    """dk/dA against a wider central difference; k_in -> K_T and k_q -> 0 as A -> 0;
    k_q -> 4 F_S/(pi A) and k_in -> alpha K_T as A -> inf (saturated hysteretic force)."""
    p = CASES[1]
    law = BoucWenJoints(p, 1)
    A = np.array([0.1, 1.0, 10.0]) * z_u(p)
    k_in, k_q, dk_in, dk_q = law.describing_derivative(A[:, None])
    h = 1e-3 * A[:, None]
    (ip, qp), (im, qm) = law.describing(A[:, None] + h), law.describing(A[:, None] - h)
    assert np.allclose(dk_in, (ip - im) / (2 * h), rtol=1e-5)
    assert np.allclose(dk_q, (qp - qm) / (2 * h), rtol=1e-5)
    small = law.describing(np.array([1e-6 * z_u(p)]))
    assert small[0][0] == pytest.approx(p.K_T, rel=1e-5) and small[1][0] < 1e-5 * p.K_T
    big = 1e4 * z_u(p)
    ki, kq = law.describing(np.array([big]))
    assert kq[0] == pytest.approx(4 * p.F_S / (np.pi * big), rel=1e-3)
    assert ki[0] == pytest.approx(p.alpha * p.K_T, rel=1e-3)


def sdof(p, m, c=0.0):
    return ReducedModel(basis=np.eye(1), omega=np.array([np.sqrt(p.K_T / m)]),
                        M=np.array([[m]]), K=np.array([[p.K_T]]), C=np.array([[c]]),
                        G=np.eye(1), K_T=np.array([p.K_T]), n_modes=1)


def test_epmc_backbone_is_the_describing_function():
    """EPMC on a mass on a Bouc-Wen joint: omega^2 = k_in(A)/m, zeta = k_q/(2 k_in)."""
    p, m = CASES[0], 2.0
    law = BoucWenJoints(p, 1)
    A = np.geomspace(1e-2, 10.0, 12) * z_u(p)
    bb = epmc_backbone(sdof(p, m), ExactHarmonics(law), 1, A)
    k_in, k_q = law.describing(A[:, None])
    assert np.allclose(bb.omega2, k_in[:, 0] / m, rtol=1e-9)
    assert np.allclose(bb.zeta, k_q[:, 0] / (2 * k_in[:, 0]), rtol=1e-8)
    assert not bb.fallbacks.any()


def test_harmonic_balance_against_newmark_steady_state():
    """Forced mass on a Bouc-Wen joint near resonance: the first-harmonic balance (fe.hb_exact
    through the law's DF) and Newmark through the law's step until periodic agree on the
    first-harmonic amplitude to the harmonic truncation (1 %); the HB sweep over lines
    follows the branch (continuation)."""
    p, m, c = CASES[0], 1.0, 20.0
    law = BoucWenJoints(p, 1)
    model = sdof(p, m, c)
    F0 = 0.6 * p.F_S
    w = 0.9 * np.sqrt(p.K_T / m)
    hb = solve_hb_exact(model, law, np.array([F0 + 0j]), w)
    sweep = continuation_exact(model, law, np.array([F0 + 0j]), w * np.linspace(0.8, 1.0, 5))
    assert sweep[-1].slip[0, 0] == pytest.approx(hb.slip[0, 0], rel=1e-9)
    T = 2 * np.pi / w
    n_per, steps = 60, 256
    dt = T / steps
    t = np.arange(n_per * steps + 1) * dt
    run = integrate(model, law, np.array([F0]), np.cos(w * t), NewmarkSettings(dt=dt))
    q = run.q[-steps - 1:-1, 0]
    tt = t[-steps - 1:-1]
    Q1 = 2 * np.mean(q * np.exp(-1j * w * tt))
    assert abs(Q1) == pytest.approx(abs(hb.q[0, 0]), rel=1e-2)
    assert abs(hb.slip[0, 0]) > z_u(p)          # in the hysteretic range, not linear
    assert run.energy is None                  # no stored energy defined for this law


def test_parameters_refused():
    with pytest.raises(ValueError, match="alpha"):
        BoucWenParameters(K_T=1.0, F_S=1.0, alpha=1.0)
    with pytest.raises(ValueError, match="shape"):
        BoucWenParameters(K_T=1.0, F_S=1.0, shape=-1.0)
    with pytest.raises(ValueError, match="K_T"):
        BoucWenParameters(K_T=-1.0, F_S=1.0)
