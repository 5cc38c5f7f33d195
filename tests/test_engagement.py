"""Engagement (feloop.engagement): the largest loss of omega^2 the joints can
give a mode, and the contradiction when the data lose more.

Truth: the full FE model's eigen-solve with the joints' stiffness removed (a second
method: the check uses the reduced basis), the monotonicity of the tracked eigenvalue
in the joint stiffness, and tables whose loss of omega^2 is scaled by a seeded factor
the code under test never sees."""
from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl

from feloop.engagement import engagement, slipped_omega2_ratio
from feloop.select import fe_noise
from cases.registry import resolve_case
from ident.measured import read_measured, write_measured

ROOT = Path(__file__).resolve().parents[1]
LAP = ROOT / "docs" / "case-files" / "bolted-lap-cantilever.toml"


def _levels(name, mode):
    case = resolve_case(str(name))
    data = read_measured(case.measured_data()).for_mode(mode)
    return case, data, case.builders["fe_levels"](data)


def _dense(a):
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a)


@pytest.mark.parametrize("name, mode", [(LAP, 2), ("brb", 4)])
def test_reduced_bound_is_the_full_models_slipped_mode(name, mode):
    """The slipped omega^2 of the reduced model against the full FE model without its
    joints (dense generalized eigen-solve, the mode of largest mass-weighted MAC with
    the stuck mode): the loss agrees within 5e-4 relative (measured 4e-5, 2.6e-4)."""
    from casefile.build import build_model
    from casefile.calibrate import calibrate

    _, _, fe = _levels(name, mode)
    lin = fe.linear(fe.default_kt)
    model = build_model(calibrate(fe.cf)[0]).model
    M = _dense(model.M)
    omega, shapes = model.modes(lin.fe_mode)
    phi = shapes[:, lin.fe_mode - 1]
    w2, V = sl.eigh(_dense(model.K_without_joints), M)
    mac = (V.T @ M @ phi) ** 2 / (phi @ M @ phi)
    full = 1.0 - w2[np.argmax(mac)] / omega[lin.fe_mode - 1] ** 2
    assert mac.max() > 0.99
    assert abs((1.0 - slipped_omega2_ratio(lin)) / full - 1.0) < 5e-4


def test_partly_slipped_joints_lie_between_stuck_and_slipped():
    """Joint stiffness scaled by c in (0, 1) (a partly slipping joint's in-phase
    stiffness): the followed mode's omega^2 falls monotonically from stuck to slipped."""
    _, _, fe = _levels(LAP, 2)
    lin = fe.linear(fe.default_kt)
    red = lin.red
    KJ = red.G.T @ (red.K_T[:, None] * red.G)
    ratios = []
    for c in (1.0, 0.7, 0.4, 0.1, 0.0):
        K = red.K - (1.0 - c) * KJ
        w2, V = np.linalg.eigh(0.5 * (K + K.T))
        ratios.append(w2[np.argmax(np.abs(V[lin.k]))] / lin.omega_k ** 2)
    assert ratios[0] == pytest.approx(1.0, rel=1e-9)
    assert np.all(np.diff(ratios) < 0)
    assert ratios[-1] == pytest.approx(slipped_omega2_ratio(lin), rel=1e-12)


@pytest.mark.parametrize("name, mode, loss_model, loss_data", [
    ("double-beam", 2, 0.0756, 3.58e-4), ("brb", 4, 0.245, 0.0934), (LAP, 2, 0.00291, 6.27e-4)])
def test_shipped_cases_are_engaged(name, mode, loss_model, loss_data):
    """The numbers docs/fe-loop.md quotes (1 % relative). The data's loss is checked
    against the table itself (numpy on its omega2 column); the model's bounds are a
    guard of the quoted numbers (their truth: the full-model test above)."""
    _, data, fe = _levels(name, mode)
    e = engagement(data, fe, fe_noise(data)[1], 1e11)
    table = read_measured(_levels(name, mode)[0].measured_data())
    omega2 = table.omega2[table.mode == mode]
    assert e.loss_data == pytest.approx(1 - omega2.min() / omega2.max(), rel=1e-12)
    assert e.verdict == "engaged" and np.isnan(e.K_T_stiffest)
    assert e.loss_model == pytest.approx(loss_model, rel=1e-2)
    assert e.loss_data == pytest.approx(loss_data, rel=1e-2)


def _lap_with_loss_scaled(tmp_path, factor):
    """The lap case file with its table's loss of omega^2 below level 1 times
    ``factor``."""
    d = read_measured(LAP.parent / "bolted-lap-cantilever-levels.csv")
    d.omega2 = d.omega2[0] - (d.omega2[0] - d.omega2) * factor
    write_measured(tmp_path / "weak.csv", d)
    text = LAP.read_text().replace("bolted-lap-cantilever-levels.csv", "weak.csv")
    (tmp_path / "weak.toml").write_text(text)
    return tmp_path / "weak.toml", tmp_path / "weak.csv"


def test_weakly_engaged_mode_is_a_contradiction_not_a_fit(tmp_path, capsys):
    """A loss of omega^2 several times what fully slipped joints can give (seeded factor
    8-20 on the lap's measured loss, 0.063 %): update, diagnose --case and loop stop
    with one line naming both numbers, exit 2, and nothing fitted is printed."""
    from cli.main import main

    factor = np.random.default_rng(20261202).uniform(8.0, 20.0)
    case, table = _lap_with_loss_scaled(tmp_path, factor)
    for argv in (["update", "--case", str(case), "--json"],
                 ["diagnose", str(table), "--case", str(case), "--json"],
                 ["loop", "--case", str(case), "--out", str(tmp_path / "loop"), "--json"]):
        assert main(argv) == 2, argv
        out, err = capsys.readouterr()
        assert out == "" and err.count("\n") == 1, argv
        loss = re.search(r"lower omega\^2 by ([0-9.]+) \+- ([0-9.]+) %", err)
        assert float(loss.group(1)) == pytest.approx(100 * 6.27e-4 * factor, rel=0.02), err
        assert "by at most 0.291 % (computed)" in err and "contradiction" in err


def test_a_loss_within_the_bound_is_engaged(tmp_path):
    """Twice the lap's measured loss (0.13 % < 0.29 %): engaged."""
    case, table = _lap_with_loss_scaled(tmp_path, 2.0)
    _, data, fe = _levels(case, 2)
    e = engagement(data, fe, fe_noise(data)[1])
    assert e.verdict == "engaged" and e.loss_data < e.loss_model
