"""Pseudo-arclength continuation (``fe/continuation.py``) through folds.

Truths: the turning points of ``x^3 - 3x = p`` (closed form); for the Duffing oscillator
``x'' + 2 zeta w0 x' + w0^2 x + k3 x^3 = F cos(w t)`` the vertical tangents of the
first-order multiple-scales frequency response (Nayfeh & Mook 1979, Sec. 4.1.4) and a
refined fold computed by another route (the extremum of ``w`` along the branch
parametrized by one coefficient, Brent's minimization on a bordered Newton solve).

Multiple scales. With ``w = w0 + sigma`` and ``x = a cos(w t - gamma) + O(eps)`` the
steady amplitude ``a`` and detuning ``sigma`` satisfy (Nayfeh & Mook eq. 4.1.27)

    a^2 [(sigma - kappa a^2)^2 + mu^2] = f^2,  kappa = 3 k3/(8 w0), mu = zeta w0,
    f = F/(2 w0).

Writing ``u = a^2``, ``Phi(u, sigma) = u ((sigma - kappa u)^2 + mu^2) - f^2``, the curve
``sigma(u)`` has a vertical tangent in the (sigma, a) plane where ``dPhi/du = 0``:
``v^2 + mu^2 - 2 kappa u v = 0`` with ``v = sigma - kappa u``. With ``Phi = 0`` this gives
``u (2 kappa u v) = f^2``, so ``v = f^2/(2 kappa u^2)``, and substituting,

    4 kappa^2 mu^2 u^4 - 4 kappa^2 f^2 u^3 + f^4 = 0,                               (MS)

whose two positive roots ``u`` give the fold frequencies ``w = w0 + kappa u + f^2/(2
kappa u^2)``. The formula is first order in ``eps = k3 a^2 / w0^2``: its error is
``O(eps^2)`` and falls four-fold when ``k3`` is halved (checked).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from fe.continuation import ContinuationSettings, continue_branch
from fe.hb_forced import ForcedBalance
from fe.law_aft import LawHarmonics
from fe.newton_path import damped_newton
from frc_laws import CubicSpring, sdof
from joints.bank import JointBank
from joints.iwan import IwanParameters


def test_cubic_turning_points_closed_form():
    def res(x, p):
        return np.array([x[0] ** 3 - 3 * x[0] - p]), np.array([[3 * x[0] ** 2 - 3]]), \
            np.array([-1.0])

    b = continue_branch(res, np.array([-2.2]), -5.0, (-5.0, 5.0),
                        ContinuationSettings(ds=0.1, ds_max=0.5))
    folds = sorted((f.p, f.x[0]) for f in b.folds)
    assert len(folds) == 2
    assert abs(folds[0][0] + 2.0) < 1e-12 and abs(folds[0][1] - 1.0) < 1e-6
    assert abs(folds[1][0] - 2.0) < 1e-12 and abs(folds[1][1] + 1.0) < 1e-6
    # the branch went back and forth: it ends on the upper root at p = 5
    assert b.p[-1] == pytest.approx(5.0, abs=1e-14)
    assert b.x[-1, 0] ** 3 - 3 * b.x[-1, 0] == pytest.approx(5.0, abs=1e-9)
    assert b.x[-1, 0] > 2.0


def ms_folds(w0, zeta, k3, F):
    """Fold frequencies of eq. (MS) of the module docstring (ascending)."""
    mu, kap, f = zeta * w0, 3 * k3 / (8 * w0), F / (2 * w0)
    r = np.roots([4 * kap ** 2 * mu ** 2, -4 * kap ** 2 * f ** 2, 0.0, 0.0, f ** 4])
    u = np.sort(r[(np.abs(r.imag) < 1e-9 * np.abs(r)) & (r.real > 0)].real)
    return w0 + kap * u + f ** 2 / (2 * kap * u ** 2)


def refined_fold(bal, fold):
    """The fold as the extremum of ``w(c)`` with the coefficient ``x_k = c`` held (``k``
    the largest tangent component), by Brent's minimization (module docstring)."""
    k = int(np.argmax(np.abs(fold.tangent[:-1])))
    start = np.append(fold.x, fold.p)

    def omega_at(c):
        def ev(y):
            R, Jx, Jw = bal(y[:-1], y[-1])
            e = np.zeros(y.size)
            e[k] = 1.0
            return np.append(R, y[k] - c), np.vstack([np.hstack([Jx, Jw[:, None]]), e])
        y0 = start.copy()
        y0[k] = c
        return damped_newton(ev, y0, 1e-14, 50, 1.0)[0][-1]

    c0 = fold.x[k]
    h = 1e-3 * abs(c0)
    sign = -1.0 if omega_at(c0 + h) < fold.p else 1.0
    res = minimize_scalar(lambda c: sign * omega_at(c), bracket=(c0 - h, c0, c0 + h),
                          tol=1e-12)
    return sign * res.fun


