"""The jointed model of a case file of each law (casefile/nonlinear.py, casefile/jointed.py)
against independent truth: a Jenkins slider's loop and energy per cycle in closed form
(``4 fs (A - fs/kt)`` for ``A > fs/kt``), the EPMC backbone's damping and frequency from
the first-harmonic energy and stiffness balance of its own orbit with those closed forms,
the Bouc-Wen describing function against its evolution equation integrated by solve_ivp,
the ring-down start on the law's steady loop; and ``case check``, ``backbone``,
``ringdown`` and the virtual tests run with every law."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp
from scipy.optimize import brentq

from cases.registry import resolve_case
from cli.main import main
from fe.epmc import epmc_backbone
from joints.bank import JointBank
from joints.bouc_wen import BoucWenJoints

ROOT = Path(__file__).resolve().parents[1]
FILES = ROOT / "docs" / "case-files"
LAW_FILES = {"iwan4": FILES / "bolted-lap-cantilever.toml",
             "jenkins": FILES / "bolted-lap-jenkins.toml",
             "bouc-wen": FILES / "bolted-lap-bouc-wen.toml"}
KT, FS = 1.0e7, 200.0          # both files' interface (N/m, N)


def _case(law: str, mode: int = 2):
    return resolve_case(str(LAW_FILES[law])).nonlinear_model(mode=mode)


def test_jenkins_file_is_one_slider_per_joint_element():
    nc = _case("jenkins")
    fe = nc.fe_model
    assert isinstance(nc.joints, JointBank) and nc.bank is nc.joints
    assert nc.joints.n_sliders == 1 and nc.joints.n_joints == 2
    assert np.array_equal(nc.joints.K_T, fe.joint_stiffness)          # kt w_j, exactly
    assert np.allclose(nc.joints.friction_force[:, 0], FS * fe.joint_stiffness / KT,
                       rtol=1e-15)                                     # fs w_j
    assert np.allclose(nc.phi_max_per_joint, FS / KT, rtol=1e-15)
    assert nc.chi is None and nc.R is None and nc.law_name == "jenkins"
    assert nc.time_path == "bank" and nc.time_law is nc.bank


def test_bouc_wen_file_carries_its_parameters_and_no_bank():
    nc = _case("bouc-wen")
    assert isinstance(nc.joints, BoucWenJoints) and nc.bank is None
    w = nc.fe_model.joint_stiffness / KT
    assert [p.K_T for p in nc.joints.params] == pytest.approx(KT * w, rel=1e-15)
    assert [p.F_S for p in nc.joints.params] == pytest.approx(FS * w, rel=1e-15)
    assert {(p.alpha, p.shape) for p in nc.joints.params} == {(0.1, 0.5)}
    assert np.allclose(nc.phi_max_per_joint, FS / (0.9 * KT), rtol=1e-14)   # z_u
    assert nc.time_path == "exact" and isinstance(nc.time_law, BoucWenJoints)
    with pytest.raises(ValueError, match="no Jenkins-bank path"):
        nc.joint_harmonics("bank")


# ---------------------------------------------------------------- Jenkins in closed form


def _marched_loop(law, A, n=40001):
    """The law's own step marched over two periods of ``s = A sin t`` (A per joint);
    the second period: (t, force (n, n_joints))."""
    t = np.linspace(0.0, 4.0 * np.pi, 2 * n - 1)
    state, F = law.initial_state(), []
    for s in np.outer(np.sin(t), A):
        f, _, state = law.step(s, state)
        F.append(f)
    return t[n - 1:] - 2.0 * np.pi, np.array(F[n - 1:])


def test_jenkins_loop_energy_per_cycle_is_the_closed_form():
    """Each element ``(k, F)`` of the file's law, marched in the time domain: the work per
    cycle ``closed-loop integral of F ds`` is ``4 F (A - F/k)`` above the slip ``F/k`` and
    0 below it; the describing function's ``pi A^2 k_q`` is the same closed form, its
    ``k_in`` the loop's Fourier coefficient."""
    law = _case("jenkins").joints
    k, F_s = law.stiffness[:, 0], law.friction_force[:, 0]
    for ratio in (0.5, 1.0, 1.7, 4.0, 25.0):
        A = ratio * F_s / k
        t, F = _marched_loop(law, A)
        work = np.array([simpson(F[:, j] * A[j] * np.cos(t), x=t) for j in range(k.size)])
        closed = 4.0 * F_s * np.maximum(A - F_s / k, 0.0)
        assert work == pytest.approx(closed, rel=1e-6, abs=1e-9 * F_s.max() * A.max())
        k_in, k_q = law.describing(A)
        assert np.pi * A ** 2 * k_q == pytest.approx(closed, rel=1e-12, abs=1e-300)
        ki = np.array([simpson(F[:, j] * np.sin(t), x=t) for j in range(k.size)]) / (np.pi * A)
        assert k_in == pytest.approx(ki, rel=1e-6)


