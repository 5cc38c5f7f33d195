"""Iwan chi and R from the growth of damping between force levels; predictions.

Theory (paper Sec. 2.2 and 4, re-derived; equation numbers are the paper's)
-----------------------------------------------------------------------------
A micro-slip Iwan joint under slip amplitude ``A`` loses in-phase stiffness
``kappa2 A^(chi+1)`` and gains quadrature stiffness ``|kappa1| A^(chi+1)`` (eq. 14, 18;
:mod:`joints.iwan`). For a mass-normalized mode ``phi`` and joint elements ``m`` with
slip rows ``g_m`` (``slip = g_m . x``) the modal changes are (eq. 30-32)

    Delta omega^2 = kappa2 B,   Delta c = |kappa1| B,
    B = sum_m w_m (g_m . phi)^2 A_m^(chi+1)                                   (1)

where ``w_m`` is joint element ``m``'s share of the one Iwan joint (``R_m = w_m R``;
kappa1 and kappa2 are linear in R, so the shares weight B; ``w_m = 1`` for identical
independent joints each of parameter R).

Damping ratio. The modal FRF denominator is ``(omega_J^2 - Delta omega^2 - w^2) +
i (2 zeta_n omega_n w + Delta c)`` (eq. 31); at resonance ``w = Omega`` with
``Omega^2 = omega_J^2 - Delta omega^2``, matching it to ``Omega^2 - w^2 + 2 i zeta_J
Omega w`` (eq. 44) gives

    zeta_J = zeta_n omega_n / Omega + Delta c / (2 Omega^2)                   (2)

The paper's eq. 45 prints ``Delta c / omega_J^2``: a factor 2 is missing. Only the
corrected form reproduces the published ``|kappa1| B = 29.431`` from the published
Table 5 (the printed form gives half of it, 14.8); see :data:`EQ45_FACTOR`.

Excitation law. With the joint amplitude proportional to the excitation ``e``
(the paper's assumption, eq. 33) and ``r = e / e_ref`` (``e_ref`` = the lowest level of
the mode, the paper's ``f_e0``), ``Delta c(e) = |kappa1| B r^(chi+1)`` with B at
``e_ref``. Between two levels ``a < b`` the damping difference is

    Delta d_ab = |kappa1| B (r_b^(chi+1) - r_a^(chi+1))                       (3)

which for a constant ratio ``z`` is eq. 34, ``log_z Delta d_v = (chi+1)(v-1) + a0``
with ``a0 = log_z(z^(chi+1) - 1) + log_z |kappa1| B`` (eq. 35). Eq. 3 is fitted by least
squares on ``ln Delta d`` (non-linear in chi for varying ratios; for a constant
ratio the minimizer is exactly the paper's straight-line fit). Differences <= 0
cannot be logged: they are excluded and reported in ``data_warnings``.

Measured damping differences (from eq. 2):

* ``paper``: ``Delta d_ab = 2 omega_b^2 (zeta_b - zeta_a)`` (eq. 46 with the factor 2,
  ``zeta_n omega_n / Omega ~ zeta_n`` as in the paper's eq. 45).
* ``exact``/``amplitude``: ``Delta c_v = 2 Omega_v^2 zeta_v - c_n Omega_v`` with
  ``c_n = 2 zeta_n omega_n`` (constant viscous modal damping), estimated together
  with the fit (fixed-point iteration); ``Delta d_ab = Delta c_b - Delta c_a``.

Predictions (eq. 43, 46): ``Delta omega^2(e) = (kappa2/|kappa1|) |kappa1| B r^(chi+1)``;
the ratio ``kappa2/|kappa1|`` depends on chi alone, so chi and ``|kappa1| B`` predict
frequency and damping without B or R. Absolute values need the linear anchors
``omega_lin^2`` (and ``zeta_n`` or ``c_n``), estimated by least squares over the fit
levels.

R (eq. 36, 37): ``R~ = |kappa1| B / (|kappa1|/R) / B~`` with ``|kappa1|/R =
4/(pi (chi+2)(chi+3))`` and ``B~`` from eq. 1 with the FE mode and the joint slip
amplitudes at the reference level, from ``(K_J - w^2 M + i w C) x = f`` at the model's
resonance (the linear-inverse variant of the paper's Sec. 3). ``C = (2 zeta/omega_l) K_J``
gives the mode the measured damping ``zeta``. The force is ``force_scale * e_ref``
(N); the paper never gives newtons (5 mV .. 2.56 V drive), so ``force_scale`` is an
explicit input, default :data:`DEFAULT_FORCE_SCALE`, and ``R~`` scales exactly as
``force_scale^-(chi+1)``.

Uncertainty: linearized least-squares covariance of ``(chi+1, ln(.))`` from the
residuals (``s^2 = SSR/(n-2)``), two-sided Student-t intervals with ``n - 2`` degrees of
freedom (for a constant ratio: the textbook t-interval on the slope); ``|kappa1| B`` and
``R`` on a log scale; predictions by the delta method. The intervals cover the fit of
chi and ``|kappa1| B`` only (anchors, FE model and force scale are taken as exact).
No interval with fewer than 3 points.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy import optimize, stats

from ident.errors import InputError
from joints.describing import kappa1, kappa2_exact, kappa2_paper

METHODS = ("paper", "exact", "amplitude")
CASES = ("double-beam",)
#: Factor of Delta c in eq. 45 as derived (2); the paper prints 1.
EQ45_FACTOR = 2.0
#: Newton per unit of the ``excitation`` column (N/V for the paper's drive voltage).
#: An assumption: a small electrodynamic shaker with its amplifier gives of the order
#: of 1 N per volt of drive signal; the paper does not report forces.
DEFAULT_FORCE_SCALE = 1.0
DEFAULT_CONFIDENCE = 0.95
_P_BOUNDS = (-4.0, 6.0)  # search range of chi + 1 (signed formulation, see _shape)


# --------------------------------------------------------------------------- theory


def kappa_ratio(chi, method: str = "paper") -> float:
    """``kappa2 / |kappa1|`` at ``chi`` (paper eq. A15; printed or exact kappa2).

    ``Delta omega^2 = kappa_ratio * Delta c`` (eq. 30, 43). ``paper``: the printed
    three-term Taylor kappa2 (eq. A12, A15); otherwise the exact one.
    """
    k2 = kappa2_paper if method == "paper" else kappa2_exact
    return float(k2(1.0, chi) / abs(kappa1(1.0, chi)))


def kappa1_per_R(chi) -> float:
    """``|kappa1| / R = 4 / (pi (chi+2)(chi+3))`` (paper eq. A15), m^-(chi+2) * m^(chi+2)."""
    return float(abs(kappa1(1.0, chi)))


def zeta_with_joint(delta_c, omega2, c_modal, factor: float = EQ45_FACTOR):
    """Measured damping ratio with a joint, eq. 2 of the module docstring (eq. 45 fixed).

    ``zeta_J = c_modal / (2 Omega) + Delta c / (factor/2 * 2 Omega^2)``; ``factor=2``
    is the derived relation, ``factor=1`` the paper's printed eq. 45.

    Parameters
    ----------
    delta_c : array_like
        Joint quadrature stiffness of the mode, ``|kappa1| B``, rad^2/s^2.
    omega2 : array_like
        ``Omega^2`` at that amplitude, rad^2/s^2.
    c_modal : float
        Viscous modal damping ``2 zeta_n omega_n``, rad/s.
    """
    omega2 = np.asarray(omega2, dtype=float)
    return c_modal / (2.0 * np.sqrt(omega2)) + np.asarray(delta_c) / (factor * omega2)


def delta_c_from_zeta(zeta, omega2, c_modal, factor: float = EQ45_FACTOR):
    """Inverse of :func:`zeta_with_joint`: ``Delta c = factor Omega^2 zeta - factor/2 c Omega``."""
    omega2 = np.asarray(omega2, dtype=float)
    return factor * (omega2 * np.asarray(zeta) - 0.5 * c_modal * np.sqrt(omega2))


def b_tilde(slip_rows, phi, slip_amplitude, chi, shares=None) -> float:
    """``B~ = sum_m w_m (g_m . phi)^2 A_m^(chi+1)`` (paper eq. 32, 37; eq. 1 above).

    Parameters
    ----------
    slip_rows : sparse or ndarray, (n_joints, n_dofs)
        Slip of each joint element from the DOFs (dimensionless / m per m).
    phi : ndarray, (n_dofs,)
        Mass-normalized mode shape, kg^-1/2.
    slip_amplitude : ndarray, (n_joints,)
        Slip amplitude of each joint at the reference level, m.
    chi : float
    shares : ndarray, (n_joints,), optional
        Share ``w_m`` of the Iwan joint carried by each element (``R_m = w_m R``);
        default 1.

    Returns
    -------
    float
        B~ in m^(chi+1)/kg.
    """
    g_phi = np.asarray(slip_rows @ np.asarray(phi, dtype=float)).ravel()
    a = np.asarray(slip_amplitude, dtype=float).ravel()
    w = np.ones_like(a) if shares is None else np.asarray(shares, dtype=float).ravel()
    return float(np.sum(w * g_phi ** 2 * a ** (chi + 1.0)))


def r_tilde(kappa1_B, chi, b) -> float:
    """``R~ = |kappa1| B / ((|kappa1|/R) B~)`` (paper eq. 36, 37), N m^-(chi+2)."""
    return float(kappa1_B / (kappa1_per_R(chi) * b))


def joint_slip_at_resonance(M, K, slip_rows, force, omega, zeta) -> np.ndarray:
    """Joint slip amplitudes of the linear model driven at resonance.

    Solves ``(K - omega^2 M + i omega C) x = force`` with ``C = (2 zeta / omega) K``
    (the mode at ``omega`` gets damping ratio ``zeta``; paper Sec. 3, "inverse
    matrix"), returns ``|slip_rows x|``.

    Parameters
    ----------
    M, K : sparse (n, n)
        Mass (kg) and stiffness with the stuck joints ``K_J`` (N/m).
    slip_rows : sparse (n_joints, n)
    force : ndarray (n,)
        Force amplitude vector, N.
    omega : float
        Drive frequency (the model's natural frequency), rad/s.
    zeta : float
        Damping ratio of that mode.

    Returns
    -------
    ndarray (n_joints,)
        Slip amplitudes, m.
    """
    Z = (sp.csc_matrix(K) * (1.0 + 2j * zeta) - omega ** 2 * sp.csc_matrix(M)).tocsc()
    x = spla.spsolve(Z, np.asarray(force, dtype=complex))
    return np.abs(np.asarray(slip_rows @ x)).ravel()


# --------------------------------------------------------------------------- fit


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
        gp = (np.asarray(fun(self.p + h, self.ln_kt)) - np.asarray(fun(self.p - h, self.ln_kt))) / (2 * h)
        gk = (np.asarray(fun(self.p, self.ln_kt + h)) - np.asarray(fun(self.p, self.ln_kt - h))) / (2 * h)
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


# --------------------------------------------------------------------------- levels


def parse_levels(text: str) -> list[int]:
    """``"1-7"`` -> [1..7]; ``"1,3-5,8"`` -> [1, 3, 4, 5, 8]. ValueError on bad input."""
    out: list[int] = []
    for item in str(text).replace(" ", "").split(","):
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", item)
        if not m:
            raise InputError(f"--fit-levels: cannot read {item!r} (use e.g. 1-7 or 1,3-7)")
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) else a
        if b < a:
            raise InputError(f"--fit-levels: range {item!r} runs backwards")
        out.extend(range(a, b + 1))
    if len(set(out)) != len(out):
        raise InputError(f"--fit-levels: {text!r} repeats a level")
    return sorted(out)


def _format_levels(levels) -> str:
    levels = list(levels)
    parts, start = [], levels[0]
    for a, b in zip(levels, levels[1:] + [None]):
        if b != a + 1:
            parts.append(f"{start}" if start == a else f"{start}-{a}")
            start = b
    return ",".join(parts)


# --------------------------------------------------------------------------- results


@dataclass
class CaseResult:
    """FE side of the estimate: B~ (eq. 37) and what it was computed from."""

    name: str
    fe_mode: int
    fe_frequency_hz: float
    force_scale: float
    reference_force: float
    slip_amplitudes: np.ndarray
    shares: np.ndarray
    B: float
    B_of_chi: object = field(repr=False, default=None)


@dataclass
class Estimate:
    """Everything the estimator returns (SI units; zeta as fractions).

    ``predictions`` holds one record per level of the mode: predicted and measured
    ``omega2``, ``zeta`` and, from the previous level, ``delta_omega2`` (loss of
    omega^2, positive = softening, the sign of the paper's Table 3) and
    ``delta_zeta`` (growth), with percent errors ``100 (pred - meas)/meas`` and
    t-intervals; ``held_out`` marks levels outside the fit. ``points_used`` /
    ``points_excluded`` are the fit's level pairs (``x = log_z(e_from/e_ref)``, ``y =
    log_z Delta d``, the model's ``model_delta_d``); ``differences`` lists every pair
    of successive levels of the mode (held-out ones too) in the same form.
    """

    method: str
    mode: int
    fit_levels: list
    reference_level: int
    reference_excitation: float
    chi: float
    chi_interval: tuple
    kappa1_B: float
    kappa1_B_interval: tuple
    kappa2_over_kappa1: float
    B: float | None
    R: float | None
    R_interval: tuple | None
    confidence: float
    ratio_z: float | None
    intercept_a0: float | None
    residual_std: float
    dof: int
    omega2_linear: float
    zeta_linear: float
    c_modal: float
    points_used: list
    points_excluded: list
    differences: list
    log_base: float
    predictions: list
    data_warnings: list
    case: CaseResult | None
    fit: PowerLawFit = field(repr=False)
    abscissa: str = "excitation"

    def to_dict(self) -> dict:
        """Plain-JSON form (``iwanfe estimate --json``)."""
        case = None
        if self.case is not None:
            c = self.case
            case = {"name": c.name, "fe_mode": c.fe_mode, "fe_frequency_hz": c.fe_frequency_hz,
                    "force_scale": c.force_scale, "reference_force": c.reference_force,
                    "slip_amplitudes": c.slip_amplitudes, "shares": c.shares}
        return {
            "method": self.method, "mode": self.mode, "fit_levels": self.fit_levels,
            "abscissa": self.abscissa,
            "reference_level": self.reference_level,
            "reference_excitation": self.reference_excitation,
            "chi": self.chi, "chi_interval": list(self.chi_interval),
            "kappa1_B": self.kappa1_B, "kappa1_B_interval": list(self.kappa1_B_interval),
            "B": self.B, "R": self.R,
            "R_interval": None if self.R_interval is None else list(self.R_interval),
            "confidence": self.confidence,
            "kappa2_over_kappa1": self.kappa2_over_kappa1,
            "ratio_z": self.ratio_z, "intercept_a0": self.intercept_a0,
            "residual_std": self.residual_std, "dof": self.dof,
            "omega2_linear": self.omega2_linear, "zeta_linear": self.zeta_linear,
            "c_modal": self.c_modal,
            "points_used": self.points_used, "points_excluded": self.points_excluded,
            "differences": self.differences, "log_base": self.log_base,
            "predictions": self.predictions, "data_warnings": self.data_warnings,
            "case": case,
        }


# --------------------------------------------------------------------------- estimator


def _select_mode(data, mode):
    modes = np.unique(data.mode)
    if mode is None:
        if modes.size != 1:
            raise InputError(f"{data.source or 'data'} holds modes "
                             f"{', '.join(map(str, modes))}: choose one with --mode")
        mode = int(modes[0])
    return int(mode), data.for_mode(int(mode))


def estimate(data, fit_levels=None, method: str = "paper", mode=None, case=None,
             force_scale: float = DEFAULT_FORCE_SCALE, amplitude=None, fe_mode=None,
             confidence: float = DEFAULT_CONFIDENCE, eq45_factor: float = EQ45_FACTOR,
             model=None) -> Estimate:
    """Identify chi, ``|kappa1| B`` (and B~, R~ with a case) and predict every level.

    Parameters
    ----------
    data : ident.measured.MeasuredData
    fit_levels : sequence of int or str, optional
        Levels used in the fit (``"1-7"``); default all levels of the mode. Successive
        fit levels give the differences (levels 1-7 -> v = 1..6).
    method : {"paper", "exact", "amplitude"}
        See the module docstring. ``amplitude`` regresses on ``amplitude`` (or the
        file's ``response_amplitude``) instead of the excitation.
    mode : int, optional
        Mode label; default the only mode in the data.
    case : {"double-beam"} or None
        FE model for B~ and R~; None leaves ``B`` and ``R`` null.
    force_scale : float
        N per unit of the excitation column (N/V for drive voltage).
    amplitude : array_like, optional
        Per-level response or joint amplitude (any unit) for ``method="amplitude"``,
        e.g. from a simulation; overrides the file's ``response_amplitude``.
    fe_mode : int, optional
        1-based FE mode index; default the slipping mode nearest in frequency.
    confidence : float
        Level of the t-intervals (default 0.95).
    eq45_factor : float
        2 (derived) or 1 (the paper's printed eq. 45, for comparison only).
    model : optional
        A prebuilt FE model (with ``M, K, slip_matrix, joint_stiffness, drive_dof,
        modes``) used instead of building ``case``.

    Returns
    -------
    Estimate
    """
    if method not in METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(METHODS)})")
    if case is not None and case not in CASES:
        raise InputError(f"unknown case {case!r} (choose {', '.join(CASES)})")
    if not (force_scale > 0 and math.isfinite(force_scale)):
        raise InputError(f"force scale must be a positive number, got {force_scale!r}")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    mode, d = _select_mode(data, mode)
    warnings = list(data.warnings)
    levels = d.level
    if fit_levels is None:
        fit = list(map(int, levels))
    elif isinstance(fit_levels, str):
        fit = parse_levels(fit_levels)
    else:
        fit = sorted(int(v) for v in fit_levels)
    missing = sorted(set(fit) - set(map(int, levels)))
    if missing:
        raise InputError(f"--fit-levels: level(s) {_format_levels(missing)} not in mode {mode} "
                         f"(levels {_format_levels(list(map(int, levels)))})")
    if len(fit) < 3:
        raise InputError(f"--fit-levels: need at least 3 levels (2 differences), got {len(fit)}")

    # abscissa: excitation, or amplitude
    abscissa = "excitation"
    amp = d.excitation
    if method == "amplitude":
        if amplitude is not None:
            amp = np.asarray(amplitude, dtype=float).ravel()
            if amp.shape != levels.shape or np.any(~(amp > 0)):
                raise InputError(f"amplitude must hold {levels.size} positive values, one per level")
            abscissa = "amplitude (supplied)"
        elif d.response_amplitude is not None:
            amp = d.response_amplitude
            abscissa = "response_amplitude"
        else:
            raise InputError(f"method 'amplitude' needs a response_amplitude column in "
                             f"{d.source or 'the data'} (or amplitudes from a simulation)")
    in_fit = np.isin(levels, fit)
    fi = np.flatnonzero(in_fit)
    if np.any(np.diff(amp[fi]) <= 0):
        raise InputError(f"{abscissa} must increase over the fit levels")
    ref = 0  # lowest level of the mode = the paper's f_e0
    r = amp / amp[ref]
    omega2, zeta = d.omega2, d.zeta
    W = np.sqrt(omega2)
    pair_from, pair_to = fi[:-1], fi[1:]

    def measured_dd_pairs(ia, ib, c=None):
        c = c_modal if c is None else c
        if method == "paper":  # eq. 46 with the factor 2
            return eq45_factor * omega2[ib] * (zeta[ib] - zeta[ia])
        dc = delta_c_from_zeta(zeta, omega2, c, eq45_factor)  # eq. 2 inverted
        return dc[ib] - dc[ia]

    def measured_dd(c):
        return measured_dd_pairs(pair_from, pair_to, c)

    c_modal = 2.0 * zeta[ref] * W[ref]
    for _ in range(100):
        dd = measured_dd(c_modal)
        good = dd > 0
        if good.sum() < 2:
            raise InputError(f"only {int(good.sum())} positive damping difference(s) in levels "
                             f"{_format_levels(fit)}: cannot fit chi")
        fitres = fit_damping_growth(r[pair_from][good], r[pair_to][good], dd[good])
        if method == "paper":
            break
        # c_n by least squares over the fit levels: 2 W^2 zeta - Delta c(model) = c_n W
        dc_model = fitres.delta_c(r[fi]) if fitres.p > 0 else np.zeros(fi.size)
        target = eq45_factor * omega2[fi] * zeta[fi] - dc_model
        new = float(np.sum(target * W[fi]) / np.sum(W[fi] ** 2)) * (2.0 / eq45_factor)
        if abs(new - c_modal) <= 1e-13 * abs(c_modal):
            c_modal = new
            break
        c_modal = new
    dd = measured_dd(c_modal)
    good = dd > 0
    if method != "paper":  # refit with the converged c_n (the same points up to round-off)
        if good.sum() < 2:
            raise InputError(f"only {int(good.sum())} positive damping difference(s) in levels "
                             f"{_format_levels(fit)}: cannot fit chi")
        fitres = fit_damping_growth(r[pair_from][good], r[pair_to][good], dd[good])

    points_used, points_excluded = [], []
    for a, b, val, ok in zip(pair_from, pair_to, dd, good):
        rec = {"from_level": int(levels[a]), "to_level": int(levels[b]),
               "delta_d": float(val), "x": float(np.log(r[a])), "used": bool(ok)}
        if ok:
            points_used.append(rec)
        else:
            rec["reason"] = "damping difference <= 0 cannot be logged"
            points_excluded.append(rec)
            warnings.append(
                f"excluded level pair {levels[a]}->{levels[b]}: damping difference "
                f"{val:.4g} rad^2/s^2 <= 0 cannot be logged (eq. 35)")
    if fitres.p <= 0:
        raise InputError(f"damping growth does not increase with {abscissa} (chi+1 = "
                         f"{fitres.p:.3g} <= 0): not an Iwan micro-slip joint")
    if not -1.0 < fitres.chi < 0.0:
        warnings.append(f"fitted chi = {fitres.chi:.4g} is outside the Iwan range (-1, 0)")
    if fitres.dof == 0:
        warnings.append("2 fit points: no residual degrees of freedom, no intervals")

    # constant-ratio summary (paper eq. 35)
    ratios = r[pair_to][good] / r[pair_from][good]
    z = float(np.exp(np.mean(np.log(ratios))))
    const = bool(np.allclose(ratios, z, rtol=1e-9) and np.allclose(np.log(r[pair_from][good]) / np.log(z),
                 np.round(np.log(r[pair_from][good]) / np.log(z)), atol=1e-9))
    ratio_z = z if const else None
    a0 = (math.log((z ** fitres.p - 1.0) * fitres.kappa1_B) / math.log(z)) if const else None

    # every successive pair of the mode's levels (held-out ones too), for plots and JSON
    dd_all = measured_dd_pairs(np.arange(levels.size - 1), np.arange(1, levels.size))
    fit_pairs = set(zip(pair_from.tolist(), pair_to.tolist()))
    differences = []
    for a in range(levels.size - 1):
        b = a + 1
        differences.append({"from_level": int(levels[a]), "to_level": int(levels[b]),
                            "delta_d": float(dd_all[a]), "x": float(np.log(r[a])),
                            "in_fit": (a, b) in fit_pairs})
    for rec, (a, b) in zip(points_used + points_excluded,
                           [(a, b) for a, b, ok in zip(pair_from, pair_to, good) if ok]
                           + [(a, b) for a, b, ok in zip(pair_from, pair_to, good) if not ok]):
        rec["model_delta_d"] = float(fitres.delta_c(r[b]) - fitres.delta_c(r[a]))
    for rec, a in zip(differences, range(levels.size - 1)):
        rec["model_delta_d"] = float(fitres.delta_c(r[a + 1]) - fitres.delta_c(r[a]))
    for rec in points_used + points_excluded + differences:
        rec["x"] = rec["x"] / math.log(z)  # log_z(e_from / e_ref): v - 1 for the paper
        rec["y"] = math.log(rec["delta_d"]) / math.log(z) if rec["delta_d"] > 0 else None
        rec["model_y"] = math.log(rec["model_delta_d"]) / math.log(z)

    # ------------------------------------------------------------ anchors, predictions
    kap = "paper" if method == "paper" else "exact"

    def q_of(p):
        return kappa_ratio(p - 1.0, kap)

    def loss(p, lk, rr):  # Delta omega^2(r) = q K r^p
        return q_of(p) * math.exp(lk) / p * np.asarray(rr) ** p

    omega2_lin = float(np.mean(omega2[fi] + loss(fitres.p, fitres.ln_kt, r[fi])))
    zeta_lin = float(np.mean(zeta[fi] - fitres.delta_c(r[fi]) / (eq45_factor * omega2[fi])))

    def absolute(p, lk):
        om2 = omega2_lin - loss(p, lk, r)
        dc = math.exp(lk) / p * r ** p
        if method == "paper":
            ze = zeta_lin + dc / (eq45_factor * om2)
        else:
            ze = zeta_with_joint(dc, om2, c_modal, eq45_factor)
        return om2, ze

    om2_p, ze_p = absolute(fitres.p, fitres.ln_kt)
    lo_om2, hi_om2 = fitres.interval(lambda p, k: absolute(p, k)[0], confidence)
    lo_ze, hi_ze = fitres.interval(lambda p, k: absolute(p, k)[1], confidence)

    def d_om2(p, k):
        om2 = absolute(p, k)[0]
        return om2[:-1] - om2[1:]

    def d_ze(p, k):
        ze = absolute(p, k)[1]
        return ze[1:] - ze[:-1]

    lo_dom, hi_dom = fitres.interval(d_om2, confidence)
    lo_dze, hi_dze = fitres.interval(d_ze, confidence)
    dom_p, dze_p = d_om2(fitres.p, fitres.ln_kt), d_ze(fitres.p, fitres.ln_kt)

    def err(pred, meas):
        return 100.0 * (pred - meas) / meas if meas != 0 else None

    predictions = []
    for i in range(levels.size):
        rec = {"level": int(levels[i]), "excitation": float(d.excitation[i]),
               "held_out": bool(not in_fit[i]),
               "omega2": float(om2_p[i]), "omega2_interval": [float(lo_om2[i]), float(hi_om2[i])],
               "measured_omega2": float(omega2[i]),
               "omega2_error_percent": err(om2_p[i], omega2[i]),
               "zeta": float(ze_p[i]), "zeta_interval": [float(lo_ze[i]), float(hi_ze[i])],
               "measured_zeta": float(zeta[i]),
               "zeta_error_percent": err(ze_p[i], zeta[i])}
        if i == 0:
            rec.update(delta_omega2=None, delta_omega2_interval=None, measured_delta_omega2=None,
                       delta_omega2_error_percent=None, delta_zeta=None,
                       delta_zeta_interval=None, measured_delta_zeta=None,
                       delta_zeta_error_percent=None)
        else:
            j = i - 1
            m_dom = float(omega2[i - 1] - omega2[i])
            m_dze = float(zeta[i] - zeta[i - 1])
            rec.update(delta_omega2=float(dom_p[j]),
                       delta_omega2_interval=[float(lo_dom[j]), float(hi_dom[j])],
                       measured_delta_omega2=m_dom,
                       delta_omega2_error_percent=err(dom_p[j], m_dom),
                       delta_zeta=float(dze_p[j]),
                       delta_zeta_interval=[float(lo_dze[j]), float(hi_dze[j])],
                       measured_delta_zeta=m_dze,
                       delta_zeta_error_percent=err(dze_p[j], m_dze))
        predictions.append(rec)

    chi_iv = fitres.interval(lambda p, k: p - 1.0, confidence)
    k1b_iv = fitres.interval(lambda p, k: math.exp(k) / p if p > 0 else math.nan, confidence, log=True)

    # ------------------------------------------------------------ case: B~ and R~
    case_res, B, R, R_iv = None, None, None, None
    if case is not None or model is not None:
        case_res = case_b_tilde(case or "model", d, ref, force_scale, fe_mode=fe_mode,
                                chi=fitres.chi, model=model)
        B = case_res.B
        R = r_tilde(fitres.kappa1_B, fitres.chi, B)

        def ln_r(p, k):
            return k - math.log(p) - math.log(kappa1_per_R(p - 1.0)) - math.log(case_res.B_of_chi(p - 1.0))

        if fitres.cov is not None:
            se = float(fitres.std_error(ln_r))
            t = fitres.tquantile(confidence)
            R_iv = (R * math.exp(-t * se), R * math.exp(t * se))
        else:
            R_iv = (math.nan, math.nan)

    return Estimate(
        method=method, mode=mode, fit_levels=fit, reference_level=int(levels[ref]),
        reference_excitation=float(d.excitation[ref]), chi=fitres.chi,
        chi_interval=(float(chi_iv[0]), float(chi_iv[1])), kappa1_B=fitres.kappa1_B,
        kappa1_B_interval=(float(k1b_iv[0]), float(k1b_iv[1])),
        kappa2_over_kappa1=q_of(fitres.p), B=B, R=R, R_interval=R_iv, confidence=confidence,
        ratio_z=ratio_z, intercept_a0=a0, residual_std=fitres.residual_std, dof=fitres.dof,
        omega2_linear=omega2_lin, zeta_linear=zeta_lin,
        c_modal=(c_modal if method != "paper" else 2.0 * zeta_lin * math.sqrt(omega2_lin)),
        points_used=points_used, points_excluded=points_excluded, differences=differences,
        log_base=z, predictions=predictions,
        data_warnings=warnings, case=case_res, fit=fitres, abscissa=abscissa)


# --------------------------------------------------------------------------- FE case


def build_case(name: str):
    """The FE model of a named case (``double-beam``)."""
    if name == "double-beam":
        from cases.double_beam.model import build_double_beam
        return build_double_beam()
    raise InputError(f"unknown case {name!r} (choose {', '.join(CASES)})")


def pick_fe_mode(model, omega_measured: float, n_modes: int = 24) -> int:
    """1-based index of the model mode nearest ``omega_measured`` that slips the joints.

    Modes whose joint slip ``|slip_matrix phi|`` is below 1e-6 of the largest one (e.g.
    out-of-phase modes of identical strips) cannot show the joint and are skipped.
    """
    omega, shapes = model.modes(n_modes)
    slip = np.linalg.norm(np.asarray(model.slip_matrix @ shapes), axis=0)
    ok = slip > 1e-6 * slip.max()
    cand = np.flatnonzero(ok)
    return int(cand[np.argmin(np.abs(omega[cand] - omega_measured))] + 1)


def case_b_tilde(name, d, ref: int, force_scale: float, fe_mode=None, chi: float = -0.5,
                 model=None) -> CaseResult:
    """B~ (eq. 37) of the FE model at the reference level of the measured data ``d``.

    The mode is ``fe_mode`` (1-based) or :func:`pick_fe_mode`; the joint slips come
    from :func:`joint_slip_at_resonance` at the model's natural frequency with the
    measured damping ratio of the reference level and the force
    ``force_scale * excitation[ref]`` (N) at ``model.drive_dof``; shares are
    ``joint_stiffness / sum(joint_stiffness)`` (each element carries its share of the
    glue's Iwan density).
    """
    model = build_case(name) if model is None else model
    omega_meas = math.sqrt(float(d.omega2[ref]))
    if fe_mode is None:
        fe_mode = pick_fe_mode(model, omega_meas)
    fe_mode = int(fe_mode)
    if fe_mode < 1:
        raise InputError(f"--fe-mode must be >= 1, got {fe_mode}")
    omega, shapes = model.modes(max(fe_mode, 1))
    if fe_mode > omega.size:
        raise InputError(f"--fe-mode {fe_mode}: the model has only {omega.size} modes")
    w_l, phi = float(omega[fe_mode - 1]), shapes[:, fe_mode - 1]
    n = model.M.shape[0]
    force = np.zeros(n)
    F = force_scale * float(d.excitation[ref])
    force[int(model.drive_dof)] = F
    slips = joint_slip_at_resonance(model.M, model.K, model.slip_matrix, force, w_l,
                                    float(d.zeta[ref]))
    kj = np.asarray(model.joint_stiffness, dtype=float)
    shares = kj / kj.sum()

    def B_of_chi(c):
        return b_tilde(model.slip_matrix, phi, slips, c, shares)

    return CaseResult(name=str(name), fe_mode=fe_mode, fe_frequency_hz=w_l / (2 * math.pi),
                      force_scale=float(force_scale), reference_force=F,
                      slip_amplitudes=slips, shares=shares, B=B_of_chi(chi), B_of_chi=B_of_chi)


# --------------------------------------------------------------------------- text


def format_table(est: Estimate, source: str = "") -> str:
    """Readable report of an :class:`Estimate` (``iwanfe estimate`` without --json)."""
    c = est.confidence
    lines = [f"iwanfe estimate {source}  mode {est.mode}  method {est.method}  "
             f"fit levels {_format_levels(est.fit_levels)}  abscissa {est.abscissa}"]
    ci = est.chi_interval
    ki = est.kappa1_B_interval
    lines.append(f"  chi          = {est.chi:.5f}   ({c:.0%} interval {ci[0]:.3f} .. {ci[1]:.3f})")
    lines.append(f"  |kappa1| B   = {est.kappa1_B:.4g} 1/s^2   ({ki[0]:.3g} .. {ki[1]:.3g}), "
                 f"at level {est.reference_level} (excitation {est.reference_excitation:g})")
    lines.append(f"  kappa2/|kappa1| = {est.kappa2_over_kappa1:.4f} "
                 f"({'printed eq. A15' if est.method == 'paper' else 'exact'})")
    if est.ratio_z is not None:
        lines.append(f"  eq. 35: z = {est.ratio_z:.4g}, slope chi+1 = {est.chi + 1:.5f}, "
                     f"intercept a0 = {est.intercept_a0:.4f}, residual std {est.residual_std:.3g} "
                     f"(ln units), dof {est.dof}")
    if est.case is not None:
        cs = est.case
        ri = est.R_interval
        lines.append(f"  case {cs.name}: FE mode {cs.fe_mode} ({cs.fe_frequency_hz:.2f} Hz), "
                     f"force {cs.reference_force:.4g} N at level {est.reference_level} "
                     f"({cs.force_scale:g} N per excitation unit)")
        lines.append(f"  B~ = {est.B:.4g} m^(chi+1)/kg   R~ = {est.R:.4g} N/m^(chi+2)   "
                     f"({ri[0]:.3g} .. {ri[1]:.3g})")
    else:
        lines.append("  B, R: not computed (no --case)")
    used = ", ".join(f"{p['from_level']}->{p['to_level']}" for p in est.points_used)
    lines.append(f"  points used: {used}")
    if est.points_excluded:
        lines.append("  points excluded: " + ", ".join(
            f"{p['from_level']}->{p['to_level']} ({p['delta_d']:.3g})" for p in est.points_excluded))
    lines.append("")
    lines.append(" level  held  loss omega^2 [rad^2/s^2]        growth zeta [%]              "
                 "omega^2 [rad^2/s^2]       zeta [%]")
    lines.append("              pred     meas   err%        pred       meas      err%     "
                 "pred        meas         pred     meas")
    for p in est.predictions:
        if p["delta_omega2"] is None:
            dpart = " " * 60
        else:
            e1 = p["delta_omega2_error_percent"]
            e2 = p["delta_zeta_error_percent"]
            dpart = (f"{p['delta_omega2']:8.2f} {p['measured_delta_omega2']:8.2f} "
                     f"{e1 if e1 is not None else float('nan'):6.1f}   "
                     f"{100 * p['delta_zeta']:10.4e} {100 * p['measured_delta_zeta']:10.4e} "
                     f"{e2 if e2 is not None else float('nan'):7.1f}")
        lines.append(f" {p['level']:5d}  {'*' if p['held_out'] else ' ':>4}  {dpart}  "
                     f"{p['omega2']:11.1f} {p['measured_omega2']:11.1f}  "
                     f"{100 * p['zeta']:7.4f}  {100 * p['measured_zeta']:7.4f}")
    lines.append("  (* = held out of the fit; loss = omega^2[v-1] - omega^2[v]; "
                 "err% = 100 (pred - meas)/meas)")
    for w in est.data_warnings:
        lines.append(f"warning: {w}")
    return "\n".join(lines)
