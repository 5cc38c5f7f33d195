"""Held-out prediction intervals of the diagnosis: for each row of a level a fit did not
see (the held-out top levels of :func:`inverse.diagnosis.cv.held_out_top`), the
predicted omega2 and zeta with a nominal 95 % prediction interval, per candidate and
model-averaged (docs/coverage.md: why each term is there, the coverage measured).

Per candidate (:func:`prediction_intervals`). ``J`` is the Jacobian of the standardized
model at the fit ``theta_hat`` (rows: every channel and level, divided by the noise sd;
columns: the free parameters: a parameter on its bound, a non-negative linear parameter
at 0, is held there), ``T`` the training rows, ``C = (J_T^T J_T)^+`` (from the SVD of
``J_T``, not the normal equations, whose squared condition number dropped the weakest
direction) and ``h_r = J_r^T C J_r`` the leverage of training row ``r``. Variances
are in units of the row's noise variance ``sigma^2``.

* Misfit scale (:func:`misfit_scale`). A channel ``c`` whose training residuals ``e_r``
  exceed their noise is not within it. With correct noise ``E e_r^2 = 1 - h_r``
  (residual covariance ``I - H``, Seber & Lee 2003, sec. 3.3), so

      S_c^2 = sum_{r in T_c} e_r^2 / d_c,       d_c = sum_{r in T_c} (1 - h_r)      (1)

  estimates the ratio of true to assumed variance with ``d_c`` degrees of freedom. When
  ``S_c^2 > 1`` the channel's variance is scaled by ``f_c = S_c^2`` with ``d_c``
  degrees of freedom (the scale factor of the Particle Data Group, Birge 1932: only
  upwards); otherwise ``f_c = 1`` with the noise model's ``nu_c`` (inf: known).
* Nonlinear parameters (:func:`grid_posterior`): a linearization at ``theta_hat`` fails
  when the training levels do not determine them (a macro-slip onset above the fitted
  range: the prediction moves by tens of noise sd along a direction of zero curvature).
  They are integrated over the model's search grid (its bounds, flat prior) and
  ``theta_hat``, each point with the linear parameters solved on the training rows and
  weight ``exp(-chi2_f / 2)`` (``chi2_f`` the training chi2 with channel ``c``
  divided by ``f_c``, relative to ``theta_hat``): the predicted value is the weighted
  mean ``m`` of the points' predictions and their weighted variance ``D`` joins the
  variance (law of total variance; grid approximation of the posterior predictive,
  Gelman et al. 2013, sec. 3.7 and 5.3)                                               (4)
* Variance of the prediction of channel ``c`` at row ``i``: the row's own noise, the
  linear parameters' sandwich covariance ``C_L J_L^T F J_L C_L`` (``J_L`` the linear
  columns, ``F`` the scales ``f``), and ``D``:

      V = f_c + sum_k P_k' + D,  P_k' = f_k sum_{r in T_k} (g_L^T C_L J_{L,r})^2       (2)

* Degrees of freedom: ``D`` is split over the channels in the proportions of the
  linearized parameter variance of all free parameters (the channels that determine
  them), each part ``P_k`` (with ``f_c`` in the own channel) then estimated with channel
  ``k``'s degrees of freedom; Welch-Satterthwaite (Satterthwaite 1946):

      nu = V^2 / sum_k (P_k^2 / nu_k)          (known channels add nothing)        (3)

  The interval is ``m +- t_nu(0.975) sigma sqrt(V)`` (normal when ``nu = inf``). A
  prediction of one channel carries that channel's degrees of freedom, not the count of
  every channel pooled (which made a frequency sd from 4 dof look like 16).

Model-averaged (:func:`model_averaged`): the named model is one of several the data
allow, and an interval conditional on it ignores that choice. The predictions of the
eligible candidates (Akaike weights ``w_i`` renormalized, those under :data:`W_MIN`
dropped) are averaged, ``y = sum w_i y_i``, with the unconditional variance
``sum w_i (v_i + (y_i - y)^2)`` (Burnham & Anderson 2002, sec. 4.3.2, in its form
without square roots), each model's variance on the normal scale,
``v_i = (t_{nu_i} / z)^2 sd_i^2`` (their adjustment of t-based intervals, sec. 4.3),
and the interval ``y +- z sqrt(sum ...)``, ``z = 1.96``. When ``unexplained`` the
closest candidate stands alone, and as no candidate is within the noise on all levels,
(1) is taken on its fit to all levels where that is larger: a wider interval that
carries the misfit the verdict found.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from inverse.diagnosis.fit import evaluate
from inverse.diagnosis.models import Observations, design
from inverse.judge import at_bound

__all__ = ["W_MIN", "quantile", "misfit_scale", "grid_posterior", "parameter_parts",
           "satterthwaite", "prediction_intervals", "averaging_weights", "model_averaged"]

#: Candidates of smaller renormalized Akaike weight are left out of the average.
W_MIN = 0.01


def quantile(dof: float, level: float = 0.95) -> float:
    """Two-sided ``level`` quantile: normal for ``dof = inf``, else Student's t."""
    return float(stats.norm.ppf(0.5 + level / 2) if math.isinf(dof)
                 else stats.t.ppf(0.5 + level / 2, dof))


