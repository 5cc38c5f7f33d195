"""One joint, several modes (feloop/modes.py): ``update --modes`` and ``loop --fit-modes
--predict-modes`` on a Jenkins case file whose modes 1 and 2 were simulated by another
route (the Jenkins bank's multi-harmonic stepped sine, LSCF: cases.stepped_sine_test) with
a slip force drawn here from a seed the code never sees; and, with mode 1 simulated with
a weaker joint than mode 2 (a seeded factor), the miss named."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
FILES = ROOT / "docs" / "case-files"
SEED = 31
#: the top level's linear slip in slip scales (as tests/test_case_file_law_update.py)
TOP_SLIP = 40.0


def _file(tmp: Path, table: Path, fs: float | None, mode: int, name: str) -> Path:
    text = (FILES / "bolted-lap-jenkins.toml").read_text()
    text = re.sub(r"(?m)^fs = .*\n", "" if fs is None else f"fs = {fs!r}\n", text)
    text += f'\n[measured]\nfile = "{table.name}"\nmode = {mode}\n'
    path = tmp / name
    path.write_text(text)
    return path


def _two_modes(tmp: Path, fs_by_mode: dict) -> Path:
    """The table of modes 1 and 2, each simulated with its slip force; the file to fit
    (fs left out, reference mode 2)."""
    import cases.stepped_sine_test as sst
    from cases.registry import resolve_case
    from ident.measured import write_measured
    from ident.modal_data import MeasuredData

    table = tmp / "levels.csv"
    shutil.copy(FILES / "bolted-lap-cantilever-levels.csv", table)
    parts = []
    old, sst.TOP_SLIP_OTHER = sst.TOP_SLIP_OTHER, TOP_SLIP
    try:
        for mode, fs in fs_by_mode.items():
            truth = _file(tmp, table, fs, mode, f"truth-{mode}.toml")
            parts.append(sst.simulate(resolve_case(str(truth)), SEED + 100 * mode)[0])
    finally:
        sst.TOP_SLIP_OTHER = old
    write_measured(table, MeasuredData.concatenate(parts))
    return _file(tmp, table, None, 2, "fit.toml")


@pytest.fixture(scope="module")
def hidden_fs():
    return float(np.random.default_rng(SEED).uniform(120.0, 320.0))


@pytest.fixture(scope="module")
def one_joint(tmp_path_factory, hidden_fs):
    return _two_modes(tmp_path_factory.mktemp("modes"), {1: hidden_fs, 2: hidden_fs})


@pytest.fixture(scope="module")
def two_joints(tmp_path_factory, hidden_fs):
    """Mode 1 simulated with a slip force a seeded factor (0.25-0.4) of mode 2's."""
    factor = float(np.random.default_rng(SEED + 1).uniform(0.25, 0.4))
    return _two_modes(tmp_path_factory.mktemp("modes2"),
                      {1: factor * hidden_fs, 2: hidden_fs})


