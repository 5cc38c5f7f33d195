"""Convergence studies: analytic cantilever roots, observed h^4 rate, CLI output."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cases.convergence import cantilever_beta_l, cantilever_study, double_beam_study, joint_spacing


def test_cantilever_roots_solve_the_frequency_equation():
    bl = cantilever_beta_l(6)
    np.testing.assert_allclose(1 + np.cos(bl) * np.cosh(bl), 0.0, atol=1e-8 * np.cosh(bl).max())
    # published values (Blevins, table 8-1) and the asymptote (2n - 1) pi / 2
    np.testing.assert_allclose(bl[:4], [1.87510407, 4.69409113, 7.85475744, 10.99554073], rtol=1e-8)
    np.testing.assert_allclose(bl[3:], (2 * np.arange(4, 7) - 1) * np.pi / 2, rtol=1e-5)


def test_cantilever_converges_at_h4():
    c = cantilever_study()
    rate = np.asarray(c["rate"])
    assert np.all(np.abs(rate[:4] - 4.0) < 0.3), rate
    # every mode reaches 1e-8 on some mesh; where the finest is worse it is round-off
    assert np.all(np.asarray(c["best_error"]) < 1e-8)
    for err, why in zip(c["finest_error"], c["finest_limited_by"]):
        assert err < 1e-8 or why == "round-off"
    err = np.asarray(c["relative_error"])
    assert err.shape == (len(c["elements"]), 6)
    # coarse meshes: the error drops by ~16 per halving (h^4)
    ratio = err[3, :4] / err[4, :4]  # 16 -> 32 elements
    np.testing.assert_allclose(ratio, 16.0, rtol=0.15)


def test_double_beam_mesh_choice_is_converged():
    d = double_beam_study(element_sizes=(0.01, 0.005, 0.0025), joints=(3, 5, 9))
    default = d["default"]
    assert abs(default["frequency_error_estimate"]) < 1e-4
    assert abs(default["glue_slip_error_estimate"]) < 1e-2
    es = d["element_size_sweep"]["frequency_relative_change"]
    assert abs(es[0]) > abs(es[1]) > 0


@pytest.mark.parametrize("n_joints", [2, 5, 33])
def test_joint_spacing_is_the_glued_zone_mesh(n_joints):
    """The joint spacing of the refinement plots is the element length the double-beam
    mesh puts between its glued-zone nodes (the last ``n_joints`` nodes)."""
    from dataclasses import replace

    from cases.double_beam.model import DoubleBeamConfig, build_mesh

    mesh = build_mesh(replace(DoubleBeamConfig(), n_joints=n_joints))
    np.testing.assert_allclose(np.diff(mesh.x[-n_joints:]), joint_spacing([n_joints])[0],
                               rtol=1e-12)


def test_cli_convergence_json_and_plot(tmp_path, capsys):
    from cli.main import main

    assert main(["convergence", "--json", "--out", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {"elements", "relative_error", "rate"} <= set(data["cantilever"])
    assert len(data["cantilever"]["relative_error"]) == len(data["cantilever"]["elements"])
    assert "double_beam" in data
    assert (tmp_path / "convergence.png").stat().st_size > 10_000
    saved = json.loads((tmp_path / "convergence.json").read_text())
    assert saved["cantilever"]["elements"] == data["cantilever"]["elements"]
