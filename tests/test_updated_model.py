"""``--model DIR/updated_model.json``: a case file that leaves its joint to be fitted
runs ``update``, and the FE commands take the model it fitted
(feloop.updated_model).

Truth: the update's own numbers by another route. The case file rebuilt from the JSON
(calibrated values fixed, every stiffness scaled, the fitted joint) has its FE mode at
the fitted stuck frequency f0, and its EPMC backbone (another reduced basis, a free
nonlinear mode instead of the forced phase resonance of the update) gives the update's
frequency and damping at each level's slip amplitude."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
LAP = ROOT / "docs" / "case-files" / "bolted-lap-cantilever.toml"


@pytest.fixture(scope="module")
def updated(tmp_path_factory):
    """The lap file without chi, fs, beta, updated: (case file, model JSON, update.json)."""
    tmp = tmp_path_factory.mktemp("updated")
    text = re.sub(r"(?m)^(chi|fs|beta) = .*\n", "", LAP.read_text())
    (tmp / LAP.name).write_text(text)
    shutil.copy(LAP.parent / "bolted-lap-cantilever-levels.csv", tmp)
    assert main(["update", "--case", str(tmp / LAP.name), "--out", str(tmp / "up")]) == 0
    return (tmp / LAP.name, tmp / "up" / "updated_model.json",
            json.loads((tmp / "up" / "update.json").read_text()))


def _json(capsys, argv):
    assert main(argv) == 0, argv
    return json.loads(capsys.readouterr().out)


def test_without_the_model_the_nonlinear_commands_say_what_is_missing(updated, capsys):
    case, _, _ = updated
    assert main(["backbone", "--case", str(case), "--mode", "2"]) == 2
    assert "nonlinear model" in capsys.readouterr().err


def test_updated_model_has_its_mode_at_the_fitted_stuck_frequency(updated, capsys):
    case, model, s = updated
    modes = _json(capsys, ["modes", "--case", str(case), "--model", str(model), "--json"])
    fe_mode = s["derived"]["fe_mode"]
    f0 = s["parameters"]["f0_hz"]["value"]
    assert modes[fe_mode - 1]["frequency_hz"] == pytest.approx(f0, rel=1e-7)


def test_backbone_of_the_updated_model_gives_the_updates_levels(updated, capsys):
    """At each level's largest slip / phi_max, the backbone's frequency within 2e-6
    relative and its damping within 0.3 % of the update's prediction (measured: 1.5e-7
    and 2.9e-4)."""
    case, model, s = updated
    slips = np.array([row["slip_over_phi_max"] for row in s["levels"]])
    points = _json(capsys, ["backbone", "--case", str(case), "--mode", "2", "--model",
                            str(model), "--range", f"{slips.min() / 2:g}",
                            f"{slips.max() * 2:g}", "--points", "60", "--json",
                            "--no-progress"])
    a = np.log([p["amplitude"] for p in points])
    f = np.interp(np.log(slips), a, [p["frequency_hz"] for p in points])
    z = np.interp(np.log(slips), a, [p["zeta"] for p in points])
    f_upd = np.array([row["model"]["frequency_hz"] for row in s["levels"]])
    z_upd = np.array([row["model"]["zeta"] for row in s["levels"]])
    assert np.max(np.abs(f / f_upd - 1)) < 2e-6
    assert np.max(np.abs(z / z_upd - 1)) < 3e-3


def test_a_model_of_another_case_or_with_a_cause_is_one_line(updated, tmp_path, capsys):
    case, model, _ = updated
    doc = json.loads(model.read_text())
    for change, words in (({"case": "brb"}, "the update of case 'brb'"),
                          ({"cause": "quadratic-damping"}, "has no case-file form")):
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps({**doc, **change}))
        assert main(["modes", "--case", str(case), "--model", str(bad)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and words in err


# --- uncertainty --model and loop --model: the given model in the FE-levels
# parametrization (feloop.given_model). Truth: the update's own numbers (update.json),
# since the given model is drawn around / simulated exactly as update left it.

def _one_line_exit_2(capsys, argv, words):
    assert main(argv) == 2, argv
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err, err


def test_uncertainty_draws_around_the_given_model(updated, tmp_path, capsys):
    """The nominal is the model's values (1e-12) and its prediction the update's at every
    level (frequency 1e-9, zeta 1e-6 relative: the same FE-levels model from a cold
    start); the drawn sd are the update's standard errors (1e-9); no model choice runs."""
    case, model, s = updated
    r = _json(capsys, ["uncertainty", "--case", str(case), "--model", str(model),
                       "--samples", "4", "--out", str(tmp_path / "mc"), "--json",
                       "--no-progress"])
    m, dist = r["model"], r["distribution"]
    assert m["given"] == str(model) and m["candidate"] == s["model"]
    assert m["fit_levels"] == s["fit_levels"]
    for name, v in s["fit"]["values"].items():
        assert m["values"][name] == pytest.approx(v, rel=1e-12, abs=1e-15), name
    for name, sd in zip(dist["parameters"], dist["sd"]):
        assert sd == pytest.approx(s["fit"]["std_error"][name], rel=1e-9), name
    assert dist["mean"] == pytest.approx([s["fit"]["values"][n] for n in dist["parameters"]],
                                         rel=1e-12)
    for row, up in zip(r["levels"], s["levels"]):
        assert row["nominal_frequency_hz"] == pytest.approx(up["model"]["frequency_hz"],
                                                            rel=1e-9)
        assert row["nominal_zeta"] == pytest.approx(up["model"]["zeta"], rel=1e-6)
    assert r["n_failed"] == 0 and "given model" in r["timing_s"]


