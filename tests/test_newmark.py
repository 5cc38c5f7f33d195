"""Newmark/HHT with Jenkins joints (fe.newmark): closed forms and energy balance."""
import numpy as np
import pytest

from cases.lumped10.model import LumpedParameters, force_vector, lumped10_bank, lumped10_system
from fe.newmark import NewmarkSettings, NewmarkState, integrate
from fe.reduction import JointBank, reduced_basis
from joints.iwan import dissipation_per_cycle


@pytest.fixture(scope="module")
def lumped():
    p = LumpedParameters()
    s = lumped10_system(p)
    return p, s, reduced_basis(s), lumped10_bank(p, 40)


def test_linear_steady_state_matches_bilinear_transform(lumped):
    """Stuck joints: the average-acceleration steady state to cos(w t) equals the exact
    continuous response at the warped frequency (2/dt) tan(w dt/2) (closed form)."""
    p, s, m, _ = lumped
    stuck = JointBank(np.full((2, 1), 1.1e5), np.full((2, 1), 1e3))   # never slips
    w, N = 2 * np.pi * 61.0, 64
    dt = 2 * np.pi / (w * N)
    n = 700 * N
    e = np.cos(w * dt * np.arange(n + 1))
    run = integrate(m, stuck, m.load(force_vector(p)), e, NewmarkSettings(dt=dt))
    x = run.q[-N - 1:-1] @ m.basis.T
    theta = w * dt * np.arange(n - N, n)
    X = 2 / N * np.exp(-1j * theta) @ x
    W = 2 / dt * np.tan(w * dt / 2)
    exact = np.linalg.solve(s.K_J - W ** 2 * s.M + 1j * W * s.C, force_vector(p))
    np.testing.assert_allclose(X, exact, rtol=1e-7, atol=1e-9 * np.abs(exact).max())
    # and the unwarped response differs by the predicted amount (not a vacuous test)
    direct = np.linalg.solve(s.K_J - w ** 2 * s.M + 1j * w * s.C, force_vector(p))
    assert np.abs(X[4] / direct[4] - 1) > 1e-3


@pytest.mark.parametrize("alpha", [0.0, -0.05])
def test_energy_balance_closes(lumped, alpha):
    """input = viscous + joint friction + change of kinetic, strain and slider energy."""
    p, s, m, bank = lumped
    w, N = 2 * np.pi * 61.0, 256
    dt = 2 * np.pi / (w * N)
    e = np.sin(w * dt * np.arange(40 * N + 1))
    run = integrate(m, bank, m.load(force_vector(p) * 128.0), e,
                    NewmarkSettings(dt=dt, alpha=alpha))
    E = run.energy
    assert E.joint_dissipation > 0.01 * E.input          # joints really slip
    assert E.relative_residual < 1e-3
    if alpha == 0.0:
        assert E.relative_residual < 1e-5
    else:                                                # HHT: numerical dissipation > 0
        assert E.residual > 0


def test_steady_joint_dissipation_equals_iwan_closed_form(lumped):
    """Friction work per cycle in steady state = Segalman's 4R A^(chi+3)/((chi+2)(chi+3))
    (continuous Iwan) at the measured slip amplitude, to the discretization error."""
    p, s, m, _ = lumped
    bank = lumped10_bank(p, 200)
    w, N = 2 * np.pi * 61.0, 256
    dt = 2 * np.pi / (w * N)
    load = m.load(force_vector(p) * 32.0)
    st = NewmarkState.rest(m, bank)
    e = np.sin(w * dt * np.arange(300 * N + 1))
    st = integrate(m, bank, load, e, NewmarkSettings(dt=dt)).state
    st.e = e[-1]
    e2 = np.sin(w * dt * np.arange(300 * N, 301 * N + 1))
    run = integrate(m, bank, load, e2, NewmarkSettings(dt=dt), st)
    A = 0.5 * (run.slip.max(0) - run.slip.min(0))
    D = dissipation_per_cycle(p.joint, A).sum()
    assert A.max() < p.joint.phi_max                     # micro-slip regime
    assert run.energy.joint_dissipation == pytest.approx(D, rel=5e-3)


def test_compiled_and_reference_loops_agree(lumped):
    p, s, m, bank = lumped
    w = 2 * np.pi * 170.0
    dt = 2 * np.pi / (w * 128)
    e = np.sin(w * dt * np.arange(1501))
    for alpha in (0.0, -0.1):
        st = NewmarkSettings(dt=dt, alpha=alpha)
        a = integrate(m, bank, m.load(force_vector(p) * 500.0), e, st, compiled=True)
        b = integrate(m, bank, m.load(force_vector(p) * 500.0), e, st, compiled=False)
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12 * np.abs(b.q).max())
        np.testing.assert_allclose(a.state.anchor, b.state.anchor, atol=1e-15)
        assert a.energy.joint_dissipation == pytest.approx(b.energy.joint_dissipation, rel=1e-9)


def test_bad_settings():
    with pytest.raises(ValueError):
        NewmarkSettings(dt=0.0)
    with pytest.raises(ValueError):
        NewmarkSettings(dt=1e-4, alpha=-0.5)
