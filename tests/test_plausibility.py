"""Plausibility of a fitted joint (casefile.plausibility) on the lap cantilever of
docs/case-files.md. Truth: the interface's shear stiffness by hand (aluminium E 70 GPa,
nu 0.3, overlap 60 x 30 mm, two 5 mm strips: G A / 5 mm) and the issue's absurd joint
(phi_max 8.7e-14 m), which must read implausible."""
from __future__ import annotations

from pathlib import Path

import pytest

from casefile.plausibility import joint_plausibility
from casefile.schema import read_case_file

LAP = Path(__file__).resolve().parents[1] / "docs" / "case-files" / "bolted-lap-cantilever.toml"


def _checks(drag_cd=None, **joint):
    out = joint_plausibility(read_case_file(LAP), {"phi_max": 3e-4, "K_T": 1e7, "F_S": 800.0,
                                                   **joint}, drag_cd)
    return {c["parameter"]: c for c in out}


def test_shear_stiffness_bound_is_the_hand_value():
    k = 70e9 / (2 * 1.3) * (0.300 - 0.240) * 0.030 / 0.005
    c = _checks()
    assert c["K_T_N_per_m"]["high"] == pytest.approx(k, rel=1e-12)
    assert c["phi_max_m"]["high"] == pytest.approx(0.1 * 0.060, rel=1e-12)
    # F_S <= 0.03 E A over the lap (60 x 30 mm of aluminium, E = 70 GPa), by hand
    assert c["F_S_N"]["high"] == pytest.approx(0.03 * 70e9 * 0.060 * 0.030, rel=1e-12)
    assert {v["verdict"] for v in c.values()} == {"plausible"}
    assert "beta" not in c and "C_D" not in c          # beta = 0 and no drag: no check


@pytest.mark.parametrize("joint, parameter", [({"phi_max": 8.7e-14}, "phi_max_m"),
                                              ({"phi_max": 0.02}, "phi_max_m"),
                                              ({"K_T": 1e12}, "K_T_N_per_m"),
                                              ({"F_S": 1e7}, "F_S_N"),
                                              ({"beta": 1.1e4}, "beta"),
                                              ({"drag_cd": 400.0}, "C_D")])
def test_absurd_joints_are_implausible_with_their_range(joint, parameter):
    """Each out of its range is implausible, with the range's source; the issue's
    examples (phi_max 8.7e-14 m, beta 1.1e4) among them."""
    c = _checks(**joint)[parameter]
    assert c["verdict"] == "implausible" and c["source"]


def test_update_reports_plausibility(tmp_path, capsys):
    import json

    from cli.main import main

    assert main(["update", "--case", str(LAP), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    verdicts = {c["parameter"]: c["verdict"] for c in s["plausibility"]}
    assert {k: verdicts[k] for k in ("phi_max_m", "K_T_N_per_m", "F_S_N")} == {
        "phi_max_m": "plausible", "K_T_N_per_m": "plausible", "F_S_N": "plausible"}
    assert set(verdicts.values()) == {"plausible"}


def test_an_oscillating_strip_drag_inside_graham_range_is_plausible():
    """C_D = 15.4 (the shipped loop's air drag): above a plate in steady flow (about 2)
    but 8 KC^-1/3 at KC = 0.126 (a 1 mm amplitude over a 50 mm strip) is 16.0 (Graham
    1980): plausible, and the check says it rests on the assumed force scale."""
    kc = 2 * 3.141592653589793 * 1e-3 / 0.050
    assert 8 * kc ** (-1 / 3) == pytest.approx(15.97, abs=0.01)
    c = _checks(drag_cd=15.4)["C_D"]
    assert c["verdict"] == "plausible" and "force scale" in c["source"]
