"""Maximum-likelihood fits of the diagnosis models (:mod:`inverse.diagnosis_models`).

Fitting: Gaussian maximum likelihood with one unknown noise level per channel
(``omega2``, ``zeta``, and ``log response_amplitude`` when present), estimated from
the fit itself (iteratively reweighted: weights ``1/sigma``, ``sigma^2 = RSS/n``,
floored at 2 % of the paper's noise). The linear parameters are solved exactly
(non-negativity where physical) for each value of the nonlinear ones (``chi`` on a
grid refined by Brent's method; with ``x_top`` or ``gamma, kappa`` on a grid refined
by Nelder-Mead), so the fit is global in chi.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from inverse.diagnosis_models import Observations, design_matrices, log_amplitude, tie_ratio

_SIGMA_FLOOR_REL_OMEGA2 = 2e-7   # 2 % of the paper's 1e-5 relative noise
_SIGMA_FLOOR_ZETA = 2e-7         # 2 % of the paper's 1e-5 absolute noise
_SIGMA_FLOOR_RESPONSE = 2e-4     # 2 % of a 1 % response-amplitude noise


@dataclass
class Fit:
    """A fitted model: parameters, fitted values, noise levels and criteria."""

    model: str
    theta: np.ndarray           # nonlinear parameters (chi+1, ...)
    linear: np.ndarray          # [W, c, K1 or U, extra]
    omega2_fit: np.ndarray      # at every level (held-out ones are predictions)
    zeta_fit: np.ndarray
    log_response_fit: np.ndarray | None
    sigma: dict                 # noise level per channel
    n_params: int               # model parameters, without the noise levels
    n_data: int
    loglik: float
    aicc: float
    bic: float
    parameters: dict = field(default_factory=dict)

    @property
    def chi(self) -> float:
        return float(self.theta[0] - 1.0)


# nonlinear parameters of each model: grid axes and bounds (p = chi + 1)
_P_FINE = np.linspace(0.02, 0.98, 49)
_P_COARSE = np.linspace(0.02, 0.98, 25)
_NONLINEAR = {
    "base": ([_P_FINE], [0.005], [0.995]),
    "geometric-hardening": ([_P_FINE], [0.005], [0.995]),
    "thermal-drift": ([_P_FINE], [0.005], [0.995]),
    "quadratic-damping": ([_P_FINE], [0.005], [0.995]),
    # log(x_top): top slip amplitude over phi_max
    # (x_top >= 1.02: at x_top -> 1 the Dirac term vanishes and beta is unbounded)
    "macro-slip": ([_P_COARSE, np.log(np.geomspace(1.02, 4.0, 21))],
                   [0.005, np.log(1.02)], [0.995, np.log(8.0)]),
    # log(kappa), gamma: log s_eff = log s + gamma (s**kappa - 1)
    "nonproportional-amplitude": ([_P_COARSE, np.log(np.geomspace(0.3, 4.0, 7)),
                                   np.linspace(-0.6, 0.4, 21)],
                                  [0.005, np.log(0.1), -2.0], [0.995, np.log(8.0), 2.0]),
}
_N_LINEAR = {"base": 3, "nonproportional-amplitude": 3, "macro-slip": 4,
             "geometric-hardening": 4, "thermal-drift": 4, "quadratic-damping": 4}


def _solve_batched(A, b, nonneg):
    """Least squares ``min |A x - b|`` for a stack of A (G, m, k), with x_j >= 0 on
    ``nonneg`` (exact: best feasible solution over the faces of the constraint set).

    Returns (x (G, k), rss (G,))."""
    G, m, k = A.shape
    best_x = np.zeros((G, k))
    best_rss = np.full(G, np.inf)
    scale = np.sqrt(np.sum(A**2, axis=1))  # (G, k)
    scale = np.where(scale > 0, scale, 1.0)
    An = A / scale[:, None, :]
    n_c = len(nonneg)
    for mask in range(2 ** n_c):
        zeroed = [nonneg[j] for j in range(n_c) if mask >> j & 1]
        free = [j for j in range(k) if j not in zeroed]
        Af = An[:, :, free]
        Q, Rm = np.linalg.qr(Af)
        qtb = np.einsum("gmk,m->gk", Q, b)
        diag = np.abs(np.diagonal(Rm, axis1=1, axis2=2))
        ok = np.all(diag > 1e-12 * diag.max(axis=1, keepdims=True), axis=1)
        Rs = np.where(ok[:, None, None], Rm, np.eye(len(free))[None])
        y = np.linalg.solve(Rs, qtb[..., None])[..., 0]
        x = np.zeros((G, k))
        x[:, free] = y / scale[:, free]
        feasible = ok & (np.all(x[:, nonneg] >= 0.0, axis=1) if nonneg else True)
        rss = np.sum((np.einsum("gmk,gk->gm", A, x) - b) ** 2, axis=1)
        better = feasible & (rss < best_rss)
        best_x[better] = x[better]
        best_rss[better] = rss[better]
    return best_x, best_rss


def _channel_fit(model, d, theta, sig):
    """Best linear parameters and weighted total RSS for each theta (G, m).

    ``d``: dict of training arrays (s, t_run, omega2, zeta, log_r or None).
    Returns (linear (G, k), total weighted rss (G,), per-channel residual function)."""
    A_om, A_ze, nonneg, log_s = design_matrices(model, d["s"], d["t_run"], d["omega2"], theta)
    A = np.concatenate([A_om / sig["omega2"], A_ze / sig["zeta"]], axis=1)
    b = np.concatenate([d["omega2"] / sig["omega2"], d["zeta"] / sig["zeta"]])
    lin, rss = _solve_batched(A, b, nonneg)
    if d["log_r"] is not None:
        e = d["log_r"][None, :] - log_s
        e = e - e.mean(axis=1, keepdims=True)
        rss = rss + np.sum(e**2, axis=1) / sig["response"] ** 2
    return lin, rss, (A_om, A_ze, log_s)


def fit_model(model: str, obs: Observations, train=None, outer: int = 4) -> Fit:
    """Maximum-likelihood fit of ``model`` ("base" or a cause id) to ``obs[train]``.

    Channels: omega2, zeta and, when the data have it, log(response_amplitude)
    (predicted as ``alpha + log s_eff``: proportional to the joint amplitude). Each
    channel has its own noise level, re-estimated ``outer`` times from the residuals
    (``sigma^2 = RSS/n``, floored); between re-estimations the nonlinear parameters
    are found on a grid and refined (Brent in 1-D, Nelder-Mead otherwise) with the
    linear ones solved exactly.

    Returns
    -------
    Fit (fitted values cover *all* levels, so held-out levels are predictions).
    """
    if model not in _NONLINEAR:
        raise ValueError(f"unknown model {model!r}")
    if model == "nonproportional-amplitude" and obs.response is None:
        raise ValueError("nonproportional-amplitude needs the response_amplitude column")
    train = np.ones(obs.n, bool) if train is None else np.asarray(train, bool)
    s_all = obs.s_exc
    log_r_all = None if obs.response is None else np.log(obs.response)
    d = {"s": s_all[train], "t_run": obs.t_run[train], "omega2": obs.omega2[train],
         "zeta": obs.zeta[train], "log_r": None if log_r_all is None else log_r_all[train]}
    n = int(train.sum())
    med = float(np.median(obs.omega2))
    floors = {"omega2": _SIGMA_FLOOR_REL_OMEGA2 * med, "zeta": _SIGMA_FLOOR_ZETA,
              "response": _SIGMA_FLOOR_RESPONSE}
    sig = {"omega2": 1e-5 * med, "zeta": 1e-5, "response": 0.01}
    axes, lo, hi = _NONLINEAR[model]
    lo, hi = np.array(lo), np.array(hi)
    grid = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)

    def total(th):
        th = np.clip(np.atleast_1d(th), lo, hi)[None, :]
        return _channel_fit(model, d, th, sig)[1][0]

    for _ in range(outer):
        _, rss, _ = _channel_fit(model, d, grid, sig)
        i = int(np.argmin(rss))
        if grid.shape[1] == 1:
            a, b = max(grid[i, 0] - 0.02, lo[0]), min(grid[i, 0] + 0.02, hi[0])
            res = optimize.minimize_scalar(total, bounds=(a, b), method="bounded",
                                           options=dict(xatol=1e-5))
            theta = np.array([res.x])
        else:
            res = optimize.minimize(total, x0=grid[i], method="Nelder-Mead",
                                    options=dict(xatol=1e-4, fatol=1e-6, maxiter=400))
            theta = np.clip(res.x, lo, hi)
            if res.fun > rss[i]:
                theta = grid[i]
        lin, _, (A_om, A_ze, log_s) = _channel_fit(model, d, theta[None, :], sig)
        r_w = A_om[0] @ lin[0] - d["omega2"]
        r_z = A_ze[0] @ lin[0] - d["zeta"]
        sig["omega2"] = max(float(np.sqrt(np.mean(r_w**2))), floors["omega2"])
        sig["zeta"] = max(float(np.sqrt(np.mean(r_z**2))), floors["zeta"])
        if d["log_r"] is not None:
            e = d["log_r"] - log_s[0]
            sig["response"] = max(float(np.std(e)), floors["response"])

    lin = lin[0]
    om_fit, ze_fit, lr_fit = _predict(model, obs, theta, lin, train)
    channels = ["omega2", "zeta"] + (["response"] if d["log_r"] is not None else [])
    loglik = sum(-0.5 * n * (np.log(2 * np.pi * sig[c] ** 2) + 1.0) for c in channels)
    k = _N_LINEAR[model] + theta.size + (1 if d["log_r"] is not None else 0)
    kk, N = k + len(channels), n * len(channels)
    aicc = (-2 * loglik + 2 * kk + 2 * kk * (kk + 1) / (N - kk - 1)
            if N - kk - 1 > 0 else np.inf)
    bic = -2 * loglik + kk * np.log(N)
    fit = Fit(model=model, theta=theta, linear=lin, omega2_fit=om_fit, zeta_fit=ze_fit,
              log_response_fit=lr_fit, sigma={c: sig[c] for c in channels}, n_params=k,
              n_data=N, loglik=float(loglik), aicc=float(aicc), bic=float(bic))
    fit.parameters = _parameters(fit, obs)
    return fit


def _predict(model, obs, theta, linear, train):
    """(omega2, zeta, log response) at every level; the response offset alpha is the
    training mean. The zeta channel uses the measured omega2 in its 1/sqrt(omega2)
    and 1/omega2 factors (paper eq. 45), as the fit does."""
    A_om, A_ze, _, log_s = design_matrices(model, obs.s_exc, obs.t_run, obs.omega2, theta[None, :])
    lr = None
    if obs.response is not None:
        alpha = np.mean(np.log(obs.response[train]) - log_s[0][train])
        lr = alpha + log_s[0]
    return A_om[0] @ linear, A_ze[0] @ linear, lr


def predict(fit: Fit, obs: Observations):
    """Model values (omega2, zeta) of ``fit`` at every level of ``obs``."""
    om, ze, _ = _predict(fit.model, obs, fit.theta, fit.linear, np.ones(obs.n, bool))
    return om, ze


def _parameters(fit: Fit, obs: Observations) -> dict:
    """Physical parameters of a fit (JSON-friendly).

    ``kappa1_B`` is the paper's ``|kappa1| B`` (hysteretic modal stiffness at level 1,
    rad^2/s^2), ``kappa2_B`` the frequency drop at level 1."""
    W, c = fit.linear[0], fit.linear[1]
    chi, p = fit.chi, fit.chi + 1.0
    log_s = log_amplitude(fit.model, obs.s_exc, fit.theta[None, :])[0]
    s1 = float(np.exp(log_s[np.argmin(obs.level)]))  # level 1 on the fit's amplitude scale
    out = {"omega2_0": W, "zeta_0": c / (2.0 * np.sqrt(W)), "chi": chi}
    if fit.model == "macro-slip":
        U, S = fit.linear[2], fit.linear[3]
        x_top = float(np.exp(fit.theta[1]))
        K1_top = U * 4.0 / (np.pi * (chi + 2.0) * (chi + 3.0)) * x_top**p
        out.update(x_top=x_top, beta=S * p / U if U > 0 else np.inf)
    else:
        K1_top = fit.linear[2]
    out["kappa1_B"] = K1_top * s1**p
    out["kappa2_B"] = tie_ratio(chi) * out["kappa1_B"]
    out["tie_ratio_K2_over_K1"] = float(tie_ratio(chi))
    a_max = obs.a_max
    if fit.model == "geometric-hardening":
        out.update(h=fit.linear[3] / a_max**2, h_top=fit.linear[3])
    elif fit.model == "thermal-drift":
        span = float(obs.run_order.max() - obs.run_order.min())
        out.update(d=fit.linear[3] / span if span > 0 else 0.0, d_total=fit.linear[3])
    elif fit.model == "quadratic-damping":
        out.update(q=fit.linear[3] / a_max, q_top=fit.linear[3])
    elif fit.model == "nonproportional-amplitude":
        out.update(kappa=float(np.exp(fit.theta[1])), gamma=float(fit.theta[2]),
                   amplitude_shortfall_top=float(1.0 - np.exp(
                       log_s[np.argmax(obs.level)] - log_s[np.argmin(obs.level)]
                       - np.log(obs.a_max))))
    for ch, v in fit.sigma.items():
        out[f"sigma_{ch}"] = v
    return {k: float(v) for k, v in out.items()}
