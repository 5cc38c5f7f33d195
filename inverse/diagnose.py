"""Model-form diagnosis: what the Iwan modal model gets wrong, why, and the gain.

Base model (paper Sec. 2.2 and 4, with its algebra corrected): one equivalent
micro-slip four-parameter Iwan joint acting on the mode, joint amplitude proportional
to the excitation, ``s_v = a_v / a_max`` with ``a_v = excitation_v / excitation_1``:

    omega2_v = W - K2 s_v**(chi+1)                                   (paper eq. 43)
    zeta_v   = (c/2) / sqrt(omega2_v) + K1 s_v**(chi+1) / (2 omega2_v)   (eq. 45)

``K1`` is the hysteretic (quadrature) modal stiffness at the top level, ``c`` the
constant viscous modal damping (``zeta_0 = c / (2 sqrt(W))``; the factor
``omega_n/omega_J`` of eq. 45 is kept, the factor 2 the paper drops is restored).
Frequency drop and damping growth are tied by the exact first-harmonic coefficients
(paper eq. 14, A15; :func:`tie_ratio`):

    K2 / K1 = kappa2_exact / |kappa1| = B(chi+5/2, 1/2) (chi+2) / (chi+1),

a function of chi alone. The base model has four parameters ``W, c, chi, K1`` fitted
jointly to ``omega2`` and ``zeta`` (and, when the file has ``response_amplitude``,
the response predicted proportional to the excitation, one more offset parameter).

Each cause of the spec (``shared/spec/diagnosis.md``) is an extension of the base:

=============================  ==========================================================
cause                          extension (extra parameters)
=============================  ==========================================================
``macro-slip``                 exact describing function past ``phi_max`` (continuous
                               density + Dirac at ``phi_max``): joint amplitude
                               ``x_v = x_top s_v`` in units of ``phi_max`` and the Dirac
                               weight ``beta`` (2: ``x_top``, ``beta``)
``nonproportional-amplitude``  joint amplitude ``log s_v + gamma (s_v**kappa - 1)``
                               instead of ``log s_v`` (2: ``gamma``, ``kappa``); needs
                               ``response_amplitude``, which every model predicts as
                               ``alpha + log(joint amplitude)``
``geometric-hardening``        ``omega2 += h s_v**2`` (1: ``h >= 0``)
``thermal-drift``              ``omega2 += d (run_v - run_min) / (run_max - run_min)``
                               (1: ``d``)
``quadratic-damping``          ``zeta += q s_v`` (1: ``q >= 0``)
=============================  ==========================================================

Fitting: Gaussian maximum likelihood with one unknown noise level per channel
(``omega2``, ``zeta``, and ``log response_amplitude`` when present), estimated from
the fit itself (iteratively reweighted: weights ``1/sigma``, ``sigma^2 = RSS/n``,
floored at 2 % of the paper's noise). The linear parameters are solved exactly
(non-negativity where physical) for each value of the nonlinear ones (``chi`` on a
grid refined by Brent's method; with ``x_top`` or ``gamma, kappa`` on a grid refined
by Nelder-Mead), so the fit is global in chi.

Choice: every candidate is compared with the base by AICc (and BIC, reported); the
candidate with the largest AICc drop wins if the drop exceeds :data:`AICC_THRESHOLD`
*and* the leave-one-level-out cross-validation error falls (gain > 1); otherwise the
answer is ``none``. The error measure (``base_error``, ``extended_error``) is the
root-mean-square leave-one-level-out prediction error over the interior levels (the
lowest and the highest level are always kept in the fit: the end levels would test
extrapolation, where a macro-slip onset seen only at the top cannot be learnt), over
the channels (omega2, zeta, log response amplitude when present), each in units of its
noise level (``sigma`` of the best-fitting model):

    err = sqrt( mean_v,channel [ ((y_v - pred_v) / sigma_channel)^2 ] ),

every prediction coming from a fit that did not see level ``v``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, special

from ident.measured import MeasuredData

__all__ = [
    "CAUSES",
    "CANDIDATES",
    "AICC_THRESHOLD",
    "Observations",
    "Fit",
    "tie_ratio",
    "slip_shapes",
    "observations_from",
    "fit_model",
    "predict",
    "cross_validate",
    "diagnose",
    "describe_cause",
]

CAUSES = ("none", "macro-slip", "nonproportional-amplitude", "geometric-hardening",
          "thermal-drift", "quadratic-damping")
CANDIDATES = CAUSES[1:]
#: AICc drop a candidate must exceed (besides a cross-validation gain > 1) to be named.
AICC_THRESHOLD = 6.0

_SIGMA_FLOOR_REL_OMEGA2 = 2e-7   # 2 % of the paper's 1e-5 relative noise
_SIGMA_FLOOR_ZETA = 2e-7         # 2 % of the paper's 1e-5 absolute noise
_SIGMA_FLOOR_RESPONSE = 2e-4     # 2 % of a 1 % response-amplitude noise


# --------------------------------------------------------------------------- physics


def tie_ratio(chi):
    """``K2/K1 = kappa2_exact/|kappa1| = B(chi+5/2, 1/2) (chi+2)/(chi+1)``.

    From paper eq. (A15) ``|kappa1| = 4R/(pi (chi+2)(chi+3))`` and the exact
    ``kappa2 = 4R B(chi+5/2, 1/2)/(pi (chi+1)(chi+3))`` (the paper's Taylor series A12
    replaced by the Beta function). Dimensionless; 4 at chi = -1/2.
    """
    chi = np.asarray(chi, dtype=float)
    return special.beta(chi + 2.5, 0.5) * (chi + 2.0) / (chi + 1.0)


def _slider_in_phase(t):
    """In-phase describing function of a unit Jenkins element, ``t = phi/A`` in [0, 1].

    ``(psi - sin psi cos psi)/pi`` with ``cos psi = 1 - 2 t`` (elastic-perfectly-
    plastic element; 1 when stuck, t >= 1)."""
    c = np.clip(1.0 - 2.0 * t, -1.0, 1.0)
    psi = np.arccos(c)
    return (psi - np.sin(psi) * c) / np.pi


def slip_shapes(x, chi):
    """Loss of in-phase stiffness and quadrature stiffness of an Iwan joint, normalized.

    For slip amplitude ``A = x phi_max`` and ``U = R phi_max**(chi+1)``, the joint's
    first-harmonic stiffnesses are ``k_in = K_T - U P2 - S Q2`` and
    ``k_q = U P1 + S Q1`` (``S`` the Dirac weight), with ``rho = min(1, 1/x)``,
    ``m = min(x, 1)``, ``g`` the slider in-phase function:

        P2 = [1 - g(rho) + (8/pi) x**(chi+1) B(rho; chi+5/2, 3/2)] / (chi+1)
        P1 = (4/pi) [x m**(chi+2)/(chi+2) - m**(chi+3)/(chi+3)] / x**2
        Q2 = 1 - g(rho),  Q1 = 4 (x-1)/(pi x**2) for x > 1, else 0.

    (Sum of each slider's describing function over the density, integrating by parts
    with ``dg/dt = (8/pi) sqrt(t(1-t))``; dissipation per cycle ``pi A^2 k_q``.) For
    ``x <= 1``: ``P1 = |kappa1|/R x**(chi+1)``, ``P2 = kappa2_exact/R x**(chi+1)``.

    Broadcasts ``x`` against ``chi``; returns ``(P1, P2, Q1, Q2)``.
    """
    x, chi = np.broadcast_arrays(np.asarray(x, float), np.asarray(chi, float))
    p = chi + 1.0
    rho = np.minimum(1.0, 1.0 / x)
    g = np.where(x > 1.0, _slider_in_phase(rho), 1.0)
    a, b = chi + 2.5, 1.5
    inc = special.betainc(a, b, rho) * special.beta(a, b)
    P2 = (1.0 - g + 8.0 / np.pi * x**p * inc) / p
    m = np.minimum(x, 1.0)
    P1 = 4.0 / np.pi * (x * m ** (chi + 2.0) / (chi + 2.0) - m ** (chi + 3.0) / (chi + 3.0)) / x**2
    Q2 = 1.0 - g
    Q1 = np.where(x > 1.0, 4.0 * (x - 1.0) / (np.pi * x**2), 0.0)
    return P1, P2, Q1, Q2


# --------------------------------------------------------------------------- data


@dataclass
class Observations:
    """One mode's data as the fits use them (sorted by level).

    ``s_exc = excitation / max(excitation)``, ``s_resp = response / max(response)`` or
    None, ``t_run = (run - min)/(max - min)`` in [0, 1]."""

    level: np.ndarray
    excitation: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    run_order: np.ndarray
    response: np.ndarray | None
    mode: int = 1

    @property
    def n(self) -> int:
        return int(self.level.size)

    @property
    def s_exc(self) -> np.ndarray:
        return self.excitation / self.excitation.max()

    @property
    def s_resp(self) -> np.ndarray | None:
        return None if self.response is None else self.response / self.response.max()

    @property
    def t_run(self) -> np.ndarray:
        r = self.run_order.astype(float)
        span = r.max() - r.min()
        return (r - r.min()) / span if span > 0 else np.zeros_like(r)

    @property
    def a_max(self) -> float:
        """Excitation ratio of the top level to level 1 (``a_max``)."""
        return float(self.excitation.max() / self.excitation.min())


def observations_from(data: MeasuredData, mode: int | None = None) -> tuple[Observations, list]:
    """Pick one mode of ``data`` (the only one, or ``mode``); returns (obs, warnings)."""
    warnings = list(data.warnings)
    modes = data.modes
    if mode is None:
        if modes.size > 1:
            warnings.append(f"file holds modes {', '.join(map(str, modes))}; "
                            f"diagnosing mode {modes[0]} (choose with --mode)")
        mode = int(modes[0])
    d = data.for_mode(int(mode))
    resp = None if d.response_amplitude is None else np.asarray(d.response_amplitude, float)
    obs = Observations(level=d.level, excitation=d.excitation, omega2=d.omega2, zeta=d.zeta,
                       run_order=d.run_order, response=resp, mode=int(mode))
    if resp is None:
        warnings.append("no response_amplitude column: nonproportional-amplitude cannot be "
                        "tested")
    if np.array_equal(np.argsort(d.run_order, kind="stable"), np.arange(d.level.size)):
        warnings.append("run_order follows the level: thermal drift is confounded with "
                        "amplitude (shuffle the level order in the next test)")
    if obs.n < 7:
        warnings.append(f"only {obs.n} levels: extensions with 1-2 extra parameters are "
                        "weakly constrained")
    return obs, warnings


# --------------------------------------------------------------------------- fitting


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


def _log_amplitude(model, s, theta):
    """log of the relative joint amplitude s_eff (G, n) for parameters theta (G, m)."""
    logs = np.log(s)[None, :]
    if model == "nonproportional-amplitude":
        kappa, gamma = np.exp(theta[:, 1:2]), theta[:, 2:3]
        return logs + gamma * (s[None, :] ** kappa - 1.0)
    return np.broadcast_to(logs, (theta.shape[0], s.size))


def _design(model, s, t_run, omega2_meas, theta):
    """Columns of the linear parameters for every parameter point ``theta`` (G, m).

    Returns (A_omega, A_zeta, nonneg, log_s_eff): design stacks (G, n, k), the
    indices of the columns constrained >= 0, and the log relative amplitude (G, n)."""
    G, n = theta.shape[0], s.size
    p = theta[:, :1]
    chi = p - 1.0
    inv_w = 0.5 / np.sqrt(omega2_meas)[None, :] * np.ones((G, 1))
    half_inv_w2 = 0.5 / omega2_meas[None, :]
    one, zero = np.ones((G, n)), np.zeros((G, n))
    log_s = _log_amplitude(model, s, theta)
    if model == "macro-slip":
        x = np.exp(theta[:, 1:2] + log_s)
        P1, P2, Q1, Q2 = slip_shapes(x, chi)
        A_om = np.stack([one, zero, -P2, -Q2], axis=-1)
        A_ze = np.stack([zero, inv_w, P1 * half_inv_w2, Q1 * half_inv_w2], -1)
        return A_om, A_ze, [2, 3], log_s
    sp = np.exp(p * log_s)
    cols_om = [one, zero, -tie_ratio(chi) * sp]
    cols_ze = [zero, inv_w, sp * half_inv_w2]
    nonneg = [2]
    if model == "geometric-hardening":
        cols_om.append(np.exp(2.0 * log_s))
        cols_ze.append(zero)
        nonneg.append(3)
    elif model == "thermal-drift":
        cols_om.append(np.broadcast_to(t_run, (G, n)))
        cols_ze.append(zero)
    elif model == "quadratic-damping":
        cols_om.append(zero)
        cols_ze.append(np.exp(log_s))
        nonneg.append(3)
    return np.stack(cols_om, -1), np.stack(cols_ze, -1), nonneg, log_s


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
    A_om, A_ze, nonneg, log_s = _design(model, d["s"], d["t_run"], d["omega2"], theta)
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
    A_om, A_ze, _, log_s = _design(model, obs.s_exc, obs.t_run, obs.omega2, theta[None, :])
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
    log_s = _log_amplitude(fit.model, obs.s_exc, fit.theta[None, :])[0]
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


def cross_validate(model: str, obs: Observations, sigma: dict):
    """Leave-one-level-out prediction error of ``model`` over the interior levels.

    Each interior level (not the lowest, not the highest) is left out in turn, the
    model is fitted to the others and the left-out omega2, zeta (and log response
    amplitude, when the data have it) are predicted. Returns (rms error in noise units
    (module doc), standardized residuals (n, channels) with NaN rows for the end
    levels)."""
    channels = ["omega2", "zeta"] + (["response"] if obs.response is not None else [])
    res = np.full((obs.n, len(channels)), np.nan)
    order = np.argsort(obs.level)
    for v in order[1:-1]:
        train = np.ones(obs.n, bool)
        train[v] = False
        f = fit_model(model, obs, train, outer=3)
        res[v, 0] = (obs.omega2[v] - f.omega2_fit[v]) / sigma["omega2"]
        res[v, 1] = (obs.zeta[v] - f.zeta_fit[v]) / sigma["zeta"]
        if obs.response is not None:
            res[v, 2] = (np.log(obs.response[v]) - f.log_response_fit[v]) / sigma["response"]
    return float(np.sqrt(np.nanmean(res**2))), res


# --------------------------------------------------------------------------- diagnosis


def diagnose(data: MeasuredData, mode: int | None = None, cv_all: bool = False) -> dict:
    """Diagnose one mode of measured amplitude-dependent modal data.

    Parameters
    ----------
    data : MeasuredData
    mode : int or None
        Mode label (default: the only/first mode).
    cv_all : bool
        Cross-validate every candidate (slower) instead of only the ones that pass the
        AICc threshold.

    Returns
    -------
    dict with the spec's keys ``cause``, ``parameters``, ``base_error``,
    ``extended_error``, ``gain``, ``evidence``, ``data_warnings``, plus ``mode``,
    ``error_measure``, ``base_parameters``, ``noise`` and ``levels`` (data and both
    fits per level, for plots).
    """
    obs, warnings = observations_from(data, mode)
    names = [c for c in CANDIDATES
             if not (c == "nonproportional-amplitude" and obs.response is None)]
    base = fit_model("base", obs)
    fits = {c: fit_model(c, obs) for c in names}
    # common noise scale: the best-fitting (lowest AICc) model's estimates
    finite = [f for f in [base, *fits.values()] if np.isfinite(f.aicc)]
    ref = min(finite, key=lambda f: f.aicc) if finite else base
    sigma = dict(ref.sigma)
    base_err, base_res = cross_validate("base", obs, sigma)

    evidence = {}
    cv = {}
    for c in CANDIDATES:
        if c not in fits:
            evidence[c] = {"available": False,
                           "reason": "needs the response_amplitude column"}
            continue
        f = fits[c]
        d_aicc = base.aicc - f.aicc
        evidence[c] = {"available": True, "delta_aicc": d_aicc, "delta_bic": base.bic - f.bic,
                       "extra_parameters": f.n_params - base.n_params,
                       **{f"sigma_{k}": v for k, v in f.sigma.items()}}
        if cv_all or d_aicc > AICC_THRESHOLD:
            err, res = cross_validate(c, obs, sigma)
            cv[c] = (err, res)
            evidence[c]["cv_error"] = err
            evidence[c]["cv_gain"] = base_err / err
    ranked = sorted((c for c in fits if evidence[c]["delta_aicc"] > AICC_THRESHOLD),
                    key=lambda c: -evidence[c]["delta_aicc"])
    cause = next((c for c in ranked if cv[c][0] < base_err), "none")
    chosen = base if cause == "none" else fits[cause]
    ext_err = base_err if cause == "none" else cv[cause][0]
    if not np.isfinite(base.aicc):
        warnings.append("too few levels for AICc: the base model cannot be tested")
    if not 0.03 < base.chi + 1.0 < 0.97 or base.linear[2] <= 0.0:
        warnings.append(f"base fit: chi = {base.chi:.3f} at the edge of (-1, 0) or no "
                        "frequency drop: the data hardly constrain the Iwan joint")
    levels = {
        "level": obs.level, "excitation": obs.excitation, "run_order": obs.run_order,
        "omega2": obs.omega2, "zeta": obs.zeta,
        "response_amplitude": obs.response,
        "base_omega2": base.omega2_fit, "base_zeta": base.zeta_fit,
        "base_log_response": base.log_response_fit,
        "extended_log_response": chosen.log_response_fit,
        "extended_omega2": chosen.omega2_fit, "extended_zeta": chosen.zeta_fit,
        "base_cv_residual": base_res,
        "extended_cv_residual": base_res if cause == "none" else cv[cause][1],
    }
    return {
        "cause": cause,
        "mode": obs.mode,
        "parameters": dict(chosen.parameters, model=chosen.model),
        "base_parameters": base.parameters,
        "base_error": base_err,
        "extended_error": ext_err,
        "gain": base_err / ext_err,
        "error_measure": ("rms leave-one-level-out prediction error over the interior "
                          "levels of omega2, zeta" + (" and log response_amplitude"
                                                      if obs.response is not None else "")
                          + ", each in units of its noise level (noise)"),
        "noise": {**{f"sigma_{k}": v for k, v in sigma.items()}, "from_model": ref.model},
        "evidence": evidence,
        "aicc_threshold": AICC_THRESHOLD,
        "summary": describe_cause(cause, chosen.parameters, base_err / ext_err, obs),
        "data_warnings": warnings,
        "levels": levels,
    }


def describe_cause(cause: str, params: dict, gain: float, obs: Observations) -> str:
    """One paragraph in plain words naming the cause."""
    chi = params.get("chi", float("nan"))
    if cause == "none":
        return (f"The base model (one micro-slip Iwan joint, slip amplitude proportional "
                f"to the excitation, chi = {chi:.3f}) explains the frequency drop and the "
                f"damping growth together within the noise: no extension earned its "
                f"extra parameters.")
    text = {
        "macro-slip": (
            f"At the top levels the joint leaves micro-slip: the frequency drop and the "
            f"damping growth bend away from the power law, as when the slip amplitude "
            f"passes phi_max (top level at {params.get('x_top', float('nan')):.2f} "
            f"phi_max, Dirac weight beta = {params.get('beta', float('nan')):.2g})."),
        "nonproportional-amplitude": (
            f"The joint amplitude does not grow in proportion to the excitation: the "
            f"frequency drop, the damping growth and the measured response amplitude "
            f"all say that at the top level it is "
            f"{100 * params.get('amplitude_shortfall_top', float('nan')):.1f} % short of "
            f"proportional (exciter force drop-out or damping growth)."),
        "geometric-hardening": (
            f"A hardening stiffness that grows with the amplitude squared lifts the "
            f"natural frequency against the Iwan softening (omega^2 + "
            f"{params.get('h_top', float('nan')):.3g} rad^2/s^2 at the top level); the "
            f"damping is unaffected."),
        "thermal-drift": (
            f"The natural frequency drifts with the order in which the levels were run "
            f"({params.get('d', float('nan')):.3g} rad^2/s^2 per run), not with the "
            f"amplitude; the damping is unaffected."),
        "quadratic-damping": (
            f"The damping grows faster than the Iwan law tied to the frequency drop "
            f"allows: an extra damping proportional to the amplitude (air, "
            f"viscoelastic glue) adds {params.get('q_top', float('nan')):.3g} to zeta at "
            f"the top level."),
    }[cause]
    return (f"{text} Extending the base model this way cuts the cross-validated "
            f"prediction error by a factor {gain:.2f} (chi = {chi:.3f}).")