def _inverse_normal(J, rcond: float = 1e-12):
    """``(J^T J)^+`` from the SVD of ``J`` (singular values under ``rcond`` of the
    largest dropped)."""
    _, sv, vt = np.linalg.svd(J, full_matrices=False)
    keep = sv > rcond * sv.max()
    return (vt[keep].T / sv[keep] ** 2) @ vt[keep]


def misfit_scale(J_train, e_train, channel, dof):
    """Per-channel variance scales and degrees of freedom, eq. (1).

    ``J_train`` (N, k) standardized Jacobian of the training rows, ``e_train`` (N,)
    their standardized residuals, ``channel`` (N,) channel index of each row, ``dof``
    (channels,) the noise model's degrees of freedom (inf: known). Returns (``f``,
    ``nu``), each (channels,)."""
    C = _inverse_normal(J_train)
    lev = np.einsum("rk,kl,rl->r", J_train, C, J_train)
    f, nu = np.ones(len(dof)), np.array(dof, float)
    for c in range(len(dof)):
        m = channel == c
        d_c = float(np.sum(1.0 - lev[m]))
        if d_c <= 0.5:
            continue
        s2 = float(np.sum(e_train[m] ** 2)) / d_c
        if s2 > 1.0:
            f[c], nu[c] = s2, d_c
    return f, nu


def parameter_parts(g, J_train, channel, C, f):
    """Parts of eq. (2) by channel: ``f_k sum_{r in T_k} (g^T C J_r)^2`` (channels,)."""
    return f * np.bincount(channel, (J_train @ (C @ g)) ** 2, minlength=len(f))


def satterthwaite(parts, nu):
    """(``V``, ``nu``) of eq. (3): the sum of the variance ``parts`` and its degrees of
    freedom, each part estimated with ``nu`` degrees of freedom (inf: known)."""
    parts, nu = np.asarray(parts, float), np.asarray(nu, float)
    known = np.isinf(nu)
    den = float(np.sum(parts[~known] ** 2 / nu[~known]))
    V = float(parts.sum())
    return V, (V**2 / den if den > 0 else math.inf)


def _free(fit, obs: Observations, rtol: float = 1e-3):
    """Masks of the free nonlinear and linear parameters (not on a bound)."""
    nl = np.array([not at_bound(v, lo, hi, rtol)[0]
                   for v, (_, lo, hi, _) in zip(fit.theta, fit.model.nonlinear)], bool)
    nonneg = fit.model.nonneg(obs.log_r is not None)
    lin = np.array([not (j in nonneg and x <= 0.0) for j, x in enumerate(fit.linear)], bool)
    return nl, lin


def _jacobian(fit, obs: Observations):
    """Standardized model Jacobian (all rows; free parameters, the linear ones first) by
    forward differences in the nonlinear parameters (1e-5 of their range), exact in the
    linear ones. Returns (J, number of linear columns)."""
    nl_free, lin_free = _free(fit, obs)
    A = design(fit.model, obs, fit.theta[None])[0][0]
    cols = [A[:, lin_free]]
    for j in np.flatnonzero(nl_free):
        _, lo, hi, _ = fit.model.nonlinear[j]
        h = 1e-5 * (hi - lo)
        step = -h if fit.theta[j] + h > hi else h
        th = fit.theta.copy()
        th[j] += step
        Aj = design(fit.model, obs, th[None])[0][0]
        cols.append(((Aj @ fit.linear - A @ fit.linear) / step)[:, None])
    return np.hstack(cols), int(lin_free.sum())


def grid_posterior(fit, obs: Observations, f, chunk: int = 4096):
    """Predictions over the nonlinear parameters, eq. (4): the standardized residuals
    (G, rows) of the fit's optimum and of every point of the model's search grid
    (linear parameters solved on the training rows at each), and their weights
    ``exp(-(chi2_f(theta) - chi2_f(theta_hat)) / 2)`` normalized, ``chi2_f`` the
    training chi2 with channel ``c`` divided by its scale ``f[c]``."""
    rows = obs.channel_rows(fit.train)
    axes = [a[3] for a in fit.model.nonlinear]
    grid = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)
    th = np.vstack([fit.theta[None], grid])
    res = np.vstack([evaluate(fit.model, obs, th[i:i + chunk], rows)[1]
                     for i in range(0, th.shape[0], chunk)])
    scale = np.repeat(1.0 / np.asarray(f, float), obs.n)
    chi2 = np.sum((res**2 * scale)[:, rows], axis=1)
    w = np.where(np.isfinite(chi2), np.exp(-np.clip(chi2 - chi2[0], 0.0, None) / 2), 0.0)
    return res, w / w.sum()


