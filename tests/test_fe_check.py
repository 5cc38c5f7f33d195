"""FE-level check of the double beam (cases/double_beam/fe_check.py).

Truths: a second eigen-solution of every rebuilt model (finer mesh, ARPACK instead of the
dense solver), exact scaling laws of the beam (f ~ sqrt(E/rho) h / L^2), the Rayleigh
quotient's sensitivities, rigid glue as an exact constraint, and the measured frequency.
"""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as la

from cli.main import main
from cases.double_beam.calibration import calibrate_clamp_length
from cases.double_beam.model import (
    CALIBRATED_CLAMP_LENGTH,
    MEASURED_FREQUENCY_HZ,
    DoubleBeamConfig,
    build_double_beam,
)
from fe.modal import normal_modes
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


def independent_bending_hz(config, orders=(2, 3, 4, 5)):
    """Second method for the in-phase bending frequencies (Hz) of ``config``: the free
    length meshed twice as finely and ARPACK shift-invert (``dense_below=0``) instead of
    the dense eigen-solver of the check (they agree to ~1e-6 relative up to mode 5)."""
    model = build_double_beam(replace(config, element_size=0.5 * config.element_size))
    omega, shapes = normal_modes(model.K, model.M, 14, dense_below=0)
    order = model.bending_order(omega, shapes)
    return {k: float(omega[np.flatnonzero(order == k)[0]] / (2 * np.pi)) for k in orders}


def test_gap_of_the_uncalibrated_model(check):
    assert check["measured_hz"] == pytest.approx(np.sqrt(MEASURED_OMEGA2) / (2 * np.pi))
    f4 = independent_bending_hz(UNCAL, (4,))[4]
    assert check["simulated_hz"] == pytest.approx(f4, rel=2e-6)
    assert check["gap_relative"] == pytest.approx(f4 / check["measured_hz"] - 1, abs=2e-6)
    assert check["gap_relative"] < 0          # the uncalibrated model is too soft


def test_E_sensitivity_is_one_half_without_glue():
    # all stiffness proportional to E when K_T = 0: f ~ sqrt(E) exactly
    cfg = replace(UNCAL, glue_tangential_stiffness=0.0)
    assert log_sensitivity(cfg, "E") == pytest.approx(0.5, abs=1e-3)


def test_rho_sensitivity_is_minus_one_half_without_attachments():
    cfg = replace(UNCAL, exciter_mass=0.0, sensor_mass=0.0)
    assert log_sensitivity(cfg, "rho") == pytest.approx(-0.5, abs=1e-3)


def test_thickness_and_free_length_sensitivities_of_the_bare_pair():
    """No glue, no attachments: the in-phase pair bends as one strip, f = (beta L)^2 /
    (2 pi) sqrt(E I / (rho A L^4)) ~ h / L^2 exactly (the normal springs are unloaded)."""
    bare = replace(UNCAL, glue_tangential_stiffness=0.0, exciter_mass=0.0, sensor_mass=0.0)
    assert log_sensitivity(bare, "thickness") == pytest.approx(1.0, abs=1e-5)
    assert log_sensitivity(bare, "clamp") == pytest.approx(-2.0, abs=1e-5)


def test_homogeneity_identities_and_rayleigh_sensitivities(check):
    c = check["candidates"]
    # stiffness: E scales all but K_T; mass: rho scales all but the attachments
    assert c["E"]["log_sensitivity"] + c["glue"]["log_sensitivity"] == pytest.approx(0.5, abs=1e-4)
    assert (c["rho"]["log_sensitivity"] + c["mass"]["log_sensitivity"]
            == pytest.approx(-0.5, abs=1e-4))
    # Rayleigh quotient of the mode itself (no finite difference): d ln f / d ln K_T is
    # half the glue-slip participation, d ln f / d ln a (attachment masses scaled by a)
    # is -1/2 phi^T M_att phi / phi^T M phi
    model = build_double_beam(UNCAL)
    omega, shapes = model.modes(12)
    phi = shapes[:, np.flatnonzero(model.bending_order(omega, shapes) == 4)[0]]
    s_glue = 0.5 * model.glue_slip_participation(phi)
    assert c["glue"]["log_sensitivity"] == pytest.approx(s_glue, rel=1e-3)
    M_att = model.M - build_double_beam(replace(UNCAL, exciter_mass=0.0, sensor_mass=0.0)).M
    s_mass = -0.5 * (phi @ (M_att @ phi)) / (phi @ (model.M @ phi))
    assert c["mass"]["log_sensitivity"] == pytest.approx(s_mass, rel=1e-3)


def test_mass_sensitivity_negative_and_mass_cannot_close_the_gap(check):
    m = check["candidates"]["mass"]
    assert m["log_sensitivity"] < 0
    assert not m["reachable"] and m["required_value"] is None
    # no attachments at all is the upper bound: checked by the second method
    bare = independent_bending_hz(replace(UNCAL, exciter_mass=0.0, sensor_mass=0.0), (4,))[4]
    assert m["best_frequency_hz"] == pytest.approx(bare, rel=2e-6)
    assert bare < MEASURED_FREQUENCY_HZ