def test_update_modes_fits_one_joint_to_both(one_joint, hidden_fs, capsys):
    """One slip force for both modes within 5 % of the hidden one (measured 1.5 %), each
    mode's fit test passes, one joint explains both (the one-joint test), and every
    parameter says it was fitted."""
    assert main(["update", "--case", str(one_joint), "--modes", "2,1", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert abs(s["joint"]["F_S"] / hidden_fs - 1.0) < 0.05, (s["joint"]["F_S"], hidden_fs)
    assert s["fit"]["converged"] and not s["fit"]["at_bound"]
    assert set(s["parameters"]) == {"ln_slip", "zeta_v@1", "f0_hz@1", "zeta_v@2", "f0_hz@2"}
    assert all(p["kind"] == "fitted" for p in s["parameters"].values())
    assert {m["fe_mode"] for m in s["per_mode"].values()} == {1, 2}
    assert all(m["passes"] for m in s["per_mode"].values())
    assert s["one_joint"]["dof"] == 1 and s["one_joint"]["passes"]
    assert s["verdict"][0].startswith("one joint explains modes 2, 1")
    # each mode alone finds the same slip force within 5 % (the modes agree)
    for m in s["per_mode"].values():
        assert abs(m["alone"]["joint"]["F_S"] / hidden_fs - 1.0) < 0.05


def test_loop_predicts_the_unfitted_mode(one_joint, tmp_path, capsys):
    """Fit mode 2, predict mode 1: every level within its 95 % interval, the frequency
    drop (0.024 % measured, a joint barely worked by mode 1) and the damping growth
    predicted within 20 % of the measured ones, gain over no amplitude dependence > 10;
    the calibrated parameters say so; files written."""
    out = tmp_path / "loop"
    assert main(["loop", "--case", str(one_joint), "--fit-modes", "2", "--predict-modes",
                 "1", "--out", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    p = s["predicted"]["1"]
    assert p["inside_pi95"] and not p["misses"]
    c = p["change"]
    assert c["measured_frequency_drop_pct"] > 0.01
    assert abs(c["predicted_frequency_drop_pct"] / c["measured_frequency_drop_pct"] - 1) < 0.2
    assert abs((c["predicted_zeta_growth"] - 1) / (c["measured_zeta_growth"] - 1) - 1) < 0.2
    assert p["gain"] > 10
    assert all(v["kind"].startswith("calibrated") for v in p["calibrated"].values())
    assert p["rows"][0]["calibration"] and abs(p["rows"][0]["z_frequency"]) < 1e-6
    assert "within its 95 % intervals at every level" in p["verdict"]
    assert {f.name for f in out.iterdir()} >= {"modes.json", "report.md", "mode1_predicted.png"}


def test_a_joint_that_differs_between_modes_is_named(two_joints, capsys):
    """Mode 1 made with a weaker joint than mode 2 (its slip force 0.27 of mode 2's): its
    prediction from mode 2 misses (named, with sd), and fitting both gives the one-joint
    test's failure (measured D = 25 for 1 dof) with both modes' slip forces."""
    assert main(["loop", "--case", str(two_joints), "--fit-modes", "2", "--predict-modes",
                 "1", "--json"]) == 0
    p = json.loads(capsys.readouterr().out)["predicted"]["1"]
    assert p["misses"] and "MISSED" in p["verdict"] and "fails on mode 1" in p["verdict"]
    # the slip onset comes at lower levels than the joint of mode 2 puts it (measured:
    # levels 6 and 7 missed by -2.6 sd in frequency against the judge's noise, which
    # holds the assumed rig repeatability of 0.05 %)
    assert {m["level"] for m in p["misses"]} <= {5, 6, 7, 8}
    assert min(m["z_frequency"] for m in p["misses"]) < -2.2
    assert main(["update", "--case", str(two_joints), "--modes", "2,1", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert not s["one_joint"]["passes"] and s["one_joint"]["p_value"] < 1e-3
    assert "the modes disagree on the joint" in " ".join(s["verdict"])
    fs = {k: m["alone"]["joint"]["F_S"] for k, m in s["per_mode"].items()}
    assert fs["1"] < 0.6 * fs["2"], fs


def test_one_mode_set_is_the_one_mode_model(one_joint):
    """The several-mode simulator with one mode gives the one-mode model's prediction
    bitwise; a second mode takes the first's joints (the same slip force)."""
    from cases.registry import resolve_case
    from feloop.case_file import levels_builder
    from feloop.modes import ModeSet, mode_series
    from ident.measured import read_measured

    cf = resolve_case(str(one_joint)).file
    table = read_measured(cf.measured.file)
    data = {m: table.for_mode(m) for m in (2, 1)}
    series = mode_series(data, {m: np.ones(10, bool) for m in data}, levels_builder(cf))
    v = {"ln_slip": 2.5, "zeta_v": 1e-3, "f0_hz": 85.2}
    alone = levels_builder(cf)(data[2]).predict(v)
    om2, ze = ModeSet(series[:1], ("ln_slip",))({"ln_slip": 2.5, "zeta_v@2": 1e-3,
                                                 "f0_hz@2": 85.2})
    assert np.array_equal(om2, alone.omega2) and np.array_equal(ze, alone.zeta)
    j1 = series[1].fe.joint({"ln_slip": 2.5})
    assert j1["F_S"] == series[0].fe.joint({"ln_slip": 2.5})["F_S"]
    assert j1["linear"].fe_mode == 1


@pytest.mark.parametrize("argv, words", [
    (["update", "--modes", "2,2"], "distinct"),
    (["update", "--modes", "2,x"], "mode labels"),
    (["update", "--modes", "2,3"], "mode 3 not in data"),
    (["loop", "--predict-modes", "1"], "needs --fit-modes"),
    (["loop", "--fit-modes", "2", "--predict-modes", "2"], "both fitted and predicted"),
])
def test_bad_mode_arguments_are_one_line(one_joint, argv, words, tmp_path, capsys):
    extra = ["--out", str(tmp_path / "o")] if argv[0] == "loop" else []
    assert main(argv[:1] + ["--case", str(one_joint)] + argv[1:] + extra) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1, err


def test_iwan_joints_over_two_modes(tmp_path, capsys):
    """An Iwan file (chi, fs and beta left to be fitted) over modes 1 and 2 simulated with
    one seeded chi (cases.stepped_sine_test's several-mode route; 8 sliders per octave,
    micro-slip): both runs exit 0, the joint's chi within 0.1 of the hidden one (measured
    -0.397 against -0.338: mode 2's own fit test fails at p = 0.04 over all ten levels, and
    the report says so before the prediction), mode 1 predicted within its intervals."""
    import cases.stepped_sine_test as sst

    text = (FILES / "bolted-lap-cantilever.toml").read_text()
    text = re.sub(r'(?m)^file = .*$', 'file = "iwan-modes.csv"', text)
    truth = tmp_path / "truth.toml"
    truth.write_text(text)
    shutil.copy(FILES / "bolted-lap-cantilever-levels.csv", tmp_path / "iwan-modes.csv")
    assert sst.main([str(truth), str(tmp_path / "iwan-modes.csv"), "5", "1,2"]) == 0
    chi = float(re.search(r"'chi': (-[0-9.]+)", capsys.readouterr().out).group(1))
    fit = tmp_path / "fit.toml"
    fit.write_text(re.sub(r"(?m)^(chi|fs|beta) = .*\n", "", text))
    assert main(["loop", "--case", str(fit), "--fit-modes", "2", "--predict-modes", "1",
                 "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert set(s["parameters"]) == {"chi", "ln_dc1", "zeta_v@2", "f0_hz@2"}
    assert abs(s["parameters"]["chi"]["value"] - chi) < 0.1
    lo, hi = s["parameters"]["chi"]["interval"]
    assert lo < s["parameters"]["chi"]["value"] < hi and hi - lo > 0.01
    assert s["joint"]["law"] == "iwan4" and s["joint"]["beta"] >= 0
    assert s["predicted"]["1"]["inside_pi95"]
    if not s["per_mode"]["2"]["passes"]:
        assert s["verdict"][0].startswith("mode 2's fit levels are not fitted")
    assert main(["update", "--case", str(fit), "--modes", "2,1", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["one_joint"]["dof"] == 2 and s["one_joint"]["test"].startswith(("F(", "chi"))
