"""Measured-data CSV reader: every rule of docs/formats/measured-data.md."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ident.errors import InputError
from ident.measured import MeasuredData, read_measured, write_measured

ROOT = Path(__file__).resolve().parents[1]

HEADER = "level,excitation,omega2,zeta"
ROWS = [  # double-beam-like values, excitation doubling per level
    "1,0.5,2.50677e6,0.012780",
    "2,1.0,2.50676e6,0.012795",
    "3,2.0,2.50672e6,0.012791",
    "4,4.0,2.50674e6,0.012793",
    "5,8.0,2.50670e6,0.012805",
]


def write(tmp_path, text, name="m.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def good(tmp_path):
    return write(tmp_path, "\n".join([HEADER] + ROWS) + "\n")


def error_of(path):
    with pytest.raises(InputError) as info:
        read_measured(path)
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def test_reads_valid_file(tmp_path):
    d = read_measured(good(tmp_path))
    np.testing.assert_array_equal(d.level, [1, 2, 3, 4, 5])
    np.testing.assert_array_equal(d.excitation, [0.5, 1, 2, 4, 8])
    np.testing.assert_allclose(d.omega2[0], 2.50677e6)
    np.testing.assert_allclose(d.zeta[-1], 0.012805)
    np.testing.assert_array_equal(d.mode, 1)          # default mode
    np.testing.assert_array_equal(d.run_order, d.level)  # default run order
    assert d.response_amplitude is None
    assert d.warnings == []
    np.testing.assert_array_equal(d.line, [2, 3, 4, 5, 6])
    np.testing.assert_array_equal(d.modes, [1])


def test_optional_columns_any_order_and_annotations(tmp_path):
    text = ("x_note,mode,zeta,omega2,excitation,level,run_order,response_amplitude,x_temp\n"
            "a,2,0.02,4e6,1,1,3,1e-6,20.5\n"
            "b,2,0.021,3.99e6,2,2,1,2e-6,21\n"
            "c,1,0.01,1e6,1,1,2,1e-6,22\n"
            "d,2,0.022,3.98e6,4,3,2,4e-6,23\n"
            "e,1,0.011,0.99e6,2,2,4,2e-6,24\n"
            "f,2,0.023,3.97e6,8,4,4,8e-6,25\n"
            "g,1,0.012,0.98e6,4,3,5,4e-6,26\n"
            "h,1,0.013,0.97e6,8,4,6,8e-6,27\n")
    d = read_measured(write(tmp_path, text))
    np.testing.assert_array_equal(d.modes, [1, 2])
    m2 = d.for_mode(2)
    np.testing.assert_array_equal(m2.level, [1, 2, 3, 4])
    np.testing.assert_array_equal(m2.run_order, [3, 1, 2, 4])
    np.testing.assert_array_equal(m2.extra["x_note"], ["a", "b", "d", "f"])
    np.testing.assert_allclose(m2.extra["x_temp"], [20.5, 21, 23, 25])
    np.testing.assert_allclose(m2.response_amplitude, [1e-6, 2e-6, 4e-6, 8e-6])
    np.testing.assert_allclose(d.for_mode(1).omega2, [1e6, 0.99e6, 0.98e6, 0.97e6])
    with pytest.raises(ValueError, match="mode 3"):
        d.for_mode(3)


def test_write_read_round_trip(tmp_path):
    rng = np.random.default_rng(7)
    n = 6
    d = MeasuredData(level=np.arange(1, n + 1), excitation=np.cumprod(rng.uniform(1.5, 2.5, n)),
                     omega2=rng.uniform(1e5, 1e7, n), zeta=rng.uniform(1e-3, 0.1, n),
                     mode=np.full(n, 3), run_order=rng.permutation(n) + 1,
                     response_amplitude=rng.uniform(1e-6, 1e-3, n),
                     extra={"x_ok": np.array(list("abcdef"))})
    p = tmp_path / "rt.csv"
    write_measured(p, d)
    e = read_measured(p)
    for name in ("level", "excitation", "omega2", "zeta", "mode", "run_order",
                 "response_amplitude"):
        np.testing.assert_array_equal(getattr(e, name), getattr(d, name))  # exact
    np.testing.assert_array_equal(e.extra["x_ok"], d.extra["x_ok"])


@pytest.mark.parametrize("missing", ["level", "excitation", "omega2", "zeta"])
def test_missing_required_column(tmp_path, missing):
    names = HEADER.split(",")
    keep = [j for j, n in enumerate(names) if n != missing]
    lines = [",".join(np.array(r.split(","))[keep]) for r in [HEADER] + ROWS]
    p = write(tmp_path, "\n".join(lines) + "\n")
    assert error_of(p).startswith(f"{p}:1:{missing}: missing required column")


@pytest.mark.parametrize("sep", [";", "\t"])
def test_a_file_separated_by_semicolons_or_tabs_is_told_so(tmp_path, sep):
    lines = [r.replace(",", sep) for r in [HEADER] + ROWS]
    p = write(tmp_path, "\n".join(lines) + "\n")
    assert error_of(p) == (f"{p}:1:{lines[0]}: columns are separated by commas, "
                           f"not {sep!r}")


@pytest.mark.parametrize("bad,column,text", [
    ("abc", "omega2", "not a number"),
    ("nan", "omega2", "not a finite number"),
    ("inf", "excitation", "not a finite number"),
    ("", "zeta", "not a number"),
])
def test_non_numeric_or_non_finite(tmp_path, bad, column, text):
    j = HEADER.split(",").index(column)
    rows = [r.split(",") for r in ROWS]
    rows[2][j] = bad
    p = write(tmp_path, "\n".join([HEADER] + [",".join(r) for r in rows]) + "\n")
    assert error_of(p) == f"{p}:4:{column}: {text}: {bad!r}"


@pytest.mark.parametrize("row, text, message", [
    *[(1, f"2,1.0,2.50676e6,{z}", "zeta: zeta must be a fraction in (0, 1)")
      for z in ("0", "-0.01", "1", "1.278")],
    *[(4, f"5,8.0,{v},0.0128", "omega2: omega2 must be > 0") for v in ("0", "-2.5e6")],
    *[(0, f"1,{v},2.5e6,0.0128", "excitation: excitation must be > 0") for v in ("0", "-1")],
])
def test_values_outside_their_range(tmp_path, row, text, message):
    """zeta outside (0, 1), omega2 or excitation not positive: one line naming the file,
    the line (header = line 1) and the column."""
    rows = list(ROWS)
    rows[row] = text
    p = write(tmp_path, "\n".join([HEADER] + rows) + "\n")
    assert error_of(p).startswith(f"{p}:{row + 2}:{message}")


def test_duplicate_mode_level(tmp_path):
    rows = ROWS + ["3,16.0,2.5e6,0.0129"]
    p = write(tmp_path, "\n".join([HEADER] + rows) + "\n")
    assert error_of(p) == f"{p}:7:level: duplicate (mode, level, run_order) = (1, 3, 3)"
    # the same level for two different modes is fine
    rows2 = [r + ",1" for r in ROWS] + [r + ",2" for r in ROWS]
    d = read_measured(write(tmp_path, "\n".join([HEADER + ",mode"] + rows2) + "\n", "ok.csv"))
    assert len(d) == 10


def test_excitation_not_increasing_with_level(tmp_path):
    # rows out of order in the file are fine; the check is on excitation sorted by level
    rows = [ROWS[3], ROWS[0], ROWS[4], ROWS[2], ROWS[1]]
    read_measured(write(tmp_path, "\n".join([HEADER] + rows) + "\n", "shuffled.csv"))
    rows = list(ROWS)
    rows[3] = "4,2.0,2.50674e6,0.012793"   # level 4 has the excitation of level 3
    p = write(tmp_path, "\n".join([HEADER] + rows) + "\n")
    assert error_of(p) == (f"{p}:5:excitation: mode 1: excitation of level 4 (2) does not "
                           "exceed that of level 3 (2)")


def test_fewer_than_four_levels(tmp_path):
    rows = [r + ",1" for r in ROWS] + [r + ",7" for r in ROWS[:3]]
    p = write(tmp_path, "\n".join([HEADER + ",mode"] + rows) + "\n")
    assert error_of(p) == f"{p}:7:mode: mode 7 has 3 levels, at least 4 are needed"


def test_unknown_column(tmp_path):
    p = write(tmp_path, "\n".join([HEADER + ",note"] + [r + ",x" for r in ROWS]) + "\n")
    assert error_of(p).startswith(f"{p}:1:note: unknown column")


def test_extra_structural_errors(tmp_path):
    p = write(tmp_path, "")
    assert error_of(p) == f"{p}:1:1: empty file: expected a header line"
    p = write(tmp_path, "\n".join([HEADER] + ROWS[:2] + ["3,2.0,2.5e6"] + ROWS[3:]) + "\n")
    assert error_of(p) == f"{p}:4:4: row has 3 fields, header has 4"
    p = write(tmp_path, "\n".join([HEADER] + ["1.5,0.5,2.5e6,0.0128"] + ROWS[1:]) + "\n")
    assert error_of(p) == f"{p}:2:level: must be an integer, got '1.5'"
    p = write(tmp_path, "level,level,excitation,omega2,zeta\n")
    assert error_of(p) == f"{p}:1:level: duplicate column name"


def test_percent_zeta_is_one_line_unless_confirmed(tmp_path, monkeypatch):
    """A zeta median of 0.27 (percent written as a fraction): refused in one line naming
    the flag; with the flag's environment set (ident.units) a warning."""
    from ident.units import ENVIRONMENT

    rows = [",".join(r.split(",")[:3] + [str(z)]) for r, z in
            zip(ROWS, [0.25, 0.26, 0.27, 0.28, 0.29])]
    p = write(tmp_path, "\n".join([HEADER] + rows) + "\n")
    assert error_of(p) == (f"{p}: zeta median: 0.27 is above 0.2: percent (zeta is a fraction:"
                           f" 0.01278 for 1.278 %)? (if the value is right: iwanfe "
                           f"--units-confirmed ...)")
    monkeypatch.setenv(ENVIRONMENT, "1")
    d = read_measured(p)
    assert len(d.warnings) == 1 and "percent" in d.warnings[0]
    assert read_measured(good(tmp_path)).warnings == []


