"""Case files against independent truth: analytic Euler-Bernoulli frequencies of a single
strip (cantilever and free-free), a tied lap equal to the monolithic beam, stiffness
shares summing to kt, the double beam's case file equal to its Python model, calibration
reaching its target, and the Case face's one-line refusals."""
from __future__ import annotations

import numpy as np
import pytest

from casefile.build import build_model
from casefile.calibrate import calibrate
from casefile.schema import read_case_file
from casefile.tables import CaseFileError
from cases.registry import resolve_case
from ident.errors import InputError

BETA_L_CANTILEVER = np.array([1.8751040687, 4.6940911330, 7.8547574382])
BETA_L_FREE = np.array([4.7300407449, 7.8532046241, 10.9956078380])
E, RHO, B, H, L = 70e9, 2700.0, 0.03, 0.005, 0.4


def _single(tmp_path, support: str, element_size=0.005):
    text = f"""[case]
name = "strip"
[[material]]
name = "al"
E = {E}
rho = {RHO}
[[beam]]
name = "a"
material = "al"
x = [0.0, {L}]
width = {B}
thickness = {H}
{support}
[mesh]
element_size = {element_size}
"""
    p = tmp_path / "strip.toml"
    p.write_text(text)
    return p


def _analytic(beta_l):
    return beta_l**2 / (2 * np.pi * L**2) * np.sqrt(E * H**2 / (12 * RHO))


def test_single_strip_cantilever_matches_the_closed_form(tmp_path):
    p = _single(tmp_path, '[[support]]\nbeam = "a"\nkind = "clamp"\nx = [0.0, 0.0]')
    model = build_model(read_case_file(p)).model
    omega, shapes = model.modes(6)
    order = model.bending_order(omega, shapes)
    f = np.array([omega[order == k][0] for k in (1, 2, 3)]) / (2 * np.pi)
    np.testing.assert_allclose(f, _analytic(BETA_L_CANTILEVER), rtol=1e-6)


def test_single_strip_free_free_matches_the_closed_form(tmp_path):
    model = build_model(read_case_file(_single(tmp_path, ""))).model
    omega, shapes = model.modes(8)
    assert np.sum(omega < 1e-3 * omega.max()) == 3          # u, w, rotation
    order = model.bending_order(omega, shapes)
    f = np.array([omega[order == k][0] for k in (1, 2, 3)]) / (2 * np.pi)
    np.testing.assert_allclose(f, _analytic(BETA_L_FREE), rtol=1e-6)


def test_tied_lap_equals_the_monolithic_beam(tmp_path):
    """A BRB-style lap (each strip notched to half thickness over the lap), bonded:
    the free-free frequencies of the uniform strip of the full length."""
    lap = f"""[case]
name = "tied-lap"
[[material]]
name = "al"
E = {E}
rho = {RHO}
[[beam]]
name = "left"
material = "al"
x = [0.0, 0.24]
width = {B}
thickness = {H}
[[beam.section]]
x = [0.16, 0.24]
thickness = {H / 2}
z = {-H / 4}
[[beam]]
name = "right"
material = "al"
x = [0.16, {L}]
width = {B}
thickness = {H}
[[beam.section]]
x = [0.16, 0.24]
thickness = {H / 2}
z = {H / 4}
[[interface]]
beams = ["left", "right"]
x = [0.16, 0.24]
normal = "tied"
tangential = "tied"
[mesh]
element_size = 0.0025
"""
    p = tmp_path / "lap.toml"
    p.write_text(lap)
    model = build_model(read_case_file(p)).model
    omega, _ = model.modes(8)
    f = omega[3:6] / (2 * np.pi)
    np.testing.assert_allclose(f, _analytic(BETA_L_FREE), rtol=2e-3)


