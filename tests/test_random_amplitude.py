"""The Iwan joint under Rayleigh amplitudes (inverse.random_amplitude) and random series in
the estimator: closed form against quadrature, chi of a random and of a stepped-sine
series of one joint, the measured-data table with ``test`` rows."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, special

from ident.measured import read_measured, write_measured
from ident.modal_data import MeasuredData
from inverse.estimate import estimate
from inverse.random_amplitude import (equivalent_sine_amplitude, rayleigh_describing_function,
                                      rayleigh_factor, rayleigh_micro_slip,
                                      sine_equivalent_kappa1_B)
from joints.describing import describing_function
from joints.iwan import IwanParameters


def _joint(seed):
    rng = np.random.default_rng(seed)
    return IwanParameters(chi=-rng.uniform(0.1, 0.9), K_T=rng.uniform(1e4, 1e6),
                          F_S=rng.uniform(10.0, 500.0), beta=rng.uniform(0.2, 5.0))


@pytest.mark.parametrize("seed", [3, 11, 29])
def test_micro_slip_closed_form_against_quadrature_over_rayleigh_amplitudes(seed):
    """Eq. 2 (Gamma factor) against E[A^2 k(A)]/E[A^2] integrated on a grid in A of the
    exact describing function with the Rayleigh density (a route sharing no code with
    the u-substitution quadrature); phi_max = 9 sigma: P(macro) = e^-40.5."""
    p = _joint(seed)
    sigma = p.phi_max / 9.0
    A = np.linspace(1e-12, 12 * sigma, 400001)
    w = A ** 3 / sigma ** 2 * np.exp(-A ** 2 / (2 * sigma ** 2)) / (2 * sigma ** 2)
    k_in, k_q = describing_function(p, A)
    grid = (integrate.simpson(w * k_in, x=A), integrate.simpson(w * k_q, x=A))
    closed = rayleigh_micro_slip(p, sigma)
    quad = rayleigh_describing_function(p, sigma)
    assert closed[1] == pytest.approx(grid[1], rel=1e-7)
    assert p.K_T - closed[0] == pytest.approx(p.K_T - grid[0], rel=1e-6)
    assert closed[1] == pytest.approx(quad[1], rel=1e-9)
    assert p.K_T - closed[0] == pytest.approx(p.K_T - quad[0], rel=1e-8)


def test_macro_slip_tail_departs_from_the_micro_slip_law():
    """sigma = phi_max: most of the energy above phi_max, where the Dirac part of the
    density slips too; the quadrature (checked on a grid in A) leaves the micro-slip law."""
    p = IwanParameters(chi=-0.5, K_T=1e5, F_S=100.0, beta=1.0)
    sigma = p.phi_max
    k_q_quad = rayleigh_describing_function(p, sigma)[1]
    A = np.linspace(1e-12, 12 * sigma, 400001)
    w = A ** 3 / sigma ** 2 * np.exp(-A ** 2 / (2 * sigma ** 2)) / (2 * sigma ** 2)
    assert k_q_quad == pytest.approx(integrate.simpson(w * describing_function(p, A)[1], x=A),
                                     rel=1e-6)
    assert abs(k_q_quad / rayleigh_micro_slip(p, sigma)[1] - 1) > 0.3


def test_rayleigh_factor_values_and_equivalent_amplitude():
    """c(chi) at known points; the sine law at A_eq equals the random law at sigma."""
    assert rayleigh_factor(0.0) == pytest.approx(np.sqrt(2) * special.gamma(2.5), rel=1e-14)
    assert rayleigh_factor(-1.0) == pytest.approx(1.0, rel=1e-14)
    assert rayleigh_factor(-0.5) == pytest.approx(2 ** 0.25 * special.gamma(2.25), rel=1e-14)
    p = _joint(5)
    sigma = p.phi_max / 20
    a_eq = equivalent_sine_amplitude(sigma, p.chi)
    assert describing_function(p, a_eq)[1] == pytest.approx(rayleigh_micro_slip(p, sigma)[1],
                                                            rel=1e-12)


def _series(p, amplitudes, law, test, omega2_n=4e4, zeta_n=0.002, mass=1.0):
    """An SDOF mode of modal mass ``mass`` with the joint: omega^2 and zeta at each
    amplitude from ``law`` (sine DF or Rayleigh expectation), eq. 2 of inverse.iwan_modal."""
    k_in, k_q = law(p, amplitudes)
    om2 = omega2_n - (p.K_T - k_in) / mass
    zeta = zeta_n * np.sqrt(omega2_n / om2) + k_q / mass / (2 * om2)
    n = amplitudes.size
    return MeasuredData(level=np.arange(1, n + 1), excitation=np.geomspace(1, 8, n),
                        omega2=om2, zeta=zeta, mode=np.ones(n, int), run_order=None,
                        response_amplitude=amplitudes,
                        control=np.full(n, "response" if test == "stepped-sine" else "force"),
                        test=np.full(n, test))


def test_chi_from_a_random_series_equals_chi_from_a_stepped_sine_series():
    """Same joint: stepped sine at amplitudes A_v, random at RMS sigma_v = A_v: the
    estimator's chi is the same (the factor c(chi) cancels in r), |kappa1| B of the
    random series is c(chi) times the sine one and ``kappa1_B_sine`` undoes it."""
    p = _joint(17)
    amps = p.phi_max * np.geomspace(2e-3, 5e-2, 8)
    sine = estimate(_series(p, amps, describing_function, "stepped-sine"), method="exact")
    rand = estimate(_series(p, amps, rayleigh_micro_slip, "random"), method="exact")
    assert rand.abscissa.startswith("response_amplitude (RMS")
    assert sine.chi == pytest.approx(p.chi, abs=2e-3)
    assert rand.chi == pytest.approx(sine.chi, abs=2e-3)
    c = rayleigh_factor(rand.chi)
    assert rand.rayleigh_factor == pytest.approx(c)
    assert rand.kappa1_B == pytest.approx(c * sine.kappa1_B, rel=5e-3)
    assert rand.kappa1_B_sine == pytest.approx(sine.kappa1_B, rel=5e-3)
    assert sine_equivalent_kappa1_B(rand.kappa1_B, rand.chi) == rand.kappa1_B_sine
    # a constant factor on the abscissa leaves chi exactly as it was
    scaled = _series(p, amps, rayleigh_micro_slip, "random")
    scaled.response_amplitude = 7.3 * scaled.response_amplitude
    assert estimate(scaled, method="exact").chi == pytest.approx(rand.chi, abs=1e-12)


def test_measured_table_keeps_the_test_and_free_decay_rows_without_excitation(tmp_path):
    n = 6
    data = MeasuredData(level=np.arange(1, n + 1), excitation=np.full(n, np.nan),
                        omega2=np.linspace(4e4, 3.9e4, n), zeta=np.linspace(0.002, 0.004, n),
                        mode=None, run_order=np.arange(n, 0, -1),
                        response_amplitude=np.geomspace(1e-5, 1e-4, n),
                        control=np.full(n, "response"), test=np.full(n, "free-decay"))
    path = tmp_path / "decay.csv"
    write_measured(path, data)
    back = read_measured(path)
    assert list(back.test) == ["free-decay"] * n
    assert np.all(np.isnan(back.excitation))
    assert back.response_abscissa
    np.testing.assert_array_equal(back.held_amplitude, data.response_amplitude)
    from feloop.update import UpdateSettings, load_levels
    # update fits free-decay rows at their response amplitude (tests/test_fe_response_update.py)
    got, mask = load_levels(UpdateSettings(data_path=str(path), mode_label=1, fit_levels="1-5"))
    assert mask.sum() == 5 and list(got.test) == ["free-decay"] * n
    text = path.read_text().replace("free-decay", "random")
    path.write_text(text)
    with pytest.raises(ValueError, match="excitation"):
        read_measured(path)                 # a random row needs its drive RMS