def test_warning_nonconstant_excitation_ratio(tmp_path):
    rows = list(ROWS)
    rows[2] = "3,2.5,2.50672e6,0.012791"   # ratios 2, 2.5, 1.6, 2
    d = read_measured(write(tmp_path, "\n".join([HEADER] + rows) + "\n"))
    assert len(d.warnings) == 1
    assert "excitation ratios" in d.warnings[0] and "1.6 to 2.5" in d.warnings[0]


def _run_module(*args):
    return subprocess.run([sys.executable, "-m", "ident.measured", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT, timeout=60)


def test_module_entry_point(tmp_path):
    r = _run_module(good(tmp_path))
    assert r.returncode == 0, r.stderr
    assert "mode 1: 5 levels" in r.stdout
    rows = list(ROWS)
    rows[1] = "2,1.0,2.50676e6,1.2795"
    bad = write(tmp_path, "\n".join([HEADER] + rows) + "\n", "bad.csv")
    r = _run_module(bad)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert r.stderr.startswith(f"error: {bad}:3:zeta: zeta must be a fraction")
    r = _run_module(tmp_path / "does_not_exist.csv")
    assert r.returncode == 2 and r.stderr.count("\n") == 1


RESPONSE = ("level,excitation,omega2,zeta,response_amplitude,control,omega2_std,zeta_std\n"
            "1,3.0,1e5,0.010,1e-3,response,2.0,1e-5\n"
            "2,2.0,1e5,0.011,2e-3,response,2.0,1e-5\n"
            "3,2.5,1e5,0.012,4e-3,response,2.0,1e-5\n"
            "4,3.0,1e5,0.013,8e-3,response,2.0,1e-5\n")


def test_response_control_holds_the_response_amplitude(tmp_path):
    """Spec: under response control the excitation need not increase; the held
    amplitude (the abscissa) is the response amplitude, and the stds round-trip."""
    data = read_measured(write(tmp_path, RESPONSE))
    assert data.response_controlled
    np.testing.assert_array_equal(data.held_amplitude, [1e-3, 2e-3, 4e-3, 8e-3])
    np.testing.assert_array_equal(data.zeta_std, 1e-5)
    write_measured(tmp_path / "b.csv", data)
    back = read_measured(tmp_path / "b.csv")
    for name in ("omega2_std", "zeta_std", "response_amplitude", "excitation"):
        np.testing.assert_array_equal(getattr(back, name), getattr(data, name))
    assert back.response_controlled
    # a force-controlled file holds its excitation
    assert not read_measured(good(tmp_path)).response_controlled


@pytest.mark.parametrize("edit, column, message", [
    (lambda t: t.replace(",response_amplitude", "").replace(",1e-3,", ",").replace(",2e-3,", ",")
     .replace(",4e-3,", ",").replace(",8e-3,", ","), "response_amplitude", "needs a response"),
    (lambda t: t.replace("4,3.0,1e5,0.013,8e-3", "4,3.0,1e5,0.013,3e-3"), "response_amplitude",
     "does not exceed"),
    (lambda t: t.replace("2,2.0,1e5,0.011,2e-3,response", "2,2.0,1e5,0.011,2e-3,force"),
     "control", "mixes"),
    (lambda t: t.replace("3,2.5,1e5,0.012,4e-3,response", "3,2.5,1e5,0.012,4e-3,torque"),
     "control", "force or response"),
    (lambda t: t.replace("2.0,1e-5\n4", "0.0,1e-5\n4"), "omega2_std", "must be > 0"),
])
def test_response_control_rules(tmp_path, edit, column, message):
    text = error_of(write(tmp_path, edit(RESPONSE)))
    assert f":{column}:" in text and message in text, text


def test_repeats_are_legal_rows(tmp_path):
    """Repeats (spec measured-data.md): the same (mode, level) at another run order."""
    rows = [r + f",{i + 1}" for i, r in enumerate(ROWS)] + ["1,0.5,2.50679e6,0.012700,6"]
    d = read_measured(write(tmp_path, "\n".join([HEADER + ",run_order"] + rows) + "\n"))
    one = d.for_mode(1)
    assert list(one.level) == [1, 1, 2, 3, 4, 5] and list(one.run_order) == [1, 6, 2, 3, 4, 5]
    # the same run order twice is still a duplicate
    bad = rows + ["2,1.0,2.5e6,0.0128,2"]
    p = write(tmp_path, "\n".join([HEADER + ",run_order"] + bad) + "\n", "dup.csv")
    assert error_of(p) == f"{p}:8:level: duplicate (mode, level, run_order) = (1, 2, 2)"
    # a repeat must still lie below the next level's excitation
    bad = rows[:-1] + ["1,1.5,2.50679e6,0.012700,6"]
    p = write(tmp_path, "\n".join([HEADER + ",run_order"] + bad) + "\n", "order.csv")
    assert error_of(p) == (f"{p}:3:excitation: mode 1: excitation of level 2 (1) does not "
                           f"exceed that of level 1 (1.5)")
    # three distinct levels with repeats are still too few
    few = [r + f",{i + 1}" for i, r in enumerate(ROWS[:3])] + ["3,2.0,2.5e6,0.0128,9"]
    p = write(tmp_path, "\n".join([HEADER + ",run_order"] + few) + "\n", "few.csv")
    assert "mode 1 has 3 levels" in error_of(p)
