"""Every fit of the diagnosis says whether it converged (inverse/decrement.py,
inverse/diagnosis/lm.py, inverse/diagnosis/fit.py, inverse/diagnosis/cv.py).

Truths: the decrement of a linear least-squares problem is exactly chi2 minus its
minimum (lstsq); optima known in closed form (a linear problem, an exponential decay
planted without noise, a kink at a known place, an optimum beyond a bound); a one-mode
series generated exactly from the quadratic-damping model at parameters the fit does
not see (chi2 = 0 there); an iteration cap of one step, which no start meets the
criterion in.
"""
from __future__ import annotations

import numpy as np
import pytest

from inverse.decrement import DECREMENT_TOL, gauss_newton_decrement
from inverse.diagnosis.lm import levenberg_marquardt


def _linear(A, b):
    return lambda th, rows: (th @ A.T - b) * rows


def test_decrement_of_a_linear_problem_is_the_chi2_above_its_minimum():
    rng = np.random.default_rng(3)
    A, b = rng.standard_normal((12, 3)), rng.standard_normal(12)
    x_min, *_ = np.linalg.lstsq(A, b, rcond=None)
    chi2_min = float(np.sum((A @ x_min - b) ** 2))
    for _ in range(5):
        x = x_min + rng.standard_normal(3)
        r = A @ x - b
        delta = gauss_newton_decrement(A.T[None], r[None])[0]
        assert delta == pytest.approx(float(r @ r) - chi2_min, rel=1e-9)


def test_a_linear_problem_converges_to_its_lstsq_optimum():
    rng = np.random.default_rng(5)
    A = rng.standard_normal((20, 3)) * [1.0, 30.0, 0.2]     # badly scaled columns
    x_true = np.array([0.3, -0.2, 0.6])
    b = A @ x_true + 0.1 * rng.standard_normal(20)
    x_min, *_ = np.linalg.lstsq(A, b, rcond=None)
    se = np.sqrt(np.diag(np.linalg.inv(A.T @ A)))
    starts = rng.uniform(-1, 1, (6, 3))
    out = levenberg_marquardt(_linear(A, b), starts, np.ones((6, 20), bool),
                              np.full(3, -2.0), np.full(3, 2.0), 200)
    assert out.converged.all() and np.all(out.decrement <= DECREMENT_TOL)
    # the criterion's promise: within 0.01 standard errors of the optimum
    assert np.all(np.abs(out.theta - x_min) <= 0.011 * se)


def test_noise_free_planted_decay_is_recovered():
    """Data generated exactly from the model at a seeded parameter: chi2 = 0 there."""
    rng = np.random.default_rng(8)
    truth = rng.uniform([0.5, 0.2], [2.0, 0.8])
    t = np.linspace(0.0, 3.0, 25)
    y = truth[0] * np.exp(-truth[1] * t) / 0.01                    # noise sd 0.01

    def residuals(th, rows):
        return (th[:, :1] * np.exp(-th[:, 1:] * t) / 0.01 - y) * rows

    starts = np.array([[1.0, 0.5], [3.0, 1.5], [0.2, 0.05]])
    out = levenberg_marquardt(residuals, starts, np.ones((3, t.size), bool),
                              np.array([0.0, 0.0]), np.array([5.0, 2.0]), 200)
    assert out.converged.all()
    assert np.all(out.chi2 < DECREMENT_TOL)
    e = np.exp(-truth[1] * t) / 0.01                       # the Jacobian at the truth
    J = np.stack([e, -truth[0] * t * e], 1)
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    assert np.all(np.abs(out.theta - truth) <= 0.011 * se), (out.theta - truth) / se


def test_an_optimum_beyond_a_bound_is_held_there_and_converged():
    A = np.eye(2)
    b = np.array([2.0, 0.25])           # unconstrained optimum (2, 0.25); box [0, 1]^2
    out = levenberg_marquardt(_linear(A, b), np.array([[0.5, 0.5]]), np.ones((1, 2), bool),
                              np.zeros(2), np.ones(2), 200)
    assert out.converged[0]
    assert out.theta[0, 0] == 1.0                               # on the bound, held
    assert abs(out.theta[0, 1] - 0.25) <= 0.011                 # 0.01 se (se = 1)