def prediction_intervals(fit, obs: Observations, dof: dict, level: float = 0.95,
                         misfit_of=None):
    """Predicted omega2 and zeta of the rows ``fit`` did not see, with their nominal
    ``level`` prediction intervals (module doc). ``dof`` ``{channel: degrees of
    freedom}`` of the noise (inf: known); ``misfit_of`` a fit of the same model to all
    levels whose misfit scales (eq. 1) are used where larger (an ``unexplained``
    verdict: the closest candidate misses the levels above the training ones too).
    Returns a list of dicts, one per held-out row: ``{level, omega2: {measured,
    predicted, interval, sd, dof, misfit_scale, inside}, zeta: {...}}``;
    ``predicted`` the posterior mean of eq. (4)."""
    train = np.asarray(fit.train, bool)
    rows = obs.channel_rows(train)
    J, n_lin = _jacobian(fit, obs)
    n, nch = obs.n, len(obs.channels)
    channel = np.repeat(np.arange(nch), n)[rows]
    noise_dof = [dof[ch] for ch in obs.channels]
    f, nu = misfit_scale(J[rows], fit.residual[rows], channel, noise_dof)
    if misfit_of is not None:
        every = obs.channel_rows(misfit_of.train)
        fa, nua = misfit_scale(_jacobian(misfit_of, obs)[0][every], misfit_of.residual[every],
                               np.repeat(np.arange(nch), n)[every], noise_dof)
        f, nu = np.where(fa > f, fa, f), np.where(fa > f, nua, nu)
    counts = np.bincount(channel, minlength=nch).astype(float)
    J_lin = J[:, :n_lin]
    C_lin, C = _inverse_normal(J_lin[rows]), _inverse_normal(J[rows])
    res, w = grid_posterior(fit, obs, f)
    out = []
    for i in np.flatnonzero(~train):
        item = {"level": int(obs.levels[i])}
        for c, ch in enumerate(("omega2", "zeta")):
            r = c * n + i
            ok = np.isfinite(res[:, r])
            wr = w[ok] / w[ok].sum()
            mean = float(wr @ res[ok, r])
            spread = float(wr @ (res[ok, r] - mean) ** 2)
            P = parameter_parts(J_lin[r], J_lin[rows], channel, C_lin, f)
            share = parameter_parts(J[r], J[rows], channel, C, f)
            P += spread * (share / share.sum() if share.sum() > 0 else counts / counts.sum())
            P[c] += f[c]
            V, nu_i = satterthwaite(P, nu)
            sd = obs.sigma[ch][i] * math.sqrt(V)
            q = quantile(nu_i, level)
            y = [obs.omega2, obs.zeta][c][i]
            pred = y - mean * obs.sigma[ch][i]
            item[ch] = {"measured": float(y), "predicted": float(pred),
                        "interval": [float(pred - q * sd), float(pred + q * sd)],
                        "sd": float(sd), "dof": None if math.isinf(nu_i) else float(nu_i),
                        "misfit_scale": float(math.sqrt(f[c])),
                        "inside": bool(abs(y - pred) <= q * sd)}
        out.append(item)
    return out


def averaging_weights(selection) -> dict:
    """``{candidate: weight}`` of the model average (module doc): the eligible
    candidates of a :class:`inverse.judge.Selection`, renormalized, those under
    :data:`W_MIN` dropped; the closest candidate alone when ``unexplained``."""
    if not selection.eligible:
        return {selection.best: 1.0}
    w = {k: selection.weights[k] for k in selection.eligible}
    tot = sum(w.values()) or 1.0
    w = {k: v / tot for k, v in w.items() if v / tot >= W_MIN or k == selection.best}
    tot = sum(w.values())
    return {k: v / tot for k, v in w.items()}


def model_averaged(per_model: dict, weights: dict, level: float = 0.95):
    """Model-averaged held-out predictions (module doc) from ``per_model``
    ``{candidate: rows of prediction_intervals}`` (candidates whose held-out fit failed
    left out) and ``weights`` ``{candidate: w}``; rows as :func:`prediction_intervals`
    (a row without ``dof`` is taken as known noise), ``sd`` the averaged sd on the
    normal scale."""
    names = [k for k in weights if per_model.get(k)]
    if not names:
        return []
    w = np.array([weights[k] for k in names])
    w = w / w.sum()
    z = quantile(math.inf, level)
    out = []
    for rows in zip(*(per_model[k] for k in names)):
        item = {"level": rows[0]["level"]}
        for ch in ("omega2", "zeta"):
            y = rows[0][ch]["measured"]
            pred_i = np.array([r[ch]["predicted"] for r in rows])
            adj = np.array([quantile(r[ch].get("dof") or math.inf, level) / z
                            for r in rows])
            v_i = (adj * np.array([r[ch]["sd"] for r in rows])) ** 2
            pred = float(w @ pred_i)
            sd = math.sqrt(float(w @ (v_i + (pred_i - pred) ** 2)))
            item[ch] = {"measured": y, "predicted": pred,
                        "interval": [pred - z * sd, pred + z * sd], "sd": sd,
                        "inside": bool(abs(y - pred) <= z * sd)}
        out.append(item)
    return out
