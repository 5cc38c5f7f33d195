"""The case-independent FE loop (feloop/) on a case file written from the spec
(docs/case-files/bolted-lap-cantilever.toml): ``uncertainty``, ``update --assumptions``
and ``diagnose --backbone`` on a table the project simulates from a seeded random chi
that the commands never see (the file's own nonlinear model, casefile.nonlinear:
Ritz basis and the file's damping, at phase resonance; Gaussian noise from the same
seed). No module of feloop/ imports a case; only its case-file glue imports the reader."""
from __future__ import annotations

import ast
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
LAP = ROOT / "docs" / "case-files" / "bolted-lap-cantilever.toml"
SEED = 2026
SIGMA_OMEGA2, SIGMA_ZETA = 2e-7, 2e-4      # relative noise of the planted table


#: the modules of feloop/ that read a case file (the rest knows no case and no format)
CASE_FILE_GLUE = {"case_file.py", "case_levels.py", "updated_model.py"}


def test_fe_loop_imports_no_case():
    """Generic means: no module of feloop/ imports ``cases``, and only the case-file glue
    imports ``casefile`` (tests/test_architecture.py checks the package rule as well)."""
    bad = []
    modules = sorted((ROOT / "feloop").glob("*.py"))
    assert len(modules) > len(CASE_FILE_GLUE)
    for path in modules:
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            bad += [f"{path.name}: {n}" for n in names if n.split(".")[0] == "cases"
                    or (n.split(".")[0] == "casefile" and path.name not in CASE_FILE_GLUE)]
    assert not bad, bad


@pytest.fixture(scope="module")
def planted(tmp_path_factory):
    """(csv path, planted chi, noise-free omega2, zeta): the file's joints with a chi drawn
    from ``SEED``, simulated at the forces of the file's table."""
    from casefile.nonlinear import nonlinear_case
    from cases.virtual_test import simulated_table
    from cases.registry import resolve_case
    from ident.measured import read_measured, write_measured

    rng = np.random.default_rng(SEED)
    chi = float(rng.uniform(-0.75, -0.3))
    case = resolve_case(str(LAP))
    data = read_measured(case.measured_data()).for_mode(2)
    cf, _ = case.builders["calibrated_file"]()
    cf = dataclasses.replace(cf, interfaces=tuple(dataclasses.replace(i, chi=chi)
                                                  for i in cf.interfaces))
    table = simulated_table(nonlinear_case(cf, case.fe_model()), data.excitation)
    truth = table.omega2.copy(), table.zeta.copy()
    table.omega2 = table.omega2 * (1 + SIGMA_OMEGA2 * rng.standard_normal(len(table)))
    table.zeta = table.zeta * (1 + SIGMA_ZETA * rng.standard_normal(len(table)))
    table.run_order = data.run_order
    table.mode[:] = 2                                 # the file's [measured] mode label
    path = tmp_path_factory.mktemp("planted") / "planted.csv"
    write_measured(path, table)
    return path, chi, truth


def _json(capsys, *argv):
    code = main([*map(str, argv), "--json"])
    out = capsys.readouterr().out
    assert code == 0
    return json.loads(out)


def _samples(store):
    from inverse.sample_store import SampleResult

    return [SampleResult.from_npz(f) for f in sorted(Path(store).glob("sample_*.npz"))]


