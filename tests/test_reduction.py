"""Reduced bases of jointed structures and Jenkins banks (fe.reduction), checked against
direct solutions and the exact four-parameter Iwan describing function."""
import numpy as np
import pytest
import scipy.linalg as la

from fe.aft import aft_joint_force
from fe.reduction import JointBank, JointedSystem, rayleigh_damping, reduced_basis, ritz_basis
from joints.describing import describing_function
from joints.iwan import IwanParameters


def _chain(n=8, seed=0):
    """Two coupled spring-mass chains with two joints; random (seeded) masses/springs."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 2.0, 2 * n)
    k = rng.uniform(0.5e6, 2e6, 2 * n)
    K = np.zeros((2 * n, 2 * n))
    for off in (0, n):
        for i in range(n):
            a = off + i
            K[a, a] += k[a]
            if i > 0:
                K[a - 1, a - 1] += k[a]
                K[a - 1, a] -= k[a]
                K[a, a - 1] -= k[a]
    G = np.zeros((2, 2 * n))
    G[0, 0], G[0, n] = -1, 1
    G[1, 3], G[1, n + 3] = -1, 1
    K_T = np.array([1.1e5, 2.3e5])
    M = np.diag(m)
    KJ = K + G.T @ np.diag(K_T) @ G
    return JointedSystem(M=M, K=K, C=rayleigh_damping(M, KJ, 0.5, 7e-5), G=G, K_T=K_T)


def test_stuck_stiffness_is_K_plus_joint_springs():
    s = _chain()
    # joint 0 between DOF 0 and 8: adds +K_T on both diagonals, -K_T off-diagonal
    d = s.K_J - s.K
    assert d[0, 0] == pytest.approx(1.1e5)
    assert d[0, 8] == pytest.approx(-1.1e5)
    assert d[3, 11] == pytest.approx(-2.3e5)
    assert np.count_nonzero(d) == 8


def test_full_basis_is_mass_orthonormal_and_diagonalizes_KJ():
    s = _chain()
    m = reduced_basis(s)
    lam = la.eigh(s.K_J, s.M, eigvals_only=True)          # independent eigen-solve
    np.testing.assert_allclose(m.omega ** 2, lam, rtol=1e-10)
    np.testing.assert_allclose(m.M, np.eye(16), atol=1e-10)
    np.testing.assert_allclose(m.K, np.diag(lam), rtol=1e-9, atol=1e-6 * lam.max())
    q = np.random.default_rng(1).normal(size=16)
    np.testing.assert_allclose(m.slip(q), s.G @ (m.basis @ q), rtol=1e-12)


def test_static_joint_modes_reproduce_static_joint_compliance():
    s = _chain()
    exact = s.G @ np.linalg.solve(s.K_J, s.G.T)           # direct static solve
    trunc = reduced_basis(s, n_modes=3)
    enriched = reduced_basis(s, n_modes=3, static_joint_modes=True)
    for m in (trunc, enriched):
        assert m.basis.T @ s.M @ m.basis == pytest.approx(np.eye(m.n_reduced), abs=1e-9)

    def comp(m):
        return m.G @ np.linalg.solve(m.K, m.G.T)

    assert np.max(np.abs(comp(trunc) - exact) / np.abs(exact).max()) > 1e-2
    np.testing.assert_allclose(comp(enriched), exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())
    assert enriched.n_reduced == 5


def test_joint_bank_energy_bookkeeping():
    p = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)
    bank = JointBank.from_iwan(p, 20, n_joints=2)
    np.testing.assert_allclose(bank.K_T, 1.1e5, rtol=1e-12)
    anchor = bank.initial_anchor()
    s = np.array([1e-3, -2e-4])
    F, kt, new = bank.update(s, anchor)
    # stored energy of the trial state equals sum 0.5 k (s - x)^2, computed by hand
    stretch = s[:, None] - new
    assert bank.stored_energy(s, new) == pytest.approx(0.5 * np.sum(bank.stiffness * stretch ** 2))
    # a slider that moved by d dissipated k phi d
    moved = np.abs(new - anchor)
    assert bank.dissipated(anchor, new) == pytest.approx(
        np.sum(bank.stiffness * bank.slip_limit * moved))
    with pytest.raises(ValueError):
        JointBank(np.ones((2, 3)), np.ones((2, 4)))


def test_ritz_basis_has_modal_damping_and_the_static_joint_compliance():
    """Mass-orthonormal, K_J diagonal (projected here), C = diag(2 zeta omega), and the
    static joint compliance of a direct solve."""
    s = _chain()
    zeta = 0.0127
    red = ritz_basis(s, 3, zeta)
    assert red.n_reduced == 5
    np.testing.assert_allclose(red.basis.T @ s.M @ red.basis, np.eye(5), atol=1e-10)
    np.testing.assert_allclose(red.basis.T @ s.K_J @ red.basis, np.diag(red.omega ** 2),
                               rtol=1e-9, atol=1e-9 * red.omega.max() ** 2)
    np.testing.assert_array_equal(red.M, np.eye(5))
    np.testing.assert_array_equal(red.K, np.diag(red.omega ** 2))
    np.testing.assert_allclose(np.diag(red.C), 2 * zeta * red.omega, rtol=1e-14)
    assert np.count_nonzero(red.C - np.diag(np.diag(red.C))) == 0
    exact = s.G @ np.linalg.solve(s.K_J, s.G.T)
    reduced = red.G @ np.diag(1.0 / red.omega ** 2) @ red.G.T
    np.testing.assert_allclose(reduced, exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())


@pytest.mark.parametrize("chi, beta", [(-0.38, 0.0), (-0.7, 0.0), (-0.2, 1.5)])
def test_log_spaced_bank_matches_exact_describing_function(chi, beta):
    """First-harmonic stiffness and dissipation of the bank (AFT march over one sampled
    period) against the exact continuous model, 1e-3 phi_max to 2 phi_max."""
    p = IwanParameters(chi=chi, K_T=2.5e7, F_S=20.0, beta=beta)
    a_low = 1e-3 * p.phi_max / 64
    bank = JointBank.log_spaced([p, p], a_low, 16)
    np.testing.assert_allclose(bank.K_T, p.K_T, rtol=1e-12)
    N = 2048
    theta = 2 * np.pi * np.arange(N) / N
    for A in p.phi_max * np.concatenate([np.logspace(-3, 0, 13), [2.0]]):
        s = np.tile(A * np.sin(theta), (2, 1))
        F, _ = aft_joint_force(s, bank)
        k_in = 2.0 / N * F[0] @ np.sin(theta) / A
        k_q = 2.0 / N * F[0] @ np.cos(theta) / A
        e_in, e_q = describing_function(p, A)
        # in-phase: relative to the stiffness lost by slipping; quadrature: relative
        assert abs(k_in - e_in) <= 1.5e-3 * (p.K_T - e_in), (A / p.phi_max, k_in, e_in)
        assert abs(k_q - e_q) <= 1.5e-3 * e_q, (A / p.phi_max, k_q, e_q)
        np.testing.assert_allclose(F[1], F[0], rtol=0, atol=0)


def test_log_spaced_bank_rejects_bad_input():
    p = IwanParameters(chi=-0.5, K_T=1e6, F_S=10.0, beta=0.0)
    q = IwanParameters(chi=-0.4, K_T=1e6, F_S=10.0, beta=0.0)
    with pytest.raises(ValueError, match="same phi_max"):
        JointBank.log_spaced([p, q], 1e-9, 8)
    with pytest.raises(ValueError, match="a_low"):
        JointBank.log_spaced([p], 2 * p.phi_max, 8)
