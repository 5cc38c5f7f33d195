"""Iwan chi and R from the growth of damping between force levels; predictions.

:func:`estimate` fits chi and ``|kappa1| B`` to the damping differences between levels
(eq. 3 of :mod:`inverse.power_law`, paper eq. 33-35), predicts frequency and damping at
every level (eq. 43, 46; :mod:`inverse.level_predictions`) and, given an FE model,
computes B~ and R~ (eq. 36, 37; :mod:`inverse.fe_reference`). The modal relations
(eq. 1, 2 and the factor 2 of eq. 45) are in :mod:`inverse.iwan_modal`. Differences
<= 0 cannot be logged: they are excluded and reported in ``data_warnings``.
What the series shows that no Iwan joint can do (frequency rising while the damping
grows, a loss of omega^2 below the least the micro-slip tie allows, chi outside
(-1, 0)) is stated in ``contradictions`` (:mod:`inverse.contradictions`).

Abscissa: the level's excitation, as in the paper (joint amplitude proportional to
the excitation), or, for a response-controlled series (``control = response``), the
response amplitude each level held, ``r = A / A_ref``: the mode's amplitude, and with it
every joint's slip, is then known rather than assumed proportional to the force. The
rows of a free decay (``test = free-decay``: the envelope along the decay) and of a
random test (``test = random``: the response RMS) are regressed on their response
amplitude the same way. For a random series the joint sees Rayleigh amplitudes: its
expected damping is ``c(chi)`` times the sine law at the RMS amplitude
(:mod:`inverse.random_amplitude`), a constant factor on ``|kappa1| B`` that cancels in
``r``: chi is that of a stepped sine; ``kappa1_B_sine = kappa1_B / c(chi)``. B~ and R~
need the sinusoidal force of a stepped sine; for the other tests they stay null.

Measured damping differences (from eq. 2):

* ``paper``: ``Delta d_ab = 2 omega_b^2 (zeta_b - zeta_a)`` (eq. 46 with the factor 2,
  ``zeta_n omega_n / Omega ~ zeta_n`` as in the paper's eq. 45).
* ``exact``/``amplitude``: ``Delta c_v = 2 Omega_v^2 zeta_v - c_n Omega_v`` with
  ``c_n = 2 zeta_n omega_n`` (constant viscous modal damping), estimated together
  with the fit (fixed-point iteration); ``Delta d_ab = Delta c_b - Delta c_a``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ident.errors import InputError
from inverse.contradictions import iwan_contradictions
from inverse.estimate_result import Estimate
# parse_levels, format_levels, RESONANT_LAG: re-exported (imported from here elsewhere)
from inverse.estimate_series import (REF, RESONANT_LAG, Series, format_levels, parse_levels,
                                     prepare_series)
from inverse.fe_reference import fe_reference
from inverse.iwan_modal import EQ45_FACTOR, delta_c_from_zeta, kappa1_per_R, kappa_ratio, r_tilde
from inverse.level_predictions import predict_levels, unphysical
from inverse.power_law import PowerLawFit, fit_damping_growth
from inverse.random_amplitude import rayleigh_factor

METHODS = ("paper", "exact", "amplitude")
#: Newton per unit of the ``excitation`` column (N/V for the paper's drive voltage).
#: An assumption: a small electrodynamic shaker with its amplifier gives of the order
#: of 1 N per volt of drive signal; the paper does not report forces.
DEFAULT_FORCE_SCALE = 1.0
DEFAULT_CONFIDENCE = 0.95


# --------------------------------------------------------------------------- estimator


def _judged_noise(data, mode):
    """The noise of each level mean that ``diagnose`` judges by (identification plus the
    test's repeatability: :func:`inverse.diagnosis.run.level_means_and_noise`), so
    that both commands state a contradiction against the same noise."""
    from inverse.diagnosis.run import level_means_and_noise, observations_from

    return level_means_and_noise(*observations_from(data, mode)[:4])[2]


def _check_options(method: str, force_scale: float, confidence: float) -> None:
    """One-line ``InputError`` on a method, force scale or confidence out of range."""
    if method not in METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(METHODS)})")
    if not (force_scale > 0 and math.isfinite(force_scale)):
        raise InputError(f"force scale must be a positive number, got {force_scale!r}")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")


@dataclass(frozen=True)
class _Differences:
    """The measured damping differences of one mode (module doc: ``paper`` or eq. 2)."""

    method: str
    omega2: np.ndarray
    zeta: np.ndarray
    eq45_factor: float

    def between(self, ia, ib, c_modal: float) -> np.ndarray:
        """``Delta d`` from the levels ``ia`` to ``ib`` (indices), viscous ``c_modal``."""
        if self.method == "paper":  # eq. 46 with the factor 2
            return self.eq45_factor * self.omega2[ib] * (self.zeta[ib] - self.zeta[ia])
        dc = delta_c_from_zeta(self.zeta, self.omega2, c_modal, self.eq45_factor)  # eq. 2 inverted
        return dc[ib] - dc[ia]


@dataclass
class _Growth:
    """The damping-growth fit with c_n, its level pairs as records and the log base."""

    fit: PowerLawFit
    c_modal: float
    points_used: list
    points_excluded: list
    differences: list
    log_base: float
    ratio_z: float | None
    intercept_a0: float | None


def _fit_positive(r, pair_from, pair_to, delta, fit) -> tuple[PowerLawFit, np.ndarray]:
    """Eq. 3 fitted to the positive differences ``delta`` of the level pairs, their mask."""
    good = delta > 0
    if good.sum() < 2:
        raise InputError(f"only {int(good.sum())} positive damping difference(s) in levels "
                         f"{format_levels(fit)}: cannot fit chi")
    return fit_damping_growth(r[pair_from][good], r[pair_to][good], delta[good]), good


def _fit_with_c_modal(s: Series, dd: _Differences):
    """The fit, c_n by fixed-point iteration with it (``paper``: c_n not used), the
    differences of the fit's level pairs and the mask of the positive ones."""
    fi, r = s.fi, s.r
    pair_from, pair_to = fi[:-1], fi[1:]
    W = np.sqrt(dd.omega2)
    c_modal = 2.0 * dd.zeta[REF] * W[REF]
    for _ in range(100):
        fitres, _ = _fit_positive(r, pair_from, pair_to,
                                  dd.between(pair_from, pair_to, c_modal), s.fit)
        if dd.method == "paper":
            break
        # c_n by least squares over the fit levels: 2 W^2 zeta - Delta c(model) = c_n W
        dc_model = fitres.delta_c(r[fi]) if fitres.p > 0 else np.zeros(fi.size)
        target = dd.eq45_factor * dd.omega2[fi] * dd.zeta[fi] - dc_model
        new = float(np.sum(target * W[fi]) / np.sum(W[fi] ** 2)) * (2.0 / dd.eq45_factor)
        if abs(new - c_modal) <= 1e-13 * abs(c_modal):
            c_modal = new
            break
        c_modal = new
    delta = dd.between(pair_from, pair_to, c_modal)
    good = delta > 0
    if dd.method != "paper":  # refit with the converged c_n (the same points up to round-off)
        fitres, good = _fit_positive(r, pair_from, pair_to, delta, s.fit)
    return fitres, c_modal, delta, good


def _pair_records(s: Series, delta, good) -> tuple[list, list]:
    """The fit's level pairs as records, used and excluded (each excluded one warned of
    in ``s.warnings``)."""
    levels, r, fi = s.d.level, s.r, s.fi
    points_used, points_excluded = [], []
    for a, b, val, ok in zip(fi[:-1], fi[1:], delta, good):
        rec = {"from_level": int(levels[a]), "to_level": int(levels[b]),
               "delta_d": float(val), "x": float(np.log(r[a])), "used": bool(ok)}
        if ok:
            points_used.append(rec)
        else:
            rec["reason"] = "damping difference <= 0 cannot be logged"
            points_excluded.append(rec)
            s.warnings.append(
                f"excluded level pair {levels[a]}->{levels[b]}: damping difference "
                f"{val:.4g} rad^2/s^2 <= 0 cannot be logged (eq. 35)")
    return points_used, points_excluded


def _constant_ratio(r_from, r_to, fitres: PowerLawFit):
    """The mean ratio z of the pairs' abscissae and, when it is constant (paper eq. 35),
    z and the intercept a0 (else None, None)."""
    ratios = r_to / r_from
    z = float(np.exp(np.mean(np.log(ratios))))
    const = bool(np.allclose(ratios, z, rtol=1e-9)
                 and np.allclose(np.log(r_from) / np.log(z),
                                 np.round(np.log(r_from) / np.log(z)), atol=1e-9))
    ratio_z = z if const else None
    a0 = (math.log((z ** fitres.p - 1.0) * fitres.kappa1_B) / math.log(z)) if const else None
    return z, ratio_z, a0


def _all_differences(s: Series, dd: _Differences, c_modal: float) -> list:
    """Every successive pair of the mode's levels (held-out ones too), for plots and JSON."""
    levels, r, fi = s.d.level, s.r, s.fi
    dd_all = dd.between(np.arange(levels.size - 1), np.arange(1, levels.size), c_modal)
    fit_pairs = set(zip(fi[:-1].tolist(), fi[1:].tolist()))
    differences = []
    for a in range(levels.size - 1):
        b = a + 1
        differences.append({"from_level": int(levels[a]), "to_level": int(levels[b]),
                            "delta_d": float(dd_all[a]), "x": float(np.log(r[a])),
                            "in_fit": (a, b) in fit_pairs})
    return differences


def _on_log_base(records: list, pairs, fitres: PowerLawFit, r, z: float) -> None:
    """Each record of a level pair ``(a, b)`` with its ``model_delta_d``, and ``x``,
    ``y``, ``model_y`` on the log base ``z`` (``x``: v - 1 for the paper)."""
    for rec, (a, b) in zip(records, pairs):
        rec["model_delta_d"] = float(fitres.delta_c(r[b]) - fitres.delta_c(r[a]))
        rec["x"] = rec["x"] / math.log(z)  # log_z(e_from / e_ref): v - 1 for the paper
        rec["y"] = math.log(rec["delta_d"]) / math.log(z) if rec["delta_d"] > 0 else None
        rec["model_y"] = math.log(rec["model_delta_d"]) / math.log(z)


def _growth(s: Series, dd: _Differences) -> _Growth:
    """Chi and ``|kappa1| B`` from the damping differences of the fit levels (eq. 3 of
    :mod:`inverse.power_law`), with every level pair as a record."""
    fitres, c_modal, delta, good = _fit_with_c_modal(s, dd)
    points_used, points_excluded = _pair_records(s, delta, good)
    if fitres.p <= 0:
        raise InputError(f"damping growth does not increase with {s.abscissa} (chi+1 = "
                         f"{fitres.p:.3g} <= 0): not an Iwan micro-slip joint")
    if fitres.dof == 0:
        s.warnings.append("2 fit points: no residual degrees of freedom, no intervals")
    pair_from, pair_to = s.fi[:-1], s.fi[1:]
    z, ratio_z, a0 = _constant_ratio(s.r[pair_from][good], s.r[pair_to][good], fitres)
    differences = _all_differences(s, dd, c_modal)
    pairs = list(zip(pair_from, pair_to))
    ordered = ([p for p, ok in zip(pairs, good) if ok]       # as points_used + points_excluded
               + [p for p, ok in zip(pairs, good) if not ok])
    _on_log_base(points_used + points_excluded, ordered, fitres, s.r, z)
    _on_log_base(differences, [(a, a + 1) for a in range(len(differences))], fitres, s.r, z)
    return _Growth(fitres, c_modal, points_used, points_excluded, differences, z, ratio_z, a0)


def _fe_anchors(model, s: Series, fitres: PowerLawFit, force_scale: float, fe_mode,
                confidence: float, case_name: str) -> tuple:
    """B~, R~ and R~'s t-interval from an FE model (eq. 36, 37): (case, B, R, interval),
    all None without a model or (warned of in ``s.warnings``) for a test other than a
    stepped sine."""
    if model is None:
        return None, None, None, None
    if s.test != "stepped-sine":
        s.warnings.append(f"test = {s.test}: B~ and R~ need the sinusoidal force of a "
                          "stepped sine; left null")
        return None, None, None, None
    case_res = fe_reference(model, s.d, REF, force_scale, fe_mode=fe_mode, chi=fitres.chi,
                            name=case_name)
    B = case_res.B
    R = r_tilde(fitres.kappa1_B, fitres.chi, B)

    def ln_r(p, k):
        return (k - math.log(p) - math.log(kappa1_per_R(p - 1.0))
                - math.log(case_res.B_of_chi(p - 1.0)))

    if fitres.cov is not None:
        se = float(fitres.std_error(ln_r))
        t = fitres.tquantile(confidence)
        R_iv = (R * math.exp(-t * se), R * math.exp(t * se))
    else:
        R_iv = (math.nan, math.nan)
    return case_res, B, R, R_iv


def estimate(data, fit_levels=None, method: str = "paper", mode=None, model=None,
             force_scale: float = DEFAULT_FORCE_SCALE, amplitude=None, fe_mode=None,
             confidence: float = DEFAULT_CONFIDENCE, eq45_factor: float = EQ45_FACTOR,
             case_name: str = "model") -> Estimate:
    """Identify chi, ``|kappa1| B`` (and B~, R~ with a model) and predict every level.

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
    model : optional
        FE model for B~ and R~ (any object with ``M, K, slip_matrix, joint_stiffness,
        drive_dof, modes``; the shipped ones: :func:`cases.registry.build_case`); None
        leaves ``B`` and ``R`` null.
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
    case_name : str
        Name of ``model`` in the result (``case.name``).

    Returns
    -------
    Estimate
    """
    _check_options(method, force_scale, confidence)
    s = prepare_series(data, mode, fit_levels, method, amplitude)
    g = _growth(s, _Differences(method, s.d.omega2, s.d.zeta, eq45_factor))
    fitres, d = g.fit, s.d
    predictions, omega2_lin, zeta_lin = predict_levels(fitres, d, s.in_fit, s.r, method,
                                                       g.c_modal, eq45_factor, confidence)
    if bad := unphysical(predictions):
        s.warnings.append(bad)
    chi_iv = fitres.interval(lambda p, k: p - 1.0, confidence)
    k1b_iv = fitres.interval(lambda p, k: math.exp(k) / p if p > 0 else math.nan, confidence,
                             log=True)
    case_res, B, R, R_iv = _fe_anchors(model, s, fitres, force_scale, fe_mode, confidence,
                                       case_name)
    kappa = "paper" if method == "paper" else "exact"  # the kappa2 of kappa2/|kappa1|
    contradictions = iwan_contradictions(d, chi=fitres.chi, noise=_judged_noise(data, s.mode))
    random = s.test == "random" and -1.0 < fitres.chi <= 0.0
    return Estimate(
        method=method, mode=s.mode, fit_levels=s.fit, reference_level=int(d.level[REF]),
        reference_excitation=float(d.excitation[REF]), chi=fitres.chi,
        chi_interval=(float(chi_iv[0]), float(chi_iv[1])), kappa1_B=fitres.kappa1_B,
        kappa1_B_interval=(float(k1b_iv[0]), float(k1b_iv[1])),
        kappa2_over_kappa1=kappa_ratio(fitres.p - 1.0, kappa),
        B=B, R=R, R_interval=R_iv, confidence=confidence,
        ratio_z=g.ratio_z, intercept_a0=g.intercept_a0, residual_std=fitres.residual_std,
        dof=fitres.dof, omega2_linear=omega2_lin, zeta_linear=zeta_lin,
        c_modal=(g.c_modal if method != "paper" else 2.0 * zeta_lin * math.sqrt(omega2_lin)),
        points_used=g.points_used, points_excluded=g.points_excluded,
        differences=g.differences, log_base=g.log_base, predictions=predictions,
        data_warnings=s.warnings, case=case_res, fit=fitres, abscissa=s.abscissa,
        control=str(d.control[0]), reference_amplitude=float(s.amp[REF]),
        contradictions=[c.statement for c in contradictions],
        contradiction_details=[{"kind": c.kind, **c.numbers} for c in contradictions],
        test=s.test, rayleigh_factor=rayleigh_factor(fitres.chi) if random else None,
        kappa1_B_sine=fitres.kappa1_B / rayleigh_factor(fitres.chi) if random else None)