def test_a_minimum_on_a_kink_is_converged_at_the_kink():
    """chi2 = (1 + 3 |x - 0.3|)^2 + 25 (y - 0.6 + 0.1 x)^2: V-shaped in x at 0.3 (not
    differentiable there), smooth in y; the minimum is (0.3, 0.57)."""
    def residuals(th, rows):
        x, y = th[:, 0], th[:, 1]
        return np.stack([1.0 + 3.0 * np.abs(x - 0.3), 5.0 * (y - 0.6 + 0.1 * x)], 1) * rows

    starts = np.array([[0.9, 0.1], [0.05, 0.95], [0.31, 0.2]])
    out = levenberg_marquardt(residuals, starts, np.ones((3, 2), bool), np.zeros(2),
                              np.ones(2), 200)
    assert out.converged.all(), out
    np.testing.assert_allclose(out.theta[:, 0], 0.3, atol=2e-4)    # h = 1e-4 of the box
    np.testing.assert_allclose(out.theta[:, 1], 0.6 - 0.03, atol=0.011 * 0.2)  # se 0.2


def test_one_step_is_not_converged_and_says_so():
    rng = np.random.default_rng(2)
    t = np.linspace(0.0, 3.0, 25)
    y = 1.3 * np.exp(-0.4 * t) / 0.01 + rng.standard_normal(25)

    def residuals(th, rows):
        return (th[:, :1] * np.exp(-th[:, 1:] * t) / 0.01 - y) * rows

    out = levenberg_marquardt(residuals, np.array([[3.0, 1.5]]), np.ones((1, 25), bool),
                              np.array([0.0, 0.0]), np.array([5.0, 2.0]), 1)
    assert not out.converged[0] and out.iterations[0] == 1
    assert out.decrement[0] > DECREMENT_TOL


# --------------------------------------------------------------------- one-mode fits


def _exact_series(model, theta, linear, n=9):
    """Observations whose data are exactly ``model`` at ``theta`` and the linear
    parameters ``linear`` but ``W`` (returned: the offset that puts the first level's
    omega2 at itself, the design's target being ``omega2 - omega2[0]``); the design
    depends on the measured omega2 and zeta, so by fixed-point iteration."""
    from inverse.diagnosis.models import Observations, design

    s = 2.0 ** ((np.arange(n) - n + 1) / 1.5)
    omega2, zeta = np.full(n, 4.0e5), np.full(n, 0.01)
    sigma = {"omega2": np.full(n, 8.0), "zeta": np.full(n, 2e-5)}
    x = np.array(linear, float)
    for _ in range(100):
        obs = Observations(level=np.arange(1, n + 1), s=s, omega2=omega2, zeta=zeta,
                           t_run=np.linspace(0, 1, n), log_r=None,
                           response_controlled=True, sigma=sigma)
        A, _, _ = design(model, obs, theta[None])
        x[0] = 0.0
        y = A[0] @ x
        rest_w, new_z = y[:n] * sigma["omega2"], y[n:] * sigma["zeta"]
        x[0] = -rest_w[0]                      # W
        new_w = 4.0e5 + rest_w - rest_w[0]
        done = np.array_equal(new_w, omega2) and np.array_equal(new_z, zeta)
        omega2, zeta = new_w, new_z
        if done:
            break
    return obs, x