def test_rigid_glue_cannot_close_the_gap(check):
    """Rigid glue as an exact constraint (slip = 0 by a null-space basis of the slip rows,
    dense eigen-solve) instead of the check's 1e12 N/m penalty: the mode it reaches is
    that limit and stays below the measurement."""
    g = check["candidates"]["glue"]
    assert not g["reachable"] and not g["plausible"]
    assert "glue" not in check["reachable"]
    model = build_double_beam(UNCAL)
    Z = la.null_space(model.slip_matrix.toarray())
    K = Z.T @ (model.K_without_joints @ Z)
    M = Z.T @ (model.M @ Z)
    f = np.sqrt(la.eigh(K, M, eigvals_only=True, subset_by_index=[0, 9])) / (2 * np.pi)
    limit = f[np.argmin(np.abs(f - g["best_frequency_hz"]))]
    assert g["best_frequency_hz"] == pytest.approx(limit, rel=2e-6)
    assert limit < MEASURED_FREQUENCY_HZ
    assert np.sum((f > 0.9 * limit) & (f < 1.1 * limit)) == 1   # no other mode near it


def test_grip_solution_puts_the_mode_on_the_measurement(check):
    c = check["candidates"]["clamp"]
    assert c["reachable"] and c["plausible"]
    # the second method at the required grip and at the shipped calibration
    f4 = independent_bending_hz(replace(UNCAL, clamp_length=c["required_value"]), (4,))[4]
    assert f4 == pytest.approx(check["measured_hz"], rel=2e-6)
    assert independent_bending_hz(DoubleBeamConfig(), (4,))[4] == pytest.approx(
        MEASURED_FREQUENCY_HZ, rel=2e-6)
    # the free-length sensitivity by a central difference of the second method (another
    # step): ~ -2 (1/L^2), less the attachments' share
    L0, h = UNCAL.free_length, 0.01
    lo, hi = (independent_bending_hz(replace(UNCAL, length=L0 * np.exp(t)), (4,))[4]
              for t in (-h, h))
    assert c["log_sensitivity"] == pytest.approx(np.log(hi / lo) / (2 * h), abs=2e-3)


def test_clamp_calibration_reaches_its_target():
    """calibrate_clamp_length (Brent on the grip) for a target of its own, checked by the
    second method; the shipped grip is checked against 252.0 Hz above."""
    grip = calibrate_clamp_length(target_hz=245.0)
    assert 0 < grip < CALIBRATED_CLAMP_LENGTH
    f4 = independent_bending_hz(DoubleBeamConfig(clamp_length=grip), (4,))[4]
    assert f4 == pytest.approx(245.0, rel=2e-6)


def test_material_fixes_are_reachable_but_implausible(check):
    c = check["candidates"]
    assert c["E"]["reachable"] and not c["E"]["plausible"]
    assert c["E"]["required_value"] > c["E"]["plausible_range"][1]
    assert c["rho"]["reachable"] and not c["rho"]["plausible"]
    assert c["rho"]["required_value"] < c["rho"]["plausible_range"][0]


def test_every_fix_puts_the_measured_mode_on_the_measurement(check):
    """Each reachable fix, rebuilt and solved by the second method: mode 4 on the
    measurement and the predicted modes 2, 3, 5 as the check reports them."""
    sets = {"clamp": lambda c, p: replace(c, clamp_length=p),
            "E": lambda c, p: replace(c, E=p), "rho": lambda c, p: replace(c, rho=p),
            "thickness": lambda c, p: replace(c, thickness=p)}
    for name in check["reachable"]:
        fix = check["candidates"][name]
        fr = independent_bending_hz(sets[name](UNCAL, fix["required_value"]))
        assert fr[4] == pytest.approx(check["measured_hz"], rel=2e-6), name
        for k in (2, 3, 5):
            assert fix["predicted_modes_hz"][str(k)] == pytest.approx(fr[k], rel=3e-6), (name, k)
            # and raises the other modes too (all are near-uniform scalings)
            assert fr[k] > check["uncalibrated_modes_hz"][str(k)]


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


def test_cli_double_beam_json_holds_fe_check(check, capsys):
    assert main(["diagnose", "--case", "double-beam", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    fe = r["fe_check"]
    assert fe["measured_bending_order"] == 4
    assert fe["candidates"]["glue"]["reachable"] is False
    # the command reports the check of its data's level 1 (= the paper's Table 4 value)
    assert fe["measured_omega2"] == MEASURED_OMEGA2
    assert fe["candidates"]["clamp"]["required_value"] == check["candidates"]["clamp"][
        "required_value"]
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
