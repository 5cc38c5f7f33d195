"""Harmonic balance on the FE double beam over glue stiffnesses 1e6..1e11 N/m and from
micro-slip to deep macro-slip (issue 13, Deliver 4); the one-line failure.

Each case: the double beam with glue stiffness K_T, a small reduced basis, Iwan joints
(chi = -0.4, beta = 0) whose phi_max is a third of the stuck-glue slip at resonance under
1 N, and four levels (0.01 .. 1 N) swept over 15 lines through the resonance. Checked
against independent truth: every solution satisfies the condensed balance equations
evaluated with the reference (numpy) AFT, and with one harmonic the solution at the
peak equals the first-harmonic balance with the *continuous* Iwan joints (exact
describing function, fe.hb_exact) to the bank's discretization error.
"""
import pickle

import numpy as np
import pytest
import scipy.sparse as sp

from cases.double_beam.model import DoubleBeamConfig, build_double_beam
from fe.aft import aft_joint_force
from fe.harmonic_balance import (HBOperator, HBSettings, harmonic_synthesis, _to_real, continuation,
                                 solve_hb)
from fe.hb_exact import solve_hb_exact
from fe.newton_path import SteadyStateError, follow
from fe.reduction import JointBank, JointedSystem, ritz_basis
from joints.iwan import IwanParameters
from runs.campaign import Campaign, HBProtocol
from runs.stepped_sine import run_campaign

CHI = -0.4
FORCES = (0.01, 0.1, 0.3, 1.0)
SETTINGS = HBSettings(n_harmonics=7, n_time=128)


def _case(K_T):
    db = build_double_beam(DoubleBeamConfig(glue_tangential_stiffness=K_T))
    n = db.M.shape[0]
    system = JointedSystem(M=db.M, K=db.K_without_joints, C=sp.csr_matrix((n, n)),
                           G=db.slip_matrix, K_T=db.joint_stiffness)
    red = ritz_basis(system, 8, 0.0128)
    f = np.zeros(n)
    f[db.drive_dof] = 1.0
    i = int(np.argmin(np.abs(red.omega / (2 * np.pi) - 252.0)))
    f0 = red.omega[i] / (2 * np.pi)
    op = HBOperator(red, red.load(f), 2 * np.pi * f0, None, harmonics=np.array([1]))
    pm = np.abs(op.s_lin).max() / 3.0                    # stuck slip at 1 N = 3 phi_max
    params = [IwanParameters(chi=CHI, K_T=k, F_S=k * pm * (CHI + 1) / (CHI + 2), beta=0.0)
              for k in db.joint_stiffness]
    bank = JointBank.log_spaced(params, pm * 2.0 ** -8, 4)
    return db, red, f, f0, pm, params, bank


def _balance_residual(red, bank, sol, load, settings):
    """|S - S_lin + R N(S)| / |S| with the reference (numpy) AFT march."""
    op = HBOperator(red, load, sol.omega, settings)
    E, P = harmonic_synthesis(op.h, settings.n_time)
    y = _to_real(sol.slip, op.h).reshape(-1)
    s_t = (E @ y.reshape(op.nc, op.nj)).T
    F, _ = aft_joint_force(s_t, bank, compiled=False)
    yg = (P @ (F - red.K_T[:, None] * s_t).T).reshape(-1)
    return np.abs(y - op.y_lin + op.Rr @ yg).max() / np.abs(y).max()


