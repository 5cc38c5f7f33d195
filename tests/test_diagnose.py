"""Model-form diagnosis v2: physics of the model families, the fitting machinery
against independent solvers, the decision rules of the spec, hidden causes in
FRF-level synthetic series, the CLI."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import integrate, optimize

from synthetic import generate_series
from cli.main import main
from ident.measured import write_measured
from ident.modal_data import MeasuredData
from inverse.diagnose import ALL_CAUSES, diagnose
from inverse.diagnosis.fit import solve_nonneg
from inverse.diagnosis.causes.geometric_hardening import contact_shape
from inverse.diagnosis.causes.macro_slip import slip_shapes
from inverse.diagnosis.causes.nonproportional_amplitude import box_cox
from inverse.diagnosis.causes.thermal_drift import drift_shape, onset_shape
from inverse.diagnosis.models import MODELS
from inverse.judge import smooth_scatter
from inverse.iwan_modal import kappa_ratio, zeta_with_joint
from joints.describing import describing_function
from joints.iwan import IwanParameters

CHIS = [-0.9, -0.5, -0.2, -0.05]


# --------------------------------------------------------------------------- physics


def test_kappa_ratio_is_vectorized_and_four_at_minus_one_half():
    # B(2, 1/2) (3/2)/(1/2) = (4/3) 3 = 4 (hand calculation)
    r = kappa_ratio(np.array(CHIS + [-0.5]), "exact")
    assert r[-1] == pytest.approx(4.0, rel=1e-14)
    for chi, v in zip(CHIS, r):
        p = IwanParameters.from_density(R=3e5, chi=chi, phi_max=2e-4, S=50.0)
        k_in, k_q = describing_function(p, 0.4 * p.phi_max)
        assert v == pytest.approx((p.K_T - k_in) / k_q, rel=1e-10)
    assert r.min() > 3 * math.pi / 4


@pytest.mark.parametrize("beta", [0.0, 0.5, 4.0])
@pytest.mark.parametrize("chi", [-0.7, -0.3])
def test_slip_shapes_against_describing_function_micro_and_macro(chi, beta):
    R, phi_max = 2e5, 1e-4
    S = beta * R * phi_max ** (chi + 1) / (chi + 1)
    p = IwanParameters.from_density(R=R, chi=chi, phi_max=phi_max, S=S)
    x = np.array([0.2, 0.7, 1.0, 1.05, 1.5, 3.0, 10.0])
    k_in, k_q = describing_function(p, x * phi_max)
    P1, P2, Q1, Q2 = slip_shapes(x, chi)
    U = R * phi_max ** (chi + 1)
    np.testing.assert_allclose(U * P2 + S * Q2, p.K_T - k_in, rtol=1e-9, atol=1e-9 * p.K_T)
    np.testing.assert_allclose(U * P1 + S * Q1, k_q, rtol=1e-9)


def test_shape_families_limits():
    log_s = np.log(np.geomspace(0.01, 1.0, 7))
    # Box-Cox: kappa -> 0 is the steady shortfall gamma log s; zero at the top level
    np.testing.assert_allclose(box_cox(log_s, -0.3, 1e-12), -0.3 * log_s, rtol=1e-9)
    np.testing.assert_allclose(box_cox(log_s, -0.3, 2.0), -0.3 * (np.exp(2 * log_s) - 1) / 2)
    assert box_cox(np.array(0.0), 0.4, 1.5) == 0.0
    t = np.linspace(0, 1, 5)
    np.testing.assert_allclose(drift_shape(t, 0.0), t)
    np.testing.assert_allclose(drift_shape(t, 3.0), (1 - np.exp(-3 * t)) / (1 - np.exp(-3)))
    # a drift started at t0: the same shape from the start, 0 before t0, a step for large b
    np.testing.assert_allclose(onset_shape(t, 3.0, 0.0), drift_shape(t, 3.0))
    np.testing.assert_allclose(onset_shape(t, 3.0, 0.5)[t <= 0.5], 0.0)
    np.testing.assert_allclose(onset_shape(t, 3.0, 0.5)[-1], 1.0)
    assert np.all(onset_shape(np.array([0.6, 0.8]), 40.0, 0.5) > 0.98)
    # contact shape: the first harmonic of a spring engaging past a gap, by quadrature
    th = np.linspace(0, 2 * np.pi, 200001)
    for r in (0.2, 0.6, 0.95):
        f = np.maximum(np.abs(np.sin(th)) - r, 0) * np.sign(np.sin(th))
        assert contact_shape(r) == pytest.approx(
            integrate.trapezoid(f * np.sin(th), th) / np.pi, rel=1e-6)


def test_solve_nonneg_against_bounded_least_squares():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((30, 12, 4))
    b = rng.standard_normal((30, 12))
    x = solve_nonneg(A, b, [1, 3])
    for g in range(30):
        ref = optimize.lsq_linear(A[g], b[g], bounds=([-np.inf, 0, -np.inf, 0], np.inf),
                                  tol=1e-13).x
        np.testing.assert_allclose(x[g], ref, atol=1e-8)


def test_smooth_scatter_ignores_a_smooth_trend():
    rng = np.random.default_rng(1)
    x = np.sort(rng.uniform(-5, 0, 4000))
    noise = 0.3 * rng.standard_normal(x.size)
    s0, dof = smooth_scatter(x, noise)
    s1, _ = smooth_scatter(x, noise + 2 * x + 0.1 * np.exp(x) - 3 * np.exp(x / 3))
    assert dof == x.size - 5
    assert s0 == pytest.approx(0.3, rel=0.05) and s1 == pytest.approx(s0, rel=1e-3)
    # a power-law trend in amplitude cancels exactly on any spacing
    assert smooth_scatter(x[:9], 3 - 2 * np.exp(x[:9] * 2 / 3))[0] == pytest.approx(
        0.0, abs=1e-9)


# --------------------------------------------------------------------------- decision rules


def _table(omega2, zeta, control="force", excitation=None, response=None, run=None,
           rel_w=2e-5, rel_z=5e-3, seed=0):
    rng = np.random.default_rng(seed)
    n = len(omega2)
    w_std, z_std = rel_w * np.asarray(omega2), rel_z * np.asarray(zeta)
    return MeasuredData(
        level=np.arange(1, n + 1),
        excitation=excitation if excitation is not None else 2.0 ** np.arange(n),
        omega2=omega2 + w_std * rng.standard_normal(n),
        zeta=zeta + z_std * rng.standard_normal(n), mode=np.ones(n, int),
        run_order=run, response_amplitude=response, omega2_std=w_std, zeta_std=z_std,
        control=np.full(n, control))


def _iwan(chi, s, w2_0=(2 * np.pi * 80) ** 2, zeta0=0.005, growth=1.0):
    """Planted truth: eq. (2), (3) of inverse.diagnosis.models with K1 giving a damping
    growth ``growth`` x zeta0 at the top level."""
    K1 = 2 * w2_0 * zeta0 * growth
    om2 = w2_0 - kappa_ratio(chi, "exact") * K1 * s ** (chi + 1)
    return om2, zeta_with_joint(K1 * s ** (chi + 1), om2, 2 * zeta0 * np.sqrt(w2_0))


def test_frequency_rising_with_damping_growing_fourfold_under_response_control():
    # the series: response control, frequency +0.3 % (a hardening s^2), damping
    # 4x (an added damping growing as s): what no micro-slip Iwan joint can do
    n = 8
    s = np.geomspace(0.01, 1.0, n)
    omega2 = (2 * np.pi * 80) ** 2 * (1 + 0.006 * s**2)
    zeta = 0.005 * (1 + 3 * s)
    d = _table(omega2, zeta, control="response", response=1e-4 * s,
               excitation=np.full(n, 1.0), run=np.array([1, 3, 5, 7, 8, 6, 4, 2]))
    r = diagnose(d)
    rise = [c for c in r["contradiction_details"] if c["kind"] == "frequency-rises"]
    assert rise, r["contradictions"]
    text = next(c for c in r["contradictions"] if "rises by" in c)
    f_a, f_b = rise[0]["frequency_hz"]
    assert f"{100 * (f_b / f_a - 1):+.3g} %" in text and f"{rise[0]['zeta_growth']:.3g}x" in text
    assert f_b / f_a - 1 == pytest.approx(0.003, rel=0.1)
    assert rise[0]["zeta_growth"] == pytest.approx(4.0, rel=0.1)
    assert r["cause"] != "none"
    assert any(a["causes"] == ["none"] and a["refuted"] for a in r["alternatives"])
    assert sorted([r["cause"], *r["also"]]) == ["geometric-hardening", "quadratic-damping"]
    alts = [a for a in r["alternatives"] if not a["refuted"]]
    assert r["ambiguous"] == (alts[1]["weight"] >= alts[0]["weight"] / 3)
    assert "nonproportional-amplitude" in r["separability"]["untestable"]


def test_no_joint_base_fit_is_never_explained_within_the_noise():
    # force control: damping grows 4x while the frequency does not move at all
    n = 9
    zeta = 0.005 * 4.0 ** (np.linspace(0, 1, n) ** 2)
    d = _table(np.full(n, (2 * np.pi * 50) ** 2), zeta, run=np.array([3, 1, 5, 2, 9, 4, 7,
                                                                       6, 8]))
    r = diagnose(d)
    assert r["base_parameters"]["kappa1_B"] < 1e-3 * r["base_parameters"]["omega2_0"] * 0.015
    kinds = [c["kind"] for c in r["contradiction_details"]]
    assert "no-joint" in kinds
    assert r["cause"] != "none" and "within the noise" not in r["summary"]


def test_planted_iwan_series_is_none_with_its_chi():
    s = np.geomspace(0.01, 1.0, 10)
    om2, ze = _iwan(-0.4, s, growth=0.8)
    d = _table(om2, ze, control="response", response=s, excitation=np.ones(10),
               run=np.array([2, 4, 6, 8, 10, 9, 7, 5, 3, 1]))
    r = diagnose(d)
    assert r["cause"] == "none" and r["also"] == [] and not r["contradictions"]
    assert "within the noise" in r["summary"]
    assert r["parameters"]["chi"] == pytest.approx(-0.4, abs=0.05)
    assert r["parameters"]["zeta_0"] == pytest.approx(0.005, rel=0.02)
    assert sum(a["weight"] for a in r["alternatives"]) == pytest.approx(1.0)
    assert r["gain"] == 1.0 and r["fit_test"]["p_value"] > 1e-3


def test_five_levels_say_what_cannot_be_separated_and_nothing_is_minus_infinity():
    s = np.geomspace(0.06, 1.0, 5)
    om2, ze = _iwan(-0.5, s, growth=0.6)
    d = _table(om2, ze, control="response", response=s, excitation=np.ones(5),
               run=np.array([1, 3, 5, 4, 2]))
    r = diagnose(d)
    assert r["cause"] == "none"
    assert r["separability"]["inseparable"] or r["separability"]["untestable"]
    assert "cannot separate" in r["summary"] or r["separability"]["untestable"]
    text = json.dumps(r, default=str)
    assert "Infinity" not in text and "-inf" not in text
    for name, e in r["evidence"].items():   # every candidate: a number or a reason
        assert e.get("delta_aic") is not None or e.get("reason"), name


def test_unavailable_candidates_carry_a_reason():
    s = np.geomspace(0.02, 1.0, 8)
    om2, ze = _iwan(-0.3, s)
    r = diagnose(_table(om2, ze))              # force control, no response, ascending
    ev = r["evidence"]
    assert ev["nonproportional-amplitude"]["available"] is False
    assert "response_amplitude" in ev["nonproportional-amplitude"]["reason"]
    assert ev["thermal-drift"]["available"] is False
    assert "order of amplitude" in ev["thermal-drift"]["reason"]
    assert len(ev) == len(MODELS)


def test_choice_does_not_depend_on_row_order():
    s = np.geomspace(0.02, 1.0, 10)
    om2, ze = _iwan(-0.6, s)
    run = np.array([5, 1, 9, 7, 3, 10, 8, 2, 6, 4])
    # 10 levels (issue 19: the noise is no longer the residual scatter of the best
    # candidate; 10 levels let the model-free curve follow amplitude and run order)
    data = _table(om2 + 40.0 * (run - 1), ze, control="response", response=s,
                  excitation=np.ones(10), run=run)
    r1 = diagnose(data)
    perm = np.random.default_rng(3).permutation(10)
    r2 = diagnose(data.take(perm))
    assert r1["cause"] == "thermal-drift"
    assert r1["parameters"]["d"] == pytest.approx(40.0, rel=0.1)
    assert r1["cause"] == r2["cause"] and r1["parameters"]["model"] == r2["parameters"]["model"]
    num = {k: v for k, v in r1["parameters"].items() if k != "model"}
    assert {k: r2["parameters"][k] for k in num} == pytest.approx(num, rel=1e-6)


def test_a_temperature_step_in_a_shuffled_run_is_thermal_drift():
    """A step in omega2 (drawn: 25-60 noise sd, at a drawn run of a shuffled 10-level
    response-controlled test; the diagnosis sees neither): ``thermal-drift``, its onset
    within one run of the step and its size within 20 %. (Before session 8 every drift
    started with the test; on this series the steepest of them was named too, but on
    the own generator's series 80071017 that misfit made the verdict ``unexplained``.)"""
    rng = np.random.default_rng(83)
    s = np.geomspace(0.02, 1.0, 10)
    om2, ze = _iwan(-0.6, s)
    run = rng.permutation(10) + 1
    step_run = int(rng.integers(4, 8))                  # the step comes before this run
    size = rng.uniform(25, 60) * 2e-5 * om2[0]
    data = _table(om2 - size * (run >= step_run), ze, control="response", response=s,
                  excitation=np.ones(10), run=run, seed=5)
    r = diagnose(data)
    assert r["cause"] == "thermal-drift", r["summary"]
    t_step = (step_run - 1.5) / 9                       # between the two runs, scaled
    assert abs(r["parameters"]["t_onset"] - t_step) < 1 / 9 + 1e-9
    assert r["parameters"]["d_total"] == pytest.approx(-size, rel=0.2)


def test_four_levels_too_few_for_a_gain_are_judged_by_fit_test_and_ic():
    """Four levels, no repeat, force control, run in order of amplitude: a hardening
    (drawn: +1-3 % in omega2 at the top, as ``s^p`` with a drawn ``p`` of 1.5-3, on an
    Iwan joint with little damping growth; the diagnosis sees neither) lifts the
    frequency, which only ``geometric-hardening`` of the testable causes can do. No
    candidate can leave a level out (as many parameters as data without one): before
    session 18 that made every cause ineligible (``none`` or ``unexplained``), although
    the hardening brings the data within their noise. It is named now on its fit test
    and IC alone, with its gain ``n/a`` and the reason. Six draws: the model-free curve
    of 4 levels has 1 dof and can take such a rise for noise (then ``none``), so at
    least 4 of 6, and never another cause. Self-consistent by design: the base is the
    judge's own Iwan form and ``s^p`` lies in the catalogue's hardening family, so this
    tests the rule, not power on foreign forms (that is the paired run of
    docs/judge.md, session 18, on the independent generator's series)."""
    rng = np.random.default_rng(1804)
    s = np.geomspace(0.05, 1.0, 4)
    named = 0
    for _ in range(6):
        om2, ze = _iwan(-0.5, s, growth=0.1)
        rise, p = rng.uniform(1e-2, 3e-2), rng.uniform(1.5, 3.0)
        r = diagnose(_table(om2 + rise * om2[0] * s**p, ze,
                            seed=int(rng.integers(1 << 30))))
        assert r["cause"] in ("geometric-hardening", "none") and not r["also"], r["summary"]
        if r["cause"] == "none":
            continue
        named += 1
        alt = next(a for a in r["alternatives"] if a["causes"] == ["geometric-hardening"])
        assert alt["gain"] is None and "without one level" in alt["gain_untestable"]
        assert r["gain"] is None and r["fit_test"]["p_value"] >= 1e-3
        assert "cannot be tested on unseen levels" in r["summary"]
        # the base model's gain is measured (1 by definition) and never untestable
        assert all(a["gain_untestable"] is None for a in r["alternatives"]
                   if a["gain"] is not None)
    assert named >= 4


# Hidden causes in FRF-level series from the independent generator
# (synthetic) are scored by benchmarks/bench_diagnose.py on fresh seeds,
# with the rates it prints, not by seed-picked cases here.


# --------------------------------------------------------------------------- CLI

SPEC_KEYS = {"cause", "also", "alternatives", "ambiguous", "contradictions", "parameters",
             "base_error", "extended_error", "gain", "gain_held_out", "evidence",
             "data_warnings"}


def test_cli_json_and_report(tmp_path, capsys):
    s = generate_series("geometric-hardening", 2024, n_levels=10, repeats=0)
    path = tmp_path / "hardening.csv"
    write_measured(path, s.data)
    out = tmp_path / "report"
    assert main(["diagnose", str(path), "--json", "--out", str(out)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert SPEC_KEYS <= set(r) and r["cause"] in ALL_CAUSES
    assert "chi" in r["parameters"]
    assert r["gain"] == pytest.approx(r["base_error"] / r["extended_error"])
    assert sum(a["weight"] for a in r["alternatives"]) == pytest.approx(1.0)
    assert all(isinstance(c, str) for c in r["contradictions"])
    for name in ("report.md", "diagnosis.json", "diagnosis_fits.png",
                 "diagnosis_evidence.png"):
        assert (out / name).stat().st_size > 500
    text = (out / "report.md").read_text()
    assert r["cause"] in text and "diagnosis_fits.png" in text


def test_cli_text_output_on_shipped_paper_data(capsys):
    assert main(["diagnose", "--case", "double-beam"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("double-beam: mode 2 (force control, 10 levels)")
    assert "cause:" in text and "gain" in text and "contradictions" in text
    # issue 19: the noise is named, and the tie contradiction still stated with numbers
    assert "noise (identification + repeatability): omega2" in text
    assert "scatter about a smooth curve" in text
    assert "3 pi/4 x that" in text and "3.46x less" in text


def test_shipped_paper_data_json_names_noise_bounds_and_failures():
    from cases.registry import MEASURED_DATA
    from ident.measured import read_measured

    r = diagnose(read_measured(MEASURED_DATA["double-beam"]))
    tie = [c for c in r["contradiction_details"] if c["kind"] == "tie-violated"]
    assert len(tie) == 1 and tie[0]["levels"] == [1, 10]
    assert r["noise"]["omega2"]["dof"] == 5 and r["noise"]["zeta"]["identification_rel"] == 0
    assert r["verdict_identification_only"] is None      # the table has no std columns
    assert r["failures"]["total"] == 0
    bounds = r["parameter_bounds"]
    assert "chi" in bounds and all("at_bound" in b for b in bounds.values())
    for name in r["at_bound"]:
        assert name in r["summary"]
        if bounds[name]["interval"] is not None:
            assert bounds[name]["interval_kind"].startswith("profile")
    top = [p["level"] for p in r["held_out_predictions"]["levels"]]
    assert top == [8, 9, 10]
    worse = r["cause"] not in ("none", "unexplained") and (r["gain_held_out"] or 2.0) < 1
    assert ("Fitted without the top" in r["summary"]) == worse


def test_a_named_model_that_extrapolates_worse_than_the_base_says_so():
    """The summary warns when the named model, fitted without the top levels, predicts
    them worse than the base model (a gen_dev case named a pair at a top-level gain of
    0.005 while its leave-one-out gain was 1.95)."""
    from inverse.diagnosis.text import extrapolation_note

    note = extrapolation_note("geometric-hardening+macro-slip", 0.00507, 4)
    assert "top 4 levels" in note and "0.00507" in note and "geometric-hardening" in note
    for cause, gain in (("macro-slip", 1.2), ("macro-slip", None), ("none", 0.3),
                        ("unexplained", 0.3)):
        assert extrapolation_note(cause, gain, 3) == ""


@pytest.mark.parametrize("content, needle", [
    ("level,excitation,omega2\n1,1,1\n", "zeta"),
    ("level,excitation,omega2,zeta\n1,1,1e6,0.01\n2,2,1e6,0.01\n", "levels"),
])
def test_cli_bad_file_is_one_line_exit_2(tmp_path, capsys, content, needle):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    assert main(["diagnose", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("iwanfe: error:")
    assert needle in err


def test_cli_bad_case_is_one_line_exit_2(capsys):
    assert main(["diagnose", "--case", "synthetic:gremlins:1"]) == 2
    assert main(["diagnose", "--case", "synthetic:none:x"]) == 2
    assert main(["diagnose"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "label" in err and "seed" in err
