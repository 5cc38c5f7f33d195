"""Scale and speed: campaigns through runs.executor (serial, processes, dask cluster:
bitwise the same numbers), the compiled Newmark loop on the Jenkins kernel (bitwise
the joint forces of jenkins_update), the exact first-harmonic balance with continuous
Iwan joints against an independent scalar root, and the full (unreduced) model."""
import json
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

from cases.lumped10.model import LumpedParameters, force_vector, lumped10_bank, lumped10_system
from runs.executor import ExecutorSpec
from fe.harmonic_balance import HBSettings, solve_hb
from fe.hb_exact import ExactIwanJoints, iwan_describing, continuation_exact, solve_hb_exact
from fe.newmark import NewmarkIntegrator, NewmarkSettings, integrate
from fe.reduction import JointedSystem, full_model, reduced_basis
from runs.campaign import Campaign, NewmarkProtocol
from runs.stepped_sine import run_campaign
from joints.describing import describing_function
from joints.iwan import IwanParameters
from joints.jenkins import jenkins_update

SDOF_JOINT = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)


def bits(a):
    a = np.asarray(a)
    if np.iscomplexobj(a):
        a = np.stack([a.real, a.imag])
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


@pytest.fixture(scope="module")
def lumped():
    p = LumpedParameters()
    s = lumped10_system(p)
    return p, s, reduced_basis(s), lumped10_bank(p, 30)


def sdof(zeta=0.005, f_stuck=100.0, p=SDOF_JOINT):
    """Mass on an Iwan joint (the joint is the only stiffness), viscous damping."""
    mass = p.K_T / (2 * np.pi * f_stuck) ** 2
    c = 2 * zeta * np.sqrt(p.K_T * mass)
    system = JointedSystem(M=np.array([[mass]]), K=np.zeros((1, 1)), C=np.array([[c]]),
                           G=np.eye(1), K_T=np.array([p.K_T]))
    return mass, c, reduced_basis(system)


# ------------------------------------------------------------- campaigns on executors


def test_campaign_bitwise_equal_on_dask_cluster_and_process_pool(lumped, tmp_path, capsys):
    """The same campaign serially, on a LocalCluster of 2 dask workers (started by the
    campaign) and in a pool of 2 processes (legacy ``workers=2``): bitwise equal arrays;
    every level stored as it completes. dask and distributed are declared dependencies:
    the cluster (loopback interface, any free port, no dashboard) must start here."""
    p, s, m, bank = lumped
    camp = Campaign(np.arange(60.0, 62.51, 0.5), [4.0, 64.0, 512.0], force_vector(p),
                    [4, 5])
    serial = run_campaign(m, bank, camp, store=tmp_path / "serial", progress=False)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        on_dask = run_campaign(m, bank, camp, store=tmp_path / "dask", executor="dask",
                               workers=2)
    assert "local dask cluster of 2 workers" in capsys.readouterr().err   # progress shown
    pooled = run_campaign(m, bank, camp, workers=2, progress=False)
    for other in (on_dask, pooled):
        for name in ("receptance", "slip", "slip_amplitude", "work"):
            assert np.array_equal(bits(getattr(other, name)), bits(getattr(serial, name))), name
    assert on_dask.computed.all()
    manifest = json.loads((tmp_path / "dask" / "manifest.json").read_text())
    assert sorted(manifest["levels"]) == ["0", "1", "2"]
    # the joints really slip at the top level (the comparison is not a linear one)
    assert serial.slip_amplitude[-1].max() > 0.3 * p.joint.phi_max
    # a rerun on the cluster's store loads everything
    again = run_campaign(m, bank, camp, store=tmp_path / "dask", progress=False,
                         executor=ExecutorSpec("serial"))
    assert not again.computed.any()
    assert np.array_equal(bits(again.receptance), bits(serial.receptance))


def test_campaign_executor_arguments(lumped):
    p, s, m, bank = lumped
    camp = Campaign([61.0], [2.0], force_vector(p), [4])
    with pytest.raises(ValueError, match="inside the ExecutorSpec"):
        run_campaign(m, bank, camp, progress=False, workers=2,
                     executor=ExecutorSpec("processes", 2))
    with pytest.raises(ValueError, match="workers"):
        run_campaign(m, bank, camp, progress=False, workers=0)
    with pytest.raises(ValueError, match="executor must be one of"):
        run_campaign(m, bank, camp, progress=False, executor="threads")


# ------------------------------------------------------------- Newmark on the kernel


def test_newmark_joint_states_are_jenkins_update_bitwise(lumped):
    """Replaying jenkins_update over the compiled loop's slip history gives bitwise its
    committed slider states and final joint force, and its friction work to rounding."""
    p, s, m, _ = lumped
    bank = lumped10_bank(p, 100)
    w, N = 2 * np.pi * 61.5, 128
    dt = 2 * np.pi / (w * N)
    e = np.sin(w * dt * np.arange(12 * N + 1))
    run = integrate(m, bank, m.load(force_vector(p) * 200.0), e, NewmarkSettings(dt=dt))
    anchor = bank.initial_anchor()
    work = 0.0
    for s_k in run.slip[1:]:
        F, _, new = jenkins_update(s_k, anchor, bank.stiffness, bank.slip_limit)
        work += bank.dissipated(anchor, new)
        anchor = new
    assert np.array_equal(bits(anchor), bits(run.state.anchor))
    assert np.array_equal(bits(F - m.K_T * run.slip[-1]), bits(run.state.g))
    assert run.energy.joint_dissipation == pytest.approx(work, rel=1e-12)
    assert np.abs(run.slip).max() > 0.3 * p.joint.phi_max          # well into micro-slip


