"""``iwanfe reproduce double-beam --glue-kt`` and ``--protocol newmark``, and the one-line
stop when no steady state is found (issue 13).

Coarse studies (few lines, 6-8 sliders per octave, no weak-joint reruns). Truths: the
FE model's own eigenvalue (scipy) at the re-calibrated grip, the measured 252.0 Hz; the
harmonic-balance run of the same study for the Newmark run (the issue's acceptance).
"""
import dataclasses
import json

import numpy as np
import pytest
import scipy.linalg as la

import cases.double_beam.protocols as protocols
from cases.double_beam.model import DoubleBeamConfig, build_double_beam
from cli.main import main
from runs.campaign import HBProtocol

COARSE = ["--no-progress", "--json", "--no-weak-joint-runs", "--sliders-per-octave", "6"]


def test_glue_kt_recalibrates_the_grip_and_states_it(tmp_path, capsys):
    rc = main(["reproduce", "double-beam", "--out", str(tmp_path), "--glue-kt", "1e10",
               "--df", "2", *COARSE])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    cal = d["calibration"]
    assert cal["glue_kt_N_per_m"] == 1e10 and cal["glue_kt_source"] == "given"
    assert cal["calibrated_parameter"] == "clamp grip"
    assert d["assumptions"]["K_T"] == pytest.approx(1e10, rel=1e-12)
    # the model at that grip has a mode at the measured 252.0 Hz (dense eigenproblem)
    db = build_double_beam(DoubleBeamConfig(glue_tangential_stiffness=1e10,
                                            clamp_length=cal["grip_m"]))
    f = np.sqrt(la.eigh(db.K.toarray(), db.M.toarray(), eigvals_only=True)) / (2 * np.pi)
    assert np.min(np.abs(f - 252.0)) < 1e-3
    assert 0.015 < cal["grip_m"] < 0.025
    assert "K_T = 1e+10 N/m (given)" in d["assumptions"]["statements"][0]
    assert np.all(np.isfinite(d["simulated"]["omega2"]))       # every level converged


def test_no_steady_state_stops_with_one_line(tmp_path, capsys, monkeypatch):
    real = protocols.campaign_protocol

    def starved(name, hb):                    # a Newton budget no level can meet
        return HBProtocol(dataclasses.replace(hb, max_iter=1)) if name == "hb" else real(name, hb)

    monkeypatch.setattr(protocols, "campaign_protocol", starved)
    rc = main(["reproduce", "double-beam", "--out", str(tmp_path), "--df", "2", *COARSE])
    cap = capsys.readouterr()
    assert rc == 1 and cap.out == ""
    assert cap.err.count("\n") == 1, cap.err
    assert cap.err.startswith("iwanfe: harmonic balance did not converge at level 1 of 10 "
                              "(F = 0.005 N), line 236 Hz: no convergence in 1 iterations")


@pytest.mark.slow
def test_newmark_protocol_runs_every_level_and_agrees_with_harmonic_balance(tmp_path, capsys):
    rc = main(["reproduce", "double-beam", "--out", str(tmp_path), "--protocol", "newmark",
               "--df", "2", *COARSE])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    assert d["campaign"]["protocol"] == "newmark"
    c = d["protocol_comparison"]
    assert [r["level"] for r in c["levels"]] == list(range(1, 11))
    # micro-slip levels: the acceptance; the macro-slip level 10 (2.6 phi_max):
    # with this coarse bank (6 sliders per octave) the harmonic balance's 7 harmonics
    # are further from converged than with the study's 16 (which meets 1e-5, README)
    macro = np.array(d["simulated"]["slip_over_phi_max"]) >= 1.0
    assert list(macro) == [False] * 9 + [True]
    for r in c["levels"]:
        assert abs(r["frequency_hz"]["relative_difference"]) < (1e-5 if r["level"] < 10 else 5e-5)
        assert abs(r["zeta"]["relative_difference"]) < 5e-3
    assert c["max_zeta_relative_difference"] < 5e-3
    assert c["met"] == (c["max_frequency_relative_difference"] <= 1e-5)
    steps = [r["steps_per_period"] for r in c["levels"]]
    assert steps[-1] == 2048 and all(s == 256 for s, m in zip(steps, macro) if not m)
    np.testing.assert_allclose([r["frequency_hz"]["newmark"] for r in c["levels"]],
                               d["simulated"]["frequency_hz"], rtol=1e-15)
