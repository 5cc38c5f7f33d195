"""EPMC nonlinear modes (fe.epmc) against independent truth: the exact describing-function
backbone of a single-DOF Iwan oscillator, linear modal analysis, the energy balance, and
the forced response at phase resonance."""
from __future__ import annotations

import numpy as np
import pytest

from fe.epmc import epmc_backbone, linear_mode
from fe.hb_exact import solve_hb_exact
from fe.joint_harmonics import BankHarmonics, ExactHarmonics
from fe.reduction import JointBank, JointedSystem, ReducedModel, reduced_basis
from joints.describing import describing_function
from joints.iwan import IwanParameters, dissipation_per_cycle


def sdof(p: IwanParameters, m: float, c: float = 0.0) -> ReducedModel:
    """Mass ``m`` on the Iwan joint alone (``K = K_T``), optional dashpot ``c``."""
    return ReducedModel(basis=np.eye(1), omega=np.array([np.sqrt(p.K_T / m)]),
                        M=np.array([[m]]), K=np.array([[p.K_T]]), C=np.array([[c]]),
                        G=np.eye(1), K_T=np.array([p.K_T]), n_modes=1)


def random_joint(seed):
    rng = np.random.default_rng(seed)
    return (IwanParameters(chi=rng.uniform(-0.9, -0.1), K_T=10 ** rng.uniform(4, 8),
                           F_S=10 ** rng.uniform(1, 3),
                           beta=rng.choice([0.0, rng.uniform(0.1, 5)])),
            10 ** rng.uniform(-1, 1))


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_sdof_exact_path_is_the_describing_function_backbone(seed):
    """Acceptance: omega^2 = k_in(A)/m, zeta = k_q(A)/(2 m omega^2) to 1e-8 from 1e-3 to
    3 phi_max (joints.describing: a separate implementation of the closed form)."""
    p, m = random_joint(seed)
    A = np.geomspace(1e-3, 3.0, 40) * p.phi_max
    bb = epmc_backbone(sdof(p, m), ExactHarmonics(p, 1), 1, A)
    k_in, k_q = describing_function(p, A)
    w2 = k_in / m
    assert np.max(np.abs(bb.omega2 / w2 - 1)) < 1e-8
    assert np.max(np.abs(bb.zeta / (k_q / (2 * m * w2)) - 1)) < 1e-8
    assert np.allclose(bb.slip_amplitude[:, 0], A, rtol=1e-12)
    # energy: peak kinetic energy of the harmonic motion, m w^2 A^2 / 2
    assert np.allclose(bb.energy, 0.5 * m * w2 * A ** 2, rtol=1e-8)


def test_sdof_bank_path_first_harmonic_converges_to_the_describing_function():
    """Jenkins bank by AFT (one harmonic): discretization error only, falling with sliders."""
    p, m = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0), 1.0
    A = np.geomspace(1e-2, 2.0, 8) * p.phi_max
    k_in, k_q = describing_function(p, A)
    errs = []
    for n in (200, 800):
        bb = epmc_backbone(sdof(p, m), BankHarmonics(JointBank.from_iwan(p, n, 1), (1,), 512), 1, A)
        errs.append(np.max(np.abs(bb.zeta / (k_q / (2 * k_in)) - 1)))
        assert np.max(np.abs(bb.omega2 / (k_in / m) - 1)) < 1e-3
    assert errs[1] < errs[0] / 4 and errs[1] < 2e-3


