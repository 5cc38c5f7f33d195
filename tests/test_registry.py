"""The case registry (cases/registry.py): every shipped case with an FE model builds the
duck-typed model the estimator takes, its modes agree with a dense generalized
eigen-solution, and unknown names (or a missing capability) are one-line errors on every
command that takes ``--case``."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from cases.registry import CASES, MEASURED_DATA, SHIPPED, build_case, case_modes, resolve_case
from cli.main import main
from ident.errors import InputError


FE_CASES = [n for n in SHIPPED if "fe_model" in resolve_case(n).capabilities]


def test_every_shipped_case_has_a_face():
    assert set(FE_CASES) >= {"double-beam", "brb"}
    assert resolve_case("lumped").capabilities == ("nonlinear_model",)
    # the double beam: its case file's capabilities and its study's (the file leaves its
    # joint parameters to be fitted, the study's nonlinear model takes chi, R~ of its levels)
    assert set(resolve_case("double-beam").capabilities) == {
        "fe_model", "summary", "calibrated_file", "measured_data", "nonlinear_model",
        "update", "update_modes", "fe_levels", "fe_check", "uncertainty", "fe_uncertainty"}
    with pytest.raises(InputError, match="case 'lumped' has no FE strip model"):
        resolve_case("lumped").require("fe_model")


@pytest.mark.parametrize("name", FE_CASES + ["python:double-beam"])
def test_case_model_has_the_estimator_interface_and_its_modes(name):
    model = (build_case(name.split(":")[1]) if name.startswith("python:")
             else resolve_case(name).fe_model())
    n = model.M.shape[0]
    assert model.K.shape == (n, n)
    assert model.slip_matrix.shape[1] == n
    assert len(model.joint_stiffness) == model.slip_matrix.shape[0]
    assert 0 <= int(model.drive_dof) < n
    freqs, shapes = case_modes(model, 4)
    assert shapes.shape == (n, 4)
    # each pair solves K phi = omega^2 M phi, mass-normalized (residuals ~1e-6 of K phi:
    # the stiff normal springs of the joints make K ill-conditioned)
    K, M = model.K.toarray(), model.M.toarray()
    w2 = (2 * np.pi * freqs) ** 2
    resid = K @ shapes - M @ shapes * w2
    # (free-free cases: rigid-body columns have K phi ~ 0, so against the largest)
    assert np.all(np.linalg.norm(resid, axis=0) <= 1e-5 * np.linalg.norm(K @ shapes, axis=0).max())
    np.testing.assert_allclose(np.einsum("ij,ik,kj->j", shapes, M, shapes), 1.0, rtol=1e-8)
    # and they are the lowest four: dense generalized eigenvalues (a second method)
    lam = sla.eigh(K, M, eigvals_only=True)[:4]
    dense = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
    elastic = freqs > 1e-2 * freqs.max()
    np.testing.assert_allclose(freqs[elastic], dense[elastic], rtol=1e-5, atol=1e-3 * freqs.max())
    # rigid-body modes: round-off of the dense solver on a K with ~1e12 N/m entries (the
    # BRB's: 0.04-0.2 Hz, varying with the BLAS threads), far below the elastic ones
    assert np.all(dense[~elastic] < 1e-2 * freqs.max())


def test_case_modes_refuses_more_modes_than_dofs():
    model = build_case(CASES[0])
    with pytest.raises(ValueError, match="degrees of freedom"):
        case_modes(model, model.M.shape[0] + 1)
    with pytest.raises(ValueError, match=">= 1"):
        case_modes(model, 0)


def test_unknown_case_is_an_input_error_naming_the_known_ones():
    with pytest.raises(InputError, match="unknown case 'nope': give a shipped name"):
        resolve_case("nope")
    with pytest.raises(InputError, match="unknown case 'lumped'; known: double-beam"):
        build_case("lumped")


def test_every_measured_data_case_is_a_model_case():
    assert set(MEASURED_DATA) <= set(CASES)
    for path in MEASURED_DATA.values():
        assert path.exists()


@pytest.mark.parametrize("argv", [
    ["modes", "--case", "lumped"],
    ["estimate", str(MEASURED_DATA["double-beam"]), "--case", "lumped"],
    ["render", "--case", "lumped", "--mode", "1", "--out", "x.png"],
    ["export", "--case", "lumped", "--out", "x.vtu"],
    ["convergence", "--case", "lumped"],
    ["case", "check", "lumped"],
])
def test_cli_case_without_the_capability_exits_2_with_one_line(argv, capsys):
    try:  # argparse refuses a name outside --case choices by exiting
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    _, err = capsys.readouterr()
    assert err.count("\n") == 1 and "lumped" in err