def test_uncertainty_on_the_case_file(planted, capsys, tmp_path):
    """``uncertainty`` and ``update`` on the same file and levels agree: the nominal is
    update's selected model (its predictions at every level to 1e-9, its parameter
    values); the planted chi inside the samples' 5-95 % band and the noise-free truth at
    the held-out levels inside the Monte Carlo's band; every sample counted ok is
    physical (strength > 0, no level above its own stuck frequency f0_hz, no damping
    ratio below its viscous zeta_v, read back from the store); a rerun loads every
    sample (resumable) and gives the same numbers, and so does a pool of two processes
    (each sample from a cold start)."""
    path, chi, (om2, zeta) = planted
    argv = ("uncertainty", path, "--case", LAP, "--samples", 60, "--out", tmp_path,
            "--no-progress")
    r = _json(capsys, *argv)
    upd = _json(capsys, "update", "--case", LAP, "--data", path)
    # the file's own joint is named as the nominal one; each fitted value has its start
    assert "[interface.0] chi = -0.5, fs = 200 N, beta = 1" in upd["notes"][0]
    assert all("start" in p for p in upd["parameters"].values() if p["kind"] == "fitted")
    assert r["model"]["candidate"] == upd["model"]
    assert r["model"]["values"] == upd["fit"]["values"]
    for row, u in zip(r["levels"], upd["levels"]):
        assert row["nominal_frequency_hz"] == pytest.approx(u["model"]["frequency_hz"],
                                                            rel=1e-9)
        assert row["nominal_zeta"] == pytest.approx(u["model"]["zeta"], rel=1e-9)
    assert r["chi"]["lo"] < chi < r["chi"]["hi"]
    assert r["computed"] == 61 and r["n_failed"] <= 3
    f_true = np.sqrt(om2) / (2 * math.pi)
    for i, row in enumerate(r["levels"]):
        assert row["held_out"] == (i >= 7)
        if row["held_out"]:
            assert row["mc_frequency_hz"]["lo"] < f_true[i] < row["mc_frequency_hz"]["hi"]
            assert row["mc_zeta"]["lo"] < zeta[i] < row["mc_zeta"]["hi"]
    ok = [s for s in _samples(r["store"]) if s.ok]
    assert len(ok) == 60 - r["n_failed"]
    for s in ok:             # f0_hz and zeta_viscous: the sample's drawn parameters
        assert s.values["phi_max"] > 0 and s.values["F_S"] > 0
        assert np.all(s.values["frequency_hz"] <= s.values["f0_hz"] * (1 + 1e-9))
        assert np.all(s.values["zeta"] >= s.values["zeta_viscous"] * (1 - 1e-9))
    again = _json(capsys, *argv)
    assert again["computed"] == 0 and again["levels"] == r["levels"]
    pool = _json(capsys, *argv[:-3], "--out", tmp_path / "pool", "--no-progress",
                 "--executor", "processes", "--workers", "2")
    assert pool["computed"] == 61 and pool["levels"] == r["levels"]   # bit for bit


def test_update_assumptions_on_the_case_file(planted, capsys):
    """``update --case FILE --data T --assumptions``: chi within 0.05 of the planted one
    (its profile or linearized interval holds it), and each assumed property refitted:
    E, rho of the one material (-/+ 3 %, -/+ 2 %) and the exciter mass (x 0.5, x 2)."""
    path, chi, _ = planted
    s = _json(capsys, "update", "--case", LAP, "--data", path, "--assumptions")
    c = s["parameters"]["chi"]
    assert abs(c["value"] - chi) < 0.05 and c["interval"][0] < chi < c["interval"][1]
    names = [a["assumption"] for a in s["assumptions"]]
    assert [n.split()[0] for n in names] == ["material.0.E"] * 2 + ["material.0.rho"] * 2 \
        + ["mass.0.mass"] * 2
    for a in s["assumptions"]:
        assert math.isfinite(a["delta_chi2"]) and len(a["held_out_frequency_hz"]) == 3


def test_assumed_properties_move_the_stuck_frequency_as_physics_says():
    """The variants' stuck frequency against closed-form bounds: E x 1.03 scales the
    strips' stiffness only (the joints' kt stays), so omega^2 rises by a factor in (1,
    1.03]; rho x 1.02 scales the strips' mass only (the exciter mass stays): omega^2
    falls by a factor in [1/1.02, 1); a heavier exciter lowers it."""
    from feloop.case_file import assumption_variants
    from cases.registry import resolve_case
    from ident.measured import read_measured

    case = resolve_case(str(LAP))
    data = read_measured(case.measured_data()).for_mode(2)
    w2 = {name: levels(data).linear(1e7).omega_k ** 2
          for name, (_, levels) in assumption_variants(case.file).items()}
    w2_0 = case.builders["fe_levels"](data).linear(1e7).omega_k ** 2
    r = {n.split(" (")[0]: w / w2_0 for n, w in w2.items()}
    assert 1.0 < r["material.0.E 7.21e+10"] <= 1.03 * (1 + 1e-12)
    assert 1.0 / 1.02 * (1 - 1e-12) <= r["material.0.rho 2754"] < 1.0
    assert r["mass.0.mass 0.03"] < 1.0 < r["mass.0.mass 0.0075"]