def _first_harmonic_balance(model, Q, omega, xi, k_in, dissipation):
    """(omega^2, zeta) of a first-harmonic orbit ``Q`` from its stiffness and energy
    balance (Q^H of the balance): ``omega^2 Q^H M Q = Q^H K Q + sum (k_in - K_T) |S|^2``,
    ``xi pi omega Q^H M Q = pi omega Q^H C Q + sum D``."""
    S = model.G @ Q
    m = float(np.real(np.conj(Q) @ model.M @ Q))
    w2 = (float(np.real(np.conj(Q) @ model.K @ Q))
          + float(np.sum((k_in - model.K_T) * np.abs(S) ** 2))) / m
    c = float(np.real(np.conj(Q) @ model.C @ Q))
    xi_balance = (np.pi * omega * c + float(np.sum(dissipation))) / (np.pi * omega * m)
    return w2, xi_balance / (2.0 * omega)


def test_jenkins_backbone_is_its_closed_form_energy_balance():
    """The EPMC backbone of the Jenkins file (exact path): below the slip ``fs/kt`` the
    stuck mode (frequency and the file's zeta); above it, each point's zeta equals the
    energy balance of its own orbit with the closed-form dissipation ``4 F (A - F/k)`` and
    its omega^2 the stiffness balance with the Fourier ``k_in`` of the marched loop."""
    nc = _case("jenkins")
    law, model = nc.joints, nc.model
    k, F_s = law.stiffness[:, 0], law.friction_force[:, 0]
    bb = epmc_backbone(model, nc.joint_harmonics("exact"), nc.mode,
                       np.array([0.05, 0.5, 1.5, 3.0, 8.0]) * nc.phi_max, at="slip")
    for i in range(len(bb)):
        Q, A = bb.q[i, 0], bb.slip_amplitude[i]
        if A.max() <= (F_s / k).min():
            assert bb.omega[i] == pytest.approx(bb.omega_linear, rel=1e-12)
            assert bb.zeta[i] == pytest.approx(1e-3, rel=1e-9)       # [damping] zeta
            continue
        t, F = _marched_loop(law, A, 20001)
        k_in = np.array([simpson(F[:, j] * np.sin(t), x=t) for j in range(k.size)]) / (np.pi * A)
        D = 4.0 * F_s * np.maximum(A - F_s / k, 0.0)
        w2, zeta = _first_harmonic_balance(model, Q, bb.omega[i], bb.xi[i], k_in, D)
        assert bb.zeta[i] == pytest.approx(zeta, rel=1e-8)
        assert bb.omega[i] ** 2 == pytest.approx(w2, rel=1e-9)
    assert bb.zeta[-1] > 1.2e-3                     # the slider dissipates at the top


# ---------------------------------------------------------------- Bouc-Wen


def _ivp_loop(p, A, n=20001):
    """The steady loop of ``dz = ds (1 - beta sgn(ds) z - gamma |z|)`` for ``s = A sin t``
    by solve_ivp (DOP853, rtol 1e-12), closed by shooting (brentq on z at t = -pi/2)."""
    be, ga = p.beta, p.gamma
    zu = p.F_S / ((1.0 - p.alpha) * p.K_T)

    def rhs(t, y):
        sd = A * np.cos(t)
        return [sd * (1.0 - be * np.sign(sd) * y[0] - ga * abs(y[0]))]

    def period(z0, dense=False):
        return solve_ivp(rhs, (-0.5 * np.pi, 1.5 * np.pi), [z0], method="DOP853",
                         rtol=1e-12, atol=1e-15 * zu, max_step=0.05, dense_output=dense)

    z0 = brentq(lambda z: period(z).y[0, -1] - z, -zu, 0.0, xtol=1e-15 * zu)
    t = np.linspace(-0.5 * np.pi, 1.5 * np.pi, n)
    return t, period(z0, True).sol(t)[0]