def duffing_branch(zeta, k3, F, harmonics=(1, 3, 5, 7), jacobian="tangent"):
    bal = ForcedBalance(sdof(1.0, zeta), CubicSpring(k3), np.array([F]), harmonics, 64,
                        jacobian=jacobian)
    b = continue_branch(bal, bal.stuck(0.97), 0.97, (0.97, 1.05),
                        ContinuationSettings(ds=0.05, ds_max=0.3), p_scale=0.01)
    return bal, b


def test_duffing_folds_multiple_scales_and_refined():
    errors = []
    for k3 in (0.02, 0.01):
        bal, b = duffing_branch(0.002, k3, 0.004)
        assert len(b.folds) == 2 and b.p[-1] == pytest.approx(1.05)
        w = np.sort([f.p for f in b.folds])
        ms = ms_folds(1.0, 0.002, k3, 0.004)
        err = np.abs(w - ms) / ms
        assert np.all(err < 1e-3)                 # measured 2.0e-5, 1.3e-4 at k3 = 0.02
        errors.append(err)
        for f in b.folds:
            assert abs(f.residual_tangent) < 1e-10
            assert abs(f.p - refined_fold(bal, f)) < 1e-6 * f.p   # measured <= 2.2e-16
    # the discrepancy is the O(eps^2) error of the first-order expansion: x4 per halving
    assert errors[0][1] / errors[1][1] > 3.0      # measured 4.15


def test_fd_jacobian_of_the_march_matches_exact_ones():
    # memoryless law: the step's tangent is the exact Jacobian
    law = CubicSpring(0.3)
    a = LawHarmonics(law, (1, 3, 5), 64, jacobian="tangent")
    b = LawHarmonics(law, (1, 3, 5), 64, jacobian="fd", fd_central=True)
    Y = np.array([[0.8], [0.3], [0.1], [-0.05], [0.02], [0.01]])
    Ga, Ja, _ = a(Y)
    Gb, Jb, _ = b(Y)
    assert np.max(np.abs(Ga - Gb)) == 0.0
    assert np.max(np.abs(Ja - Jb)) < 1e-8 * np.abs(Ja).max()
    # Jenkins bank: its step marched by the generic path against the compiled AFT
    bank = JointBank.from_iwan(IwanParameters(-0.5, 1e4, 10.0, 0.5), 30, n_joints=2)
    pm = IwanParameters(-0.5, 1e4, 10.0, 0.5).phi_max
    Y = pm * np.array([[1.3, 0.4], [0.5, -0.2], [0.1, 0.05], [-0.07, 0.02]])
    exact = LawHarmonics(bank, (1, 3), 128)
    generic = LawHarmonics(bank, (1, 3), 128, jacobian="fd", fd_central=True, fd_step=1e-7)
    Ge, Je, Ae = exact(Y)
    Gg, Jg, Ag = generic(Y)
    assert exact.jacobian == "bank"
    assert np.max(np.abs(Ge - Gg)) < 1e-12 * np.abs(Ge).max()
    assert np.max(np.abs(Je - Jg)) < 1e-5 * np.abs(Je).max()


def test_descending_direction_passes_the_same_folds():
    def res(x, p):
        return np.array([x[0] ** 3 - 3 * x[0] - p]), np.array([[3 * x[0] ** 2 - 3]]), \
            np.array([-1.0])

    b = continue_branch(res, np.array([2.3]), 5.0, (-5.0, 5.0),
                        ContinuationSettings(ds=0.1, ds_max=0.5), direction=-1)
    assert [round(f.p, 12) for f in b.folds] == [-2.0, 2.0]
    assert b.p[0] == 5.0 and b.p[-1] == pytest.approx(-5.0, abs=1e-14)
    assert b.x[-1, 0] < -2.0                          # ends on the lower root
