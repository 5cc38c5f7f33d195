"""The globalized Newton of fe.newton_path: a step stalled at round-off is accepted only
within STALL_FACTOR of the tolerance, and says so (stall_words)."""
import numpy as np
import pytest

from fe.newton_path import (ROUNDOFF, STALL_FACTOR, SteadyStateError, damped_newton,
                            stall_words)


def _stalling_linear(cond, error, rng):
    """``r(y) = A y - b`` with ``A`` of condition number ``cond`` (singular values from 1
    down to ``1/cond``) whose residual carries an error of size ``error`` along the
    weakest direction, its sign alternating between evaluations: a stand-in for
    round-off that never averages out, so the full Newton step stays at ``2 cond
    error`` once the iterates have converged."""
    n = 6
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    A = Q1 @ np.diag(np.geomspace(1.0, 1.0 / cond, n)) @ Q2.T
    y_true = rng.uniform(0.5, 1.0, n)
    b = A @ y_true
    sign = [1.0]

    def evaluate(y):
        sign[0] = -sign[0]
        return A @ y - b + sign[0] * error * Q1[:, -1], A
    return evaluate, y_true


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_step_stalled_at_round_off_is_accepted_and_named(seed):
    rng = np.random.default_rng(seed)
    tol, error = 1e-13, 1e-16                  # the residual error sits at round-off
    factor = rng.uniform(2.0, 0.5 * STALL_FACTOR)
    cond = factor * tol / (2 * error)          # the stalled step: factor * tol (of max |y| ~ 1)
    assert error < ROUNDOFF * 0.5
    evaluate, y_true = _stalling_linear(cond, error, rng)
    y, it, upd, _ = damped_newton(evaluate, np.zeros(y_true.size), tol, 20, 1.0)
    assert it == 20 and tol < upd <= STALL_FACTOR * tol
    assert upd == pytest.approx(factor * tol / np.abs(y).max(), rel=1e-3)
    assert np.abs(y - y_true).max() < 1e-10
    words = stall_words(upd, tol)
    assert words.startswith("Newton step stalled at round-off") and f"{upd:.1e}" in words
    # the same stall with a tolerance it exceeds by more than STALL_FACTOR: no convergence
    with pytest.raises(SteadyStateError, match="no convergence in 20 iterations"):
        damped_newton(evaluate, np.zeros(y_true.size), upd / (2 * STALL_FACTOR), 20, 1.0)


def test_an_ordinary_convergence_has_no_words():
    rng = np.random.default_rng(4)
    evaluate, y_true = _stalling_linear(10.0, 0.0, rng)
    y, it, upd, _ = damped_newton(evaluate, np.zeros(y_true.size), 1e-10, 20, 1.0)
    assert it < 20 and upd < 1e-10 and stall_words(upd, 1e-10) == ""
    np.testing.assert_allclose(y, y_true, rtol=1e-12)