def test_diagnose_backbone_on_the_case_file(planted, capsys):
    """``diagnose T --case FILE --backbone``: the joint estimated from levels 1-7 (chi
    within 0.06 of the planted one) read off the EPMC backbone: level 1 matched, the
    held-out levels' omega^2 loss from level 1 within 5 % of the noise-free truth's, and
    their zeta within 0.5 %."""
    path, chi, (om2, zeta) = planted
    bb = _json(capsys, "diagnose", path, "--case", LAP, "--backbone")["backbone"]
    assert abs(bb["chi"] - chi) < 0.06
    lv = bb["levels"]
    assert [r["held_out"] for r in lv] == [False] * 7 + [True] * 3
    assert lv[0]["omega2"] == pytest.approx(lv[0]["measured_omega2"], rel=1e-6)
    assert lv[0]["zeta"] == pytest.approx(lv[0]["measured_zeta"], rel=2e-4)
    loss = lv[0]["omega2"] - np.array([r["omega2"] for r in lv])
    true_loss = om2[0] - om2
    assert np.all(np.abs(loss[7:] / true_loss[7:] - 1) < 0.05)
    assert np.all(np.abs(np.array([r["zeta"] for r in lv[7:]]) / zeta[7:] - 1) < 5e-3)


@pytest.mark.parametrize("argv, words", [
    (("uncertainty", "--case", "lumped", "--samples", "2"), "no Monte Carlo"),
    (("diagnose", str(ROOT / "cases" / "data" / "double_beam_measured.csv"), "--case",
      "lumped", "--backbone"), "no FE-levels model"),
    (("uncertainty", "--case", str(LAP), "--df", "0.5"), "--df: only for a case with"),
])
def test_a_case_without_the_capability_says_so_in_one_line(capsys, argv, words):
    code = main(list(argv))
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err


def test_estimate_with_the_case_file_as_fe_model(planted, capsys):
    """``estimate --case FILE``: B~ and R~ from the file's FE model. The FE mode is the
    measured one (its stiff-joint frequency within 0.5 % of level 1), the planted chi lies
    in the interval, and B~ and R~ are positive and finite."""
    path, chi, (omega2, _) = planted
    out = _json(capsys, "estimate", path, "--case", LAP)
    assert out["case"]["fe_mode"] == 2
    assert abs(out["case"]["fe_frequency_hz"] / (np.sqrt(omega2[0]) / (2 * np.pi)) - 1) < 5e-3
    lo, hi = out["chi_interval"]
    assert lo <= chi <= hi
    assert math.isfinite(out["R"]) and out["R"] > 0 and out["B"] > 0


def test_measured_frf_files_named_by_a_pattern_are_identified(planted, tmp_path, capsys,
                                                              monkeypatch):
    """``[measured] file = "frf/level_*.csv"``: the FRF files of a series (one per level,
    synthesized here as the planted table's single modes: receptance
    ``1 / (omega2 - w^2 + 2 i zeta sqrt(omega2) w)``) are identified by LSCF into the
    table the FE loop reads: every level's frequency within 1e-6 and damping within 1 %
    of the file's; ``update --case FILE`` on it recovers the planted chi within 0.05;
    the table is cached."""
    from ident.frf_files import FRFSet, write_frf
    from ident.measured import read_measured

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    table = read_measured(planted[0])
    (tmp_path / "frf").mkdir()
    for k in range(len(table)):
        w0, z = np.sqrt(table.omega2[k]), table.zeta[k]
        f = np.linspace(0.97, 1.03, 301) * w0 / (2 * np.pi)
        w = 2 * np.pi * f
        H = 1e-3 / (w0 ** 2 - w ** 2 + 2j * z * w0 * w)
        write_frf(tmp_path / "frf" / f"level_{k + 1:02d}.csv",
                  FRFSet(f, H[:, None], ["1"], quantity="receptance",
                         excitation=float(table.excitation[k]), reference="1",
                         control="force", run_order=int(table.run_order[k])))
    text = LAP.read_text()
    start = text.index("[measured]")
    line = next(x for x in text[start:].splitlines() if x.startswith("file"))
    case_file = tmp_path / "lap.toml"
    case_file.write_text(text.replace(line, 'file = "frf/level_*.csv"'))
    from cases.registry import resolve_case

    path = resolve_case(str(case_file)).measured_data()
    got = read_measured(path)
    assert len(got) == len(table)
    assert np.allclose(np.sqrt(got.omega2 / table.omega2), 1, atol=1e-6)
    assert np.allclose(got.zeta / table.zeta, 1, atol=1e-2)
    assert resolve_case(str(case_file)).measured_data() == path         # cached
    c = _json(capsys, "update", "--case", case_file)["parameters"]["chi"]
    assert abs(c["value"] - planted[1]) < 0.05


