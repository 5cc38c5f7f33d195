"""Batched first-harmonic balance at phase resonance (fe/hb_resonance.py).

Truths: the closed-form single-mode balance with the exact describing function
(joints.describing, an independent implementation of the same law), the linear limit,
the existing single-level exact-DF solver (fe/hb_exact.py), and the Jenkins-bank AFT
path (fe/harmonic_balance.py) on the FE double beam, whose differences are the bank's
discretization (1 harmonic) plus the truncation to one harmonic (7 harmonics).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from fe.harmonic_balance import HBSettings, continuation
from fe.hb_exact import continuation_exact
from fe.hb_resonance import CubicSpring, QuadraticDamper, frf_levels, resonance_levels
from fe.reduction import ReducedModel
from joints.describing import describing_function
from joints.iwan import IwanParameters


def _sdof(k=4.0e4, c=2.0, kT=1.0e4):
    one = np.eye(1)
    return ReducedModel(basis=one, omega=np.array([math.sqrt(k)]), M=one, K=k * one,
                        C=c * one, G=one.copy(), K_T=np.array([kT]))


JOINT = IwanParameters(chi=-0.4, K_T=1.0e4, F_S=3.0, beta=0.5)
FORCES = np.array([0.01, 0.1, 0.5, 2.0, 6.0])          # micro- and macro-slip


def test_single_mode_balance_matches_the_describing_function():
    """q = slip; at phase resonance w^2 = k - K_T + k_in(A), A = F/(w c + k_q(A)),
    zeta = (w c + k_q)/(2 w^2) with k_in, k_q from joints.describing."""
    k, c = 4.0e4, 2.0
    res = resonance_levels(_sdof(k, c), JOINT, np.ones(1), FORCES, 0)
    A = res.slip_amplitude[:, 0]
    assert np.any(A > JOINT.phi_max) and np.any(A < 0.1 * JOINT.phi_max)
    kin, kq = describing_function(JOINT, A)
    w = res.omega
    np.testing.assert_allclose(res.omega2, k - JOINT.K_T + kin, rtol=1e-12)
    np.testing.assert_allclose(A, FORCES / (w * c + kq), rtol=1e-10)
    np.testing.assert_allclose(res.zeta, (w * c + kq) / (2 * w ** 2), rtol=1e-10)


def test_stiffness_scale_scales_structure_and_joint():
    """With a stiffness scale a: w^2 = a (k - K_T + k_in(A)), zeta = (w c + a k_q)/(2 w^2)."""
    k, c = 4.0e4, 2.0
    a = np.array([1.0, 1.21, 0.9])
    res = resonance_levels(_sdof(k, c), JOINT, np.ones(1), [0.5, 0.5, 2.0], 0, scale=a)
    A = res.slip_amplitude[:, 0]
    kin, kq = describing_function(JOINT, A)
    w = res.omega
    np.testing.assert_allclose(res.omega2, a * (k - JOINT.K_T + kin), rtol=1e-12)
    np.testing.assert_allclose(res.zeta, (w * c + a * kq) / (2 * w ** 2), rtol=1e-10)


def test_elements_cubic_spring_and_quadratic_damper():
    """Closed forms on the single mode (joint slip and element coordinate are both q):
    w^2 = k - K_T + k_in(A) + 3/4 k3 A^2 and zeta = (c w + k_q(A) + 8 c2 w^2 A/(3 pi))
    / (2 w^2), A = F / (2 zeta w^2)."""
    k, c, k3, c2 = 4.0e4, 2.0, 3.0e9, 50.0
    one = np.ones((1, 1))
    F = np.array([0.2, 1.0])
    res = resonance_levels(_sdof(k, c), JOINT, np.ones(1), F, 0,
                           elements=[CubicSpring(one, np.array([k3])),
                                     QuadraticDamper(one, np.array([c2]))])
    A = res.element_amplitude[:, 0]
    np.testing.assert_allclose(A, res.slip_amplitude[:, 0], rtol=1e-14)
    kin, kq = describing_function(JOINT, A)
    w = res.omega
    np.testing.assert_allclose(res.omega2, k - JOINT.K_T + kin + 0.75 * k3 * A ** 2, rtol=1e-12)
    imd = c * w + kq + 8 * c2 * w ** 2 * A / (3 * np.pi)
    np.testing.assert_allclose(res.zeta, imd / (2 * w ** 2), rtol=1e-10)
    np.testing.assert_allclose(A, F / imd, rtol=1e-10)


def test_warm_start_gives_the_same_answer():
    model = _sdof()
    cold = resonance_levels(model, JOINT, np.ones(1), FORCES, 0)
    near = resonance_levels(model, JOINT, np.ones(1), FORCES * 1.001, 0)
    warm = resonance_levels(model, JOINT, np.ones(1), FORCES, 0, guess=near)
    np.testing.assert_allclose(warm.omega2, cold.omega2, rtol=1e-13)
    np.testing.assert_allclose(warm.zeta, cold.zeta, rtol=1e-10)


def test_rejects_a_model_not_in_modal_form():
    m = _sdof()
    full = ReducedModel(basis=np.eye(2), omega=np.ones(2), M=np.eye(2),
                        K=np.array([[2.0, -1.0], [-1.0, 2.0]]), C=np.zeros((2, 2)),
                        G=np.array([[1.0, -1.0]]), K_T=m.K_T)
    with pytest.raises(ValueError, match="modal form"):
        resonance_levels(full, JOINT, np.ones(2), [1.0], 0)


@pytest.fixture(scope="module")
def beam():
    """The reproduction's reduced double beam, its Iwan glue and bank (levels 1, 7, 9)."""
    from cases.double_beam.joint_setup import joint_setup, nonlinear_model
    from cases.double_beam.model import build_double_beam
    from cases.double_beam.settings import DoubleBeamStudy, measured_levels

    m = build_double_beam()
    study = DoubleBeamStudy()
    setup = joint_setup(m, measured_levels(study), study)
    red, bank = nonlinear_model(m, setup, study)
    f = np.zeros(m.M.shape[0])
    f[m.drive_dof] = 1.0
    _, shapes = m.modes(setup.fe_mode)
    k = int(np.argmax(np.abs(red.basis.T @ (m.M @ shapes[:, setup.fe_mode - 1]))))
    return red, bank, setup, red.load(f), k