def _ivp_describing(p, A):
    t, z = _ivp_loop(p, A)
    F = p.K_T * (p.alpha * A * np.sin(t) + (1.0 - p.alpha) * z)
    return (simpson(F * np.sin(t), x=t) / (np.pi * A),
            simpson(F * np.cos(t), x=t) / (np.pi * A))


def test_bouc_wen_backbone_is_its_time_domain_loop():
    """The Bouc-Wen file's EPMC backbone (exact path): at each point, zeta and omega^2
    from the balance of the point's own orbit with ``k_in``, ``k_q`` of the evolution
    equation's steady loop integrated in time (solve_ivp) at each joint's slip amplitude:
    1e-7 (the describing function's quadrature against the loop: 1e-9 of k_in)."""
    nc = _case("bouc-wen")
    model = nc.model
    bb = epmc_backbone(model, nc.joint_harmonics("exact"), nc.mode,
                       np.array([0.2, 1.0, 4.0]) * nc.phi_max, at="slip")
    for i in range(len(bb)):
        A = bb.slip_amplitude[i]
        kk = np.array([_ivp_describing(p, a) for p, a in zip(nc.joints.params, A)])
        w2, zeta = _first_harmonic_balance(model, bb.q[i, 0], bb.omega[i], bb.xi[i],
                                           kk[:, 0], np.pi * A ** 2 * kk[:, 1])
        assert bb.zeta[i] == pytest.approx(zeta, rel=1e-7)
        assert bb.omega[i] ** 2 == pytest.approx(w2, rel=1e-9)


def test_ring_down_starts_on_the_bouc_wen_steady_loop():
    """runs.ringdown.law_orbit_state: the hysteretic state at phase 0 of an EPMC orbit is
    the steady loop's (the law's step from the loop's turning point ``-z_m`` at ``-A``,
    :meth:`BoucWenJoints.loop_amplitude`, independent of the marching)."""
    from fe.epmc import solve_epmc
    from runs.ringdown import law_orbit_state, warped_step

    nc = _case("bouc-wen")
    law, model = nc.joints, nc.model
    pt = solve_epmc(model, nc.joint_harmonics("exact"), nc.mode, 1.5 * nc.phi_max)
    dt = warped_step(float(pt.omega[0]), 64)[0]
    st = law_orbit_state(model, law, pt.harmonics, pt.q[0], float(pt.omega[0]), dt)
    S = model.G @ pt.q[0, 0]
    A = np.abs(S)
    up = S.imag < 0
    turn = np.where(up, -1.0, 1.0)
    ref = np.stack([turn * A, turn * law.loop_amplitude(A)], axis=-1)
    F, _, ref = law.step(S.real, ref)
    assert st.anchor == pytest.approx(ref, rel=1e-10, abs=1e-12 * nc.phi_max)
    assert st.g == pytest.approx(F - model.K_T * S.real, rel=1e-9)


# ---------------------------------------------------------------- commands and campaigns


