"""The FE-level diagnosis (cases/double_beam/fe_diagnosis.py) and the update command.

Truth: synthetic series of the FE double beam hiding a randomly drawn, seeded FE-level
effect (cases/double_beam/fe_synthetic.py: FRF lines, LSCF identification, noise); the
diagnosis never sees the drawn parameters. The benchmark
(benchmarks/bench_fe_hidden_effect.py) runs 10 draws; the suite keeps two.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cases.double_beam.fe_diagnosis import default_fit_mask
from cases.double_beam.fe_synthetic import EFFECT_SIGMA, SIGMA_OMEGA2_REL, draw_case
from cli.main import main


def test_default_fit_mask_holds_out_the_top_three():
    assert default_fit_mask(np.arange(1, 11)).tolist() == [True] * 7 + [False] * 3
    assert default_fit_mask(np.arange(1, 7)).sum() == 5


def test_synthetic_hardening_plants_the_drawn_effect_size():
    """The drawn cubic spring moves the top level's omega^2 by the drawn number of noise
    units (within the softening it also changes), and the series carries its noise."""
    from cases.double_beam.fe_causes import EXTENSIONS
    from cases.double_beam.fe_levels import DoubleBeamLevels
    from cases.double_beam.fe_synthetic import EXCITATION

    case = draw_case(1, "geometric-hardening")
    v = case.truth["values"]
    fe = DoubleBeamLevels(EXCITATION, case.data.run_order, (2 * np.pi * 252) ** 2, 0.0125)
    rise = fe.predict(v, EXTENSIONS["geometric-hardening"]).omega2[-1] - fe.predict(v).omega2[-1]
    units = rise / (SIGMA_OMEGA2_REL * fe.predict(v).omega2[-1])
    assert 0.5 * EFFECT_SIGMA[0] < units < 1.5 * EFFECT_SIGMA[1]
    assert np.all(case.data.omega2_std > 0) and np.all(case.data.zeta_std > 0)
    assert sorted(case.data.run_order.tolist()) == list(range(1, 11))


@pytest.mark.slow
@pytest.mark.parametrize("seed, cause", [(4, None), (7, "quadratic-damping")])
def test_hidden_fe_effect_is_named_and_recovered(seed, cause):
    """Fitted on all levels, the FE diagnosis names the hidden effect and recovers its
    physical parameter within 15 %."""
    from cases.double_beam.fe_diagnosis import fe_diagnosis

    case = draw_case(seed, cause)
    r = fe_diagnosis(case.data, mask=np.ones(len(case.data), dtype=bool))
    assert r["fe"]["cause"] == case.cause
    got = r["fe"]["reading"][case.truth["key"]]
    assert got == pytest.approx(case.truth["recovered"], rel=0.15)


@pytest.mark.slow
def test_diagnose_case_double_beam_holds_fe_levels(capsys, tmp_path):
    """``diagnose --case double-beam --json``: fe_levels per level, the FE cause with
    gain and gain_held_out, the held-out errors consistent with fe_levels."""
    assert main(["diagnose", "--case", "double-beam", "--json", "--out", str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    rows = r["fe_levels"]
    assert [row["level"] for row in rows] == list(range(1, 11))
    assert [row["held_out"] for row in rows] == [False] * 7 + [True] * 3
    for row in rows:
        for key in ("measured", "base", "extended"):
            assert set(row[key]) == {"frequency_hz", "zeta"}
    fe = r["fe"]
    assert fe["cause"] in ("none", "macro-slip", "nonproportional-amplitude",
                           "geometric-hardening", "thermal-drift", "quadratic-damping")
    assert fe["gain"] > 0 and fe["gain_held_out"] > 0
    meas = rows[9]["measured"]
    assert meas["frequency_hz"] == pytest.approx(math.sqrt(2505871.55) / (2 * math.pi))
    err = rows[9]["extended"]["frequency_hz"] - meas["frequency_hz"]
    assert fe["held_out"][-1]["extended_error_hz"] == pytest.approx(err)
    assert (tmp_path / "fe_levels.png").stat().st_size > 1000


def test_update_command_rejects_bad_input(capsys):
    assert main(["update", "--case", "double-beam", "--fit-levels", "7-1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fit-levels" in err[0]
    with pytest.raises(SystemExit) as e:
        main(["update", "--case", "double-beam", "--force-scale", "-1"])
    assert e.value.code == 2


@pytest.mark.slow
def test_update_on_the_shipped_data_reports_the_misfit(tmp_path):
    """A reduced run (3 K_T values, 2 profile points per side): the files, every
    parameter's kind and status, and the tie statement with the data's own numbers
    (loss of omega^2 273.1 rad^2/s^2 = 0.73 x 2 omega^2 dzeta over levels 1-7)."""
    from cases.double_beam.update_report import summary, write_update
    from cases.double_beam.update_study import UpdateSettings, run_update

    r = run_update(UpdateSettings(kt_grid=(7.0, 8.0, 9.0), profile_points=2,
                                  assumptions=False), store=str(tmp_path / "profiles"))
    s = summary(r)
    assert s["fit_levels"] == list(range(1, 8)) and s["held_out_levels"] == [8, 9, 10]
    assert s["tie"]["loss_omega2"] == pytest.approx(2506770.0 - 2506496.94)
    assert s["tie"]["ratio"] == pytest.approx(0.726, abs=0.002)
    assert s["tie"]["ratio"] < s["tie"]["iwan_minimum"]
    assert s["fit"]["chi2"] > 3 * s["fit"]["dof"]              # the base model misfits
    for name in ("chi", "ln_dc1", "zeta_v", "f0_hz"):
        assert s["parameters"][name]["kind"] == "fitted"
        assert s["parameters"][name]["status"] in ("determined", "bounded below",
                                                   "bounded above", "not determined")
    files = write_update(r, tmp_path)
    assert all(f.exists() for f in files)
    model = json.loads((tmp_path / "updated_model.json").read_text())
    assert model["joint"]["K_T_N_per_m"] in (1e7, 1e8, 1e9)
