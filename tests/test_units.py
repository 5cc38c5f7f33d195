"""Values that look like another unit (ident.units): a case file in millimetres, E in
MPa, omega2 written in Hz: one line, exit 2, naming the flag; ``iwanfe
--units-confirmed`` runs on. Truth: the lap cantilever of docs/case-files.md with each
value rewritten in the other unit by the test (its SI file passes)."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from cli.main import main
from ident.measured import read_measured, write_measured
from ident.units import ENVIRONMENT

ROOT = Path(__file__).resolve().parents[1]
LAP = ROOT / "docs" / "case-files" / "bolted-lap-cantilever.toml"
TABLE = LAP.parent / "bolted-lap-cantilever-levels.csv"


def _file(tmp_path, name, *replace):
    text = LAP.read_text()
    for old, new in replace:
        assert old in text
        text = text.replace(old, new)
    shutil.copy(TABLE, tmp_path / TABLE.name)
    (tmp_path / name).write_text(text)
    return tmp_path / name


@pytest.mark.parametrize("name, replace, words", [
    ("mm.toml", [("x = [0.0, 0.300]", "x = [0.0, 300.0]"), ("width = 0.030", "width = 30.0")],
     "[beam.0] x: 300 is above 20: millimetres (the case file is in metres)?"),
    ("mpa.toml", [("E = 70e9", "E = 70e3")], "[material.0] E: 70000 is below 1e+08: MPa or GPa"),
    ("gcc.toml", [("rho = 2700.0", "rho = 2.7")], "[material.0] rho: 2.7 is below 100: g/cm^3"),
])
def test_case_file_in_another_unit_is_one_line_unless_confirmed(tmp_path, capsys, name,
                                                                replace, words):
    path = _file(tmp_path, name, *replace)
    assert main(["case", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "iwanfe --units-confirmed" in err
    assert main(["--units-confirmed", "case", "check", str(path), "--json"]) == 0
    capsys.readouterr()
    assert ENVIRONMENT not in os.environ          # the flag holds for its run only


def test_si_case_file_passes(capsys):
    assert main(["case", "check", str(LAP)]) == 0


def test_omega2_in_hz_is_named_with_the_mode_it_matches(tmp_path, capsys):
    """omega2 column holding f (Hz): 85.23 Hz read as rad^2/s^2 is 1.47 Hz; read as Hz
    it is the lap's FE mode 2 (85.2366 Hz, case check)."""
    d = read_measured(TABLE)
    d.omega2 = np.sqrt(d.omega2) / (2 * np.pi)
    write_measured(tmp_path / "hz.csv", d)
    path = _file(tmp_path, "hz.toml", (TABLE.name, "hz.csv"))
    assert main(["update", "--case", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "omega2 in Hz? (read so, 85.2343 matches FE mode 2 at 85.2366 Hz" in err