@pytest.mark.parametrize("law", ["iwan4", "jenkins", "bouc-wen"])
def test_case_check_and_backbone_run_with_every_law(capsys, law):
    path = str(LAW_FILES[law])
    assert main(["case", "check", path]) == 0
    assert f"joint law of interface 0: {law} (" in capsys.readouterr().out
    assert main(["backbone", "--case", path, "--mode", "2", "--points", "6",
                 "--no-progress", "--json"]) == 0
    points = json.loads(capsys.readouterr().out)
    assert len(points) == 6 and points[-1]["zeta"] > points[0]["zeta"]
    assert main(["backbone", "--case", path, "--mode", "2", "--points", "4",
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert ("chi, R: n/a" in out) == (law != "iwan4")


def test_bouc_wen_has_no_bank_path_and_no_compare(capsys):
    path = str(LAW_FILES["bouc-wen"])
    assert main(["backbone", "--case", path, "--path", "bank", "--points", "3",
                 "--no-progress"]) == 2
    assert "no Jenkins-bank path" in capsys.readouterr().err
    assert main(["backbone", "--case", path, "--compare", "--no-progress"]) == 2
    assert "needs Iwan joints" in capsys.readouterr().err


def test_jenkins_bank_path_is_its_exact_path_below_the_slip():
    """The Jenkins law on both paths: the same stuck mode below ``fs/kt``; above it the
    AFT bank path (harmonics 1, 3, 5, 7) within 1e-3 in zeta of the first harmonic."""
    nc = _case("jenkins")
    amps = np.array([0.5, 3.0]) * nc.phi_max
    ex = epmc_backbone(nc.model, nc.joint_harmonics("exact"), nc.mode, amps, at="slip")
    bk = epmc_backbone(nc.model, nc.joint_harmonics("bank"), nc.mode, amps, at="slip")
    assert bk.omega[0] == pytest.approx(ex.omega[0], rel=1e-12)
    assert bk.zeta[1] == pytest.approx(ex.zeta[1], rel=0.05)
    assert bk.omega[1] == pytest.approx(ex.omega[1], rel=1e-5)


@pytest.mark.parametrize("law, amplitude", [("iwan4", 0.5), ("jenkins", 3.0),
                                            ("bouc-wen", 2.0)])
def test_ringdown_runs_with_every_law_and_meets_the_backbone(tmp_path, capsys, law,
                                                             amplitude):
    """``iwanfe ringdown`` exits 0; the identified decay lies on the EPMC backbone of the
    same joints (frequency within 1e-4; zeta within 5 %: 32 steps per period, a short
    record); Jenkins (its bank, compiled) states its energy balance, Bouc-Wen (its own
    step) says n/a."""
    out = tmp_path / "rd"
    argv = ["ringdown", "--case", str(LAW_FILES[law]), "--mode", "2", "--cycles", "80",
            "--steps-per-period", "32", "--amplitude", str(amplitude), "--response-levels",
            "0", "--no-progress", "--out", str(out)]
    assert main(argv + ["--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    dev = rep["comparison"]["max_deviation"]["ringdown"]
    assert dev["frequency"] < 1e-4 and dev["zeta"] < 0.05, dev
    energy = rep["record"]["energy_J"]
    assert (energy is None) == (law == "bouc-wen")
    if energy is not None:
        assert energy["relative_residual"] < 1e-2
    assert rep["comparison"]["backbone"]["path"] == ("exact" if law == "bouc-wen" else "bank")
    assert main(argv) == 0                          # the stored record, as text
    text = capsys.readouterr().out
    assert "stored record reused" in text
    assert ("energy balance: n/a" in text) == (law == "bouc-wen")


def test_virtual_test_of_a_jenkins_file_is_stuck_below_the_slip():
    """Phase resonance of every level (cases.virtual_test): forces whose resonant slip
    stays below ``fs/kt`` give the stuck mode exactly; above it the frequency falls and
    the slider adds damping (which peaks and falls again in gross slip, ``k_q ~ 4 fs /
    (pi A)``)."""
    from cases.virtual_test import campaign, simulated_table

    nc = _case("jenkins")
    res = campaign(nc)
    stuck = res.slip_amplitude.max(axis=1) < nc.phi_max
    assert stuck[0] and not stuck[-1]
    w0 = float(nc.model.omega[nc.mode - 1])
    assert res.omega2[stuck] == pytest.approx(w0 ** 2, rel=1e-12)
    assert res.zeta[stuck] == pytest.approx(1e-3, rel=1e-9)
    table = simulated_table(nc)
    assert np.all(np.diff(table.omega2[~stuck]) < 0) and np.all(table.zeta[~stuck] > 1.01e-3)


@pytest.mark.parametrize("law", ["jenkins", "bouc-wen"])
def test_stepped_sine_test_of_another_law_agrees_with_phase_resonance(monkeypatch, law):
    """cases.stepped_sine_test on a file of another law (the file's joints, seeded noise):
    the Jenkins bank by multi-harmonic stepped sine, Bouc-Wen by first-harmonic balance
    line by line, each identified by LSCF, against the phase resonance of the same joints
    at the same forces (cases.virtual_test): omega^2 within 1e-4 (the Jenkins slider's
    higher harmonics; measured 3.5e-5), zeta within 3 %."""
    import cases.stepped_sine_test as sst
    from cases.virtual_test import campaign

    monkeypatch.setattr(sst, "LINES", 25)
    case = resolve_case(str(LAW_FILES[law]))
    data, truth = sst.simulate(case, 7)
    assert truth["law"] == law and "chi" not in truth
    assert truth["top_slip_over_phi_max"] == sst.TOP_SLIP_OTHER
    res = campaign(case.nonlinear_model(), data.excitation)
    assert data.omega2 == pytest.approx(res.omega2, rel=1e-4)
    assert data.zeta == pytest.approx(res.zeta, rel=0.03)
    assert data.zeta[-1] > 1.03 * data.zeta[0]         # the top levels slip