def test_integrator_reuse_equals_integrate_and_chunks_equal_one_run(lumped):
    """A NewmarkIntegrator run in two chunks = one integrate() over both (bitwise)."""
    p, s, m, bank = lumped
    w, N = 2 * np.pi * 173.0, 64
    dt = 2 * np.pi / (w * N)
    e = np.cos(w * dt * np.arange(20 * N + 1))
    load = m.load(force_vector(p) * 300.0)
    one = integrate(m, bank, load, e, NewmarkSettings(dt=dt, alpha=-0.05))
    stepper = NewmarkIntegrator(m, bank, NewmarkSettings(dt=dt, alpha=-0.05))
    a = stepper.run(load, e[:7 * N + 1])
    b = stepper.run(load, e[7 * N:], a.state)
    assert np.array_equal(bits(np.vstack([a.q, b.q[1:]])), bits(one.q))
    assert np.array_equal(bits(b.state.anchor), bits(one.state.anchor))


def test_full_model_equals_all_modes_basis(lumped):
    """Physical coordinates (identity basis) and the basis of all modes integrate the
    same equations: same response to round-off (different algebra)."""
    p, s, m, bank = lumped
    full = full_model(s)
    assert full.n_reduced == s.n_dof
    np.testing.assert_allclose(full.omega, m.omega, rtol=1e-10)
    w, N = 2 * np.pi * 61.5, 128
    dt = 2 * np.pi / (w * N)
    e = np.cos(w * dt * np.arange(30 * N + 1))
    a = integrate(full, bank, full.load(force_vector(p) * 128.0), e, NewmarkSettings(dt=dt))
    b = integrate(m, bank, m.load(force_vector(p) * 128.0), e, NewmarkSettings(dt=dt))
    x_b = b.q @ m.basis.T
    np.testing.assert_allclose(a.q, x_b, rtol=0, atol=1e-9 * np.abs(x_b).max())
    assert a.energy.joint_dissipation == pytest.approx(b.energy.joint_dissipation, rel=1e-7)


# ------------------------------------------------------ exact first-harmonic balance


def test_describing_function_derivatives():
    """The law of two joints (iwan_describing) equals the one-joint call
    joints.describing.describing_function (micro and macro-slip, beta > 0 and = 0; one
    implementation, its closed form checked against quadrature of the Masing loop in
    tests/test_iwan.py) and its A-derivatives equal central differences."""
    for p in (SDOF_JOINT, IwanParameters(chi=-0.3, K_T=2e7, F_S=90.0, beta=0.0)):
        J = ExactIwanJoints([p, p], 2)
        for x in (0.01, 0.3, 0.97, 1.05, 2.4, 7.0):   # A/2 never at phi_max (kink)
            A = np.array([x, 0.5 * x]) * p.phi_max
            k_in, k_q, dk_in, dk_q = iwan_describing(J, A)
            ref_in, ref_q = describing_function(p, A)
            np.testing.assert_allclose(k_in, ref_in, rtol=1e-14)
            np.testing.assert_allclose(k_q, ref_q, rtol=1e-14)
            h = 1e-6 * A
            fd = [(a - b) / (2 * h) for a, b in zip(iwan_describing(J, A + h)[:2],
                                                    iwan_describing(J, A - h)[:2])]
            np.testing.assert_allclose(dk_in, fd[0], rtol=1e-6)
            np.testing.assert_allclose(dk_q, fd[1], rtol=1e-6)


@pytest.mark.parametrize("level", [0.1, 0.5, 2.0])
def test_exact_first_harmonic_balance_equals_scalar_root(level):
    """SDOF with the exact Iwan joint: the first-harmonic amplitude solves
    |k_in(A) - m w^2 + i(k_q(A) + w c)| A = P (a scalar root found by Brent's method on
    joints.describing.describing_function) to 1e-10, along a sweep through resonance."""
    p = SDOF_JOINT
    mass, c, model = sdof()
    A0 = level * p.phi_max
    k_in, k_q = describing_function(p, A0)
    w_r = np.sqrt(k_in / mass)
    P = A0 * (k_q + w_r * c)                       # phase resonance at slip A0
    zeta = min(3 * (k_q + w_r * c) / (2 * k_in), 0.5)
    omegas = w_r * np.linspace(1 - zeta, 1 + zeta, 13)
    sols = continuation_exact(model, p, model.load(np.array([P])), omegas)
    worst = 0.0
    for sol in sols:
        w = sol.omega

        def residual(A):
            ki, kq = describing_function(p, A)
            return abs(ki - mass * w * w + 1j * (kq + w * c)) * A - P

        grid = np.geomspace(1e-4, 50, 400) * p.phi_max
        vals = np.array([residual(a) for a in grid])
        roots = [brentq(residual, grid[i], grid[i + 1], xtol=1e-15 * p.phi_max, rtol=1e-15)
                 for i in np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))]
        A_true = min(roots, key=lambda a: abs(a - sol.slip_amplitude[0]))
        ki, kq = describing_function(p, A_true)
        X_true = P / (ki - mass * w * w + 1j * (kq + w * c))
        worst = max(worst, abs(sol.slip[0, 0] - X_true) / abs(X_true))
    assert worst < 1e-10
    peak = max(s.slip_amplitude[0] for s in sols)
    assert peak == pytest.approx(A0, rel=0.02)     # the sweep reaches the level asked for


