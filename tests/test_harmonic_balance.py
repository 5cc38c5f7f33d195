"""Harmonic balance with AFT Jenkins joints (fe.harmonic_balance, fe.aft)."""
import numpy as np
import pytest
from scipy.optimize import brentq

from cases.lumped10.model import LumpedParameters, force_vector, lumped10_bank, lumped10_system
from fe.aft import aft_joint_force
from fe.harmonic_balance import HBSettings, harmonic_synthesis, solve_hb
from fe.newmark import NewmarkSettings, integrate
from fe.reduction import JointBank, JointedSystem, reduced_basis
from joints.describing import describing_function
from joints.iwan import IwanParameters


@pytest.fixture(scope="module")
def lumped():
    p = LumpedParameters()
    s = lumped10_system(p)
    return p, s, reduced_basis(s), lumped10_bank(p, 40)


def test_stuck_joints_give_the_linear_solution(lumped):
    p, s, m, _ = lumped
    stuck = JointBank(np.full((2, 1), 1.1e5), np.full((2, 1), 1e3))
    w = 2 * np.pi * 170.0
    sol = solve_hb(m, stuck, m.load(force_vector(p)), w)
    exact = np.linalg.solve(s.K_J - w ** 2 * s.M + 1j * w * s.C, force_vector(p))
    np.testing.assert_allclose(sol.first_harmonic(m), exact, rtol=1e-10)
    assert np.abs(sol.q[1:]).max() < 1e-14           # no higher harmonics


def test_aft_jacobian_matches_reference_and_finite_differences(lumped):
    p, s, m, bank = lumped
    N = 128
    th = 2 * np.pi * np.arange(N) / N
    rng = np.random.default_rng(7)
    st = np.array([1e-3 * np.sin(th) + 2e-4 * np.sin(3 * th + rng.uniform()) + 1e-4,
                   5e-4 * np.cos(th + rng.uniform())])
    E, P = harmonic_synthesis(np.array([1, 3, 5]), N)
    F1, J1 = aft_joint_force(st, bank, P, E)
    F2, J2 = aft_joint_force(st, bank, compiled=False)
    np.testing.assert_allclose(F1, F2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(J1, P @ J2 @ E, atol=1e-6 * np.abs(J1).max())
    # central differences of the harmonic force w.r.t. the harmonic slip coefficients
    y = P @ st[0]
    h = 1e-10
    for c in range(E.shape[1]):
        d = np.zeros_like(y)
        d[c] = h
        fp, _ = aft_joint_force(np.array([E @ (y + d), st[1]]), bank)
        fm, _ = aft_joint_force(np.array([E @ (y - d), st[1]]), bank)
        fd = P @ (fp[0] - fm[0]) / (2 * h)
        np.testing.assert_allclose(fd, J1[0][:, c], atol=2e-3 * np.abs(J1[0]).max())


def test_single_harmonic_sdof_equals_describing_function_solution():
    """Mass on a Iwan joint (in parallel with a spring), H = 1: the HB amplitude must
    solve |k + k_in(A) + i(w c + k_q(A)) - w^2 m| A = F with the continuous describing
    function of joints.describing (independent closed form), to the discretization error."""
    p = IwanParameters(chi=-0.5, K_T=1e5, F_S=300.0, beta=2.0)
    mass, k, c, F = 1.0, 4e5, 20.0, 40.0
    s = JointedSystem(M=np.eye(1), K=np.array([[k]]), C=np.array([[c]]),
                      G=np.eye(1), K_T=np.array([p.K_T]))
    bank = JointBank.from_iwan(p, 400, n_joints=1)
    m = reduced_basis(s)
    w = np.sqrt((k + p.K_T) / mass) * 0.99
    sol = solve_hb(m, bank, m.load(np.array([F])), w, HBSettings(n_harmonics=1, n_time=512))
    A_hb = abs(sol.slip[0, 0])

    def residual(A):
        kin, kq = describing_function(p, A)
        return abs(k + kin - w ** 2 * mass + 1j * (w * c + kq)) * A - F

    A_df = brentq(residual, 1e-7, 1e-1)
    assert A_df > 0.3 * p.phi_max                       # deep into micro-slip
    assert A_hb == pytest.approx(A_df, rel=2e-3)


def test_hb_matches_newmark_steady_state(lumped):
    """Acceptance: HB and Newmark steady-state amplitudes agree within 0.5 %."""
    p, s, m, bank = lumped
    load = m.load(force_vector(p) * 128.0)
    N = 256
    for f_hz in (61.0, 62.0):
        w = 2 * np.pi * f_hz
        sol = solve_hb(m, bank, load, w, HBSettings(n_harmonics=7, n_time=256))
        # Newmark with pre-warped drive (see runs.campaign), from rest, 400 periods
        wp = w * np.pi / (N * np.tan(np.pi / N))
        dt = 2 * np.pi / (wp * N)
        e = np.cos(wp * dt * np.arange(400 * N + 1))
        run = integrate(m, bank, load, e, NewmarkSettings(dt=dt))
        theta = wp * dt * np.arange(399 * N, 400 * N)
        X = 2 / N * np.exp(-1j * theta) @ (run.q[-N - 1:-1] @ m.basis.T)
        ref = sol.first_harmonic(m)
        assert np.max(np.abs(np.abs(X) / np.abs(ref) - 1)) < 5e-3
        amp = 0.5 * (run.slip[-N:].max(0) - run.slip[-N:].min(0))
        np.testing.assert_allclose(amp, sol.slip_amplitude, rtol=5e-3)
        assert sol.slip_amplitude.max() > 1e-3           # joints well into micro-slip
