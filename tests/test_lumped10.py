"""The paper's 10-DOF study (cases.lumped10) and ``iwanfe reproduce lumped``."""
import csv
import json

import numpy as np
import pytest
from conftest import SHARED_PAPER
import scipy.linalg as la

from cases.lumped10.improved_fit import fit_improved
from cases.lumped10.model import LumpedParameters, force_vector, lumped10_system, mode_topology
from cases.lumped10.report import TABLE1_TEXT, TABLE2_TEXT, paper_table
from cli.main import main
from fe.modal import modal_inverse_receptance, normal_modes
from joints.describing import describing_function
from joints.iwan import IwanParameters

PAPER = SHARED_PAPER


def test_topology_symmetric_modes_are_single_chain_modes():
    """Modes 1,3,5,7,9 do not stretch the joints and are the modes of one fixed-free
    chain (independent 5-DOF eigenproblem); 2,4,6,8,10 stretch them."""
    s = lumped10_system()
    top = mode_topology(s)
    assert list(top.joint_modes()) == [2, 4, 6, 8, 10]
    k = [1.5e6, 1e6, 1e6, 1e6, 1e6]
    Kc = np.zeros((5, 5))
    for i, ki in enumerate(k):
        Kc[i, i] += ki
        if i:
            Kc[i - 1, i - 1] += ki
            Kc[i - 1, i] -= ki
            Kc[i, i - 1] -= ki
    f_chain = np.sqrt(la.eigh(Kc, eigvals_only=True)) / (2 * np.pi)
    np.testing.assert_allclose(top.frequency_hz[::2], f_chain, rtol=1e-10)
    np.testing.assert_allclose(top.joint_slip[::2], 0.0, atol=1e-10)
    assert np.all(np.abs(top.joint_slip[1::2]).max(axis=1) > 0.1)


def test_joint_slip_ratios_match_paper_table1():
    """The ratio Iwan1/Iwan2 of the paper's Table 1 (levels 5-7, >= 2 printed digits)
    is the mode shapes' slip ratio: a check of the topology reading."""
    top = mode_topology(lumped10_system())
    t1 = paper_table(TABLE1_TEXT)
    for m in (2, 4, 6):
        ratio = np.abs(top.joint_slip[m - 1, 0] / top.joint_slip[m - 1, 1])
        printed = t1[f"mode{m}_iwan1"][4:7] / t1[f"mode{m}_iwan2"][4:7]
        np.testing.assert_allclose(printed, ratio, rtol=0.1)


def test_transcribed_tables_equal_shared_files():
    for text, name in ((TABLE1_TEXT, "table1_lumped_relative_displacement.csv"),
                       (TABLE2_TEXT, "table2_lumped_R_error_percent.csv")):
        if not (PAPER / name).exists():
            pytest.skip("paper tables not available")
        with open(PAPER / name) as fh:
            rows = list(csv.DictReader(fh))
        ours = paper_table(text)
        for key in rows[0]:
            np.testing.assert_allclose(ours[key], [float(r[key]) for r in rows])


def test_modal_filter_of_linear_model_is_one_mode():
    """Linear 10-DOF model (stuck joints, proportional damping): the modal filter of the
    direct solution of ``(K_J - w^2 M + i w C) x = f`` is the single-mode inverse
    receptance ``w_n^2 - w^2 + i w (a + b w_n^2)`` in closed form (paper eq. 40)."""
    p = LumpedParameters()
    s = lumped10_system(p)
    omega_n, shapes = normal_modes(s.K_J, s.M, 10)
    load = force_vector(p)
    w = 2 * np.pi * np.arange(40.0, 320.0, 7.3)
    x = np.array([np.linalg.solve(s.K_J - wi ** 2 * s.M + 1j * wi * s.C, load) for wi in w])
    for n in (0, 1, 5):
        D = modal_inverse_receptance(x, shapes[:, n], s.M, load)
        exact = omega_n[n] ** 2 - w ** 2 + 1j * w * (p.a + p.b * omega_n[n] ** 2)
        np.testing.assert_allclose(D, exact, rtol=1e-9, atol=1e-9 * omega_n[n] ** 2)


def test_improved_fit_recovers_hidden_parameters():
    """Receptances built with the continuous describing function of joints.iwan for a
    seeded random (chi, R) the fit never sees; the fit recovers them."""
    rng = np.random.default_rng(20240601)
    chi = float(rng.uniform(-0.8, -0.2))
    p0 = LumpedParameters()
    joint = IwanParameters(chi=chi, K_T=1.1e5, F_S=float(rng.uniform(300, 600)), beta=4.0)
    s = lumped10_system(LumpedParameters(joint=joint))
    _, shapes = normal_modes(s.K_J, s.M, 10)
    f = np.arange(55.0, 68.01, 0.5)
    w = 2 * np.pi * f
    load = force_vector(p0)
    levels = 4
    rec = np.empty((levels, f.size, 10), complex)
    amp = np.empty((levels, f.size, 2))
    for lv in range(levels):
        # hidden per-line slip amplitudes (as a simulation would give)
        amp[lv] = (1e-5 * 2 ** lv) * np.exp(-((f - 61.7) / 3.0) ** 2)[:, None] * [0.32, 1.0]
        kin, kq = describing_function(joint, amp[lv])
        for i in range(f.size):
            Z = (s.K + s.G.T @ np.diag(kin[i] + 1j * kq[i]) @ s.G - w[i] ** 2 * s.M
                 + 1j * w[i] * s.C)
            rec[lv, i] = np.linalg.solve(Z, load)
    fit = fit_improved(s, shapes[:, 1], load, f, rec, amp, 2, joint.phi_max)
    assert fit.chi == pytest.approx(chi, abs=1e-6)
    assert fit.R == pytest.approx(joint.R, rel=1e-5)
    assert fit.chi_with_frequency == pytest.approx(chi, abs=1e-6)


@pytest.fixture(scope="module")
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp("lumped")
    import contextlib
    import io
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["reproduce", "lumped", "--bands-only", "--json", "--no-progress",
                     "--out", str(out)])
    assert code == 0
    return out, json.loads(buf.getvalue())


def test_reproduce_lumped_acceptance(reproduced):
    out, d = reproduced
    assert set(d["chi_improved"]) == {"2", "4", "6"}
    assert abs(d["chi_improved"]["2"] / -0.5 - 1) < 0.01
    for m in ("4", "6"):
        assert abs(d["chi_improved"][m] / -0.5 - 1) < 0.03
    # the paper's regression on the same data is visibly worse (> 2 % off)
    assert max(abs(v / -0.5 - 1) for v in d["chi_paper_method"].values()) > 0.02
    for m in ("2", "4", "6"):
        assert abs(d["R_error_percent"][m]["improved"]) < 3.0
        t = d["table1"][m]
        assert len(t["iwan1"]) == 12 and len(t["paper_iwan2"]) == 12
    for name in ("fig4_frf_levels.png", "fig5_mode2.png", "fig5_improved.png"):
        assert (out / name).stat().st_size > 10_000


def test_reproduce_resumes_from_store(reproduced, capsys):
    out, d = reproduced
    assert main(["reproduce", "lumped", "--bands-only", "--json", "--no-progress",
                 "--out", str(out)]) == 0
    d2 = json.loads(capsys.readouterr().out)
    assert d2["timings_s"]["campaign_levels_computed"] == 0
    assert d2["chi_improved"] == d["chi_improved"]


def test_reproduce_bad_input(capsys):
    assert main(["reproduce", "lumped", "--n-sliders", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "n-sliders" in err