def test_stiffness_shares_sum_to_kt_trapezoidal_and_equal():
    cf = read_case_file("cases/double_beam/double-beam.toml")
    built = build_model(cf)
    shares = np.array([j["share"] for j in built.joint_table])
    np.testing.assert_allclose(shares, [0.125, 0.25, 0.25, 0.25, 0.125], rtol=1e-12)
    assert built.model.joint_stiffness.sum() == pytest.approx(cf.interfaces[1].kt, rel=1e-14)
    brb_file = read_case_file("cases/brb/brb.toml")    # the bolt patch's joints, lap ends open
    brb = build_model(brb_file)
    assert brb.model.joint_stiffness.sum() == pytest.approx(
        sum(i.kt for i in brb_file.interfaces if i.tangential == "joint"), rel=1e-14)


def test_double_beam_case_file_equals_its_python_model():
    from cases.double_beam.model import CALIBRATED_CLAMP_LENGTH, build_double_beam

    cf, report = calibrate(read_case_file("cases/double_beam/double-beam.toml"))
    assert report["converged"]
    assert report["parameters"][0]["calibrated"] == pytest.approx(CALIBRATED_CLAMP_LENGTH, abs=5e-8)
    model, ref = build_model(cf).model, build_double_beam()
    assert model.M.shape == ref.M.shape
    np.testing.assert_array_equal(model.slip_matrix.toarray(), ref.slip_matrix.toarray())
    assert (model.drive_dof, model.response_dof) == (ref.drive_dof, ref.response_dof)
    np.testing.assert_allclose(model.joint_stiffness, ref.joint_stiffness, rtol=1e-14)
    w, _ = model.modes(10)
    w_ref, _ = ref.modes(10)
    # the grip rounded to 7 digits in the Python model (1e-7), and round-off: the 62.56 Hz
    # mode of either model moves by up to 8e-7 between shift-invert shifts -1 .. -1e6
    np.testing.assert_allclose(w, w_ref, rtol=2e-6)


def test_cantilever_lap_case_from_the_spec_runs_the_face():
    case = resolve_case("docs/case-files/bolted-lap-cantilever.toml")
    s = case.summary()
    assert s["joint_stiffness_total"] == pytest.approx(1.0e7)
    assert s["mass_kg"] == pytest.approx(2 * 0.3 * 0.03 * 0.005 * 2700 + 0.015)
    nc = case.nonlinear_model(mode=2)
    assert nc.mode == 2 and len(nc.joints) == 2


def test_capability_missing_is_one_line():
    with pytest.raises(InputError, match="case 'lumped' has no FE strip model"):
        resolve_case("lumped").fe_model()
    with pytest.raises(InputError, match="unknown case 'nope'"):
        resolve_case("nope")


def test_convergence_against_the_finest_mesh_is_reached_at_the_coarsest():
    """A lap whose tied contact keeps one slope: the lap cantilever's first six modes
    change by less than 2e-5 from 5 mm to 0.625 mm elements, or by less than ten times
    their round-off, and no mode is warned about (before the rotation tie: 2e-3, falling
    as h^2)."""
    from cases.case_convergence import case_convergence

    r = case_convergence(resolve_case("docs/case-files/bolted-lap-cantilever.toml"), levels=4)
    change = np.array(r["relative_change_vs_finest"])
    # the 14 Hz mode's frequency at 0.625 mm is round-off limited (two shifts: 5e-5)
    noise = 10 * np.maximum(r["roundoff_estimate"][:-1], r["roundoff_estimate"][-1])
    assert np.all((change[:-1] < 2e-5) | (change[:-1] < noise)) and np.all(change[-1] == 0.0)
    assert not [w for w in r["warnings"] if w.startswith("WARNING")]
    assert r["element_size_m"] == [0.005, 0.0025, 0.00125, 0.000625]


