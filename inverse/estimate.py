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
import re

import numpy as np

from ident.errors import InputError
from ident.modal_data import mean_per_level
from inverse.contradictions import iwan_contradictions
from inverse.estimate_result import Estimate
from inverse.fe_reference import fe_reference
from inverse.iwan_modal import EQ45_FACTOR, delta_c_from_zeta, kappa1_per_R, kappa_ratio, r_tilde
from inverse.level_predictions import predict_levels, unphysical
from inverse.power_law import fit_damping_growth
from inverse.random_amplitude import rayleigh_factor

METHODS = ("paper", "exact", "amplitude")
#: Newton per unit of the ``excitation`` column (N/V for the paper's drive voltage).
#: An assumption: a small electrodynamic shaker with its amplifier gives of the order
#: of 1 N per volt of drive signal; the paper does not report forces.
DEFAULT_FORCE_SCALE = 1.0
DEFAULT_CONFIDENCE = 0.95


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
        if b > 10_000:   # a stepped-sine test has tens of levels; this bounds the list
            raise InputError(f"--fit-levels: level {b} in {item!r} exceeds 10000")
        out.extend(range(a, b + 1))
    if len(set(out)) != len(out):
        raise InputError(f"--fit-levels: {text!r} repeats a level")
    return sorted(out)


def format_levels(levels) -> str:
    """[1, 2, 3, 5] -> ``"1-3,5"`` (the inverse of :func:`parse_levels`)."""
    levels = list(levels)
    parts, start = [], levels[0]
    for a, b in zip(levels, levels[1:] + [None]):
        if b != a + 1:
            parts.append(f"{start}" if start == a else f"{start}-{a}")
            start = b
    return ",".join(parts)


# --------------------------------------------------------------------------- estimator


def _select_mode(data, mode):
    modes = np.unique(data.mode)
    if mode is None:
        if modes.size != 1:
            raise InputError(f"{data.source or 'data'} holds modes "
                             f"{', '.join(map(str, modes))}: choose one with --mode")
        mode = int(modes[0])
    return int(mode), data.for_mode(int(mode))


#: A resonant amplitude that falls this far behind the excitation over the fit levels is
#: worth a warning (the paper's abscissa then misplaces the top levels by as much).
RESONANT_LAG = 1.2


def _resonant_lag(zeta_omega2) -> list:
    """A warning when the excitation is the abscissa (force control: the paper takes the
    joint amplitude proportional to it) but the resonant amplitude ``E / (2 zeta
    omega^2)`` falls behind it, because ``zeta omega^2`` grew over the fit levels."""
    lag = float(np.max(zeta_omega2) / zeta_omega2[0])
    if lag <= RESONANT_LAG:
        return []
    return [f"zeta omega^2 grows {lag:.3g}x over the fit levels: under force control the "
            f"resonant amplitude E / (2 zeta omega^2) then grows {lag:.3g}x less than the "
            f"excitation, which the paper's abscissa (joint amplitude proportional to the "
            f"excitation) ignores, and chi comes out biased; `iwanfe diagnose` takes the "
            f"resonant amplitude; with a response_amplitude column use --method amplitude"]