def test_energy_balance_multi_harmonic_bank_path():
    """Work of the artificial damping per period = viscous + joint dissipation; the joint's
    from the AFT force loop integrated over the synthesized slip (trapezoid on the closed
    loop), independent of the balance's Fourier coefficients."""
    p = IwanParameters(chi=-0.4, K_T=2e5, F_S=300.0, beta=0.5)
    m, c = 2.0, 3.0
    model = sdof(p, m, c)
    joints = BankHarmonics(JointBank.from_iwan(p, 300, 1), (1, 3, 5, 7), 512)
    bb = epmc_backbone(model, joints, 1, np.array([0.3, 1.0, 2.0]) * p.phi_max)
    from fe.aft import aft_joint_force

    for i in range(len(bb)):
        w, Q = bb.omega[i], bb.q[i, :, 0]
        theta = 2 * np.pi * np.arange(512) / 512
        s = (Q[None, :] * np.exp(1j * np.outer(theta, bb.harmonics))).real.sum(axis=1)
        F, _ = aft_joint_force(s[None, :], joints.bank)
        ds = np.roll(s, -1) - s
        W_joint = np.sum(0.5 * (F[0] + np.roll(F[0], -1)) * ds)
        hw2 = (bb.harmonics * w) ** 2
        W_visc = np.pi / w * c * np.sum(hw2 * np.abs(Q) ** 2)
        W_xi = np.pi / w * bb.xi[i] * m * np.sum(hw2 * np.abs(Q) ** 2)
        assert W_xi == pytest.approx(W_visc + W_joint, rel=1e-4)   # trapezoid: 2.5e-5


def lumped_like(K_T=1e4, F_S=1e6):
    """3 masses with a joint between masses 1 and 3 and Rayleigh damping."""
    M = np.diag([1.0, 2.0, 1.5])
    K = np.array([[3e5, -1e5, 0], [-1e5, 2e5, -1e5], [0, -1e5, 1.5e5]])
    G = np.array([[-1.0, 0.0, 1.0]])
    K_J = K + K_T * G.T @ G
    a, b = 0.8, 2e-5
    system = JointedSystem(M=M, K=K, C=a * M + b * K_J, G=G, K_T=np.array([K_T]))
    return system, IwanParameters(chi=-0.2, K_T=K_T, F_S=F_S, beta=1.0), (a, b)


@pytest.mark.parametrize("mode", [1, 2, 3])
def test_linear_limit_is_the_modal_analysis(mode):
    """Far below phi_max the joint is stuck: the EPMC frequency is the undamped natural
    frequency and zeta the Rayleigh modal damping a/(2w) + b w/2 (closed form)."""
    system, p, (a, b) = lumped_like(F_S=1e9)      # phi_max huge: deep micro-slip
    model = reduced_basis(system)
    w_ref = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(system.M, system.K_J)).real))
    bb = epmc_backbone(model, ExactHarmonics(p, 1), mode, [1e-14 * p.phi_max], at="modal")
    assert bb.omega[0] == pytest.approx(w_ref[mode - 1], rel=1e-9)
    w = w_ref[mode - 1]
    assert bb.zeta[0] == pytest.approx(a / (2 * w) + b * w / 2, rel=1e-7)


def test_normalizations_give_one_backbone():
    """At the same amplitude the slip-, modal- and DOF-normalized branches agree."""
    system, p, _ = lumped_like(F_S=50.0)
    model = reduced_basis(system)
    J = ExactHarmonics(p, 1)
    ref = epmc_backbone(model, J, 2, np.geomspace(1e-2, 2, 15) * p.phi_max, at="slip")
    _, phi = linear_mode(model, 2)
    proj = np.abs(ref.first_harmonic @ (model.M @ phi))      # "modal": projection on phi
    by_modal = epmc_backbone(model, J, 2, proj[3:10], at="modal")
    assert np.allclose(by_modal.omega, ref.omega[3:10], rtol=1e-9)
    assert np.allclose(by_modal.zeta, ref.zeta[3:10], rtol=1e-7)
    xd = ref.dof_amplitude(0)
    by_dof = epmc_backbone(model, J, 2, xd[3:10], at=0)
    assert np.allclose(by_dof.omega, ref.omega[3:10], rtol=1e-9)
    # reading the backbone between points (monotone cubic in ln a)
    mid = ref.at(np.sqrt(ref.amplitude[5] * ref.amplitude[6]))
    exact = epmc_backbone(model, J, 2, [np.sqrt(ref.amplitude[5] * ref.amplitude[6])])
    assert mid["omega2"][0] == pytest.approx(exact.omega2[0], rel=1e-6)
    assert mid["zeta"][0] == pytest.approx(exact.zeta[0], rel=1e-3)


