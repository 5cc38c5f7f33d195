"""Bad case files: every fault is one line naming the file, the table and the key, exit
status 2 on the command line (``iwanfe case check FILE``); ``x_`` keys are ignored."""
from __future__ import annotations

import re

import pytest

from casefile.schema import read_case_file
from casefile.tables import CaseFileError
from cli.main import main

# without its [measured] table (the cases below add their own, in tmp directories)
GOOD = open("docs/case-files/bolted-lap-cantilever.toml").read().split("\n[measured]")[0]


def _edit(old: str, new: str) -> str:
    assert old in GOOD, old
    return GOOD.replace(old, new, 1)


#: (file text, table label the message must name, key it must name)
BAD = [
    (_edit('name = "bolted-lap-cantilever"', 'name = "Bolted Lap"'), "[case]", "name"),
    (_edit("[case]\n", "[case]\ncolour = 1\n"), "[case]", "colour"),
    (_edit("E = 70e9", "E = -70e9"), "[material.0]", "E"),
    (_edit("rho = 2700.0", 'rho = "heavy"'), "[material.0]", "rho"),
    (_edit("E = 70e9\n", ""), "[material.0]", "E"),
    (_edit('material = "aluminium"\nx = [0.0, 0.300]', 'material = "steel"\nx = [0.0, 0.300]'),
     "[beam.0]", "material"),
    (_edit("x = [0.0, 0.300]", "x = [0.300, 0.0]"), "[beam.0]", "x"),
    (_edit("width = 0.030\nthickness = 0.005\nz = 0.0", "width = 0.030\nthickness = 0.0"),
     "[beam.0]", "thickness"),
    (_edit("z = 0.005", "z = 0.0051"), "[interface.0]", "beams"),
    (_edit('beams = ["lower", "upper"]', 'beams = ["lower", "middle"]'), "[interface.0]", "beams"),
    (_edit("x = [0.240, 0.300]\nnormal", "x = [0.240, 0.350]\nnormal"), "[interface.0]", "x"),
    (_edit('normal = "tied"', 'normal = "glued"'), "[interface.0]", "normal"),
    (_edit("joints_at = [0.255, 0.285]", "joints_at = [0.255, 0.385]"),
     "[interface.0]", "joints_at"),
    (_edit("joints_at = [0.255, 0.285]", "joints_at = [0.255, 0.285]\njoint_elements = 3"),
     "[interface.0]", "joints_at"),
    (_edit("kt = 1.0e7\n", ""), "[interface.0]", "kt"),
    (_edit("chi = -0.5", "chi = -1.5"), "[interface.0]", "chi"),
    (_edit('law = "iwan4"', 'law = "valanis"'), "[interface.0]", "law"),
    (_edit('kind = "clamp"', 'kind = "weld"'), "[support.0]", "kind"),
    (_edit('kind = "clamp"\nx = [0.0, 0.0]', 'kind = "clamp"\nx = [0.0, 0.0]\nk_w = 1e5'),
     "[support.0]", "k_w"),
    (_edit('kind = "clamp"', 'kind = "pin"\nbogus = 2'), "[support.0]", "bogus"),
    (_edit("x = 0.100\nmass = 0.015", "x = 0.400\nmass = 0.015"), "[mass.0]", "x"),
    (_edit("mass = 0.015", "mass = -0.015"), "[mass.0]", "mass"),
    (_edit('[drive]\nbeam = "lower"', '[drive]\nbeam = "upper"'), "[drive]", "x"),
    (_edit('label = "laser"', 'label = "laser"\nmass = [1]'), "[sensor.0]", "mass"),
    (_edit("element_size = 0.005", "element_size = 0"), "[mesh]", "element_size"),
    (_edit("[damping]\nzeta = 0.001", "[damping]\nzeta = 1.5"), "[damping]", "zeta"),
    (GOOD + '\n[measured]\nfile = "nowhere.csv"\nmode = 2\n', "[measured]", "file"),
    (GOOD + "\n[measured]\nmode = 0\n", "[measured]", "mode"),
    (GOOD + '\n[calibrate]\nparameters = ["mass.3.mass"]\nfrequencies_hz = [20.0]\n',
     "[calibrate]", "parameters"),
    (GOOD + '\n[calibrate]\nparameters = ["mass.0.mass", "support.0.x"]\nfrequencies_hz = [20.0]\n',
     "[calibrate]", "frequencies_hz"),
    (GOOD + "\n[gravity]\ng = 9.81\n", "[gravity]", ""),
    ('[case]\nname = "a"\n[[material]]\nname = "al"\nE = 1e9\nrho = 1.0\n[beam]\nname = "b"\n',
     "[beam]", ""),
]


@pytest.mark.parametrize("text, table, key", BAD,
                         ids=[f"{t}{k}-{i}" for i, (_, t, k) in enumerate(BAD)])
def test_bad_case_file_is_one_line_naming_table_and_key(tmp_path, capsys, text, table, key):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(CaseFileError) as exc:
        read_case_file(path)
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg and table in msg
    assert re.search(rf"\] {re.escape(key)}\b", msg) if key else True, msg
    assert main(["case", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and table in err


def test_not_toml_and_missing_file_are_one_line(tmp_path, capsys):
    path = tmp_path / "broken.toml"
    path.write_text("[case\nname = 1")
    assert main(["case", "check", str(path)]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    assert main(["case", "check", str(tmp_path / "absent.toml")]) == 2
    assert "no such case file" in capsys.readouterr().err


def test_x_keys_are_kept_and_ignored(tmp_path):
    path = tmp_path / "x.toml"
    path.write_text(_edit("[case]\n", "[case]\nx_author = 'me'\n") + "\n[x_notes]\ntext = 'free'\n")
    cf = read_case_file(path)
    assert cf.extra["case"] == {"x_author": "me"}
    assert cf.name == "bolted-lap-cantilever"