def _judged_noise(data, mode):
    """The noise of each level mean that ``diagnose`` judges by (identification plus the
    test's repeatability: :func:`inverse.diagnosis.run.level_means_and_noise`), so
    that both commands state a contradiction against the same noise."""
    from inverse.diagnosis.run import level_means_and_noise, observations_from

    return level_means_and_noise(*observations_from(data, mode)[:4])[2]


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
    if method not in METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(METHODS)})")
    if not (force_scale > 0 and math.isfinite(force_scale)):
        raise InputError(f"force scale must be a positive number, got {force_scale!r}")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    mode, d = _select_mode(data, mode)
    warnings = list(data.warnings)
    d, averaged = mean_per_level(d)
    if averaged:
        warnings.append(averaged)
    levels = d.level
    if fit_levels is None:
        fit = list(map(int, levels))
    elif isinstance(fit_levels, str):
        fit = parse_levels(fit_levels)
    else:
        fit = sorted(int(v) for v in fit_levels)
    missing = sorted(set(fit) - set(map(int, levels)))
    if missing:
        raise InputError(f"--fit-levels: level(s) {format_levels(missing)} not in mode {mode} "
                         f"(levels {format_levels(list(map(int, levels)))})")
    if len(fit) < 3:
        raise InputError(f"--fit-levels: need at least 3 levels (2 differences), got {len(fit)}")

    # abscissa: what each level held (excitation; the response amplitude under response
    # control, where it is the level's abscissa), or a supplied/measured amplitude
    test = str(d.test[0])
    held_label = {"random": "response_amplitude (RMS of a random test)",
                  "free-decay": "response_amplitude (envelope of a free decay)"}.get(
        test, "response_amplitude (held: control = response)")
    abscissa = "excitation"
    amp = d.excitation
    if d.response_abscissa:
        amp = d.held_amplitude
        abscissa = held_label
    if method == "amplitude":
        if amplitude is not None:
            amp = np.asarray(amplitude, dtype=float).ravel()
            if amp.shape != levels.shape or np.any(~(amp > 0)):
                raise InputError(f"amplitude must hold {levels.size} positive values, "
                                 "one per level")
            abscissa = "amplitude (supplied)"
        elif d.response_amplitude is not None:
            amp = d.response_amplitude
            abscissa = held_label if d.response_abscissa else "response_amplitude"
        else:
            raise InputError(f"method 'amplitude' needs a response_amplitude column in "
                             f"{d.source or 'the data'} (or amplitudes from a simulation)")
    in_fit = np.isin(levels, fit)
    fi = np.flatnonzero(in_fit)
    if abscissa == "excitation":
        warnings += _resonant_lag(d.zeta[fi] * d.omega2[fi])
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
                             f"{format_levels(fit)}: cannot fit chi")
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
                             f"{format_levels(fit)}: cannot fit chi")
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
    if fitres.dof == 0:
        warnings.append("2 fit points: no residual degrees of freedom, no intervals")

    # constant-ratio summary (paper eq. 35)
    ratios = r[pair_to][good] / r[pair_from][good]
    z = float(np.exp(np.mean(np.log(ratios))))
    const = bool(np.allclose(ratios, z, rtol=1e-9)
                 and np.allclose(np.log(r[pair_from][good]) / np.log(z),
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
    predictions, omega2_lin, zeta_lin = predict_levels(fitres, d, in_fit, r, method, c_modal,
                                                       eq45_factor, confidence)
    if bad := unphysical(predictions):
        warnings.append(bad)

    chi_iv = fitres.interval(lambda p, k: p - 1.0, confidence)
    k1b_iv = fitres.interval(lambda p, k: math.exp(k) / p if p > 0 else math.nan, confidence,
                             log=True)

    # ------------------------------------------------------------ model: B~ and R~
    case_res, B, R, R_iv = None, None, None, None
    if model is not None and test != "stepped-sine":
        warnings.append(f"test = {test}: B~ and R~ need the sinusoidal force of a stepped "
                        "sine; left null")
    elif model is not None:
        case_res = fe_reference(model, d, ref, force_scale, fe_mode=fe_mode, chi=fitres.chi,
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

    kappa = "paper" if method == "paper" else "exact"  # the kappa2 of kappa2/|kappa1|
    contradictions = iwan_contradictions(d, chi=fitres.chi, noise=_judged_noise(data, mode))
    random = test == "random" and -1.0 < fitres.chi <= 0.0
    return Estimate(
        method=method, mode=mode, fit_levels=fit, reference_level=int(levels[ref]),
        reference_excitation=float(d.excitation[ref]), chi=fitres.chi,
        chi_interval=(float(chi_iv[0]), float(chi_iv[1])), kappa1_B=fitres.kappa1_B,
        kappa1_B_interval=(float(k1b_iv[0]), float(k1b_iv[1])),
        kappa2_over_kappa1=kappa_ratio(fitres.p - 1.0, kappa),
        B=B, R=R, R_interval=R_iv, confidence=confidence,
        ratio_z=ratio_z, intercept_a0=a0, residual_std=fitres.residual_std, dof=fitres.dof,
        omega2_linear=omega2_lin, zeta_linear=zeta_lin,
        c_modal=(c_modal if method != "paper" else 2.0 * zeta_lin * math.sqrt(omega2_lin)),
        points_used=points_used, points_excluded=points_excluded, differences=differences,
        log_base=z, predictions=predictions,
        data_warnings=warnings, case=case_res, fit=fitres, abscissa=abscissa,
        control=str(d.control[0]), reference_amplitude=float(amp[ref]),
        contradictions=[c.statement for c in contradictions],
        contradiction_details=[{"kind": c.kind, **c.numbers} for c in contradictions],
        test=test, rayleigh_factor=rayleigh_factor(fitres.chi) if random else None,
        kappa1_B_sine=fitres.kappa1_B / rayleigh_factor(fitres.chi) if random else None)