def test_phase_resonance_of_the_forced_response():
    """Driving the SDOF at the EPMC frequency with the force of eq. 1 of fe.backbone gives
    the backbone's amplitude 90 degrees behind the force (fe.hb_exact: another solver)."""
    p, m, c = IwanParameters(chi=-0.3, K_T=5e4, F_S=80.0, beta=2.0), 0.7, 2.0
    model = sdof(p, m, c)
    bb = epmc_backbone(model, ExactHarmonics(p, 1), 1, np.geomspace(0.05, 2.5, 12) * p.phi_max)
    F = bb.force_at_resonance(0)
    for i in (2, 7, 11):
        sol = solve_hb_exact(model, p, np.array([F[i]]), bb.omega[i])
        X = sol.q[0, 0]
        assert abs(X) == pytest.approx(bb.amplitude[i], rel=1e-9)
        assert np.angle(X) == pytest.approx(-np.pi / 2, abs=1e-9)
    pred = bb.at_force(F[4:9], 0)
    assert np.allclose(pred["omega2"], bb.omega2[4:9], rtol=1e-12)
    assert np.allclose(pred["dof_amplitude"], bb.amplitude[4:9], rtol=1e-10)


def test_double_beam_energy_balance_exact_path():
    """xi = modal viscous damping of the shape + joint dissipation / (pi w a^2), the joint
    term from joints.iwan.dissipation_per_cycle (independent of the describing function)."""
    from cases.nonlinear_case import build_nonlinear_case

    case = build_nonlinear_case("double-beam")
    bb = epmc_backbone(case.model, case.joint_harmonics("exact"), case.mode,
                       np.geomspace(1e-3, 3, 6) * case.phi_max)
    Q = bb.first_harmonic
    a2 = bb.modal_amplitude ** 2
    visc = np.einsum("ni,ij,nj->n", Q.conj(), case.model.C, Q).real / a2
    D = np.array([[dissipation_per_cycle(p, A) for p, A in zip(case.joints, row)]
                  for row in bb.slip_amplitude]).sum(axis=1)
    assert np.allclose(bb.xi, visc + D / (np.pi * bb.omega * a2), rtol=1e-10)
    w0, _ = linear_mode(case.model, case.mode)
    assert w0 / (2 * np.pi) == pytest.approx(252.0, abs=0.01)
    assert np.all(np.diff(bb.omega) < 0) and np.all(np.diff(bb.zeta) > 0)


def test_bad_input():
    p, m = IwanParameters(chi=-0.5, K_T=1e5, F_S=100.0, beta=1.0), 1.0
    J = ExactHarmonics(p, 1)
    with pytest.raises(ValueError, match="increase"):
        epmc_backbone(sdof(p, m), J, 1, [2e-6, 1e-6])
    with pytest.raises(ValueError, match="> 0"):
        epmc_backbone(sdof(p, m), J, 1, [0.0, 1e-6])
    with pytest.raises(ValueError, match="mode must be"):
        epmc_backbone(sdof(p, m), J, 2, [1e-6])
    system, p2, _ = lumped_like()
    sym = ReducedModel(basis=np.eye(2), omega=np.ones(2), M=np.eye(2), K=np.diag([1.0, 4.0]),
                       C=np.zeros((2, 2)), G=np.array([[0.0, 1.0]]), K_T=np.array([1.0]))
    with pytest.raises(ValueError, match="does not slip"):
        epmc_backbone(sym, ExactHarmonics(IwanParameters(-0.5, 1.0, 1.0, 0.0), 1), 1, [1e-3])
