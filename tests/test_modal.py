"""Modal analysis and FRFs: analytic beams, a second method (direct solve)."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from fe.assembly import assemble, free_dofs, restrict
from fe.beam import Section, frame_mass, frame_stiffness
from fe.mesh import DofMap, line_mesh
from fe.modal import frf_direct, frf_modal, modal_damping_ratios, normal_modes

SEC = Section(70e9, 2700.0, 0.05, 1e-3)
L = 0.35
BETA_L = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613,
                   10.99554073487547])  # Blevins


def cantilever(n_el):
    mesh = line_mesh(np.linspace(0, L, n_el + 1))
    dm = DofMap(mesh.n_nodes)
    dofs = dm.element_dofs(mesh.elements)
    K = assemble(frame_stiffness(mesh.element_length, SEC.EA, SEC.EI), dofs, dm.n_dofs)
    M = assemble(frame_mass(mesh.element_length, SEC.mass_per_length), dofs, dm.n_dofs)
    free = free_dofs(dm.n_dofs, dm.node_dofs([0]).ravel())
    return restrict(K, free), restrict(M, free), free


def test_cantilever_bending_frequencies_match_analytic():
    K, M, free = cantilever(40)
    omega, phi = normal_modes(K, M, 5)
    exact = BETA_L**2 * np.sqrt(SEC.EI / (SEC.mass_per_length * L**4))
    np.testing.assert_allclose(omega[:4], exact, rtol=1e-5)
    # the lead's numbers for a single 1 mm strip: 6.7, 42, 118, 231 Hz
    np.testing.assert_allclose(omega[:4] / (2 * np.pi), [6.71, 42.08, 117.82, 230.88], rtol=2e-3)


def test_axial_bar_frequencies_match_analytic():
    """Clamped-free bar: omega_n = (2n - 1) pi / (2 L) sqrt(E / rho); linear elements, O(h^2)."""
    K, M, free = cantilever(400)
    axial = (free % 3) == 0
    Ka, Ma = K[axial][:, axial], M[axial][:, axial]
    omega, _ = normal_modes(Ka, Ma, 3)
    exact = (2 * np.arange(1, 4) - 1) * np.pi / (2 * L) * np.sqrt(SEC.E / SEC.rho)
    np.testing.assert_allclose(omega, exact, rtol=2e-5)


def test_modes_are_mass_normalized_and_sparse_equals_dense():
    K, M, free = cantilever(60)
    w_sparse, p_sparse = normal_modes(K, M, 6, dense_below=0)          # ARPACK
    w_dense, p_dense = normal_modes(K, M, 6, dense_below=10**6)
    np.testing.assert_allclose(w_sparse, w_dense, rtol=1e-7)  # dense: ~3e-9 round-off
    np.testing.assert_allclose(p_sparse.T @ (M @ p_sparse), np.eye(6), atol=1e-9)
    np.testing.assert_allclose(p_sparse.T @ (K @ p_sparse), np.diag(w_sparse**2), rtol=1e-7,
                               atol=1e-9 * w_sparse[-1] ** 2)
    np.testing.assert_allclose(np.abs(p_sparse.T @ (M @ p_dense)), np.eye(6), atol=1e-7)


def test_modal_damping_ratios_paper_eq28():
    w = np.array([10.0, 100.0])
    np.testing.assert_allclose(modal_damping_ratios(w, proportional=(2.0, 1e-4)),
                               2.0 / (2 * w) + 0.5e-4 * w)
    with pytest.raises(ValueError):
        modal_damping_ratios(w)


def _random_system(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    K = A @ A.T + n * np.eye(n)
    B = rng.normal(size=(n, n))
    M = B @ B.T / n + np.eye(n)
    return K, M


def test_frf_modal_equals_direct_solve_proportional_damping():
    K, M = _random_system(8, 11)
    a, b = 0.3, 2e-3
    omega_n, phi = normal_modes(K, M, 8)
    w = np.linspace(0.1, 1.3 * omega_n[-1], 57)
    f = np.zeros(8)
    f[2] = 1.0
    H_modal = frf_modal(w, omega_n, phi, drive=2, response=[5, 2, 0], proportional=(a, b))
    H_direct = frf_direct(w, K, M, f, C=a * M + b * K, response=[5, 2, 0])
    np.testing.assert_allclose(H_modal, H_direct, rtol=1e-9, atol=1e-12 * np.abs(H_direct).max())


def test_frf_modal_equals_direct_solve_modal_damping():
    """C = M Phi diag(2 zeta omega) Phi^T M is the damping matrix with modal ratios zeta."""
    K, M = _random_system(6, 5)
    omega_n, phi = normal_modes(K, M, 6)
    zeta = np.array([0.01, 0.02, 0.005, 0.03, 0.012, 0.05])
    C = M @ phi @ np.diag(2 * zeta * omega_n) @ phi.T @ M
    w = np.linspace(0.5 * omega_n[0], 1.2 * omega_n[-1], 41)
    f = np.zeros(6)
    f[4] = 1.0
    H_modal = frf_modal(w, omega_n, phi, drive=4, response=1, zeta=zeta)
    H_direct = frf_direct(w, sp.csr_matrix(K), M, f, C=C, response=1)
    np.testing.assert_allclose(H_modal, H_direct, rtol=1e-9)


def test_sparse_modes_are_bitwise_deterministic_and_equal_dense():
    """Repeated ARPACK calls return the same bits (fixed start vector); ARPACK's own random
    start moves the modes by ~1e-7 relative between calls, which the same loop would catch.
    Second method: the dense shift-invert path."""
    K, M, free = cantilever(80)          # 240 DOFs, ARPACK path forced
    runs = [normal_modes(K, M, 8, dense_below=0) for _ in range(4)]
    for w, p in runs[1:]:
        assert np.array_equal(w, runs[0][0]) and np.array_equal(p, runs[0][1])
    w_dense, p_dense = normal_modes(K, M, 8, dense_below=10**6)
    np.testing.assert_allclose(runs[0][0], w_dense, rtol=1e-7)
    np.testing.assert_allclose(np.abs(runs[0][1].T @ (M @ p_dense)), np.eye(8), atol=1e-7)
    # the dense path is deterministic as well
    w2, p2 = normal_modes(K, M, 8, dense_below=10**6)
    assert np.array_equal(w2, w_dense) and np.array_equal(p2, p_dense)


@pytest.mark.parametrize("n_el", [300, 500])
def test_sparse_modes_of_free_free_beams_match_the_closed_form(n_el):
    """Two unconnected free-free beams (250 x 40 x 8 mm aluminium: 6 rigid-body modes,
    each elastic mode twice) on the sparse path: the elastic modes are the closed form
    ``(beta L)^2 sqrt(EI / (rho A L^4))``, beta L = 4.7300408, 7.8532046. A shift-invert at
    -1 rad^2/s^2 let the rigid-body modes drown the elastic ones in the solve's round-off:
    a spurious mode at 1.15 (300 elements) or 0.28 (500) times the first."""
    sec, length = Section(69e9, 2700.0, 0.04, 0.008), 0.25
    mesh = line_mesh(np.linspace(0, length, n_el + 1))
    dm = DofMap(mesh.n_nodes)
    dofs = dm.element_dofs(mesh.elements)
    K = assemble(frame_stiffness(mesh.element_length, sec.EA, sec.EI), dofs, dm.n_dofs)
    M = assemble(frame_mass(mesh.element_length, sec.mass_per_length), dofs, dm.n_dofs)
    K2, M2 = sp.block_diag([K, K], format="csr"), sp.block_diag([M, M], format="csr")
    assert K2.shape[0] > 1000                           # the sparse (ARPACK) path
    omega, _ = normal_modes(K2, M2, 10)
    scale = np.sqrt(sec.EI / (sec.mass_per_length * length**4))
    exact = np.array([4.730040745, 4.730040745, 7.853204624, 7.853204624]) ** 2 * scale
    assert np.all(omega[:6] < 1e-3 * exact[0])          # the rigid-body modes, no more
    np.testing.assert_allclose(omega[6:], exact, rtol=1e-5)
