"""2-D Euler-Bernoulli frame element: closed forms and quadrature of the shape functions."""
from __future__ import annotations

import numpy as np
import pytest

from fe.beam import Section, fibre_axial_row, frame_mass, frame_stiffness

E, RHO, B, H = 70e9, 2700.0, 0.05, 1e-3
SEC = Section(E, RHO, B, H)


def hermite(xi, L):
    """Cubic Hermite shape functions on [0, L] and their 2nd derivatives (x = xi L)."""
    N = np.array([1 - 3 * xi**2 + 2 * xi**3, L * (xi - 2 * xi**2 + xi**3),
                  3 * xi**2 - 2 * xi**3, L * (-xi**2 + xi**3)])
    d2 = np.array([-6 + 12 * xi, L * (-4 + 6 * xi), 6 - 12 * xi, L * (-2 + 6 * xi)]) / L**2
    return N, d2


def test_section_properties():
    assert SEC.area == pytest.approx(5e-5)
    assert SEC.second_moment == pytest.approx(0.05 * 1e-9 / 12)
    assert SEC.EI == pytest.approx(70e9 * 0.05e-9 / 12)
    with pytest.raises(ValueError):
        Section(-1.0, RHO, B, H)


def test_matrices_match_gauss_quadrature_of_shape_functions():
    """K_b = int EI N'' N''^T dx, M_b = int rho A N N^T dx (5-point Gauss, exact for these)."""
    L = np.array([0.013, 0.2])
    K = frame_stiffness(L, SEC.EA, SEC.EI)
    M = frame_mass(L, SEC.mass_per_length)
    g, wg = np.polynomial.legendre.leggauss(5)
    xi, wg = 0.5 * (g + 1), 0.5 * wg
    bend = [1, 2, 4, 5]
    for e, Le in enumerate(L):
        N, d2 = hermite(xi, Le)
        Kq = SEC.EI * Le * (d2 * wg) @ d2.T
        Mq = SEC.mass_per_length * Le * (N * wg) @ N.T
        np.testing.assert_allclose(K[e][np.ix_(bend, bend)], Kq, rtol=1e-12,
                                   atol=1e-9 * np.abs(Kq).max())
        np.testing.assert_allclose(M[e][np.ix_(bend, bend)], Mq, rtol=1e-12,
                                   atol=1e-12 * np.abs(Mq).max())
        # axial: linear shape functions
        Na = np.array([1 - xi, xi])
        Maq = SEC.mass_per_length * Le * (Na * wg) @ Na.T
        np.testing.assert_allclose(M[e][np.ix_([0, 3], [0, 3])], Maq, rtol=1e-12)
        np.testing.assert_allclose(K[e][np.ix_([0, 3], [0, 3])],
                                   SEC.EA / Le * np.array([[1, -1], [-1, 1]]))
        # no axial-bending coupling
        assert np.all(K[e][np.ix_([0, 3], bend)] == 0) and np.all(M[e][np.ix_([0, 3], bend)] == 0)


def test_one_element_cantilever_tip_load_is_exact():
    """Tip force P: w = P L^3 / 3EI, theta = P L^2 / 2EI; tip moment: M L^2/2EI, M L/EI."""
    L, P, Mt, N = 0.35, 0.7, 0.03, 12.0
    K = frame_stiffness([L], SEC.EA, SEC.EI)[0]
    Kf = K[3:, 3:]  # node 1 clamped
    x = np.linalg.solve(Kf, [N, P, Mt])
    EI = SEC.EI
    assert x[0] == pytest.approx(N * L / SEC.EA, rel=1e-12)
    assert x[1] == pytest.approx(P * L**3 / (3 * EI) + Mt * L**2 / (2 * EI), rel=1e-12)
    assert x[2] == pytest.approx(P * L**2 / (2 * EI) + Mt * L / EI, rel=1e-12)


def test_free_element_has_three_rigid_body_modes():
    x1, x2 = 0.1, 0.13
    K = frame_stiffness([x2 - x1], SEC.EA, SEC.EI)[0]
    alpha = 1e-3
    rigid = np.array([
        [1, 0, 0, 1, 0, 0],                                  # axial translation
        [0, 1, 0, 0, 1, 0],                                  # transverse translation
        [0, alpha * x1, alpha, 0, alpha * x2, alpha],        # rotation about the origin
    ], dtype=float)
    np.testing.assert_allclose(K @ rigid.T, 0.0, atol=1e-9 * np.abs(K).max())
    ev = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(ev) < 1e-9 * ev.max()) == 3


def test_translational_mass_sums_to_rho_A_L():
    L = np.array([0.02, 0.35])
    M = frame_mass(L, SEC.mass_per_length)
    for e, Le in enumerate(L):
        for comp in (0, 1):  # u and w translations
            r = np.zeros(6)
            r[[comp, comp + 3]] = 1.0
            assert r @ M[e] @ r == pytest.approx(SEC.mass_per_length * Le, rel=1e-14)
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_fibre_axial_row_is_u_minus_zeta_theta():
    row = fibre_axial_row(np.array([0.5e-3, -0.5e-3]))
    np.testing.assert_allclose(row, [[1, 0, -0.5e-3], [1, 0, 0.5e-3]])


def test_bad_lengths_raise():
    with pytest.raises(ValueError):
        frame_stiffness([0.0], SEC.EA, SEC.EI)
    with pytest.raises(ValueError):
        frame_mass([-1.0], 1.0)
