"""The FRF-level synthetic series: describing functions against quadrature, the steady
state against energy and force balance, the noise and the identification path, and the
drawn series against their design."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from cases.synthetic_series import CATALOGUE, OUT_OF_CATALOGUE, generate_series, truth_of
from cases.synthetic_series import effects as fx
from cases.synthetic_series.levels import noisy
from cases.synthetic_series.mode import Exciter, JointedMode, level_frf
from joints.iwan import IwanParameters, dissipation_per_cycle

THETA = np.linspace(0.0, 2 * np.pi, 200001)


def _first_harmonic_in_phase(force_of_x, X):
    """(1/(pi X)) int f(X sin t) sin t dt, by quadrature (no closed form involved)."""
    return integrate.trapezoid(force_of_x(X * np.sin(THETA)) * np.sin(THETA), THETA) / (np.pi * X)


@pytest.mark.parametrize("a", [1.0, 1.5, 2.0, 3.0, 4.3])
def test_power_spring_coefficient_against_quadrature(a):
    X = 0.7
    k_eq = _first_harmonic_in_phase(lambda x: np.abs(x) ** a * np.sign(x), X)
    assert fx.power_coefficient(a) * X ** (a - 1) == pytest.approx(k_eq, rel=1e-7)
    assert fx.power_coefficient(3.0) == pytest.approx(0.75, rel=1e-14)
    assert fx.power_coefficient(2.0) == pytest.approx(8 / (3 * math.pi), rel=1e-14)


@pytest.mark.parametrize("gap", [0.1, 0.5, 0.9])
def test_gap_spring_against_quadrature(gap):
    X, k = 1.0, 3.0
    k_eq = _first_harmonic_in_phase(lambda x: k * np.maximum(np.abs(x) - gap, 0) * np.sign(x), X)
    assert fx.GapSpring(k, gap)(np.array(X), 0.0, 1)[0] == pytest.approx(k_eq, rel=1e-6)


def test_run_shapes_span_zero_to_one():
    for tau in (None, 0.3, 2.0):
        f = fx.run_shape(np.arange(1, 8), 7, tau)
        assert f[0] == pytest.approx(0.0, abs=1e-15) and f[-1] == pytest.approx(1.0)
        assert np.all(np.diff(f) > 0)


def _mode(effects=(), c0=8.0):
    joint = IwanParameters.from_density(R=3e6, chi=-0.4, phi_max=1e-4, S=40.0)
    w0 = 2 * np.pi * 60
    return JointedMode(w0**2 - joint.K_T, c0, joint, list(effects))


def test_force_control_balances_force_and_energy():
    # |D X| = F at every line, and the work of the transducer force per cycle equals
    # viscous + Iwan (joints.iwan.dissipation_per_cycle) + power-damper dissipation
    damper = fx.PowerDamper(2.0e3, 2.0)
    mode = _mode([damper, fx.PowerSpring(1e12, 3.0)])
    W = mode.omega0 * np.linspace(0.97, 1.03, 25)
    H, F, X, fold = level_frf(mode, W, "force", 2e-3)
    assert not fold
    np.testing.assert_allclose(F, 2e-3, rtol=1e-9)
    q = X                                  # phase reference: q real, force = q / H
    work = np.pi * np.imag((q / H) * np.conj(q))
    expected = (np.pi * mode.c0 * W * X**2 + dissipation_per_cycle(mode.joint, X)
                + np.pi * X**2 * damper(X, W, 1)[1])
    np.testing.assert_allclose(work, expected, rtol=1e-9)
    # quadratic damper: (8/3) c W^2 X^3 per cycle (closed form)
    np.testing.assert_allclose(np.pi * X**2 * damper(X, W, 1)[1],
                               8 / 3 * 2.0e3 * W**2 * X**3, rtol=1e-12)


def test_response_control_holds_the_amplitude_and_the_exciter_loses_force():
    mode = _mode()
    W = mode.omega0 * np.linspace(0.98, 1.02, 11)
    H, F, X, _ = level_frf(mode, W, "response", 3e-5)
    np.testing.assert_allclose(X, 3e-5)
    np.testing.assert_allclose(np.abs(H) * F, 3e-5, rtol=1e-12)
    # voltage drive with back-EMF: transducer force + back-EMF force = exciter output
    exc = Exciter(g=0.05, c_e=20.0)
    H, F, X, fold = level_frf(mode, W, "force", 0.1, exciter=exc)
    assert not fold
    D = 1 / H
    np.testing.assert_allclose(np.abs(D + 1j * W * exc.c_e) * X, exc.force(0.1), rtol=1e-9)
    assert np.all(F < exc.force(0.1))


def test_frf_noise_has_the_stated_level():
    # relative complex noise eps (std of the real and imaginary parts eps/sqrt(2) each)
    # plus a floor of 2 % eps of the peak
    rng = np.random.default_rng(2)
    H = np.full(200000, 1.0 + 0j)
    e = noisy(rng, H, 1e-3) - H
    assert np.std(e.real) == pytest.approx(1e-3 * math.sqrt((1 + 0.02**2) / 2), rel=0.01)
    assert np.std(e.imag) == pytest.approx(np.std(e.real), rel=0.01)


def test_the_table_comes_from_the_project_identification():
    # the generator's table is what `iwanfe diagnose FILE...` makes of its FRF files
    from ident.frf_files import FRFSet
    from ident.series import identify_series
    from ident.series_table import series_table

    s = generate_series("none", 21, n_levels=6)
    sets = [FRFSet(f["freq_hz"], f["frf"], ["1"], quantity="receptance",
                   excitation=f["held"], reference="1", control=f["control"],
                   run_order=f["run_order"], force=f["force"]) for f in s.frfs]
    d = series_table(identify_series(sets, n_modes=1, check_band=False))
    np.testing.assert_array_equal(d.omega2, s.data.omega2)
    np.testing.assert_array_equal(d.zeta_std, s.data.zeta_std)
    np.testing.assert_array_equal(d.response_amplitude, s.data.response_amplitude)


def test_labels():
    assert truth_of("none") == ()
    assert truth_of("macro-slip+thermal-drift") == ("macro-slip", "thermal-drift")
    assert truth_of("softening") == truth_of("out-of-catalogue") == ("unexplained",)
    for bad in ("gremlins", "macro-slip+macro-slip", "a+b+c"):
        with pytest.raises(ValueError, match="label"):
            truth_of(bad)


@pytest.mark.parametrize("label", ["none", "macro-slip", "nonproportional-amplitude",
                                   "thermal-drift+quadratic-damping", "preload-loss"])
def test_series_respect_their_design(label):
    s = generate_series(label, 11)
    d, t = s.data, s.truth
    n = len(d)
    assert 5 <= n <= 12 and len(s.frfs) == n
    assert sorted(d.run_order) == list(range(1, n + 1))
    assert np.all(d.omega2_std > 0) and np.all(d.zeta_std > 0)
    assert t["causes"] == truth_of(label) and -0.85 <= t["chi"] <= -0.15
    held = np.array([f["held"] for f in s.frfs])
    assert np.all(np.diff(held) > 0)
    if t["control"] == "response":
        np.testing.assert_allclose(d.response_amplitude, held)
    else:
        np.testing.assert_allclose(d.excitation, held)
    if label == "macro-slip":
        assert t["x_peak"][-1] > 1.02 > t["x_peak"][0]
    if label == "nonproportional-amplitude":
        assert t["control"] == "force" and 0.08 <= t["shortfall_top"] <= 0.4
    if "thermal-drift" in label or label == "preload-loss":
        assert t["run_kind"] != "ascending"


def test_same_seed_same_series_and_fixed_level_count():
    a, b = generate_series("geometric-hardening", 3), generate_series("geometric-hardening", 3)
    np.testing.assert_array_equal(a.data.omega2, b.data.omega2)
    c = generate_series("geometric-hardening", 4, n_levels=5, control="response")
    assert len(c.data) == 5 and c.data.response_controlled
    assert not np.array_equal(a.data.zeta[:5], c.data.zeta)
    with pytest.raises(ValueError, match="force control"):
        generate_series("nonproportional-amplitude", 1, control="response")
    assert set(CATALOGUE).isdisjoint(OUT_OF_CATALOGUE)
