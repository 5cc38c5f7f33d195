"""The double-beam reproduction (cases.double_beam.study and its modules) and
``iwanfe reproduce double-beam``.

Coarse studies (1 Hz lines, 8 sliders per octave) keep the file fast; the full run is
the command's job. Truths used: a sparse static solve, the full FE model's modal FRF
(fe.modal.frf_modal), the decoupled modal joint damping of paper eq. 30-32 with the
simulated slips, the exact scaling law of the Iwan density under a change of force
scale, the planted (input) chi of the simulation, the estimator called directly, and
one golden value (tests/golden/double_beam_estimates.json, its note says where it
comes from).
"""
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import runs.stepped_sine as stepped_sine
from cases.double_beam.joint_setup import joint_setup, nonlinear_model, phi_max_of
from cases.double_beam.model import build_double_beam
from cases.double_beam.settings import DoubleBeamStudy, measured_levels
from cases.double_beam.study import run_study
from cli.main import main
from fe.modal import frf_modal, normal_modes
from ident.measured import read_measured
from inverse.estimate import estimate

GOLDEN = Path(__file__).resolve().parent / "golden" / "double_beam_estimates.json"

COARSE = dict(df_hz=1.0, band_hz=(236.0, 268.0), sliders_per_octave=8, weak_joint_scales=())


@pytest.fixture(scope="module")
def model():
    return build_double_beam()


@pytest.fixture(scope="module")
def source(model):
    """The estimate-driven joint of the coarse study (chi, R from measured levels 1-7)."""
    st = DoubleBeamStudy(**COARSE)
    return joint_setup(model, measured_levels(st), st)


@pytest.fixture(scope="module")
def weak(model, source):
    """Coarse run with R / 100: the glue stays nearly stuck (top slip 6e-4 phi_max)."""
    st = DoubleBeamStudy(**COARSE, chi=source.chi, R=0.01 * source.R)
    return run_study(st, progress=False, model=model)


# --------------------------------------------------------------------------- model


def test_modes_are_deterministic_and_agree_with_arpack(model):
    w1, s1 = model.modes(6)
    w2, s2 = build_double_beam().modes(6)
    assert np.array_equal(w1, w2) and np.array_equal(s1, s2)
    w3, _ = normal_modes(model.K, model.M, 6, dense_below=0)      # ARPACK
    np.testing.assert_allclose(w1, w3, rtol=2e-6)


def test_nonlinear_model_holds_the_static_joint_compliance_of_the_fe_model(model, source):
    """The reduced double beam (stuck-glue modes + static joint modes, modal damping
    zeta_v) reproduces the joints' static compliance ``G K^-1 G^T`` of the full FE model
    (sparse direct solve), and its banks rebuild each joint's stuck stiffness."""
    st = DoubleBeamStudy(df_hz=1.0, band_hz=(236.0, 268.0), sliders_per_octave=8,
                         weak_joint_scales=(), n_modes=12)
    red, bank = nonlinear_model(model, source, st)
    np.testing.assert_allclose(red.basis.T @ (model.M @ red.basis), np.eye(red.n_reduced),
                               atol=1e-10)
    np.testing.assert_allclose(np.diag(red.C), 2 * source.zeta_viscous * red.omega, rtol=1e-14)
    G = model.slip_matrix.toarray()
    static = G @ spla.splu(sp.csc_matrix(model.K)).solve(G.T.copy())
    reduced = red.G @ np.diag(1.0 / red.omega ** 2) @ red.G.T
    np.testing.assert_allclose(reduced, static, rtol=1e-8)
    np.testing.assert_allclose(bank.K_T, model.joint_stiffness, rtol=1e-12)


def test_phi_max_is_largest_at_beta_zero_and_joints_share_K_T(model, source):
    """Eq. (1): the per-joint Iwan elements rebuild K_T and share one phi_max."""
    assert source.beta == 0.0
    np.testing.assert_allclose([p.K_T for p in source.params],
                               source.shares * source.K_T, rtol=1e-12)
    np.testing.assert_allclose([p.phi_max for p in source.params], source.phi_max, rtol=1e-12)
    np.testing.assert_allclose(sum(p.R for p in source.params), source.R, rtol=1e-12)
    for beta in (0.5, 4.0):
        assert phi_max_of(source.K_T, source.R, source.chi, beta) < source.phi_max


# --------------------------------------------------------------------------- simulation