def test_uncertainty_refuses_a_model_of_another_case_data_or_levels(updated, tmp_path,
                                                                    capsys):
    case, model, _ = updated
    doc = json.loads(model.read_text())
    base = ["uncertainty", "--case", str(case), "--samples", "2", "--out",
            str(tmp_path / "mc"), "--no-progress", "--model"]
    other = tmp_path / "other.json"
    other.write_text(json.dumps({**doc, "case": "brb"}))
    _one_line_exit_2(capsys, base + [str(other)], "the update of case 'brb'")
    old = tmp_path / "old.json"
    old.write_text(json.dumps({k: v for k, v in doc.items() if k not in ("fit", "data")}))
    _one_line_exit_2(capsys, base + [str(old)], "older iwanfe update")
    _one_line_exit_2(capsys, base + [str(model), "--fit-levels", "1-6"],
                     "fitted to levels [1, 2, 3, 4, 5, 6, 7], not")
    csv = case.parent / "bolted-lap-cantilever-levels.csv"
    lines = csv.read_text().splitlines()
    cells = lines[1].split(",")
    cells[2] = repr(float(cells[2]) * (1 + 1e-6))       # one omega^2 moved by 1e-6
    moved = tmp_path / "moved.csv"
    moved.write_text("\n".join([lines[0], ",".join(cells), *lines[2:]]) + "\n")
    _one_line_exit_2(capsys, base + [str(model), str(moved)], "fitted to other data")


def test_loop_reports_what_the_given_model_gets_wrong(updated, tmp_path, capsys):
    """loop --model: the loop as without it, and the given model's errors at every level
    (its prediction the update's, 1e-9 / 1e-6 relative; its rms over its fit levels the
    update's sqrt(chi2 / n), 1e-6), beside the loop's own model (the same fit here:
    the same rms to 1e-6)."""
    case, model, s = updated
    out = tmp_path / "loop"
    loop = _json(capsys, ["loop", "--case", str(case), "--model", str(model), "--out",
                          str(out), "--json", "--no-progress"])
    g = loop["given_model"]
    assert g["path"] == str(model) and g["same_fit_levels"]
    for row, up in zip(g["errors"]["levels"], s["levels"]):
        assert row["frequency_hz"] == pytest.approx(up["model"]["frequency_hz"], rel=1e-9)
        assert row["zeta"] == pytest.approx(up["model"]["zeta"], rel=1e-6)
        assert row["fitted"] == (row["level"] in s["fit_levels"])
    chi2, n = s["fit"]["chi2"], s["fit"]["n_residuals"]
    assert g["errors"]["rms_fitted_sd"] == pytest.approx((chi2 / n) ** 0.5, rel=1e-6)
    assert g["loop_errors"]["rms_fitted_sd"] == pytest.approx(g["errors"]["rms_fitted_sd"],
                                                              rel=1e-6)
    assert "## The given model" in (out / "report.md").read_text()
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({**json.loads(model.read_text()), "case": "brb"}))
    _one_line_exit_2(capsys, ["loop", "--case", str(case), "--model", str(bad), "--out",
                              str(tmp_path / "l2"), "--no-progress"], "the update of case")


def test_an_unbounded_side_survives_the_json(updated, tmp_path):
    """JSON has no inf: an unbounded side (the air drag's C_D >= 0) is written null and
    read back as inf, the rest of the fit block exactly."""
    from feloop.given_model import read_given

    case, model, s = updated
    doc = json.loads(model.read_text())
    doc["fit"]["bounds"]["ln_dc1"] = [None, None]
    path = tmp_path / "unbounded.json"
    path.write_text(json.dumps(doc))
    g = read_given(path, doc["case"])
    assert g.bounds["ln_dc1"].lower == -np.inf and g.bounds["ln_dc1"].upper == np.inf
    assert g.bounds["chi"].lower == doc["fit"]["bounds"]["chi"][0]
    assert g.fit.values == s["fit"]["values"] and g.fit.chi2 == s["fit"]["chi2"]
