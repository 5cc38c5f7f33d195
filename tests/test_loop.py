"""``iwanfe loop`` (the main job): the held-out scores against a planted prediction, and
the page on the shipped double beam."""
from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from cases.loop_report import held_out_scores


def test_held_out_scores_against_hand_computed_residuals():
    rng = np.random.default_rng(20261125)
    omega2 = (2 * math.pi * rng.uniform(50, 500)) ** 2 * (1 - 1e-4 * np.arange(6))
    zeta = 0.01 * (1 + 0.01 * np.arange(6))
    data = SimpleNamespace(level=np.arange(1, 7), omega2=omega2, zeta=zeta)
    noise = SimpleNamespace(sigma_omega2=np.full(6, 20.0), sigma_zeta=np.full(6, 1e-5))
    planted = rng.normal(size=(2, 6))              # residuals in noise units
    om2 = omega2 + planted[0] * 20.0
    z = zeta + planted[1] * 1e-5
    pred = SimpleNamespace(omega2=om2, zeta=z, frequency_hz=np.sqrt(om2) / (2 * math.pi))
    mask = np.array([True] * 4 + [False] * 2)
    s = held_out_scores(data, mask, noise, pred)
    assert s["rms_noise_units"] == pytest.approx(np.sqrt(np.mean(planted[:, 4:] ** 2)), rel=1e-9)
    assert [r["level"] for r in s["levels"]] == [5, 6]
    f = np.sqrt(omega2[4]) / (2 * math.pi)
    assert s["levels"][0]["error_hz"] == pytest.approx(np.sqrt(om2[4]) / (2 * math.pi) - f)
    assert s["levels"][1]["error_zeta_percent"] == pytest.approx(100 * (z[5] / zeta[5] - 1))


@pytest.mark.slow
def test_loop_on_the_double_beam_writes_one_page(tmp_path, capsys):
    from cli.main import main

    assert main(["loop", "--out", str(tmp_path), "--no-progress"]) == 0
    text = capsys.readouterr().out
    s = json.loads((tmp_path / "loop.json").read_text())
    page = (tmp_path / "report.md").read_text()
    assert "update_levels.png" in page and (tmp_path / "update_levels.png").is_file()
    assert (tmp_path / "update" / "updated_model.json").is_file()
    # the cause named is the model the update wrote, and its gain is the ratio of the
    # two held-out errors
    model = json.loads((tmp_path / "update" / "updated_model.json").read_text())
    assert s["cause"] == model["cause"]
    if s["gain_held_out"] is not None:
        assert s["gain_held_out"] == pytest.approx(
            s["base"]["held_out"]["rms_noise_units"] / s["extended"]["held_out"]["rms_noise_units"])
    # the base model's misfit and the tie contradiction are stated with numbers
    assert s["base"]["fit_test"]["p_value"] < 1e-2
    assert "3 pi/4" in s["tie"]["text"] and "gain at the held-out levels" in text