def test_lowest_level_matches_linear_fe_frf(weak, model):
    """Level 1 of the weak-joint campaign at Acc. 1 against the modal FRF of the full FE
    model (all 400 modes, the same modal damping). Measured 1.9e-5: the truncation of
    the 40-mode Ritz basis (1e-3 with 12 modes, 7e-6 with 48) and the level-1 joint
    (zeta share 6e-8)."""
    om, sh = normal_modes(model.K, model.M, model.M.shape[0] - 2, dense_below=10 ** 6)
    camp = weak.campaign
    w = 2 * np.pi * camp.frequency_hz
    H = frf_modal(w, om, sh, model.drive_dof, model.response_dof, zeta=weak.setup.zeta_viscous)
    sim = camp.receptance[0, :, model.response_dof]
    err = np.abs(sim - H.ravel()) / np.abs(H.ravel())
    assert err.max() < 5e-5, err.max()


def test_modal_joint_damping_matches_decoupled_theory_for_a_weak_joint(weak):
    """Paper eq. 30-32 (|kappa1| B, kappa2 B with the exact kappas and the simulated
    slips) against the modal-filter projection of the HB response, levels 1-4."""
    mf = weak.modal_filter
    np.testing.assert_allclose(mf.delta_c[:4], mf.delta_c_decoupled[:4], rtol=0.012)
    np.testing.assert_allclose(mf.delta_omega2[:4], mf.delta_omega2_decoupled[:4], rtol=0.012)
    # the LSCF identification at Acc. 1 agrees with the modal filter
    np.testing.assert_allclose(weak.simulated.zeta, mf.zeta, rtol=1e-4)
    np.testing.assert_allclose(weak.simulated.omega2, mf.omega2, rtol=1e-5)
    # level 1 has the measured damping (the viscous part was chosen for it)
    assert abs(weak.simulated.zeta[0] - weak.measured.zeta[0]) < 2e-6


def test_estimator_recovers_the_input_chi_from_a_weak_joint(weak):
    """With R / 100 every method recovers chi within 0.003 (measured 0.0011-0.0014: the
    remaining bias is linear in R) and R~ within 15 % (measured 0.5-9 %)."""
    for which in ("lscf", "modal_filter"):
        rec = weak.recovery(which)
        for method in ("paper", "exact", "amplitude"):
            r = rec[method]
            assert abs(r["chi_error"]) < 3e-3, (which, method, r["chi_error"])
            assert abs(r["R_error_percent"]) < 15.0, (which, method, r["R_error_percent"])
            assert r["chi_interval"][0] < r["chi_input"] + 3e-3


def test_force_scale_changes_R_and_phi_max_but_not_the_simulated_modal_data(model):
    """R~ ~ s^-(chi+1), phi_max ~ s; omega2, zeta identical; slips ~ s (exact scaling of
    the Iwan density and of the log-spaced bank)."""
    a = run_study(DoubleBeamStudy(**COARSE, n_levels=7), progress=False, model=model)
    b = run_study(DoubleBeamStudy(**COARSE, n_levels=7, force_scale=10.0),
                      progress=False, model=model)
    chi = a.setup.chi
    assert b.setup.chi == chi
    np.testing.assert_allclose(b.setup.R / a.setup.R, 10.0 ** -(chi + 1), rtol=1e-9)
    np.testing.assert_allclose(b.setup.phi_max / a.setup.phi_max, 10.0, rtol=1e-9)
    np.testing.assert_allclose(b.simulated.omega2, a.simulated.omega2, rtol=1e-10)
    np.testing.assert_allclose(b.simulated.zeta, a.simulated.zeta, rtol=1e-8)
    np.testing.assert_allclose(b.identification.slip, 10.0 * a.identification.slip, rtol=1e-8)
    np.testing.assert_allclose(b.campaign.receptance, a.campaign.receptance, rtol=1e-8,
                               atol=1e-8 * np.abs(a.campaign.receptance).max())


class Stop(Exception):
    pass


