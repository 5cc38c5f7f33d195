"""Model-form diagnosis: what the Iwan modal model gets wrong, why, and the gain.

The base model and one extension per cause (:mod:`inverse.diagnosis_models`) are
fitted to one mode's observations (:mod:`inverse.diagnosis_fit`); this module picks
the observations from the measured data, cross-validates, and decides.

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

import numpy as np

from ident.measured import MeasuredData
from inverse.diagnosis_fit import fit_model
from inverse.diagnosis_models import Observations
from inverse.diagnosis_text import describe_cause

__all__ = [
    "CAUSES",
    "CANDIDATES",
    "AICC_THRESHOLD",
    "observations_from",
    "cross_validate",
    "diagnose",
]

CAUSES = ("none", "macro-slip", "nonproportional-amplitude", "geometric-hardening",
          "thermal-drift", "quadratic-damping")
CANDIDATES = CAUSES[1:]
#: AICc drop a candidate must exceed (besides a cross-validation gain > 1) to be named.
AICC_THRESHOLD = 6.0


# --------------------------------------------------------------------------- data


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


# --------------------------------------------------------------------------- cross-validation


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