def test_convergence_table_decides_round_off_on_a_bound_not_on_a_sample():
    """The lap's round-off is judged against the componentwise bound eps |phi|^T|K||phi|
    / (2 lambda), the same on every machine; the two-shift estimate (a sample of the
    round-off, which moved a change across the old 10x line between BLAS kernels) stays
    below 0.3 of it. A change within 3 bounds reads round-off and its rate '-'."""
    from cases.case_convergence import (FLOOR_MARGIN, case_convergence,
                                        format_case_convergence, roundoff_floor)

    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    phi = np.array([[1.0], [1.0]]) / np.sqrt(2.0)           # lambda = 1 with M = I
    assert roundoff_floor(K, [1.0], phi)[0] == pytest.approx(np.finfo(float).eps * 3.0 / 2)
    r = case_convergence(resolve_case("docs/case-files/bolted-lap-cantilever.toml"), levels=4)
    floor, sample = np.array(r["roundoff_floor"]), np.array(r["roundoff_estimate"])
    assert np.all(sample < 0.3 * floor)
    change = np.array(r["relative_change_vs_finest"])[:-1]
    table = format_case_convergence(r).splitlines()
    rows = [ln.split() for ln in table[3::2][:3]]          # the change rows, coarsest first
    for k, row in enumerate(rows):
        for j, word in enumerate(row):
            resolved = change[k, j] > FLOOR_MARGIN * (floor[k, j] + floor[-1, j])
            assert (word != "round-off") == resolved
    rate = table[2 * len(r["element_size_m"]) + 2].split()[1:]
    assert rate[0] == "-" and len(rate) == 6