def test_interrupted_run_resumes_without_recomputing(model, tmp_path, monkeypatch):
    st = DoubleBeamStudy(**COARSE, n_levels=8)
    ref = run_study(st, store=tmp_path / "ref", progress=False, model=model)
    assert ref.campaign.computed.all()
    real = stepped_sine.run_level
    done = []

    def stop_at_level_3(m, bank, camp, level, tick=None):
        if level == 3:
            raise Stop
        done.append(level)
        return real(m, bank, camp, level, tick)

    monkeypatch.setattr(stepped_sine, "run_level", stop_at_level_3)
    with pytest.raises(Stop):
        run_study(st, store=tmp_path / "b", progress=False, model=model)
    monkeypatch.setattr(stepped_sine, "run_level", real)
    again = run_study(st, store=tmp_path / "b", progress=False, model=model)
    assert done == [0, 1, 2]
    assert list(np.flatnonzero(again.campaign.computed)) == list(range(3, 8))
    assert np.array_equal(again.campaign.receptance, ref.campaign.receptance)
    third = run_study(st, store=tmp_path / "b", progress=False, model=model)
    assert not third.campaign.computed.any()
    assert np.array_equal(third.simulated.zeta, ref.simulated.zeta)


# --------------------------------------------------------------------------- CLI


def test_cli_json_holds_the_estimates_and_the_simulation(tmp_path, capsys):
    out = tmp_path / "db"
    rc = main(["reproduce", "double-beam", "--out", str(out), "--json", "--no-progress",
               "--df", "2", "--band", "240", "264", "--sliders-per-octave", "6",
               "--no-weak-joint-runs"])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    for method in ("paper", "exact", "amplitude"):
        e = d["methods"][method]
        for key in ("chi", "kappa1_B", "B", "R", "chi_interval", "predictions", "data_warnings"):
            assert key in e, (method, key)
        assert -1 < e["chi"] < 0 and e["R"] > 0 and e["B"] > 0
        assert [p["level"] for p in e["predictions"]] == list(range(1, 11))
        for p in e["predictions"][1:]:
            for key in ("delta_omega2", "delta_zeta", "measured_delta_omega2",
                        "measured_delta_zeta"):
                assert isinstance(p[key], float), (method, key)
    # the report carries the estimator's own result on the measured levels 1-7 ...
    direct = estimate(measured_levels(DoubleBeamStudy()), fit_levels=list(range(1, 8)),
                      method="paper", model=build_double_beam(), force_scale=1.0)
    assert d["methods"]["paper"]["chi"] == direct.chi
    assert d["methods"]["paper"]["kappa1_B"] == direct.kappa1_B
    # ... whose value on the shipped data has no independent truth (the paper prints
    # -0.37366 with an unstated variant, cases/data/README.md): a golden value only;
    # the estimator's recovery of a planted chi is test_estimator_recovers_the_input_chi...
    golden = json.loads(GOLDEN.read_text())["paper_method_levels_1_7"]
    assert abs(d["methods"]["paper"]["chi"] - golden["chi"]) < golden["tolerance"]
    assert len(d["simulated"]["omega2"]) == 10 and len(d["simulated"]["zeta"]) == 10
    assert d["assumptions"]["beta"] == 0.0 and d["assumptions"]["force_scale_N_per_V"] == 1.0
    sim = read_measured(out / "simulated_measured.csv")
    np.testing.assert_allclose(sim.omega2, d["simulated"]["omega2"], rtol=1e-15)
    np.testing.assert_allclose(sim.zeta, d["simulated"]["zeta"], rtol=1e-15)
    for name in ("report.md", "report.json", "levels_measured_vs_simulated.png",
                 "joint_slips_and_damping.png", "frf_levels.png", "fig8_measured_paper.png"):
        assert (out / name).stat().st_size > 0, name
    text = (out / "report.md").read_text()
    assert "## Table 3" in text and "## Table 6" in text and "times" in text


@pytest.mark.parametrize("argv, message", [
    (["double-beam", "--beta", "-1"], "beta must be >= 0"),
    (["double-beam", "--fit-levels", "1-12"], "exceed"),
    (["double-beam", "--protocol", "paper"], "lumped target only"),
    (["double-beam", "--glue-kt", "1e12"], "glue K_T must lie in 1e+06..1e+11 N/m"),
    (["double-beam", "--glue-kt", "nan"], "glue K_T must lie in"),
    (["lumped", "--glue-kt", "1e8"], "--glue-kt applies to the double-beam target only"),
    (["double-beam", "--band", "260", "250"], "band"),
    (["lumped", "--beta", "0"], "double-beam target only"),
])
def test_cli_bad_input_is_one_line_exit_2(argv, message, tmp_path, capsys):
    rc = main(["reproduce", *argv, "--out", str(tmp_path / "x"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and err.count("\n") == 1, err
