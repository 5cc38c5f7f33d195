"""Stability of harmonic-balance solutions: Hill's method (``fe/hill.py``) against the
Floquet multipliers of the Newmark period map (``fe/floquet.py``).

Truths: the linear oscillator's exponents ``-zeta w0 +- i w0 sqrt(1 - zeta^2)`` (closed
form); for the Duffing oscillator the multipliers of the time integration (a second
method: the average-acceleration rule linearized on the orbit, which converges as
``dt^2`` to the exact monodromy) and the saddle-node theorem (the multiplier crosses 1
exactly at the folds the continuation locates); for a hysteretic joint the period map of
the nonlinear Newmark integration differentiated numerically.

Duffing, ``x'' + 0.1 x' + x + 0.5 x^3 = 0.1 cos(w t)``, harmonics 1, 3, 5, 7, 128 AFT
samples, Hill perturbation harmonics 0..7: Hill's ``max |exp(lam T)|`` and the Newmark
multiplier differ by 8.4e-6, 2.1e-6, 5.3e-7 with 4096, 8192, 16384 steps per period
(ratio 4.00 per halving) on the lower branch; 1.1e-10 after Richardson extrapolation.
"""
from __future__ import annotations

import numpy as np
import pytest

from fe.continuation import ContinuationSettings, continue_branch
from fe.floquet import floquet_multipliers, period_map_monodromy, tangent_monodromy
from fe.hb_exact import solve_hb_exact
from fe.hb_forced import ForcedBalance
from fe.hill import hill_stability
from frc_laws import CubicSpring, HardenedIwan, sdof
from joints.describing import IwanJoints
from joints.iwan import IwanParameters


def test_linear_oscillator_exponents_closed_form():
    zeta, w = 0.03, 0.9
    bal = ForcedBalance(sdof(1.0, zeta), CubicSpring(0.0), np.array([1.0]), (1, 3), 32,
                        jacobian="tangent")
    h = hill_stability(bal, bal.stuck(w), w)
    assert h.exponents.size == 2
    assert np.allclose(h.exponents.real, -zeta, rtol=0, atol=1e-12)
    wd = np.sqrt(1 - zeta ** 2)
    # each exponent is -zeta +- i wd up to a multiple of i w
    k = (h.exponents.imag - wd) / w
    k2 = (h.exponents.imag + wd) / w
    ok = np.minimum(np.abs(k - np.round(k)), np.abs(k2 - np.round(k2)))
    assert np.all(ok < 1e-10)
    assert h.max_modulus == pytest.approx(np.exp(-zeta * 2 * np.pi / w), rel=1e-12)
    assert h.stable


@pytest.fixture(scope="module")
def duffing():
    bal = ForcedBalance(sdof(1.0, 0.05), CubicSpring(0.5), np.array([0.1]), (1, 3, 5, 7),
                        128, jacobian="tangent")
    b = continue_branch(bal, bal.stuck(0.5), 0.5, (0.5, 2.0),
                        ContinuationSettings(ds=0.05, ds_max=0.3), p_scale=0.1)
    return bal, b


def test_duffing_unstable_exactly_between_the_folds(duffing):
    bal, b = duffing
    assert len(b.folds) == 2
    a0, a1 = sorted(f.after for f in b.folds)
    mods = np.array([hill_stability(bal, x, w).max_modulus for x, w in zip(b.x, b.p)])
    between = np.zeros(b.p.size, dtype=bool)
    between[a0 + 1:a1 + 1] = True
    assert np.array_equal(mods > 1.0, between)
    # at each fold itself a multiplier is 1 (saddle-node)
    for f in b.folds:
        assert hill_stability(bal, f.x, f.p).max_modulus == pytest.approx(1.0, abs=1e-6)