@pytest.mark.parametrize("n_levels, fitted", [(9, [1, 2, 3, 4, 5, 6]), (7, [1, 2, 3, 4, 5]),
                                              (5, [1, 2, 3, 4, 5])])
def test_default_fit_levels_hold_out_the_top_three_and_count_a_repeat_once(
        tmp_path, n_levels, fitted):
    """All but the top three levels, at least 5 fitted (feloop/case_file.py); a
    repeated level (a legal row, measured-data spec) is one level, not two."""
    from feloop.case_file import _defaults
    from casefile.schema import read_case_file

    rows = [(v, v) for v in range(1, n_levels + 1)] + [(2, n_levels + 1)]   # level 2 again
    lines = ["mode,level,excitation,omega2,zeta,run_order"] + [
        f"2,{v},{0.1 * v},{1e6 * (1 - 1e-3 * v)},{0.01 + 1e-3 * v},{k}" for v, k in rows]
    csv = tmp_path / "levels.csv"
    csv.write_text("\n".join(lines) + "\n")
    got = _defaults(read_case_file(LAP), csv)["fit_levels"]
    assert got == ",".join(map(str, fitted))


@pytest.mark.parametrize("change, words", [
    ({}, None),
    ({"slip_scale": 0.0}, "no joint"),
    ({"F_S": -1.0}, "no joint"),
    ({"frequency_hz": 80.0 * (1 + 1e-4)}, "above the stuck-joint frequency"),
    ({"zeta": 0.002 * (1 - 1e-4)}, "below the viscous one"),
])
def test_an_unphysical_sample_is_a_failure_with_its_reason(change, words):
    """What the user's steel lap sample 9 showed (phi_max 5e-45 m, a level above its own
    stuck frequency, a damping ratio below the viscous one): each is a ValueError
    naming it (counted as a failed sample, left out of the quantiles); a softening,
    dissipating prediction passes; a stiffening cause may pass the stuck frequency."""
    from feloop.causes import EXTENSIONS
    from feloop.levels import LevelPrediction
    from feloop.uncertainty import physical_check

    f = np.array([79.99, 79.9, 79.5])
    z = np.array([0.00201, 0.0025, 0.004])
    joint = {"slip_scale": 1e-6, "F_S": 10.0}       # slip_scale: phi_max of Iwan joints
    if "frequency_hz" in change:
        f[1] = change["frequency_hz"]
    if "zeta" in change:
        z[2] = change["zeta"]
    joint.update({k: v for k, v in change.items() if k in joint})
    pred = LevelPrediction((2 * math.pi * f) ** 2, z, np.ones(3), joint)
    values = {"f0_hz": 80.0, "zeta_v": 0.002}
    if words is None:
        physical_check(pred, values)
        return
    with pytest.raises(ValueError, match=words):
        physical_check(pred, values)
    stiffens = EXTENSIONS["geometric-hardening"].stiffens
    assert stiffens and not EXTENSIONS["quadratic-damping"].stiffens
    if "slip_scale" not in change and "F_S" not in change:
        physical_check(pred, values, stiffens)