def test_exact_balance_matches_fine_jenkins_bank_on_two_joints(lumped):
    """Two joints (10-DOF model): the exact first-harmonic balance and the H = 1 AFT
    balance on a fine Jenkins bank agree to the bank's discretization error."""
    p, s, m, _ = lumped
    fine = lumped10_bank(p, 800)
    load = m.load(force_vector(p) * 64.0)
    for f_hz in (60.5, 61.5):
        w = 2 * np.pi * f_hz
        exact = solve_hb_exact(m, p.joint, load, w)
        bank = solve_hb(m, fine, load, w, HBSettings(n_harmonics=1, n_time=1024))
        assert exact.slip_amplitude.max() > 0.2 * p.joint.phi_max
        np.testing.assert_allclose(bank.slip[0], exact.slip[0], rtol=2e-4)
        np.testing.assert_allclose(bank.q[0], exact.q[0], rtol=2e-4,
                                   atol=1e-6 * np.abs(exact.q[0]).max())


def test_exact_balance_input_checks(lumped):
    p, s, m, _ = lumped
    other = IwanParameters(chi=-0.5, K_T=2e5, F_S=400.0, beta=4.0)
    with pytest.raises(ValueError, match="K_T"):
        solve_hb_exact(m, other, m.load(force_vector(p)), 2 * np.pi * 61.0)
    with pytest.raises(ValueError, match="one IwanParameters per joint"):
        solve_hb_exact(m, [p.joint] * 3, m.load(force_vector(p)), 2 * np.pi * 61.0)


def test_newmark_protocol_on_full_model_matches_reduced(lumped):
    """Stepped-sine Newmark protocol, full model vs all-modes basis: same receptance."""
    p, s, m, bank = lumped
    camp = Campaign([61.0, 61.5], [64.0], force_vector(p), [4, 5], NewmarkProtocol(tol=1e-6))
    a = run_campaign(full_model(s), bank, camp, progress=False)
    b = run_campaign(m, bank, camp, progress=False)
    np.testing.assert_allclose(a.receptance, b.receptance, rtol=1e-6)


# ------------------------------------------------------------- commands on executors


def _numbers(d):
    """The JSON report without wall times and output paths."""
    return {k: v for k, v in d.items() if k not in ("timings_s", "files")}


def test_reproduce_lumped_command_on_a_process_pool_equals_serial(tmp_path, capsys):
    """``iwanfe reproduce lumped --executor processes --workers 2`` prints the same
    numbers (chi, R errors, Tables 1-2, identified modes) as the serial run, bit for bit
    in the JSON; contradictory options are one-line errors."""
    from cli.main import main

    common = ["reproduce", "lumped", "--bands-only", "--n-sliders", "20", "--json",
              "--no-progress"]
    assert main(common + ["--out", str(tmp_path / "serial")]) == 0
    serial = json.loads(capsys.readouterr().out)
    assert main(common + ["--out", str(tmp_path / "pool"), "--executor", "processes",
                          "--workers", "2"]) == 0
    pooled = json.loads(capsys.readouterr().out)
    assert _numbers(pooled) == _numbers(serial)
    assert all(-1.0 < v < 0.0 for v in serial["chi_paper_method"].values())
    assert main(common + ["--executor", "serial", "--workers", "2"]) == 2
    assert "--executor serial takes neither" in capsys.readouterr().err


def test_convergence_meshes_on_a_process_pool_equal_serial():
    """The double-beam mesh loop of cases.convergence through runs.executor.run_sweep: a
    2-process pool gives the serial numbers exactly (two strip meshes, two joint meshes)."""
    from cases.convergence import double_beam_study

    kw = dict(element_sizes=(0.02, 0.01, 0.005), joints=(2, 3, 5))
    serial = double_beam_study(**kw)
    pooled = double_beam_study(**kw, executor=ExecutorSpec("processes", 2))
    for key in ("element_size_sweep", "joint_sweep"):
        for q in ("frequency_hz", "glue_slip"):
            assert np.array_equal(bits(pooled[key][q]), bits(serial[key][q]))
    assert pooled["default"] == serial["default"]
    # the measured mode near 252 Hz on every mesh (a physical sanity bound)
    assert np.all(np.abs(serial["element_size_sweep"]["frequency_hz"] - 252.0) < 15.0)
