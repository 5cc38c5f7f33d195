"""Synthetic measured-data generator: physics of the virtual test against closed forms."""
from __future__ import annotations

import time

import numpy as np
import pytest

from cases.synthetic import (
    CAUSES,
    EFFECT_RANGE,
    SIGMA_OMEGA2_REL,
    SIGMA_ZETA,
    Exciter,
    ModalOscillator,
    generate_case,
    identify_sdof,
    simulate_level,
    steady_amplitude,
)
from joints.describing import describing_function
from joints.iwan import IwanParameters, dissipation_per_cycle


def _oscillator(R=2e4, k3=0.0, c2=0.0, beta=1.0):
    omega0 = 2 * np.pi * 80.0
    joint = IwanParameters.from_density(R=R, chi=-0.5, phi_max=1e-4,
                                        S=beta * R * 1e-4**0.5 / 0.5)
    return ModalOscillator(omega2_lin=omega0**2 - joint.K_T, zeta0=0.01, joint=joint,
                           k3=k3, c2=c2)


def test_linear_limit_matches_sdof_receptance():
    # a joint so weak and a drive so small that the oscillator is linear:
    # receptance 1 / (omega0^2 - W^2 + 2 i zeta0 omega0 W), exact
    osc = _oscillator(R=1e-6)
    exc = Exciter(gain=1e-9, c_e=5.0)
    w0 = osc.omega0
    W = w0 * np.linspace(0.95, 1.05, 41)
    X, frf, fold = steady_amplitude(osc, exc, 1.0, W)
    exact = 1.0 / (w0**2 - W**2 + 2j * osc.zeta0 * w0 * W)
    assert not fold
    np.testing.assert_allclose(frf, exact, rtol=1e-9)
    # amplitude with the exciter's back-EMF damping in series
    Xe = 1e-9 / np.abs(w0**2 - W**2 + 1j * W * (2 * osc.zeta0 * w0 + 5.0))
    np.testing.assert_allclose(X, Xe, rtol=1e-9)
    w2, z = identify_sdof(W, frf)
    assert w2 == pytest.approx(w0**2, rel=1e-9)
    assert z == pytest.approx(osc.zeta0, rel=1e-6)


@pytest.mark.parametrize("gain, regime", [(3.0, "micro"), (20.0, "macro")])
def test_harmonic_balance_and_energy_balance(gain, regime):
    # steady state: |D_total| X = G V, and the work of the measured force per cycle,
    # pi Im(F conj q), equals viscous + Iwan (dissipation_per_cycle) + quadratic damper
    osc = _oscillator(R=4e5, c2=3e3)
    exc = Exciter(gain=gain, c_e=3.0)
    W = osc.omega0 * np.linspace(0.97, 1.03, 13)
    X, frf, fold = steady_amplitude(osc, exc, 1.0, W)
    assert not fold
    x = X / osc.joint.phi_max
    assert np.all((0.5 < x) & (x < 1.0)) if regime == "micro" else np.all(x > 1.5)
    q = X  # phase reference: q real, F = D q
    F = q / frf
    work_in = np.pi * np.imag(F * np.conj(q))
    viscous = np.pi * 2 * osc.zeta0 * osc.omega0 * W * X**2
    quadratic = 8.0 / 3.0 * osc.c2 * W**2 * X**3
    iwan = dissipation_per_cycle(osc.joint, X)
    np.testing.assert_allclose(work_in, viscous + quadratic + iwan, rtol=1e-10)
    # force balance including the back-EMF of the exciter
    Ftot = np.abs(F + 1j * W * exc.c_e * q)
    np.testing.assert_allclose(Ftot, exc.gain * 1.0, rtol=1e-8)
    # first-harmonic in-phase balance: Re(D) = omega2_lin + k_in(X) - W^2
    k_in, _ = describing_function(osc.joint, X)
    np.testing.assert_allclose(np.real(1 / frf), osc.omega2_lin + k_in - W**2, rtol=1e-10,
                               atol=1e-9 * osc.omega0**2)


def test_hardening_shift_is_three_quarters_k3_X2():
    # a cubic spring lifts the identified omega2 by 3/4 k3 X^2 (first harmonic)
    base = _oscillator(R=1e3)
    k3 = 2e11
    hard = _oscillator(R=1e3, k3=k3)
    exc = Exciter(gain=0.2, c_e=0.0)
    W = base.omega0 * (1 + 0.01 * np.linspace(-6, 6, 61))
    w2_b, _, X_b, _ = simulate_level(base, exc, 1.0, W, 1.0)
    w2_h, _, X_h, _ = simulate_level(hard, exc, 1.0, W, 1.0)
    shift = 0.75 * k3 * X_h**2
    assert shift / base.omega0**2 > 1e-4  # far above the 1e-5 noise
    # the fit averages over the resonance, where the amplitude is <= the dwell X
    assert 0.7 * shift < w2_h - w2_b < 1.02 * shift