def test_case_check_and_modes_on_the_command_line(capsys):
    import json

    from cli.main import main

    assert main(["case", "check", "docs/case-files/bolted-lap-cantilever.toml", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    kinds = {p["parameter"]: p["kind"] for p in s["parameters"]}
    assert kinds["interface.0.kt"] == "given" and kinds["sensor.0.mass"] == "default"
    assert main(["modes", "--case", "brb", "--band", "0", "700", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["bending_order"] for r in rows if r["frequency_hz"] > 1] == [1, 2]


CLAMPED_LAP = """[case]
name = "al-lap-calibrate"
[[material]]
name = "al"
E = 70e9
rho = 2700.0
[[beam]]
name = "lower"
material = "al"
x = [0.0, 0.300]
width = 0.030
thickness = 0.005
[[beam]]
name = "upper"
material = "al"
x = [0.240, 0.540]
width = 0.030
thickness = 0.005
z = 0.005
[[support]]
beam = "lower"
kind = "clamp"
x = [0.0, 0.005]
[[interface]]
beams = ["lower", "upper"]
x = [0.240, 0.300]
normal = "tied"
tangential = "joint"
joints_at = [0.250, 0.270, 0.290]
law = "iwan4"
kt = 1.0e7
chi = -0.3
fs = 80.0
beta = 1.0
[[mass]]
beam = "lower"
x = 0.100
mass = 0.010
label = "exciter"
[[sensor]]
beam = "upper"
x = 0.540
label = "laser"
[mesh]
element_size = 0.005
[calibrate]
parameters = ["support.0.x", "mass.0.mass"]
frequencies_hz = {targets}
"""


def _with_calibration(tmp_path, text: str):
    p = tmp_path / "cal.toml"
    p.write_text(open("docs/case-files/bolted-lap-cantilever.toml").read().split("\n[measured]")[0]
                 + text)
    return read_case_file(p)


def test_calibration_reaches_its_target_and_says_when_it_cannot(tmp_path):
    cf = _with_calibration(tmp_path, '\n[calibrate]\nparameters = ["mass.0.mass"]\n'
                                     'frequencies_hz = [13.5]\n')
    assert cf.kinds["mass.0.mass"][0] == "calibrated"
    out, report = calibrate(cf)
    assert report["converged"] and report["targets"][0]["bending_mode"] == 1
    m = out.masses[0].mass
    assert m > 0.015                                  # heavier exciter, lower frequency
    model = build_model(out).model                    # a second build at that mass
    assert model.bending_mode_frequency(1) == pytest.approx(13.5, rel=1e-6)
    cf = _with_calibration(tmp_path, '\n[calibrate]\nparameters = ["mass.0.mass"]\n'
                                     'frequencies_hz = [40.0]\n')
    # no exciter mass >= 0 lifts mode 1 from 13.9 to 40 Hz: one line naming [calibrate]
    with pytest.raises(CaseFileError, match=r"\[calibrate\]: failed .* relative frequency "
                                            r"error \d\.\d\de-01 remains .* at mass\.0\.mass = "):
        calibrate(cf)


def test_a_failed_calibration_stops_every_command_that_needs_it(tmp_path, capsys):
    """``case check`` and ``modes`` exit 2 with the one line naming [calibrate] and label
    nothing calibrated; ``modes --uncalibrated`` (the file's values) still runs."""
    from cli.main import main

    p = tmp_path / "cal.toml"
    p.write_text(open("docs/case-files/bolted-lap-cantilever.toml").read().split("\n[measured]")[0]
                 + '\n[calibrate]\nparameters = ["mass.0.mass"]\nfrequencies_hz = [40.0]\n')
    for command in (["case", "check", str(p)], ["modes", "--case", str(p)]):
        assert main(command) == 2
        captured = capsys.readouterr()
        (line,) = captured.err.strip().splitlines()
        assert "[calibrate]: failed" in line and "calibrated" not in captured.out
    assert main(["modes", "--case", str(p), "--uncalibrated"]) == 0
    assert "uncalibrated model" in capsys.readouterr().out


def test_two_parameter_calibration_recovers_a_planted_truth_on_a_fine_mesh(tmp_path):
    """An outside user's clamped lap (clamp end and exciter mass unknown) at 1.25 mm
    elements: targets made by the model at the planted clamp end 0.015 m and mass 0.025 kg,
    started from 0.005 m and 0.010 kg. Finite-difference steps of 1e-6 relative were below
    the eigen-solution's round-off: nothing moved (14.19 Hz), at 0.625 mm it stopped at
    0.0082 m / 0.0031 kg."""
    import dataclasses

    from casefile.calibrate import _bending_frequencies
    from casefile.parameters import set_parameter

    text = CLAMPED_LAP
    p = tmp_path / "lap.toml"
    p.write_text(text.format(targets="[14.0, 90.0]"))
    cf = dataclasses.replace(read_case_file(p), element_size=0.00125)
    truth = set_parameter(set_parameter(cf, "support.0.x", 0.015), "mass.0.mass", 0.025)
    targets = _bending_frequencies(truth, 2)
    p.write_text(text.format(targets=f"[{float(targets[0])!r}, {float(targets[1])!r}]"))
    out, report = calibrate(dataclasses.replace(read_case_file(p), element_size=0.00125))
    assert report["converged"] and report["max_relative_error"] < 1e-5
    assert out.supports[0].x[1] == pytest.approx(0.015, rel=1e-4)
    assert out.masses[0].mass == pytest.approx(0.025, rel=1e-3)


def test_air_drag_integral_counts_a_lap_once():
    """``lambda3 = int b |w|^3 dx`` over the projected area: on the lap cantilever (normal
    tied by a penalty, so both strips share ``w`` there to 1e-7) it is the two strips'
    integrals less the narrower strip's over the lap, evaluated here strip by strip."""
    from feloop.case_levels import _lambda3

    cf = read_case_file("docs/case-files/bolted-lap-cantilever.toml")
    model = build_model(cf).model
    x0, x1 = cf.interfaces[0].x
    _, shapes = model.modes(3)
    for phi in shapes.T:
        parts, laps = [], []
        for mesh, disp in zip(model.strip_meshes, model.strip_displacements(phi)):
            x, b = np.asarray(mesh.x, float), float(np.mean(mesh.width))
            w3 = b * np.abs(disp["w"]) ** 3
            on = (x >= x0 - 1e-12) & (x <= x1 + 1e-12)
            parts.append(np.trapezoid(w3, x))
            laps.append(np.trapezoid(w3[on], x[on]))
        assert _lambda3(model, phi) == pytest.approx(sum(parts) - min(laps), rel=1e-6)


def test_convergence_warns_on_a_spectrum_that_does_not_converge():
    """Planted sequences: an h^4 sequence passes; the outside user's lap whose steps grew
    (213.9448, 213.9422, 213.9385, 213.9321 Hz at 4, 1, 0.5, 0.25 mm) and a mode that
    jumped (634.40, 634.40, 635.18, 634.40 Hz) are warned about; changes at round-off are
    noted as converged."""
    from cases.case_convergence import convergence_warnings

    def report(f, roundoff=1e-10):
        f = np.asarray(f, float)[:, None]
        change = np.abs(f / f[-1] - 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            return convergence_warnings(change, np.log2(change[-3] / change[-2]),
                                        np.full(f.shape, roundoff), [0.004, 0.002, 0.001, 0.0005])

    h = 0.004 / 2.0 ** np.arange(4)
    assert report(100.0 * (1 + (h / 0.1) ** 4)) == []
    for bad in ([213.9448, 213.9422, 213.9385, 213.9321], [634.40, 634.40, 635.18, 634.40]):
        w = report(bad)
        assert len(w) == 1 and w[0].startswith("WARNING mode 1: does not converge")
    (note,) = report([634.39590, 634.39591, 634.39589, 634.39590], roundoff=1e-7)
    assert "round-off" in note and not note.startswith("WARNING")
    (w,) = report([634.40, 634.40, 661.18, 634.40], roundoff=0.04)   # two shifts disagree
    assert w.startswith("WARNING mode 1: two eigen-solutions differ by 4.0e-02")


def test_case_check_reads_and_checks_the_measured_table(tmp_path, capsys):
    """``case check`` reads the file's ``[measured]`` table against the measured-data spec:
    a NaN in it is one line naming file, line and column (exit 2), as every other command
    that reads it would say; the good table is reported with its modes and levels."""
    import shutil
    from pathlib import Path

    from cli.main import main

    src = Path(__file__).resolve().parents[1] / "docs" / "case-files"
    shutil.copy(src / "bolted-lap-cantilever.toml", tmp_path)
    table = (src / "bolted-lap-cantilever-levels.csv").read_text().splitlines()
    (tmp_path / "bolted-lap-cantilever-levels.csv").write_text("\n".join(table) + "\n")
    case = str(tmp_path / "bolted-lap-cantilever.toml")
    assert main(["case", "check", case]) == 0
    out = capsys.readouterr().out
    assert f"measured data: {tmp_path / 'bolted-lap-cantilever-levels.csv'} read and " \
           f"checked ({len(table) - 1} rows; mode 2: {len(table) - 1} levels)" in out
    header = table[0].split(",")
    row = table[3].split(",")
    row[header.index("zeta")] = "nan"
    table[3] = ",".join(row)
    (tmp_path / "bolted-lap-cantilever-levels.csv").write_text("\n".join(table) + "\n")
    assert main(["case", "check", case]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"iwanfe: error: {tmp_path / 'bolted-lap-cantilever-levels.csv'}:4:zeta: "
                   "not a finite number: 'nan'"]


def test_case_check_says_when_the_declared_mode_is_not_the_one_the_data_lie_nearest(
        tmp_path, capsys):
    """The lap's table was measured on bending mode 2; a file declaring ``mode = 3`` is
    told that the table's lowest level lies nearest bending mode 2, which the FE loop
    follows; the file as shipped (``mode = 2``) is not."""
    import shutil
    from pathlib import Path

    from cli.main import main

    src = Path(__file__).resolve().parents[1] / "docs" / "case-files"
    shutil.copy(src / "bolted-lap-cantilever-levels.csv", tmp_path)
    text = (src / "bolted-lap-cantilever.toml").read_text()
    assert "\nmode = 2" in text
    for mode, warned in ((2, False), (3, True)):
        case = tmp_path / f"lap{mode}.toml"
        case.write_text(text.replace("\nmode = 2", f"\nmode = {mode}"))
        assert main(["case", "check", str(case)]) == 0
        out = capsys.readouterr().out
        assert (f"warning: [measured] mode = {mode} (bending mode {mode}) but the table's "
                f"lowest level" in out) == warned
        if warned:
            assert "lies nearest bending mode 2" in out
