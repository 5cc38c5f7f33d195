"""Response-controlled stepped sine (runs.response_control) against independent truth: the
linear FRF, the force-controlled solvers at the force it finds, and the EPMC backbone."""
from __future__ import annotations

import numpy as np
import pytest

from fe.harmonic_balance import HBSettings, solve_hb
from fe.hb_exact import solve_hb_exact
from fe.joint_harmonics import BankHarmonics, ExactHarmonics
from fe.reduction import JointBank, JointedSystem, reduced_basis
from joints.iwan import IwanParameters
from runs.campaign import Campaign
from runs.response_control import (ResponseControlProtocol, line_forces,
                                   solve_response_controlled)
from runs.stepped_sine import run_campaign


def three_dof(F_S=30.0):
    M = np.diag([1.0, 2.0, 1.5])
    K = np.array([[3e5, -1e5, 0], [-1e5, 2e5, -1e5], [0, -1e5, 1.5e5]])
    G = np.array([[-1.0, 0.0, 1.0]])
    p = IwanParameters(chi=-0.4, K_T=5e4, F_S=F_S, beta=0.8)
    K_J = K + p.K_T * G.T @ G
    system = JointedSystem(M=M, K=K, C=0.5 * M + 3e-5 * K_J, G=G, K_T=np.array([p.K_T]))
    return reduced_basis(system), system, p


def test_linear_structure_holds_the_amplitude_with_the_linear_force():
    """Joint stuck (huge F_S): the force is A / |H_dd(w)| of the linear FRF (direct solve)."""
    model, system, p = three_dof(F_S=1e20)      # slip / phi_max ~ 1e-20: stuck
    J = ExactHarmonics(p, 1)
    load, control = model.load(np.array([0, 1.0, 0])), model.basis[1]
    for w in (150.0, 251.3, 410.0):
        sol = solve_response_controlled(model, J, load, w, control, 2e-4)
        H = np.linalg.solve(system.K_J - w * w * system.M + 1j * w * system.C, [0, 1.0, 0])[1]
        assert sol.force == pytest.approx(2e-4 / abs(H), rel=1e-10)
        assert abs(control @ sol.q[0]) == pytest.approx(2e-4, rel=1e-12)


@pytest.mark.parametrize("path", ["exact", "bank"])
def test_force_found_reproduces_the_held_amplitude_in_the_force_controlled_solver(path):
    """At the force the response control finds, the force-controlled balance (another
    solver: fe.hb_exact / fe.harmonic_balance) gives the held amplitude, at every line."""
    model, _, p = three_dof()
    load, control = model.load(np.array([0, 1.0, 0])), model.basis[1]
    if path == "exact":
        J = ExactHarmonics(p, 1)
    else:
        settings = HBSettings(n_harmonics=5, n_time=128)
        bank = JointBank.from_iwan(p, 60, 1)
        J = BankHarmonics(bank, settings.harmonics, settings.n_time)
    A = 0.5 * p.phi_max / abs(model.G[0] @ np.linalg.solve(model.K, load)) * 1e-2
    for w in np.linspace(230.0, 270.0, 5):
        sol = solve_response_controlled(model, J, load, w, control, A)
        if path == "exact":
            ref = solve_hb_exact(model, p, load * sol.force, w)
        else:
            ref = solve_hb(model, bank, load * sol.force, w, settings)
        i1 = int(np.flatnonzero(ref.harmonics == 1)[0])
        assert abs(control @ ref.q[i1]) == pytest.approx(A, rel=1e-8)
        assert np.allclose(ref.q, sol.q, rtol=1e-7, atol=1e-9 * np.abs(sol.q).max())


def test_campaign_store_resumes(tmp_path):
    """Through runs.stepped_sine.run_campaign: stored levels are loaded, not recomputed, and
    the line forces are the held amplitude over the receptance."""
    model, _, p = three_dof()
    proto = ResponseControlProtocol.exact(1, [p])
    camp = Campaign(np.linspace(35.0, 45.0, 11), [1e-5, 4e-5], np.array([0, 1.0, 0]),
                    np.array([1, 2]), proto)
    first = run_campaign(model, JointBank.from_iwan(p, 10, 1), camp, store=tmp_path,
                         progress=False)
    again = run_campaign(model, JointBank.from_iwan(p, 10, 1), camp, store=tmp_path,
                         progress=False)
    assert not again.computed.any() and np.array_equal(first.receptance, again.receptance)
    F = line_forces(first, camp)
    assert np.allclose(F * np.abs(first.receptance[:, :, 0]), camp.force[:, None], rtol=1e-12)
    with pytest.raises(ValueError, match="not among"):
        line_forces(first, Campaign(camp.frequency_hz, camp.force, camp.load, np.array([2]),
                                    proto))


@pytest.mark.parametrize("path", ["exact", "bank"])
def test_double_beam_response_control_agrees_with_epmc(path):
    """Acceptance: at 10 drive-point amplitudes across micro-slip (largest slip 1e-3 to
    0.46 phi_max) the response-controlled virtual test, identified by LSCF as measured data
    are, agrees with the EPMC backbone within 1e-5 in frequency and 1 % in damping."""
    from cases.backbone_routes import epmc_route, response_route
    from cases.nonlinear_case import build_nonlinear_case
    from fe.epmc import epmc_backbone

    case = build_nonlinear_case("double-beam")
    J = case.joint_harmonics(path)
    slips = np.geomspace(1e-3, 0.46, 10) * case.phi_max
    held = epmc_backbone(case.model, J, case.mode, slips).dof_amplitude(case.drive_dof)
    if path == "bank":
        held = held[::3]                                  # 4 levels: the bank path is slower
    data, slip = response_route(case, held, path)
    ref, _, _ = epmc_route(case, held, path)
    assert np.max(slip.max(axis=1) / case.phi_max) < 0.5
    assert np.max(np.abs(np.sqrt(data.omega2 / ref.omega2) - 1)) < 1e-5
    assert np.max(np.abs(data.zeta / ref.zeta - 1)) < 1e-2
    assert np.all(data.control == "response")
