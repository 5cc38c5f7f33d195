"""``iwanfe frc``: JSON form, the curve against another solver (the exact first-harmonic
balance of ``fe.hb_exact``, the Iwan describing function), one-line errors."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cli.main import main
from fe.hb_exact import solve_hb_exact
from fe.reduction import ReducedModel
from joints.iwan import IwanParameters


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_frc_json_against_the_describing_function(capsys):
    code, out, _ = run_cli(capsys, "frc", "--force", "1.5", "--harmonics", "1", "--n-time",
                           "256", "--range", "6", "9", "--json")
    assert code == 0
    d = json.loads(out)
    (curve,) = d["curves"]
    assert curve["force_N"] == 1.5 and curve["folds"] == []
    pts = curve["points"]
    assert len(pts) > 10
    for p in pts:
        assert {"frequency_hz", "amplitude", "peak", "max_multiplier", "stable"} <= set(p)
    assert pts[0]["frequency_hz"] == pytest.approx(6.0) and \
        pts[-1]["frequency_hz"] == pytest.approx(9.0)
    assert all(p["stable"] for p in pts)
    amp = np.array([p["amplitude"] for p in pts])
    assert amp.max() > 8 * d["model"]["phi_max_m"]                  # macro-slip (8.4)
    prm = IwanParameters(-0.5, 2000.0, 1.0, 1.0)
    k = 4000.0
    model = ReducedModel(basis=np.eye(1), omega=np.array([math.sqrt(k)]), M=np.eye(1),
                         K=np.array([[k]]), C=np.array([[0.02 * math.sqrt(k)]]), G=np.eye(1),
                         K_T=np.array([2000.0]), n_modes=1)
    errs = [abs(p["amplitude"] - solve_hb_exact(model, [prm], np.array([1.5]),
                                                2 * math.pi * p["frequency_hz"])
                .slip_amplitude[0]) / p["amplitude"] for p in pts[::4]]
    assert max(errs) < 3e-4              # measured 1.5e-4 (AFT sampling, 256 samples)


@pytest.mark.parametrize("argv, words", [
    (["--force", "-1"], "--force must be finite and > 0"),
    (["--force", "1", "--harmonics", "4"], "--harmonics must be an odd number"),
    (["--force", "1", "--range", "9", "6"], "--range must satisfy 0 < LO < HI"),
    (["--force", "1", "--chi", "0.5"], "chi must lie in (-1, 0)"),
])
def test_frc_one_line_errors(capsys, argv, words):
    code, out, err = run_cli(capsys, "frc", *argv)
    assert code == 2 and out == ""
    assert words in err and len(err.strip().splitlines()) == 1


def test_frc_case_lumped_against_the_condensed_balance(capsys):
    """``--case lumped``: the curve at the drive DOF against ``fe.harmonic_balance.solve_hb``
    (the slip-condensed multi-harmonic balance of the same Jenkins banks: another
    formulation, same harmonics and samples); Hill's multiplier against the Newmark
    period map's (``--floquet period_map``) on the 10-DOF model."""
    from cases.nonlinear_case import build_nonlinear_case
    from fe.harmonic_balance import HBSettings, solve_hb

    code, out, _ = run_cli(capsys, "frc", "--case", "lumped", "--force", "100",
                           "--harmonics", "3", "--n-time", "64", "--floquet", "period_map",
                           "--json")
    assert code == 0
    d = json.loads(out)
    assert d["model"]["case"] == "lumped" and d["model"]["mode"] == 2
    pts = d["curves"][0]["points"]
    hill = np.array([p["max_multiplier"] for p in pts])
    floq = np.array([p["floquet_multiplier"] for p in pts])
    assert np.all(hill < 1.0) and np.max(np.abs(hill - floq)) < 1e-5   # measured 4.1e-7
    case = build_nonlinear_case("lumped")
    st = HBSettings(n_harmonics=3, n_time=64, odd_only=True)
    errs = []
    for p in pts[::6]:
        sol = solve_hb(case.model, case.bank, 100 * case.load(), 2 * math.pi * p["frequency_hz"],
                       st)
        ref = abs(sol.first_harmonic(case.model)[case.response_dof])
        errs.append(abs(p["amplitude"] - ref) / ref)
    assert max(errs) < 1e-10                                         # measured 3.3e-15
