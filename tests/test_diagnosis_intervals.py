"""Held-out prediction intervals (``inverse.diagnosis.intervals``) against planted,
seeded truths the code never sees: linear-Gaussian models, where the coverage of the
interval is known exactly, and series simulated from the base model with known noise,
where the coverage over many draws must lie in a binomial band."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, special, stats

from inverse.diagnosis.fit import fit_model
from inverse.diagnosis.intervals import (misfit_scale, parameter_parts, prediction_intervals,
                                         quantile, satterthwaite)
from inverse.diagnosis.models import Model, Observations


def _band(n, p=0.95, k=3.5):
    """Binomial band: p +- k sd of a fraction of n."""
    half = k * math.sqrt(p * (1 - p) / n)
    return p - half, p + half


def _linear_coverage(seed, true_sd, nu_est, draws, pooled_dof=False, scale=True):
    """Coverage per channel of eqs. (1)-(3) on a planted two-channel linear model with
    shared parameters (channel 0: quadratic in x, channel 1: line sharing the offset),
    extrapolated to x = 1.3 from 8 levels in [0.1, 1]. ``true_sd`` the true noise sd
    per channel in units of the assumed one; ``nu_est`` the degrees of freedom of the
    assumed noise (drawn as sd * sqrt(chi2_nu / nu); inf: known exactly); ``scale``
    False leaves out the misfit scale of eq. (1)."""
    rng = np.random.default_rng(seed)
    n = 8
    x = np.linspace(0.1, 1.0, n)
    A = np.zeros((2 * n, 4))
    A[:n, :3] = np.column_stack([np.ones(n), x, x**2])
    A[n:, 0], A[n:, 3] = 1.0, x
    G = np.array([[1.0, 1.3, 1.69, 0.0], [1.0, 0.0, 0.0, 1.3]])
    beta = np.array([1.0, -2.0, 0.5, 3.0])
    ch = np.repeat([0, 1], n)
    true_sd = np.asarray(true_sd, float)
    hits = np.zeros(2)
    for _ in range(draws):
        est = np.array([1.0 if math.isinf(v) else math.sqrt(rng.chisquare(v) / v)
                        for v in nu_est])
        y = A @ beta + rng.standard_normal(2 * n) * true_sd[ch]
        y_new = G @ beta + rng.standard_normal(2) * true_sd
        J = A / est[ch][:, None]
        C = np.linalg.pinv(J.T @ J)
        b = C @ J.T @ (y / est[ch])
        f, nu = misfit_scale(J, y / est[ch] - J @ b, ch, list(nu_est))
        if not scale:
            f, nu = np.ones(2), np.array(nu_est, float)
        if pooled_dof:                       # one dof for every channel, as before
            nu = np.full(2, len(ch) ** 2 / sum(n**2 / v for v in nu_est if v < math.inf))
        for c in range(2):
            g = G[c] / est[c]
            P = parameter_parts(g, J, ch, C, f)
            P[c] += f[c]
            V, dof = satterthwaite(P, nu)
            hits[c] += abs(y_new[c] / est[c] - g @ b) <= quantile(dof) * math.sqrt(V)
    return hits / draws


def test_a_misfit_of_three_noise_sd_is_covered_exactly_by_the_misfit_scale():
    # true noise 3x the assumed one: S^2 of eq. (1) replaces it with d_c dof, and the
    # standardized prediction error is then Student t: coverage exactly 95 %
    cov = _linear_coverage(1, (3.0, 3.0), (math.inf, math.inf), 2000)
    lo, hi = _band(2000)
    assert np.all((cov > lo) & (cov < hi)), cov
    # without it (the noise taken as known) the interval is +-1.96/3 true sd: about 49 %
    unscaled = _linear_coverage(1, (3.0, 3.0), (math.inf, math.inf), 2000, scale=False)
    assert np.all(unscaled < 0.6), unscaled


def _exact_coverage_with_scale(d):
    """Coverage of eqs. (1)-(3) for one channel, known correct noise, ``d`` residual
    dof: the prediction error ``Z ~ N(0, 1 + g^T C g)`` is independent of the residuals,
    ``S^2 ~ chi2_d / d``; the interval is the normal one when ``S^2 <= 1``, else
    ``t_d S``: ``P(S^2 <= 1) 0.95 + E[1{S^2 > 1} (2 Phi(t_d S) - 1)]``."""
    q = stats.t.ppf(0.975, d)
    tail, _ = integrate.quad(lambda u: (2 * stats.norm.cdf(q * math.sqrt(u / d)) - 1)
                             * stats.chi2.pdf(u, d), d, np.inf)
    return stats.chi2.cdf(d, d) * 0.95 + tail


def test_a_correct_model_is_covered_as_the_scale_rule_predicts():
    # the scale only widens (Birge): with correct known noise it acts in the draws where
    # chi2 > d by chance; planted line + parabola, 10 levels, prediction at 1.3
    rng = np.random.default_rng(2)
    x = np.linspace(0.1, 1.0, 10)
    X = np.column_stack([np.ones(10), x, x**2])
    g = np.array([1.0, 1.3, 1.69])
    C = np.linalg.pinv(X.T @ X)
    hits, draws = 0, 6000
    for _ in range(draws):
        y = X @ [1.0, -2.0, 0.5] + rng.standard_normal(10)
        b = C @ X.T @ y
        f, nu = misfit_scale(X, y - X @ b, np.zeros(10, int), [math.inf])
        P = parameter_parts(g, X, np.zeros(10, int), C, f)
        V, dof = satterthwaite(P + f, nu)
        hits += abs(g @ [1.0, -2.0, 0.5] + rng.standard_normal() - g @ b) <= (
            quantile(dof) * math.sqrt(V))
    exact = _exact_coverage_with_scale(7)
    assert 0.96 < exact < 0.975                    # the cost of widening only
    sd = math.sqrt(exact * (1 - exact) / draws)
    assert abs(hits / draws - exact) < 3.5 * sd, (hits / draws, exact)


def test_each_channel_carries_its_own_degrees_of_freedom():
    # channel 0's noise estimated with 3 dof, channel 1 known: one pooled dof (12)
    # for both channels under-covers channel 0 compared with eq. (3)
    own = _linear_coverage(3, (1.0, 1.0), (3, math.inf), 2000)
    pooled = _linear_coverage(3, (1.0, 1.0), (3, math.inf), 2000, pooled_dof=True)
    assert own[0] > _band(2000)[0] and own[0] < 0.99
    assert pooled[0] < own[0] - 0.01


def test_satterthwaite_of_one_part_is_its_own_dof_and_known_parts_add_none():
    assert satterthwaite([2.0], [5.0]) == pytest.approx((2.0, 5.0))
    assert satterthwaite([1.0, 1.0], [4.0, math.inf]) == pytest.approx((2.0, 16.0))
    assert satterthwaite([1.0, 1.0], [math.inf, math.inf])[1] == math.inf


def _base_series(rng, chi=-0.5, n=10, assumed=1.0):
    """A planted series of the base model (model doc of ``inverse.diagnosis.models``,
    eqs. 2-4, written out here with scipy's Beta function): 100 Hz, 2 % frequency loss,
    viscous damping 0.5 %, noise 2e-4 of omega2 and 2 % of zeta (Gaussian, seeded);
    the noise given to the fit is the true one divided by ``assumed``."""
    s = np.geomspace(0.1, 1.0, n)
    kappa = special.beta(chi + 2.5, 0.5) * (chi + 2) / (chi + 1)
    W = (2 * np.pi * 100.0) ** 2
    K1, c = 0.02 * W / kappa, 0.01 * np.sqrt(W)
    zeta = np.full(n, 0.005)
    for _ in range(50):        # omega2 = |pole|^2 holds zeta (eq. 4), zeta holds omega2
        om2 = W - K1 * s ** (chi + 1) * (kappa - zeta)
        zeta = c / (2 * np.sqrt(om2)) + K1 * s ** (chi + 1) / (2 * om2)
    so, sz = 2e-4 * om2, 0.02 * zeta
    return Observations(level=np.arange(n), s=s, omega2=om2 + so * rng.standard_normal(n),
                        zeta=zeta + sz * rng.standard_normal(n), t_run=np.linspace(0, 1, n),
                        log_r=None, response_controlled=True,
                        sigma={"omega2": so / assumed, "zeta": sz / assumed})


@pytest.mark.parametrize("assumed, lo, hi", [(1.0, 0.95, 0.985), (3.0, 0.91, 0.97)])
def test_held_out_predictions_of_the_base_model_cover_their_planted_values(assumed, lo, hi):
    # 400 planted series, the top 3 of 10 levels held out (the diagnosis's protocol):
    # known correct noise, the rule of eq. (1) widens in some draws (exact linear value
    # 96.8 %, test above); noise understated 3x, eq. (1) restores the coverage (7
    # training levels: about 5 residual dof per channel)
    rng = np.random.default_rng(11)
    hits = []
    for _ in range(400):
        obs = _base_series(rng, assumed=assumed)
        f = fit_model(Model(), obs, obs.level < 7, n_starts=2, iters=15)
        hits += [it[ch]["inside"] for it in
                 prediction_intervals(f, obs, {"omega2": math.inf, "zeta": math.inf})
                 for ch in ("omega2", "zeta")]
    assert len(hits) == 2400
    assert lo < np.mean(hits) < hi, np.mean(hits)
