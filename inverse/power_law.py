"""Least-squares fit of the damping growth between levels, with t-intervals (eq. 33-35).

Excitation law. With the joint amplitude proportional to the excitation ``e``
(the paper's assumption, eq. 33) and ``r = e / e_ref`` (``e_ref`` = the lowest level of
the mode, the paper's ``f_e0``), ``Delta c(e) = |kappa1| B r^(chi+1)`` with B at
``e_ref``. Between two levels ``a < b`` the damping difference is

    Delta d_ab = |kappa1| B (r_b^(chi+1) - r_a^(chi+1))                       (3)

which for a constant ratio ``z`` is eq. 34, ``log_z Delta d_v = (chi+1)(v-1) + a0``
with ``a0 = log_z(z^(chi+1) - 1) + log_z |kappa1| B`` (eq. 35). Eq. 3 is fitted by least
squares on ``ln Delta d`` (non-linear in chi for varying ratios; for a constant
ratio the minimizer is exactly the paper's straight-line fit).

Uncertainty: linearized least-squares covariance of ``(chi+1, ln(.))`` from the
residuals (``s^2 = SSR/(n-2)``), two-sided Student-t intervals with ``n - 2`` degrees of
freedom (for a constant ratio: the textbook t-interval on the slope); ``|kappa1| B`` and
``R`` on a log scale; predictions by the delta method. The intervals cover the fit of
chi and ``|kappa1| B`` only (anchors, FE model and force scale are taken as exact).
No interval with fewer than 3 points.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from ident.errors import InputError

_P_BOUNDS = (-4.0, 6.0)  # search range of chi + 1 (signed formulation, see _shape)


def _shape(p, r_from, r_to):
    """``(r_to^p - r_from^p) / p``, smooth and > 0 through ``p = 0`` (r_to > r_from)."""
    p = float(p)
    lr = np.log(r_to / r_from)
    if abs(p) < 1e-12:
        return lr * r_from ** p
    return r_from ** p * np.expm1(p * lr) / p


def _dln_shape(p, r_from, r_to):
    """``d ln(_shape) / dp`` (series for small ``p ln(r_to/r_from)``)."""
    lr = np.log(r_to / r_from)
    x = p * lr
    small = np.abs(x) < 1e-4
    xs = np.where(small, 1.0, x)
    big = lr * np.exp(xs) / np.expm1(xs) - (1.0 / p if p != 0 else 0.0)
    series = lr * (0.5 + x / 12.0)
    return np.log(r_from) + np.where(small, series, big)


@dataclass
class PowerLawFit:
    """Least-squares fit of ``Delta d = K (r_b^p - r_a^p)`` on ``ln Delta d`` (eq. 3).

    ``p = chi + 1``; ``K = |kappa1| B`` at ``r = 1``. ``cov`` is the covariance of
    ``(p, ln Kt)`` with ``Kt = K p`` (so ``K = Kt / p``) (the signed formulation); ``dof = n - 2``.
    """

    p: float
    ln_kt: float
    cov: np.ndarray | None
    dof: int
    residual_std: float
    r_from: np.ndarray
    r_to: np.ndarray
    delta_d: np.ndarray

    @property
    def chi(self) -> float:
        return self.p - 1.0

    @property
    def kappa1_B(self) -> float:
        return math.exp(self.ln_kt) / self.p if self.p > 0 else math.nan

    @property
    def cov_kappa1_B(self) -> np.ndarray | None:
        """Covariance of ``(chi + 1, ln |kappa1| B)``: :attr:`cov` mapped by the delta
        method through ``ln |kappa1| B = ln Kt - ln p`` (Jacobian ``[[1, 0], [-1/p, 1]]``);
        None without residual degrees of freedom."""
        if self.cov is None:
            return None
        J = np.array([[1.0, 0.0], [-1.0 / self.p, 1.0]])
        return J @ self.cov @ J.T

    def delta_c(self, r, p=None, ln_kt=None):
        """Joint damping ``|kappa1| B r^p`` (rad^2/s^2) at relative amplitude ``r``."""
        p = self.p if p is None else p
        ln_kt = self.ln_kt if ln_kt is None else ln_kt
        return math.exp(ln_kt) / p * np.asarray(r, dtype=float) ** p

    def tquantile(self, confidence: float) -> float:
        return float(stats.t.ppf(0.5 + confidence / 2.0, self.dof)) if self.dof > 0 else math.nan

    def gradient(self, fun, h: float = 1e-6) -> np.ndarray:
        """Central-difference gradient of ``fun(p, ln_kt)`` (scalar or array)."""
        gp = (np.asarray(fun(self.p + h, self.ln_kt))
              - np.asarray(fun(self.p - h, self.ln_kt))) / (2 * h)
        gk = (np.asarray(fun(self.p, self.ln_kt + h))
              - np.asarray(fun(self.p, self.ln_kt - h))) / (2 * h)
        return np.stack([gp, gk], axis=-1)

    def std_error(self, fun) -> np.ndarray:
        """Delta-method standard error of ``fun(p, ln_kt)``; NaN without covariance."""
        value = np.asarray(fun(self.p, self.ln_kt), dtype=float)
        if self.cov is None:
            return np.full(value.shape, np.nan)
        g = self.gradient(fun)
        return np.sqrt(np.maximum(np.einsum("...i,ij,...j->...", g, self.cov, g), 0.0))

    def interval(self, fun, confidence: float, log: bool = False):
        """Two-sided t-interval of ``fun(p, ln_kt)``; on a log scale if ``log``."""
        t = self.tquantile(confidence)
        if log:
            value = np.asarray(fun(self.p, self.ln_kt), dtype=float)
            se = self.std_error(lambda p, k: np.log(fun(p, k)))
            return value * np.exp(-t * se), value * np.exp(t * se)
        value = np.asarray(fun(self.p, self.ln_kt), dtype=float)
        se = self.std_error(fun)
        return value - t * se, value + t * se


def fit_damping_growth(r_from, r_to, delta_d) -> PowerLawFit:
    """Fit eq. 3 to positive damping differences by least squares on ``ln Delta d``.

    For fixed ``p`` the best ``ln(K p)`` is the mean residual; ``p`` minimizes the sum
    of squares (bounded Brent search). For a constant ratio ``z`` this equals the
    paper's straight-line fit of ``log_z Delta d`` against ``v - 1`` (eq. 35): slope
    ``p`` and intercept ``a0 = log_z((z^p - 1) K)``.

    Parameters
    ----------
    r_from, r_to : array_like, (n,)
        Relative amplitudes (excitation / reference) of the lower and upper level of
        each difference, ``0 < r_from < r_to``.
    delta_d : array_like, (n,)
        Damping differences, rad^2/s^2, all > 0.

    Returns
    -------
    PowerLawFit
    """
    r_from = np.asarray(r_from, dtype=float)
    r_to = np.asarray(r_to, dtype=float)
    delta_d = np.asarray(delta_d, dtype=float)
    n = delta_d.size
    if n < 2:
        raise InputError(f"need at least 2 positive damping differences to fit chi, got {n}")
    if np.any(delta_d <= 0) or np.any(r_to <= r_from) or np.any(r_from <= 0):
        raise ValueError("fit_damping_growth: needs delta_d > 0 and 0 < r_from < r_to")
    y = np.log(delta_d)

    def ln_shape(p):
        return np.log(_shape(p, r_from, r_to))

    def ssr(p):
        e = y - ln_shape(p)
        return float(np.sum((e - e.mean()) ** 2))

    # coarse scan, Brent, then Gauss-Newton to machine precision (the objective is
    # exactly quadratic in p for constant ratios)
    grid = np.linspace(*_P_BOUNDS, 201)
    k = int(np.argmin([ssr(p) for p in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    res = optimize.minimize_scalar(ssr, bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-10, "maxiter": 500})
    p = float(res.x)
    yc = y - y.mean()
    for _ in range(50):
        dL = _dln_shape(p, r_from, r_to)
        J = dL - dL.mean()
        e = yc - (ln_shape(p) - ln_shape(p).mean())
        step = float(np.sum(J * e) / np.sum(J * J))
        if not math.isfinite(step) or ssr(p + step) > ssr(p) * (1 + 1e-12) + 1e-300:
            break
        p += step
        if abs(step) < 1e-15 * max(1.0, abs(p)):
            break
    e = y - ln_shape(p)
    ln_kt = float(e.mean())
    resid = e - ln_kt
    dof = n - 2
    cov = None
    std = math.nan
    if dof > 0:
        std = float(math.sqrt(np.sum(resid ** 2) / dof))
        J = np.column_stack([_dln_shape(p, r_from, r_to), np.ones(n)])
        cov = std ** 2 * np.linalg.inv(J.T @ J)
    return PowerLawFit(p=p, ln_kt=ln_kt, cov=cov, dof=dof, residual_std=std,
                       r_from=r_from, r_to=r_to, delta_d=delta_d)
