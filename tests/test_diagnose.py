"""Model-form diagnosis: physics tie, shapes past phi_max, hidden causes found, CLI."""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import integrate

from cli.main import main
from inverse.diagnose import CANDIDATES, diagnose
from inverse.diagnosis_models import slip_shapes, tie_ratio
from ident.measured import write_measured
from cases.synthetic import generate_case
from joints.describing import describing_function
from joints.iwan import IwanParameters, steady_loop

CHIS = [-0.9, -0.75, -0.5, -0.37366, -0.2, -0.05]


# --------------------------------------------------------------------------- physics


def test_tie_ratio_is_four_at_minus_one_half():
    # B(2, 1/2) = 4/3, (chi+2)/(chi+1) = 3 -> K2/K1 = 4 (hand calculation)
    assert tie_ratio(-0.5) == pytest.approx(4.0, rel=1e-14)


@pytest.mark.parametrize("chi", CHIS)
def test_tie_ratio_against_describing_function(chi):
    # K2/K1 = (K_T - k_in)/k_q of the exact describing function, at any micro-slip A
    p = IwanParameters.from_density(R=3e5, chi=chi, phi_max=2e-4, S=50.0)
    A = np.array([0.05, 0.3, 0.9]) * p.phi_max
    k_in, k_q = describing_function(p, A)
    np.testing.assert_allclose((p.K_T - k_in) / k_q, tie_ratio(chi), rtol=1e-10)


@pytest.mark.parametrize("chi", [-0.75, -0.37366, -0.2])
def test_tie_ratio_against_fourier_series_of_the_loop(chi):
    # second method: first Fourier coefficients of the steady Masing loop, integrated
    # numerically (no closed form involved)
    p = IwanParameters.from_density(R=3e5, chi=chi, phi_max=2e-4, S=50.0)
    A = 0.6 * p.phi_max
    theta, u, F = steady_loop(p, A, 200001)
    k_in = integrate.trapezoid(F * np.sin(theta), theta) / (np.pi * A)
    k_q = integrate.trapezoid(F * np.cos(theta), theta) / (np.pi * A)
    assert (p.K_T - k_in) / k_q == pytest.approx(tie_ratio(chi), rel=1e-6)


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


# --------------------------------------------------------------------------- hidden causes


@pytest.mark.parametrize("seed", [1000, 1001])
@pytest.mark.parametrize("cause", CANDIDATES)
def test_hidden_cause_is_found_with_gain(cause, seed):
    case = generate_case(cause, seed)
    r = diagnose(case.data)
    assert r["cause"] == cause, (r["cause"], case.truth["effect_sigma"])
    assert r["gain"] > 1.0
    assert r["extended_error"] < r["base_error"]
    assert r["evidence"][cause]["delta_aicc"] > r["aicc_threshold"]
    # chi of the extended model close to the hidden one
    assert abs(r["parameters"]["chi"] - case.truth["chi"]) < 0.06


@pytest.mark.parametrize("seed", [1000, 1001, 1002])
def test_none_cases_come_back_none(seed):
    case = generate_case("none", seed)
    r = diagnose(case.data)
    assert r["cause"] == "none"
    assert r["gain"] == 1.0
    assert r["parameters"]["model"] == "base"
    assert abs(r["parameters"]["chi"] - case.truth["chi"]) < 0.03
    # the base model's zeta_0 and omega2_0 are the structure's small-amplitude values
    assert r["parameters"]["zeta_0"] == pytest.approx(case.truth["zeta0"], abs=5e-5)
    assert r["parameters"]["omega2_0"] == pytest.approx(case.truth["omega0"] ** 2, rel=3e-5)


def test_macro_slip_parameters_near_truth():
    case = generate_case("macro-slip", 1000)
    r = diagnose(case.data)
    assert r["cause"] == "macro-slip"
    x_true = case.truth["slip_over_phi_max"][-1]
    assert x_true > 1.0
    assert r["parameters"]["x_top"] == pytest.approx(x_true, rel=0.15)


def test_quadratic_damping_size_near_truth():
    # extra zeta at the top level: 8 c2 W X / (3 pi) / (2 omega0), from the hidden c2
    case = generate_case("quadratic-damping", 1001)
    t = case.truth
    X = t["slip_amplitude"][-1]
    true_top = 8 * t["c2"] * t["omega0"] * X / (3 * np.pi) / (2 * t["omega0"])
    r = diagnose(case.data)
    assert r["parameters"]["q_top"] == pytest.approx(true_top, rel=0.3)


def test_nonproportional_needs_the_response_column():
    case = generate_case("nonproportional-amplitude", 1000)
    data = case.data
    data.response_amplitude = None
    r = diagnose(data)
    assert r["evidence"]["nonproportional-amplitude"]["available"] is False
    assert r["cause"] != "nonproportional-amplitude"
    assert any("response_amplitude" in w for w in r["data_warnings"])


def test_choice_does_not_depend_on_row_order():
    case = generate_case("thermal-drift", 1001)
    r1 = diagnose(case.data)
    perm = np.random.default_rng(3).permutation(len(case.data))
    r2 = diagnose(case.data.take(perm))
    assert r1["cause"] == r2["cause"] == "thermal-drift"
    assert r2["gain"] == pytest.approx(r1["gain"], rel=1e-6)
    assert r2["parameters"]["d"] == pytest.approx(r1["parameters"]["d"], rel=1e-6)


def test_drift_estimate_near_truth():
    case = generate_case("thermal-drift", 1000)
    t = case.truth
    r = diagnose(case.data)
    # hidden drift of the identified omega2 per run: drift_per_run * omega2_lin
    true_d = t["drift_per_run"] * (t["omega0"] ** 2 - t["K_T"])
    assert r["parameters"]["d"] == pytest.approx(true_d, rel=0.25)


# --------------------------------------------------------------------------- CLI

SPEC_KEYS = {"cause", "parameters", "base_error", "extended_error", "gain", "evidence",
             "data_warnings"}


def test_cli_json_and_report(tmp_path, capsys):
    case = generate_case("geometric-hardening", 1000)
    path = tmp_path / "hardening.csv"
    write_measured(path, case.data)
    out = tmp_path / "report"
    rc = main(["diagnose", str(path), "--json", "--out", str(out)])
    assert rc == 0
    result = json.loads(capsys.readouterr().out)
    assert SPEC_KEYS <= set(result)
    assert result["cause"] == "geometric-hardening"
    assert "chi" in result["parameters"]
    assert result["gain"] == pytest.approx(result["base_error"] / result["extended_error"])
    assert set(CANDIDATES) == set(result["evidence"])
    for name in ("report.md", "diagnosis.json", "diagnosis_fits.png",
                 "diagnosis_evidence.png"):
        assert (out / name).stat().st_size > 500
    text = (out / "report.md").read_text()
    assert "geometric-hardening" in text and "diagnosis_fits.png" in text


def test_cli_text_output_on_shipped_paper_data(capsys):
    rc = main(["diagnose", "--case", "double-beam"])
    assert rc == 0
    text = capsys.readouterr().out
    assert text.startswith("double-beam: mode 2")
    assert "cause:" in text and "gain" in text


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
    assert main(["diagnose"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 2
