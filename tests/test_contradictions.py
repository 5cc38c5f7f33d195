"""Contradictions with the Iwan model (inverse/contradictions.py), on series made from
the exact describing function of a four-parameter Iwan joint (joints.describing), with
seeded random parameters and noise the checks never see."""
from __future__ import annotations

import math

import numpy as np
import pytest

from ident.modal_data import MeasuredData
from inverse.contradictions import MIN_TIE, iwan_contradictions, noise_levels
from joints.describing import describing_function, kappa1, kappa2_exact
from joints.iwan import IwanParameters


def iwan_series(rng, n=10, extra_zeta=0.0, extra_omega2=0.0, top=0.8, response=False):
    """One mode on one Iwan joint: omega^2 = k0 + k_in(A), Delta c = k_q(A) (unit modal
    mass, paper eq. 30-31), zeta from eq. 45 with its factor 2; A doubling per level up
    to ``top`` phi_max; plus optional extra terms growing like (A/A_top)^2."""
    chi = rng.uniform(-0.8, -0.1)
    p = IwanParameters(chi=chi, K_T=rng.uniform(2e4, 1e5), F_S=rng.uniform(50, 500),
                       beta=rng.uniform(0.5, 5))
    A = top * p.phi_max * 2.0 ** np.arange(1 - n, 1)
    k_in, k_q = describing_function(p, A)
    k0 = rng.uniform(5e5, 2e6)
    s = (A / A[-1]) ** 2
    omega2 = k0 + k_in + extra_omega2 * k0 * s
    c_n = 2 * rng.uniform(0.002, 0.01) * math.sqrt(k0 + p.K_T)
    zeta = c_n / (2 * np.sqrt(omega2)) + k_q / (2 * omega2) + extra_zeta * s
    sw, sz = 1e-6 * omega2, 1e-6 * np.ones(n)
    omega2 = omega2 + sw * rng.standard_normal(n)
    zeta = zeta + sz * rng.standard_normal(n)
    return chi, MeasuredData(
        level=np.arange(1, n + 1), excitation=A / A[0], omega2=omega2, zeta=zeta, mode=None,
        run_order=None, response_amplitude=A if response else None,
        omega2_std=sw, zeta_std=sz, control=np.full(n, "response" if response else "force"))


def test_least_tie_is_the_chi_to_zero_limit_of_the_exact_kappas():
    chis = np.linspace(-0.99, -1e-4, 400)
    ratio = np.array([kappa2_exact(1.0, c) / abs(kappa1(1.0, c)) for c in chis])
    assert np.all(np.diff(ratio) < 0)                       # falls with chi
    assert ratio.min() > MIN_TIE and ratio[-1] == pytest.approx(MIN_TIE, rel=1e-3)


@pytest.mark.parametrize("seed", range(8))
def test_micro_slip_iwan_series_contradict_nothing(seed):
    chi, d = iwan_series(np.random.default_rng(seed))
    assert iwan_contradictions(d, chi=chi) == []


@pytest.mark.parametrize("seed", range(4))
def test_extra_damping_breaks_the_micro_slip_tie(seed):
    rng = np.random.default_rng(100 + seed)
    chi, d = iwan_series(rng, extra_zeta=rng.uniform(0.01, 0.03))
    kinds = [c.kind for c in iwan_contradictions(d)]
    assert kinds == ["tie-violated"]
    c = iwan_contradictions(d)[0]
    # the numbers: the least loss is 3 pi/4 x the damping growth, the loss is the data's
    assert c.numbers["least_loss_micro_slip"] == pytest.approx(
        MIN_TIE * c.numbers["joint_damping_growth"])
    assert c.numbers["omega2_loss"] == pytest.approx(d.omega2[0] - d.omega2[-1])


def test_a_damping_growth_that_would_need_more_than_all_of_omega2_is_stated_not_a_crash():
    """zeta 20 % -> 45 % (a percent column read as fractions): the least loss 3 pi/4 x the
    joint damping growth exceeds omega^2 itself, which has no frequency drop to print."""
    n = 4
    omega2 = np.array([1e6, 0.99e6, 0.98e6, 0.97e6])
    d = MeasuredData(level=np.arange(1, n + 1), excitation=2.0 ** np.arange(n), omega2=omega2,
                     zeta=np.array([0.20, 0.25, 0.32, 0.45]), mode=None, run_order=None,
                     response_amplitude=None, omega2_std=1e-4 * omega2,
                     zeta_std=np.full(n, 1e-3), control=np.full(n, "force"))
    (c,) = [c for c in iwan_contradictions(d) if c.kind == "tie-violated"]
    growth = 2 * (0.97e6 * 0.45 - 1e6 * 0.20)
    assert c.numbers["least_loss_micro_slip"] == pytest.approx(MIN_TIE * growth)
    assert c.numbers["least_loss_micro_slip"] > omega2[0]
    assert "more than the whole omega^2" in c.statement and "(1.51 %)" in c.statement


