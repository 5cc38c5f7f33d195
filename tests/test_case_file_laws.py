"""Joint laws of a case file (``law = "iwan4" | "jenkins" | "bouc-wen"``, casefile/laws.py):
each law's own keys, a key of another law refused in one line naming file, table and key
(exit status 2), ``case check`` listing the law and the kind of each of its keys, and
the estimator's backbone prediction (an Iwan joint's) refusing another law in one
line."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from casefile.schema import read_case_file
from casefile.tables import CaseFileError
from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
FILES = ROOT / "docs" / "case-files"
LAW_FILES = {"iwan4": FILES / "bolted-lap-cantilever.toml",
             "jenkins": FILES / "bolted-lap-jenkins.toml",
             "bouc-wen": FILES / "bolted-lap-bouc-wen.toml"}
LEVELS = FILES / "bolted-lap-cantilever-levels.csv"


def _text(law: str) -> str:
    """The law's file without its ``[measured]`` table (the iwan4 file has one)."""
    return LAW_FILES[law].read_text().split("\n[measured]")[0]


def _write(tmp_path, text: str, name: str = "lap.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("law, given", [
    ("iwan4", {"chi": -0.5, "fs": 200.0, "beta": 1.0}),
    ("jenkins", {"fs": 200.0}),
    ("bouc-wen", {"fs": 200.0, "alpha": 0.1, "shape": 0.5}),
])
def test_each_law_reads_its_own_keys(law, given):
    cf = read_case_file(LAW_FILES[law])
    itf = cf.interfaces[0]
    assert itf.law == law and itf.kt == 1.0e7
    for key, value in given.items():
        assert getattr(itf, key) == value
        assert cf.kinds[f"interface.0.{key}"] == ("given", "")
    others = {"chi", "beta", "alpha", "shape"} - set(given)
    assert all(getattr(itf, k) is None for k in others)


#: (law, the key of another law written into its file, the laws that key belongs to)
FOREIGN = [("jenkins", "chi = -0.5", "iwan4"), ("jenkins", "shape = 0.5", "bouc-wen"),
           ("bouc-wen", "beta = 1.0", "iwan4"), ("bouc-wen", "chi = -0.4", "iwan4"),
           ("iwan4", "alpha = 0.1", "bouc-wen"), ("iwan4", "shape = 1.0", "bouc-wen")]


@pytest.mark.parametrize("law, line, owner", FOREIGN, ids=[f"{a}+{b.split()[0]}"
                                                          for a, b, _ in FOREIGN])
