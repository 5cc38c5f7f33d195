"""FE-level check of the double beam (cases/fe_check.py)."""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cli.main import main
from cases.double_beam.model import (
    CALIBRATED_CLAMP_LENGTH,
    MEASURED_FREQUENCY_HZ,
    DoubleBeamConfig,
    bending_mode_frequency,
    build_double_beam,
)
from cases.double_beam.fe_check import (
    MEASURED_OMEGA2,
    double_beam_fe_check,
    format_fe_check_md,
    log_sensitivity,
)

UNCAL = DoubleBeamConfig(clamp_length=0.0)
DATA = str(Path(__file__).resolve().parent.parent / "cases" / "data" / "double_beam_measured.csv")


@pytest.fixture(scope="module")
def check():
    return double_beam_fe_check()


def test_gap_of_the_uncalibrated_model(check):
    assert check["measured_hz"] == pytest.approx(np.sqrt(MEASURED_OMEGA2) / (2 * np.pi))
    f4 = bending_mode_frequency(build_double_beam(UNCAL), 4)
    assert check["simulated_hz"] == pytest.approx(f4, rel=1e-9)
    assert check["simulated_hz"] == pytest.approx(227.1, abs=0.05)
    assert check["gap_relative"] == pytest.approx(-0.099, abs=0.001)


def test_E_sensitivity_is_one_half_without_glue():
    # all stiffness proportional to E when K_T = 0: f ~ sqrt(E) exactly
    cfg = replace(UNCAL, glue_tangential_stiffness=0.0)
    assert log_sensitivity(cfg, "E") == pytest.approx(0.5, abs=1e-3)


def test_rho_sensitivity_is_minus_one_half_without_attachments():
    cfg = replace(UNCAL, exciter_mass=0.0, sensor_mass=0.0)
    assert log_sensitivity(cfg, "rho") == pytest.approx(-0.5, abs=1e-3)


def test_homogeneity_identities(check):
    c = check["candidates"]
    # stiffness: E scales all but K_T; mass: rho scales all but the attachments
    assert c["E"]["log_sensitivity"] + c["glue"]["log_sensitivity"] == pytest.approx(0.5, abs=1e-4)
    assert c["rho"]["log_sensitivity"] + c["mass"]["log_sensitivity"] == pytest.approx(-0.5, abs=1e-4)
    # glue participation of the measured mode: 2 S_KT is its glue-slip participation
    assert 0 < c["glue"]["log_sensitivity"] < 0.01


def test_mass_sensitivity_negative_and_mass_cannot_close_the_gap(check):
    m = check["candidates"]["mass"]
    assert m["log_sensitivity"] < 0
    assert not m["reachable"] and m["required_value"] is None
    assert m["best_frequency_hz"] < MEASURED_FREQUENCY_HZ  # no attachments at all


def test_rigid_glue_cannot_close_the_gap(check):
    g = check["candidates"]["glue"]
    assert not g["reachable"] and not g["plausible"]
    assert g["best_frequency_hz"] < MEASURED_FREQUENCY_HZ
    assert g["best_frequency_hz"] == pytest.approx(227.54, abs=0.05)
    assert "glue" not in check["reachable"]


def test_grip_solution_is_the_calibrated_clamp_length(check):
    c = check["candidates"]["clamp"]
    assert c["reachable"] and c["plausible"]
    assert c["required_value"] == pytest.approx(CALIBRATED_CLAMP_LENGTH, rel=1e-3)
    assert c["log_sensitivity"] == pytest.approx(-1.9, abs=0.1)  # ~ 1/L^2, less the masses
    # exactly at 252.0 Hz it is the shipped calibration
    exact = double_beam_fe_check((2 * np.pi * MEASURED_FREQUENCY_HZ) ** 2)
    assert exact["candidates"]["clamp"]["required_value"] == pytest.approx(
        CALIBRATED_CLAMP_LENGTH, rel=1e-5)


def test_material_fixes_are_reachable_but_implausible(check):
    c = check["candidates"]
    assert c["E"]["reachable"] and not c["E"]["plausible"]
    assert c["E"]["required_value"] == pytest.approx(86e9, rel=0.01)
    assert c["rho"]["reachable"] and not c["rho"]["plausible"]
    assert c["rho"]["required_value"] < c["rho"]["plausible_range"][0]


def test_every_fix_puts_the_measured_mode_on_the_measurement(check):
    for name in check["reachable"]:
        fr = check["candidates"][name]["predicted_modes_hz"]
        assert fr["4"] == pytest.approx(check["measured_hz"], rel=1e-6), name
        # and raises the other modes too (all are near-uniform scalings)
        for k in ("2", "3", "5"):
            assert fr[k] > check["uncalibrated_modes_hz"][k]


def test_discrimination_and_statement(check):
    assert set(check["reachable"]) == {"clamp", "E", "rho", "thickness"}
    assert check["plausible_fixes"] == ["clamp"]
    d = check["discrimination"]
    assert set(d) == {"2", "3", "5"}
    for k, v in d.items():
        spread = max(v["by_candidate_hz"].values()) - min(v["by_candidate_hz"].values())
        assert v["spread_hz"] == pytest.approx(spread)
        assert 0 < v["spread_relative"] < 0.01
    s = check["statement"]
    assert "no evidence between them" in s and "E/rho" in s
    assert "## FE-level check" in format_fe_check_md(check)


def test_cli_double_beam_json_holds_fe_check(capsys):
    assert main(["diagnose", "--case", "double-beam", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    fe = r["fe_check"]
    assert fe["measured_bending_order"] == 4
    assert fe["candidates"]["glue"]["reachable"] is False
    assert fe["candidates"]["clamp"]["required_value"] == pytest.approx(
        CALIBRATED_CLAMP_LENGTH, rel=1e-3)
    # FILE with the model case: the file's data, the case's FE check (the form)
    assert main(["diagnose", DATA, "--case", "double-beam", "--json"]) == 0
    r2 = json.loads(capsys.readouterr().out)
    assert r2["cause"] == r["cause"] and "fe_check" in r2
    # FILE with a synthetic case makes no sense: one-line error, exit 2
    assert main(["diagnose", DATA, "--case", "synthetic:none:1"]) == 2
    capsys.readouterr()


def test_cli_report_has_fe_section(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["diagnose", "--case", "double-beam", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "FE check" in text and "cannot reach" in text
    md = (out / "report.md").read_text()
    assert "FE-level check" in md and "no evidence between them" in md
    assert "fe_check" in json.loads((out / "diagnosis.json").read_text())


def test_file_input_has_no_fe_check(tmp_path, capsys):
    assert main(["diagnose", DATA, "--json"]) == 0
    assert "fe_check" not in json.loads(capsys.readouterr().out)