def test_response_controlled_rise_with_fourfold_damping_is_stated_with_both_numbers():
    """Issue 14: frequency +0.3 % while damping grows 4x, response-controlled."""
    rng = np.random.default_rng(7)
    n = 8
    A = 1e-5 * 2.0 ** np.arange(n)
    f = 80.0 * (1 + 0.003 * (np.arange(n) / (n - 1)) ** 2)
    zeta = 0.005 * (1 + 3 * (np.arange(n) / (n - 1)) ** 1.5)
    omega2 = (2 * np.pi * f) ** 2 * (1 + 2e-7 * rng.standard_normal(n))
    d = MeasuredData(level=np.arange(1, n + 1), excitation=np.full(n, 1.0), omega2=omega2,
                     zeta=zeta, mode=None, run_order=None, response_amplitude=A,
                     control=np.full(n, "response"))
    found = iwan_contradictions(d)
    rise = [c for c in found if c.kind == "frequency-rises"]
    assert rise, found
    text = rise[0].statement
    assert "+0.3 %" in text and "4x" in text, text
    assert noise_levels(d).source == "scatter"


def test_chi_outside_the_iwan_range():
    chi, d = iwan_series(np.random.default_rng(3))
    assert [c.kind for c in iwan_contradictions(d, chi=0.69)] == ["chi-out-of-range"]
    assert "0.69" in iwan_contradictions(d, chi=0.69)[0].statement


@pytest.mark.parametrize("dof", [1.0, 2.0, 5.0, 20.0])
def test_threshold_with_an_estimated_noise_keeps_the_known_noise_tail(dof):
    """A contradiction stated at 3 sd with known noise keeps its false-alarm tail when
    the noise sd is estimated on ``dof`` degrees of freedom: Student's t quantile."""
    from scipy import stats

    from inverse.contradictions import Z_STATE, threshold
    assert threshold(math.inf) == Z_STATE
    assert stats.t.sf(threshold(dof), dof) == pytest.approx(stats.norm.sf(Z_STATE), rel=1e-9)
    # Monte Carlo of the ratio (planted normal / sd estimated on dof): same tail
    rng = np.random.default_rng(int(10 * dof))
    z = rng.standard_normal(400_000) / np.sqrt(rng.chisquare(dof, 400_000) / dof)
    rate = np.mean(z > threshold(dof))
    assert abs(rate - stats.norm.sf(Z_STATE)) < 5 * math.sqrt(stats.norm.sf(Z_STATE) / 4e5)


def test_a_rise_of_six_sd_is_stated_with_known_noise_not_with_a_two_dof_estimate():
    from inverse.contradictions import NoiseLevels
    n = 6
    w = np.full(n, 1e6)
    w[-1] += 6.0 * math.sqrt(2.0)           # +6 sd of the difference of two levels
    z = np.linspace(0.01, 0.02, n)
    d = MeasuredData(level=np.arange(1, n + 1), excitation=np.arange(1.0, n + 1), omega2=w,
                     zeta=z, mode=None, run_order=None, control=np.full(n, "force"))
    sd_w, sd_z = np.ones(n), np.full(n, 1e-5)
    known = NoiseLevels(sd_w, sd_z, "identification")
    two = NoiseLevels(sd_w, sd_z, "scatter about a smooth curve", 2.0, 2.0)
    many = NoiseLevels(sd_w, sd_z, "repeats", 200.0, 200.0)

    def kinds(s):
        return [c.kind for c in iwan_contradictions(d, None, s)]

    assert "frequency-rises" in kinds(known) and "frequency-rises" in kinds(many)
    assert "frequency-rises" not in kinds(two)


def test_estimate_and_diagnose_state_a_contradiction_against_the_same_noise():
    """The paper's double-beam table (no std columns, no repeats): both commands judge the
    tie against the judge's repeatability from the smooth curve (and its dof), so they
    give one z-score, not 32.6 "known noise" sd in one and 23.3 sd on 5 dof in the other."""
    from cases.paper_data import DATA_FILE
    from ident.measured import read_measured
    from inverse.diagnose import diagnose
    from inverse.estimate import estimate

    data = read_measured(DATA_FILE)
    by_diagnose = {c["kind"]: c for c in diagnose(data)["contradiction_details"]}
    by_estimate = {c["kind"]: c for c in estimate(data, method="exact").contradiction_details}
    tie_d, tie_e = by_diagnose["tie-violated"], by_estimate["tie-violated"]
    assert tie_e["z_score"] == pytest.approx(tie_d["z_score"], rel=1e-12)
    assert tie_e["least_loss_micro_slip"] == pytest.approx(MIN_TIE * tie_e["joint_damping_growth"])
    assert 5 < tie_e["z_score"] < 30