def test_frf_levels_equals_the_single_level_exact_solver(beam):
    red, _, setup, load, _ = beam
    w = 2 * np.pi * np.arange(248.0, 254.01, 1.0)
    q, amp = frf_levels(red, setup.params, load, setup.force[[0, 6, 8]], w)
    for i, lv in enumerate((0, 6, 8)):
        ref = continuation_exact(red, setup.params, load * setup.force[lv], w)
        np.testing.assert_allclose(q[i], [s.q[0] for s in ref], rtol=1e-9, atol=0)
        np.testing.assert_allclose(amp[i], [s.slip_amplitude for s in ref], rtol=1e-9)


def _bank_resonance(red, bank, load, force, k, f0, n_harmonics):
    """Phase resonance of the bank path: modal filter over lines, root of Re D."""
    lines = np.arange(f0 - 2.0, f0 + 2.001, 0.25)
    settings = HBSettings(n_harmonics=n_harmonics, n_time=max(64, 32 * n_harmonics))
    sols = continuation(red, bank, load * force, 2 * np.pi * lines, settings)
    D = load[k] * force / np.array([s.q[list(s.harmonics).index(1), k] for s in sols])
    roots = CubicSpline(lines, D.real).roots(extrapolate=False)
    fr = roots[np.argmin(np.abs(roots - f0))]
    return (2 * np.pi * fr) ** 2, CubicSpline(lines, D.imag)(fr) / (2 * (2 * np.pi * fr) ** 2)


def test_agrees_with_the_jenkins_bank_path(beam):
    """At levels 1 and 7 (0.002 and 0.13 phi_max) the exact-DF resonance and the
    16-per-octave Jenkins bank (1 harmonic) differ only by the bank's discretization:
    within 0.5 % of the joint's own softening and 0.5 % of its damping share (the bank's
    stated accuracy is 1.7e-4 and 1e-3 of the joint terms); with 7 harmonics the
    first-harmonic truncation adds about 1 % of the softening at level 7."""
    red, bank, setup, load, k = beam
    res = resonance_levels(red, setup.params, load, setup.force, k)
    w_k2 = red.omega[k] ** 2
    for lv in (0, 6):
        soft = w_k2 - res.omega2[lv]                       # the glue's softening
        joint_zeta = res.zeta[lv] - setup.zeta_viscous     # the glue's damping share
        om2, ze = _bank_resonance(red, bank, load, setup.force[lv], k,
                                  res.omega[lv] / (2 * np.pi), 1)
        assert abs(om2 - res.omega2[lv]) <= 5e-3 * soft + 1e-3
        assert abs(ze - res.zeta[lv]) <= 5e-3 * joint_zeta + 1e-9
    om2_7h, ze_7h = _bank_resonance(red, bank, load, setup.force[6], k,
                                    res.omega[6] / (2 * np.pi), 7)
    soft = w_k2 - res.omega2[6]
    assert abs(om2_7h - res.omega2[6]) <= 0.03 * soft
    assert abs(ze_7h - res.zeta[6]) <= 0.01 * (res.zeta[6] - setup.zeta_viscous)


def test_a_round_off_acceptance_is_recorded_at_its_level_only(monkeypatch):
    """Round-off planted in the residual of two drawn levels (a term of a drawn 2-20
    tolerances of |Y| whose sign flips at every evaluation, so that no Newton step can
    fall below the tolerance there): the levels accepted at round-off are named in
    ``fallbacks`` with their last update (between tol and STALL_FACTOR tol), the other
    levels are not, and the answer moves by no more than the planted size."""
    import fe.hb_resonance as hb
    from fe.newton_path import STALL_FACTOR

    rng = np.random.default_rng(1931)
    hit = np.zeros(FORCES.size, dtype=bool)
    hit[rng.choice(FORCES.size, 2, replace=False)] = True
    size = rng.uniform(2.0, 20.0) * 1e-12
    clean = resonance_levels(_sdof(), JOINT, np.ones(1), FORCES, 0)
    assert clean.fallbacks == [""] * FORCES.size
    original, calls = hb._Balance.residual, [0]

    def jittered(self, Y, R, Ylin, omega):
        res, *rest = original(self, Y, R, Ylin, omega)
        calls[0] += 1
        planted = (-1.0) ** calls[0] * size * hit * np.abs(Y).max(axis=1)
        return (res + planted[:, None], *rest)

    monkeypatch.setattr(hb._Balance, "residual", jittered)
    res = resonance_levels(_sdof(), JOINT, np.ones(1), FORCES, 0)
    named = np.array([bool(w) for w in res.fallbacks])
    assert named.any() and not np.any(named & ~hit)
    for w in np.array(res.fallbacks)[named]:
        upd = float(w.split("relative update ")[1].split(",")[0])
        assert 1e-12 <= upd < STALL_FACTOR * 1e-12
    np.testing.assert_allclose(res.omega2, clean.omega2, rtol=1e-9)