def test_duffing_hill_agrees_with_newmark_floquet(duffing):
    bal, b = duffing
    a0, a1 = sorted(f.after for f in b.folds)
    for i in (a0 - 3, (a0 + a1) // 2, a1 + 3):          # lower, middle, upper branch
        x, w = b.x[i], b.p[i]
        hill = hill_stability(bal, x, w).max_modulus
        m = {n: np.abs(floquet_multipliers(tangent_monodromy(bal, x, w, n))).max()
             for n in (4096, 8192, 16384)}
        assert abs(m[16384] - hill) < 1e-6                       # measured <= 5.3e-7
        assert (m[8192] - hill) / (m[16384] - hill) == pytest.approx(4.0, rel=0.02)
        assert abs((4 * m[16384] - m[8192]) / 3 - hill) < 1e-9   # measured <= 1.1e-10
        assert (hill > 1.0) == (a0 < i <= a1)


@pytest.fixture(scope="module")
def hardened_iwan():
    """Iwan joint (macro-slip from F_S = 0.002 N) in parallel with a cubic spring, on a
    one-DOF oscillator: the hysteresis softens (stuck 1 rad/s, slipping 0.894 rad/s), the
    cubic spring hardens at large amplitude and folds the response."""
    law = HardenedIwan(IwanJoints(IwanParameters(-0.5, 0.2, 0.002, 1.0), 1), 0.05)
    bal = ForcedBalance(sdof(1.0, 0.005, k_joint=0.2), law, np.array([0.01]), (1, 3, 5),
                        128)
    b = continue_branch(bal, bal.stuck(0.85), 0.85, (0.85, 1.0),
                        ContinuationSettings(ds=0.05, ds_max=0.3), x_scale=0.1,
                        p_scale=0.1)
    return bal, b


def test_hysteretic_folds_middle_branch_unstable_by_hill_and_floquet(hardened_iwan):
    bal, b = hardened_iwan
    assert b.p[0] == pytest.approx(0.85) and b.p[-1] == pytest.approx(1.0)
    assert len(b.folds) == 2
    assert sorted(f.p for f in b.folds) == pytest.approx([0.907944, 0.909486], abs=2e-6)
    amp = np.hypot(b.x[:, 0], b.x[:, 1])
    assert amp.max() > 40 * bal.law.iwan.phi_max[0]               # deep macro-slip
    a0, a1 = sorted(f.after for f in b.folds)
    for i, unstable in ((a0 - 2, False), ((a0 + a1) // 2, True), (a1 + 2, False)):
        x, w = b.x[i], b.p[i]
        hill = hill_stability(bal, x, w)
        floq = np.abs(floquet_multipliers(period_map_monodromy(bal, x, w, 1024))).max()
        assert (hill.max_modulus > 1.0) == unstable == (floq > 1.0)
        assert abs(hill.max_modulus - floq) < 2e-3               # measured <= 1.1e-3


def test_softening_iwan_first_harmonic_is_the_describing_function():
    """One harmonic: the AFT of the marched Iwan law is its describing function, so the
    branch is the exact first-harmonic balance of ``fe.hb_exact`` (another solver)."""
    p = IwanParameters(-0.5, 0.5, 0.01, 1.0)
    model = sdof(1.0, 0.01, k_joint=0.5)
    bal = ForcedBalance(model, IwanJoints(p, 1), np.array([0.03]), (1,), 512)
    b = continue_branch(bal, bal.stuck(0.6), 0.6, (0.6, 0.9),
                        ContinuationSettings(ds=0.05, ds_max=0.3), x_scale=1.0,
                        p_scale=0.1)
    assert b.folds == []          # a Masing joint on one DOF does not fold (report)
    amp = np.hypot(b.x[:, 0], b.x[:, 1])
    assert amp.max() > 20 * p.phi_max
    errs = []
    for i in range(0, b.p.size, max(1, b.p.size // 6)):
        ref = solve_hb_exact(model, [p], np.array([0.03]), b.p[i]).slip_amplitude[0]
        errs.append(abs(amp[i] - ref) / ref)
    assert max(errs) < 1e-4                                       # measured 3.5e-5


def test_iwan_oscillator_first_harmonic_curve_never_folds_on_a_grid():
    """Why the folds above need the cubic spring: on one DOF, ``(k + k_in(A) - w^2)^2 +
    (2 zeta w0 w + k_q(A))^2 = F^2/A^2`` with the exact Iwan describing function gives
    ``w^2 = k + k_in -+ sqrt(F^2/A^2 - D^2)`` (``D`` the quadrature term at the backbone
    frequency), and on a grid of joint shares, beta, chi, damping and force (through
    macro-slip) the lower branch rises and the upper one falls monotonically in ``A``:
    one response per frequency, no fold (the friction damping grows with the softening)."""
    folds = 0
    for share, beta, chi in [(0.5, 1.0, -0.5), (0.9, 1.0, -0.5), (0.5, 100.0, -0.5),
                             (0.9, 100.0, -0.1), (0.5, 0.1, -0.9), (0.97, 10.0, -0.5)]:
        p = IwanParameters(chi, share, 0.01, beta)
        A = np.geomspace(0.01, 1e4, 8000) * p.phi_max
        k_in, k_q = IwanJoints(p, 1).describing(A[:, None])
        kap = (1.0 - share) + k_in[:, 0]
        for zeta in (1e-4, 1e-3, 1e-2):
            D = 2 * zeta * np.sqrt(kap) + k_q[:, 0]
            for F in 0.01 * np.geomspace(0.3, 30, 60):
                ok = F / A > D
                s = np.sqrt(F ** 2 / A[ok] ** 2 - D[ok] ** 2)
                w2 = np.concatenate([(kap[ok] - s), (kap[ok] + s)[::-1]])
                folds += int(np.count_nonzero(np.diff(np.sign(np.diff(w2)))))
    assert folds == 0