def test_identified_damping_grows_like_iwan_quadrature():
    # micro-slip: identified zeta - zeta0 ~ k_q(X)/(2 omega^2) at the dwell amplitude
    osc = _oscillator(R=3e5)
    exc = Exciter(gain=0.2, c_e=0.0)
    W = osc.omega0 * (1 + 0.012 * np.linspace(-6, 6, 61))
    w2, z, X, fold = simulate_level(osc, exc, 1.0, W, 1.0)
    assert not fold and X < osc.joint.phi_max
    k_in, k_q = describing_function(osc.joint, X)
    dz = z - osc.zeta0 * osc.omega0 / np.sqrt(w2)
    # identification averages over the resonance (amplitudes <= X): 0.6 .. 1.0 of it
    # (hysteretic damping seen through a viscous fit: allow 10 % above)
    assert 0.6 * k_q / (2 * w2) < dz < 1.1 * k_q / (2 * w2)
    dw2 = osc.omega0**2 - w2
    assert 0.6 * (osc.joint.K_T - k_in) < dw2 < 1.02 * (osc.joint.K_T - k_in)


@pytest.mark.parametrize("cause", CAUSES)
def test_generated_case_respects_its_design(cause):
    t0 = time.perf_counter()
    case = generate_case(cause, 11)
    elapsed = time.perf_counter() - t0
    assert elapsed < 5.0
    d, t = case.data, case.truth
    n = d.level.size
    assert 10 <= n <= 12
    assert sorted(d.run_order) == list(range(1, n + 1))
    assert -0.8 <= t["chi"] <= -0.2
    x_top = t["slip_over_phi_max"][-1]
    if cause == "macro-slip":
        assert x_top > 1.0
    else:
        assert 0.3 < x_top < 1.0
    if cause in EFFECT_RANGE and cause != "macro-slip":
        lo, hi = EFFECT_RANGE[cause]
        assert lo <= abs(t["effect_sigma"]) <= hi
    if cause == "nonproportional-amplitude":
        assert d.response_amplitude is not None
        assert t["nonproportionality"] > 0.5 * t["effect_sigma"]
    else:
        assert t["nonproportionality"] < 0.03
    # noise as specified: compare with the noise-free identified values
    rel = d.omega2 / t["omega2_clean"] - 1.0
    dz = d.zeta - t["zeta_clean"]
    assert np.std(rel) < 3 * SIGMA_OMEGA2_REL and np.std(dz) < 3 * SIGMA_ZETA
    assert np.std(rel) > 0.2 * SIGMA_OMEGA2_REL and np.std(dz) > 0.2 * SIGMA_ZETA


def test_thermal_drift_moves_identified_omega2_by_run_order():
    # drift of the structure's stiffness with run order: identified omega2 moves by
    # drift * omega2_lin * (run - 1), the damping ratio only by zeta0 (w0/w - 1)
    osc = _oscillator(R=1e2)  # joint nearly linear: only the drift moves omega2
    osc.drift_per_run = 3e-5
    exc = Exciter(gain=2e-3, c_e=1.0)
    W = osc.omega0 * (1 + 0.012 * np.linspace(-6, 6, 61))
    w2_1, z_1, X_1, _ = simulate_level(osc, exc, 1.0, W, 1.0)
    w2_5, z_5, X_5, _ = simulate_level(osc, exc, 1.0, W, 5.0)
    expected = 4 * 3e-5 * osc.omega2_lin
    assert w2_5 - w2_1 == pytest.approx(expected, rel=0.02)
    assert abs(z_5 - z_1) < 0.2 * SIGMA_ZETA
    assert X_5 == pytest.approx(X_1, rel=1e-3)


def test_same_seed_same_data():
    a, b = generate_case("quadratic-damping", 5), generate_case("quadratic-damping", 5)
    np.testing.assert_array_equal(a.data.omega2, b.data.omega2)
    np.testing.assert_array_equal(a.data.run_order, b.data.run_order)
    c = generate_case("quadratic-damping", 6)
    assert not np.array_equal(a.data.zeta, c.data.zeta)


def test_unknown_cause_is_rejected():
    with pytest.raises(ValueError, match="unknown cause"):
        generate_case("gremlins", 1)