def test_a_key_of_another_law_is_one_line_naming_file_table_and_key(tmp_path, capsys, law,
                                                                     line, owner):
    text = _text(law).replace("kt = 1.0e7", f"kt = 1.0e7\n{line}", 1)
    path = _write(tmp_path, text)
    key = line.split()[0]
    with pytest.raises(CaseFileError) as exc:
        read_case_file(path)
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg and f"[interface.0] {key}:" in msg, msg
    assert f"not a key of law {law!r}" in msg and owner in msg, msg
    assert main(["case", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[interface.0]" in err and key in err


@pytest.mark.parametrize("law, old, new, key", [
    ("jenkins", "fs = 200.0", "fs = 0.0", "fs"),
    ("bouc-wen", "alpha = 0.1", "alpha = 1.0", "alpha"),
    ("bouc-wen", "shape = 0.5", "shape = -1.0", "shape"),
    ("bouc-wen", "fs = 200.0", 'fs = "strong"', "fs"),
])
def test_a_law_key_out_of_range_names_table_and_key(tmp_path, law, old, new, key):
    assert old in _text(law)
    path = _write(tmp_path, _text(law).replace(old, new, 1))
    with pytest.raises(CaseFileError, match=rf"\[interface\.0\] {key}:"):
        read_case_file(path)


def test_unknown_law_lists_the_three(tmp_path):
    path = _write(tmp_path, _text("jenkins").replace('law = "jenkins"', 'law = "valanis"'))
    with pytest.raises(CaseFileError, match=r"\[interface\.0\] law: must be one of "
                                            r"iwan4, jenkins, bouc-wen"):
        read_case_file(path)


@pytest.mark.parametrize("law", ["iwan4", "jenkins", "bouc-wen"])
def test_case_check_lists_the_law_and_the_kind_of_each_key(tmp_path, capsys, law):
    """A key left out is ``fitted``; the others ``given``; in the text and the JSON."""
    keys = {"iwan4": ("chi", "fs", "beta"), "jenkins": ("fs",),
            "bouc-wen": ("fs", "shape", "alpha")}[law]
    left_out = keys[-1]
    text = re.sub(rf"(?m)^{left_out} = .*\n", "", _text(law))
    path = _write(tmp_path, text)
    assert main(["case", "check", str(path)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("joint law of interface 0"))
    assert f": {law} (" in line and "kt = 1e+07 N/m given" in line
    assert f"{left_out} = - fitted" in line
    for k in keys[:-1]:
        assert re.search(rf"\b{k} = \S+( N)? given", line), line
    assert re.search(rf"interface\.0\.{left_out} +- +fitted", out)
    assert main(["case", "check", str(path), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    (entry,) = s["joint_laws"]
    kinds = {p["key"]: p["kind"] for p in entry["parameters"]}
    assert entry["law"] == law and kinds == {"kt": "given", **{k: "given" for k in keys[:-1]},
                                             left_out: "fitted"}
    assert s["fitted_by_update"] == [f"interface.0.{left_out}"]


def test_a_bouc_wen_shape_left_out_is_assumed_by_update(tmp_path, capsys):
    """update fits fs and alpha of a Bouc-Wen joint, not its loop shape: left out, it is
    ``assumed`` (0.5, feloop.joint_forms.BOUC_WEN_SHAPE), never called fitted."""
    path = _write(tmp_path, re.sub(r"(?m)^shape = .*\n", "", _text("bouc-wen")))
    assert main(["case", "check", str(path), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    kinds = {p["key"]: p["kind"] for p in s["joint_laws"][0]["parameters"]}
    assert kinds["shape"] == "assumed" and s["assumed_by_update"] == ["interface.0.shape"]
    assert s["fitted_by_update"] == []


def test_backbone_needs_every_key_of_the_law(tmp_path, capsys):
    path = _write(tmp_path, re.sub(r"(?m)^fs = .*\n", "", _text("jenkins")))
    assert main(["backbone", "--case", str(path), "--mode", "2", "--points", "3",
                 "--no-progress"]) == 2
    assert "nonlinear model" in capsys.readouterr().err


def test_one_nonlinear_model_takes_one_law(tmp_path, capsys):
    """Two joint interfaces side by side with different laws: the file reads (case check
    exits 0), the nonlinear model is one line naming both."""
    text = _text("jenkins").replace("x = [0.240, 0.300]\nnormal", "x = [0.240, 0.270]\nnormal")
    text = text.replace("joints_at = [0.255, 0.285]", "joints_at = [0.255]")
    extra = ('\n[[interface]]\nbeams = ["lower", "upper"]\nx = [0.270, 0.300]\n'
             'normal = "tied"\ntangential = "joint"\njoints_at = [0.285]\nlaw = "bouc-wen"\n'
             'kt = 1.0e7\nfs = 200.0\nalpha = 0.0\nshape = 0.5\n')
    path = _write(tmp_path, text.replace("\n[[mass]]", extra + "\n[[mass]]", 1))
    assert main(["case", "check", str(path)]) == 0
    capsys.readouterr()
    assert main(["backbone", "--case", str(path), "--mode", "2", "--points", "3",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "different laws" in err and "[interface.0] jenkins" in err \
        and "[interface.1] bouc-wen" in err


def _with_table(tmp_path, law: str) -> Path:
    shutil.copy(LEVELS, tmp_path / LEVELS.name)
    return _write(tmp_path, _text(law) + f'\n[measured]\nfile = "{LEVELS.name}"\nmode = 2\n',
                  f"lap-{law}.toml")


COMMANDS = {
    "update": lambda f, t: ["update", "--case", f],
    "diagnose-case": lambda f, t: ["diagnose", "--case", f],
    "diagnose-file-case": lambda f, t: ["diagnose", t, "--case", f],
    "loop": lambda f, t: ["loop", "--case", f],
    "uncertainty": lambda f, t: ["uncertainty", "--case", f],
    "estimate-backbone": lambda f, t: ["estimate", t, "--case", f, "--backbone"],
}


@pytest.mark.parametrize("law", ["jenkins", "bouc-wen"])
def test_the_estimators_backbone_refuses_another_law_in_one_line(tmp_path, capsys, law):
    """The backbone prediction of the paper's estimator is an Iwan joint's: one line,
    exit 2, naming the law; update, diagnose --case, loop and uncertainty take every law
    (tests/test_case_file_law_update.py)."""
    path = _with_table(tmp_path, law)
    argv = COMMANDS["estimate-backbone"](str(path), str(tmp_path / LEVELS.name))
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert law in err and "Iwan joint" in err and "iwanfe update fits them" in err


def test_the_iwan4_file_keeps_the_fe_loop():
    from cases.registry import resolve_case

    case = resolve_case(str(LAW_FILES["iwan4"]))
    assert {"update", "fe_levels", "fe_uncertainty"} <= set(case.capabilities)
    assert case.refused == {}


def test_an_updated_model_of_another_law_is_refused(tmp_path, capsys):
    path = _with_table(tmp_path, "jenkins")
    model = tmp_path / "updated_model.json"
    model.write_text(json.dumps({"case": "bolted-lap-jenkins", "cause": "none",
                                 "joint": {"law": "iwan4"}}))
    assert main(["backbone", "--case", str(path), "--model", str(model), "--points", "3",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "an update of iwan4 joints" in err and err.count("\n") == 1


def test_every_package_raises_input_faults():
    """A ValueError raised in any project package is a verdict on the input (exit 2,
    cli.main.input_fault): casefile, feloop and synthetic included."""
    from cli.main import PROJECT_PACKAGES

    packages = {p.name for p in ROOT.iterdir() if (p / "__init__.py").exists()} - {"tests"}
    assert packages <= set(PROJECT_PACKAGES), packages - set(PROJECT_PACKAGES)