@pytest.mark.parametrize("K_T", [1e6, 1e9, 1e11])
def test_hb_converges_from_micro_to_macro_slip_over_the_glue_stiffness_range(K_T):
    db, red, f, f0, pm, params, bank = _case(K_T)
    lines = f0 * np.linspace(0.94, 1.01, 15)
    camp = Campaign(lines, FORCES, f, [db.response_dof], HBProtocol(SETTINGS))
    res = run_campaign(red, bank, camp, progress=False)
    top = res.slip_amplitude.max(axis=(1, 2)) / pm
    assert top[0] < 0.1 and top[-1] > 3.0                  # micro- to macro-slip
    # the top level's solutions satisfy the balance equations (independent AFT)
    sols = continuation(red, bank, red.load(f) * FORCES[-1], 2 * np.pi * lines, SETTINGS)
    np.testing.assert_allclose([s.slip_amplitude.max() for s in sols],
                               res.slip_amplitude[-1].max(axis=1), rtol=1e-9)
    for s in sols[::3]:
        assert _balance_residual(red, bank, s, red.load(f) * FORCES[-1], SETTINGS) < 1e-8
    # one harmonic: the bank against the continuous Iwan joints (exact describing function)
    i = int(np.argmax([s.slip_amplitude.max() for s in sols]))
    one = HBSettings(n_harmonics=1, n_time=256)
    sol1 = solve_hb(red, bank, red.load(f) * FORCES[-1], sols[i].omega, one)
    exact = solve_hb_exact(red, params, red.load(f) * FORCES[-1], sols[i].omega,
                           guess=sol1.slip)
    np.testing.assert_allclose(np.abs(sol1.slip[0]), exact.slip_amplitude, rtol=2e-2)


def test_fresh_start_by_load_continuation_reaches_the_direct_solution():
    """Deep macro-slip from the stuck-joint guess: with a Newton budget too small for a
    direct start, solve_hb raises the load gradually from the all-stuck level; the
    result is the directly converged steady state."""
    db, red, f, f0, pm, params, bank = _case(1e9)
    load, w = red.load(f), 2 * np.pi * f0 * 0.98
    direct = solve_hb(red, bank, load, w, SETTINGS)
    assert direct.slip_amplitude.max() > 20 * pm
    small = HBSettings(n_harmonics=7, n_time=128, max_iter=direct.iterations - 2)
    via = solve_hb(red, bank, load, w, small)
    assert via.iterations > small.max_iter                 # went through the continuation
    np.testing.assert_allclose(via.slip, direct.slip, rtol=0,
                               atol=1e-8 * np.abs(direct.slip).max())


def test_follow_halves_the_step_until_the_corrector_converges():
    """A corrector that only converges from a guess within 0.05 of the root of x^3 = p:
    follow() must reach p = 8 from p = 1 by shrinking and re-growing the step."""
    calls = []

    def solve(p, guess):
        root = p ** (1.0 / 3.0)
        calls.append(p)
        if abs(guess - root) > 0.05:
            raise RuntimeError("too far")
        return root

    def predictor(p, hist):
        (p2, x2) = hist[-1]
        return x2 if len(hist) < 2 else x2 + (p - p2) * (x2 - hist[-2][1]) / (p2 - hist[-2][0])

    x, n = follow(solve, [(1.0, 1.0)], 8.0, predictor, max_halvings=8)
    assert x == pytest.approx(2.0, rel=1e-14)
    assert n == len(calls) and n > 3
    with pytest.raises(RuntimeError):
        follow(solve, [(1.0, 1.0)], 8.0, predictor, max_halvings=1)


def test_failure_is_one_line_naming_level_line_and_reason():
    db, red, f, f0, pm, params, bank = _case(1e9)
    camp = Campaign(f0 * np.array([0.97, 0.98]), [0.01, 0.1, 1.0], f, [db.response_dof],
                    HBProtocol(HBSettings(n_harmonics=7, n_time=128, max_iter=3)))
    with pytest.raises(SteadyStateError) as info:
        run_campaign(red, bank, camp, progress=False)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith("harmonic balance did not converge at level 3 of 3 (F = 1 N), "
                          f"line {f0 * 0.97:.6g} Hz: no convergence in 3 iterations")
    # picklable (levels run in worker processes) with the same message
    assert str(pickle.loads(pickle.dumps(info.value))) == msg
