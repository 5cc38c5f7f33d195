"""Jenkins-bank discretization and state update (joints/jenkins.py) against the exact
continuous Iwan model, single-slider closed forms and measured convergence rates."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from joints.describing import describing_function
from joints.iwan import IwanParameters, backbone, dissipation_per_cycle, force_history
from joints.jenkins import JenkinsDiscretization, discretize, discretize_log, jenkins_update

PAPER = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)
params = st.builds(
    IwanParameters,
    chi=st.floats(-0.95, -0.05),
    K_T=st.floats(1e3, 1e8),
    F_S=st.floats(1.0, 1e5),
    beta=st.one_of(st.just(0.0), st.floats(0.0, 10.0)),
)


def simulate(disc, u, n_joints=1):
    """Drive a bank (one joint, or copies) along slip path u; return forces, tangents."""
    anchor = np.zeros((n_joints, disc.n_sliders))
    force = np.empty((u.size, n_joints))
    tangent = np.empty((u.size, n_joints))
    for i, x in enumerate(u):
        force[i], tangent[i], anchor = jenkins_update(
            np.full(n_joints, x), anchor, disc.stiffness, disc.slip_limit)
    return force, tangent


# ----------------------------------------------------------------- discretize


@settings(max_examples=50, deadline=None)
@given(params, st.integers(2, 3000))
def test_stiffness_sums_to_KT_and_limits_ordered(p, n):
    d = discretize(p, n)
    assert d.stiffness.shape == d.slip_limit.shape == (n,)
    assert d.stiffness.sum() == pytest.approx(p.K_T, rel=1e-13)
    assert np.all(d.stiffness >= 0) and np.all(np.diff(d.slip_limit) >= 0)
    assert 0 < d.slip_limit[0] and d.slip_limit[-1] <= p.phi_max * (1 + 1e-15)
    # saturated force sum k phi -> F_S: midpoint rule for int_0^1 s^m ds, m = 1/(chi+1),
    # f'' increasing => relative error <= (m+1) m (1+h)^(m-1) h^2 / 24, h = 1/n_c
    m, h = 1.0 / (p.chi + 1.0), 1.0 / (n - 1 if p.S > 0 else n)
    bound = (m + 1) * m * (1 + h) ** (m - 1) * h * h / 24 + 1e-12
    assert np.dot(d.stiffness, d.slip_limit) == pytest.approx(p.F_S, rel=bound)


def test_dirac_slider_and_beta_zero():
    d = discretize(PAPER, 11)
    assert d.stiffness[-1] == pytest.approx(PAPER.S) and d.slip_limit[-1] == PAPER.phi_max
    np.testing.assert_allclose(d.stiffness[:-1], (PAPER.K_T - PAPER.S) / 10, rtol=1e-15)
    p0 = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=0.0)
    d0 = discretize(p0, 10)
    np.testing.assert_allclose(d0.stiffness, 1.1e4, rtol=1e-15)
    # midpoints in s = (phi/phi_max)^(chi+1): s = 0.05, 0.15, ... -> phi = phi_max s^2
    np.testing.assert_allclose(d0.slip_limit, p0.phi_max * ((np.arange(10) + 0.5) / 10) ** 2)
    for bad in (1, 0, 2.5):
        with pytest.raises(ValueError, match="n_sliders"):
            discretize(PAPER, bad)


@pytest.mark.parametrize("p", [PAPER, IwanParameters(-0.8, 3e6, 25.0, 0.0),
                               IwanParameters(-0.2, 5e4, 900.0, 1.0)])
def test_convergence_rates(p):
    """Measured: max backbone error (|u| <= phi_max) and max relative micro-slip
    dissipation error (A in [0.1, 0.9] phi_max) both fall as n**-2 (docstring)."""
    ns = np.array([10, 30, 100, 300, 1000])
    u = np.linspace(0.0, p.phi_max, 1501)
    A = np.linspace(0.1, 0.9, 161) * p.phi_max
    e_bb, e_d = [], []
    for n in ns:
        d = discretize(p, n)
        F = np.minimum(u[:, None], d.slip_limit) @ d.stiffness  # bank backbone
        e_bb.append(np.max(np.abs(F - backbone(p, u))) / p.F_S)
        phi = d.slip_limit
        D = np.where(phi < A[:, None], 4 * phi * (A[:, None] - phi), 0.0) @ d.stiffness
        e_d.append(np.max(np.abs(D / dissipation_per_cycle(p, A) - 1)))
    slope_bb = np.polyfit(np.log(ns), np.log(e_bb), 1)[0]
    slope_d = np.polyfit(np.log(ns), np.log(e_d), 1)[0]
    assert slope_bb == pytest.approx(-2.0, abs=0.3)
    assert slope_d == pytest.approx(-2.0, abs=0.3)
    assert e_bb[2] < 5e-4 and e_d[2] < 3e-3  # n = 100


# ----------------------------------------------------------------- jenkins_update


def test_single_slider_elastic_perfectly_plastic():
    k, phi = 2.0e4, 1e-3
    u = np.array([0.5e-3, 1.5e-3, 2.0e-3, 1.0e-3, -0.5e-3, 0.0])
    anchor = np.zeros((1, 1))
    expected_F = [10.0, 20.0, 20.0, 0.0, -20.0, -10.0]
    expected_T = [k, 0.0, 0.0, k, 0.0, k]
    for x, Fe, Te in zip(u, expected_F, expected_T):
        F, T, anchor = jenkins_update(np.array([x]), anchor, [k], [phi])
        assert F[0] == pytest.approx(Fe, abs=1e-12) and T[0] == Te


def test_update_is_pure_and_shapes_broadcast():
    rng = np.random.default_rng(7)
    d = discretize(PAPER, 50)
    slip = rng.normal(0, PAPER.phi_max, 4)
    anchor = rng.normal(0, PAPER.phi_max, (4, 50))
    before = anchor.copy()
    F1, T1, a1 = jenkins_update(slip, anchor, d.stiffness, d.slip_limit)
    assert np.array_equal(anchor, before)
    assert F1.shape == T1.shape == (4,) and a1.shape == (4, 50)
    F2, T2, a2 = jenkins_update(slip, anchor, np.tile(d.stiffness, (4, 1)),
                                np.tile(d.slip_limit, (4, 1)))
    np.testing.assert_allclose(F2, F1, rtol=1e-14)
    np.testing.assert_allclose(T2, T1, rtol=1e-14)
    np.testing.assert_array_equal(a2, a1)
    # by definition, slider by slider
    lo, hi = slip[:, None] - d.slip_limit, slip[:, None] + d.slip_limit
    ref = np.minimum(np.maximum(anchor, lo), hi)
    np.testing.assert_array_equal(a1, ref)
    np.testing.assert_allclose(F1, ((slip[:, None] - ref) * d.stiffness).sum(1), rtol=1e-13)
    stuck = (anchor >= lo) & (anchor <= hi)
    np.testing.assert_allclose(T1, (stuck * d.stiffness).sum(1), rtol=1e-14)
    assert np.all(np.abs(slip[:, None] - a1) <= d.slip_limit + 4e-16 * np.abs(slip).max())


def test_tangent_is_derivative_of_force():
    d = discretize(PAPER, 200)
    rng = np.random.default_rng(3)
    anchor = rng.uniform(-1, 1, (3, 200)) * d.slip_limit
    slip = np.array([0.2, -0.5, 0.7]) * PAPER.phi_max
    h = 1e-9 * PAPER.phi_max
    Fp, Tp, _ = jenkins_update(slip + h, anchor, d.stiffness, d.slip_limit)
    Fm, _, _ = jenkins_update(slip, anchor, d.stiffness, d.slip_limit)
    np.testing.assert_allclose((Fp - Fm) / h, Tp, rtol=1e-5)


def test_bank_follows_exact_memory_rules_on_random_path():
    rng = np.random.default_rng(12345)
    p = IwanParameters(chi=-0.6, K_T=8e5, F_S=150.0, beta=2.0)
    turns = rng.uniform(-1.6, 1.6, 12) * p.phi_max
    u = np.concatenate([np.linspace(a, b, 40, endpoint=False)
                        for a, b in zip(np.r_[0.0, turns[:-1]], turns)])
    d = discretize(p, 2000)
    F_bank, _ = simulate(d, u)
    err = np.max(np.abs(F_bank[:, 0] - force_history(p, u))) / p.F_S
    assert err < 1e-5


def test_bank_describing_function_and_loop_energy():
    """First harmonic of a simulated steady cycle (trapezoid Fourier sums) vs the exact
    describing function, and loop area vs the per-slider energy sum 4 k phi (A - phi)."""
    p = PAPER
    d = discretize(p, 1000)
    n = 4000
    theta = np.linspace(0.0, 4 * np.pi, 2 * n + 1)
    for frac in (0.3, 0.8, 2.5):
        A = frac * p.phi_max
        F, _ = simulate(d, A * np.sin(theta))
        th, Fc = theta[n:-1], F[n:-1, 0]  # second (steady) cycle, periodic samples
        k_in = 2 * np.mean(Fc * np.sin(th)) / A
        k_q = 2 * np.mean(Fc * np.cos(th)) / A
        e_in, e_q = describing_function(p, A)
        assert k_in == pytest.approx(e_in, rel=2e-4)
        assert k_q == pytest.approx(e_q, rel=2e-4)
        u2, F2 = A * np.sin(theta[n:]), F[n:, 0]
        area = 0.5 * abs(np.dot(u2[:-1], F2[1:]) - np.dot(u2[1:], F2[:-1]))
        phi = d.slip_limit
        per_slider = np.sum(d.stiffness * np.where(phi < A, 4 * phi * (A - phi), 0.0))
        assert area == pytest.approx(per_slider, rel=1e-5)


def test_hand_built_bank_against_its_closed_forms():
    """A bank of three sliders built by hand (k = 1, 2, 3 N/m at phi = 1, 2, 3 m): its
    virgin loading curve is ``F(u) = sum k_i min(u, phi_i)`` with tangent the stiffness
    of the sliders not yet slipping, and the loop of amplitude A dissipates
    ``sum_{phi_i < A} 4 k_i phi_i (A - phi_i)`` (each slider's rectangle), worked out
    here by hand: 12.5 N and 3 N/m at u = 2.5 m; 4 (1)(1)(1.5) + 4 (2)(2)(0.5) = 14 J
    at A = 2.5 m. Steps of 0.25 m put every kink of the loop on a sample, so the
    trapezoidal loop area is exact to rounding."""
    d = JenkinsDiscretization(stiffness=np.array([1.0, 2.0, 3.0]),
                              slip_limit=np.array([1.0, 2.0, 3.0]))
    assert d.n_sliders == 3
    up = np.linspace(0.0, 2.5, 11)
    u = np.concatenate([up, np.linspace(2.5, -2.5, 21)[1:], np.linspace(-2.5, 2.5, 21)[1:]])
    F, T = simulate(d, u)
    assert F[10, 0] == 12.5 and T[10, 0] == 3.0
    assert F[2, 0] == 0.5 * 6.0 and T[2, 0] == 6.0        # u = 0.5 m: all stuck
    assert F[-1, 0] == 12.5                                # the loop closes
    loop_F, loop_u = F[10:, 0], u[10:]                     # from u = A down and back
    area = 0.5 * np.sum((loop_F[1:] + loop_F[:-1]) * np.diff(loop_u))    # work done on it
    assert area == pytest.approx(14.0, rel=1e-14)


@pytest.mark.parametrize("chi", [-0.5, -0.2])
def test_low_amplitude_error_rule(chi):
    """Docstring rule: relative dissipation error ~ c / m_A**2, m_A = n (A/phi_max)^(chi+1)
    sliders slipping, c between 0.5 and 1.2."""
    p = IwanParameters(chi=chi, K_T=1e5, F_S=10.0, beta=0.0)
    for n, m_target in ((100, 10), (1000, 40)):
        d = discretize(p, n)
        f0 = (m_target / n) ** (1 / (chi + 1))
        A = np.linspace(f0, 1.3 * f0, 200) * p.phi_max
        phi = d.slip_limit
        D = np.where(phi < A[:, None], 4 * phi * (A[:, None] - phi), 0.0) @ d.stiffness
        err = np.max(np.abs(D / dissipation_per_cycle(p, A) - 1))
        assert 0.2 < err * m_target**2 < 2.0


# ----------------------------------------------------------------- discretize_log


def jenkins_first_harmonic(d, A):
    """Closed-form first harmonic of a Jenkins bank under slip ``A sin(wt)`` (steady
    cycle; Caughey 1960, bilinear hysteresis with zero post-slip stiffness): per slider
    with ``phi < A``, ``k_in = k/pi (t - sin(2t)/2)``, ``cos t = 1 - 2 phi/A``, and
    dissipation ``4 k phi (A - phi)``; stuck sliders give ``k`` and nothing."""
    k, phi = d.stiffness[:, None], d.slip_limit[:, None]
    A = np.atleast_1d(A)[None, :]
    slipping = phi < A
    t = np.arccos(1.0 - 2.0 * np.where(slipping, phi / A, 1.0))
    k_in = np.where(slipping, k / np.pi * (t - 0.5 * np.sin(2 * t)), k).sum(axis=0)
    D = np.where(slipping, 4 * k * phi * (A - phi), 0.0).sum(axis=0)
    return k_in, D


def test_closed_form_jenkins_harmonic_matches_simulated_cycle():
    """The closed form used below against a simulated steady cycle of three sliders."""
    d = JenkinsDiscretization(stiffness=np.array([1e5, 2e5, 5e4]),
                              slip_limit=np.array([1e-6, 3e-6, 8e-6]))
    n, A = 4000, 5e-6
    theta = np.linspace(0.0, 4 * np.pi, 2 * n + 1)
    F, _ = simulate(d, A * np.sin(theta))
    th, Fc = theta[n:-1], F[n:-1, 0]
    k_in, D = jenkins_first_harmonic(d, A)
    # periodic trapezoid sums over a cycle with kinks: O(h^2), 1e-8 here
    assert 2 * np.mean(Fc * np.sin(th)) / A == pytest.approx(k_in[0], rel=1e-7)
    assert np.pi * A * 2 * np.mean(Fc * np.cos(th)) == pytest.approx(D[0], rel=1e-7)


@settings(max_examples=50, deadline=None)
@given(params, st.integers(1, 40), st.floats(1e-8, 0.9))
def test_log_discretization_contract(p, n, frac):
    """Stiffnesses sum to K_T, sum k phi = F_S (exact cell moments), K + 1 (+1) sliders."""
    a_low = frac * p.phi_max
    d = discretize_log(p, a_low, n)
    n_cuts = math.ceil(n * math.log2(1.0 / frac))
    assert d.n_sliders == n_cuts + 1 + (p.S > 0)
    assert d.stiffness.sum() == pytest.approx(p.K_T, rel=1e-13)
    assert np.dot(d.stiffness, d.slip_limit) == pytest.approx(p.F_S, rel=1e-12)
    assert np.all(d.stiffness >= 0) and np.all(np.diff(d.slip_limit) > 0)
    assert d.slip_limit[-1] <= p.phi_max * (1 + 1e-15)
    if n_cuts:   # the second slider is the first resolved cell, just above a_low
        assert a_low * 2 ** (-1.0 / n) * (1 - 1e-12) <= d.slip_limit[1] <= 2 * a_low


@pytest.mark.parametrize("chi, beta", [(-0.9, 0.0), (-0.5, 0.0), (-0.5, 4.0), (-0.1, 0.0)])
def test_log_discretization_accuracy_over_three_decades(chi, beta):
    """Docstring numbers: dissipation and in-phase stiffness loss against the exact
    four-parameter model from 1e-3 phi_max to phi_max (a_low 6 octaves lower), 16 and 32
    sliders per octave; the error falls as (cell width)^2; macro-slip up to 4 phi_max."""
    p = IwanParameters(chi=chi, K_T=2.5e7, F_S=20.0, beta=beta)
    A = p.phi_max * np.logspace(-3, 0, 61)
    e_in, _ = describing_function(p, A)
    D_exact = dissipation_per_cycle(p, A)
    err = {}
    for n in (16, 32):
        k_in, D = jenkins_first_harmonic(discretize_log(p, 1e-3 * p.phi_max / 64, n), A)
        err[n] = (np.max(np.abs(D / D_exact - 1)), np.max(np.abs(k_in - e_in) / (p.K_T - e_in)))
    assert err[16][0] < 1.0e-3 and err[16][1] < 1.8e-4
    assert err[32][0] < 2.5e-4 and err[32][1] < 8.5e-5
    if chi >= -0.5:   # second order (near chi = -1 the lumped cell below a_low dominates)
        assert 3.5 < err[16][0] / err[32][0] < 4.5
    if chi == -0.5:
        assert err[16][0] < 6.5e-4 and err[16][1] < 7.5e-5
        # macro-slip: the continuous part saturates, the cell moments hold it
        A = p.phi_max * np.array([1.0, 1.5, 2.0, 4.0])
        k_in, D = jenkins_first_harmonic(discretize_log(p, 1e-3 * p.phi_max / 64, 16), A)
        assert np.max(np.abs(D / dissipation_per_cycle(p, A) - 1)) < 2.5e-4
        np.testing.assert_allclose(k_in, describing_function(p, A)[0], rtol=1.2e-4)
        # the uniform rule with as many sliders (257) is far worse at 1e-3 phi_max
        d_u = discretize(p, discretize_log(p, 1e-3 * p.phi_max / 64, 16).n_sliders)
        A = p.phi_max * 1e-3
        _, D_u = jenkins_first_harmonic(d_u, A)
        assert abs(D_u[0] / dissipation_per_cycle(p, A) - 1) > 5 * err[16][0]


def test_log_discretization_rejects_bad_input():
    with pytest.raises(ValueError, match="a_low"):
        discretize_log(PAPER, 2 * PAPER.phi_max, 8)
    with pytest.raises(ValueError, match="a_low"):
        discretize_log(PAPER, 0.0, 8)
    with pytest.raises(ValueError, match="sliders_per_octave"):
        discretize_log(PAPER, 1e-3 * PAPER.phi_max, 0)