def test_fit_of_a_series_generated_exactly_from_the_model_converges_to_its_parameters():
    from inverse.diagnosis.fit import evaluate, fit_model
    from inverse.diagnosis.models import Model

    model = Model(("quadratic-damping",))
    assert model.linear_names(False) == ["W", "c", "K1", "q"]
    rng = np.random.default_rng(17)
    # p = chi + 1, the damping's exponent and saturation: inside their boxes, seeded
    # (the fit sees only the data)
    theta = rng.uniform([0.4, 1.2, 0.3], [0.8, 2.2, 1.5])
    obs, linear = _exact_series(model, theta, [0.0, 10.0, 400.0, 2e-3])
    rows = np.ones(2 * obs.n, bool)
    _, r, _ = evaluate(model, obs, theta[None], rows)
    assert np.sum(r**2) < 1e-12                            # exact: chi2 = 0 at the truth
    f = fit_model(model, obs)
    assert f.converged and f.decrement <= DECREMENT_TOL and f.iterations < 200
    assert f.chi2 < 1e-4
    # standard errors of the nonlinear parameters at the truth (linear ones profiled)
    h = 1e-6
    J = np.stack([(evaluate(model, obs, (theta + h * e)[None], rows)[1][0]
                   - evaluate(model, obs, (theta - h * e)[None], rows)[1][0]) / (2 * h)
                  for e in np.eye(3)], 1)
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    assert np.all(np.abs(f.theta - theta) <= 0.05 * se), (f.theta, theta, se)
    np.testing.assert_allclose(f.linear, linear, rtol=1e-2)


def test_no_step_leaves_every_fold_unconverged_and_failed():
    from inverse.diagnosis.cv import leave_one_out
    from inverse.diagnosis.fit import fit_model
    from inverse.diagnosis.models import Model

    model = Model(("quadratic-damping",))
    obs, _ = _exact_series(model, np.array([0.6, 1.6, 0.8]), [0.0, 10.0, 400.0, 2e-3])
    obs.omega2 = obs.omega2 + 8.0 * np.sin(np.arange(obs.n))     # a misfit of ~1 sigma
    full = fit_model(model, obs)
    assert full.converged
    capped = fit_model(model, obs, iters=1)
    assert not capped.converged and capped.iterations == 1
    # no step at all: every fold stays at its start (a grid point), far outside the
    # 0.1 standard errors a converged fit must reach (inverse.decrement.ACCEPT_TOL)
    folds = leave_one_out(full, obs, iters=0)
    n_folds = obs.n - 2
    assert folds.error is None
    assert folds.failed == n_folds and folds.unconverged == n_folds
    assert "did not converge" in folds.reason
    ok = leave_one_out(full, obs)
    assert ok.error is not None and ok.failed == ok.unconverged == 0


def test_the_diagnosis_counts_unconverged_folds_and_gives_no_gain(monkeypatch):
    """Folds capped at one step: those that did not converge are counted as failed and as
    unconverged, and no gain comes from them; nothing is named on such a gain."""
    import inverse.diagnosis.cv as cv
    from ident.measured import read_measured
    from inverse.diagnosis.run import diagnose

    real = cv.fit_folds
    monkeypatch.setattr(cv, "fit_folds", lambda full, obs, trains, iters=200:
                        real(full, obs, trains, 1))
    r = diagnose(read_measured("cases/data/double_beam_measured.csv"))
    fl = r["failures"]
    assert fl["unconverged_folds"] > 0 and fl["unconverged_folds"] == fl["folds"]
    assert fl["total"] >= fl["folds"]
    hit = set(fl["unconverged"]["folds"])
    assert hit and set(fl["failed_folds"]) >= hit
    for a in r["alternatives"]:
        name = "+".join(a["causes"])
        if name in hit and name != "none":
            assert a["gain"] is None, a
    assert "+".join([r["cause"]] + r["also"]) not in hit


def test_shipped_data_every_fit_converged():
    """The shipped double beam table: every fit, fold, held-out fit and profile point of
    the diagnosis converged, and the JSON says so."""
    from ident.measured import read_measured
    from inverse.diagnosis.run import diagnose

    r = diagnose(read_measured("cases/data/double_beam_measured.csv"))
    fl = r["failures"]
    for key in ("unconverged_fits", "unconverged_folds", "unconverged_held_out",
                "unconverged_profile_points", "unconverged_separability_fits", "total"):
        assert fl[key] == 0, (key, fl)
    assert fl["unconverged"] == {"fits": [], "folds": {}, "held_out": []}
    assert all(e["converged"] for e in r["evidence"].values() if e["available"])
