"""The JSON object of a diagnosis (``shared/spec/diagnosis.md`` v2), from the pieces
:func:`inverse.diagnose.diagnose` computed.

Keys: ``cause``, ``also``, ``alternatives``, ``ambiguous`` (+ ``ambiguity``: who ties
and what measurement separates them), ``contradictions`` (plain strings) and
``contradiction_details``, ``parameters`` (model, chi, ...; fitted), ``base_parameters``,
``base_error``, ``extended_error``, ``gain``, ``gain_held_out``, ``error_measure``,
``evidence`` (per candidate), ``fit_test`` (the named or closest model against the
noise), ``noise``, ``separability``, ``data_warnings``, ``summary``, ``mode``,
``control``, ``levels`` (data, fits and residuals per level, for the plots).
"""
from __future__ import annotations

import numpy as np

from inverse.diagnosis_noise import P_UNEXPLAINED
from inverse.diagnosis_separability import separating_measurement
from inverse.diagnosis_text import describe

__all__ = ["assemble", "ERROR_MEASURE"]

ERROR_MEASURE = ("rms standardized prediction error ((data - prediction) / noise level) "
                 "over the levels left out of the fit and every channel (omega2, zeta, "
                 "log response amplitude when present); gain: leave one interior level "
                 "out; gain_held_out: fit the lower levels, predict the top {top}")


def _ratio(a, b):
    return None if a is None or b is None or b <= 0 else float(a / b)


def _predictions(fit, obs):
    """Fitted values in data units (omega2, zeta, response amplitude or None)."""
    n = obs.n
    out = []
    for i, (ch, v) in enumerate(zip(obs.channels, (obs.omega2, obs.zeta, obs.log_r))):
        out.append(v - fit.residual[i * n:(i + 1) * n] * obs.sigma[ch])
    resp = np.exp(out[2] + np.log(obs.s)) if obs.log_r is not None else None
    return out[0], out[1], resp


def _evidence(fits, unavailable, weight, ic, tests):
    none = fits["none"]
    ev = {}
    for name, reason in unavailable.items():
        ev[name] = {"causes": name.split("+"), "available": False, "reason": reason,
                    "weight": 0.0}
    for name, f in fits.items():
        e = {"causes": list(f.model.causes) or ["none"], "available": True,
             "chi2": f.chi2, "n_params": f.n_params, "n_data": f.n_data, "aic": f.aic,
             "aicc": f.aicc, "bic": f.bic, "delta_bic": none.bic - f.bic,
             "weight": weight[name], "p_value": tests[name]["p_value"]}
        e["delta_aicc"] = (None if f.aicc is None or none.aicc is None
                           else none.aicc - f.aicc)
        if f.aic is None:
            e["delta_aic"] = None
            e["reason"] = (f"cannot be fitted: {f.n_data} data for {f.n_params} "
                           f"parameters")
        elif none.aic is None:
            e["delta_aic"] = None
            e["reason"] = "the base model cannot be fitted (too few data)"
        else:
            e["delta_aic"] = none.aic - f.aic
        ev[name] = e
    return ev


def assemble(*, obs, d, raw, fits, params, weight, ic, tests, cv, held, n_top, noise,
             unavailable, contradictions, refuted, cause, also, best, rivals,
             separability, warnings, t_cause, w_ambiguous) -> dict:
    """The diagnosis as one JSON-ready dict (module doc)."""
    base_err = cv["none"][0]
    alternatives = []
    for name, f in fits.items():
        err = cv.get(name, (None, None, "not in the pool (refuted)"))
        alternatives.append({
            "causes": list(f.model.causes) or ["none"], "weight": weight[name],
            "gain": _ratio(base_err, err[0]) if name != "none" else 1.0,
            "within_noise": (tests[name]["p_value"] or 0.0) >= P_UNEXPLAINED,
            "refuted": bool(refuted and name == "none")})
    alternatives.sort(key=lambda a: -a["weight"])
    ext = fits[best]
    ext_err = cv.get(best, (None,))[0]
    held_base, held_ext = held["none"][0], held[best][0]
    ambiguity = None
    if rivals:
        ambiguity = {"between": [best] + rivals,
                     "weights": [weight[best]] + [weight[r] for r in rivals],
                     "measurement": [separating_measurement(ext.model.causes,
                                                            fits[r].model.causes)
                                     for r in rivals]}
    extra_warn = []
    named_gain = _ratio(base_err, ext_err)
    if cause not in ("none", "unexplained") and named_gain is not None and named_gain <= 1:
        extra_warn.append(f"the named model predicts left-out levels no better than the "
                          f"base model (gain {named_gain:.3g})")
    bo, bz, br = _predictions(fits["none"], obs)
    eo, ez, er = _predictions(ext, obs)
    n = obs.n
    ch = len(obs.channels)
    stdres = lambda f: f.residual.reshape(ch, n).T  # noqa: E731
    unfit = [k for k, f in fits.items() if f.aic is None]
    summary = describe(cause, also, params[best], named_gain, tests[best],
                       contradictions, best, rivals, n, separability["inseparable"], unfit)
    return {
        "cause": cause, "also": also, "mode": int(d.mode[0]),
        "control": "response" if obs.response_controlled else "force",
        "alternatives": alternatives, "ambiguous": bool(rivals), "ambiguity": ambiguity,
        "contradictions": [c.statement for c in contradictions],
        "contradiction_details": [{"kind": c.kind, **c.numbers} for c in contradictions],
        "parameters": dict(params[best], model=best),
        "base_parameters": params["none"],
        "base_error": base_err, "extended_error": ext_err, "gain": named_gain,
        "cv_note": cv["none"][2] or cv.get(best, (None, None, None))[2],
        "gain_held_out": _ratio(held_base, held_ext),
        "held_out_errors": {"base": held_base, "extended": held_ext,
                            "note": held["none"][1] or held[best][1]},
        "error_measure": ERROR_MEASURE.format(top=n_top),
        "evidence": _evidence(fits, unavailable, weight, ic, tests),
        "criterion": {"t_cause": t_cause, "w_ambiguous": w_ambiguous,
                      "p_unexplained": P_UNEXPLAINED},
        "fit_test": dict(tests[best], model=best),
        "noise": {"source": noise.source,
                  **{f"sigma_{c}": float(np.median(s)) for c, s in noise.sigma.items()},
                  "dof": {c: (None if not np.isfinite(v) else int(v))
                          for c, v in noise.dof.items()}},
        "separability": separability,
        "summary": summary,
        "data_warnings": warnings + extra_warn,
        "levels": {
            "level": obs.level, "abscissa": raw, "s": obs.s, "run_order": d.run_order,
            "omega2": obs.omega2, "zeta": obs.zeta,
            "response_amplitude": d.response_amplitude,
            "base_omega2": bo, "base_zeta": bz, "base_response": br,
            "extended_omega2": eo, "extended_zeta": ez, "extended_response": er,
            "base_residual": stdres(fits["none"]), "extended_residual": stdres(ext),
            "base_cv_residual": cv["none"][1],
            "extended_cv_residual": cv.get(best, (None, cv["none"][1]))[1],
            "channels": obs.channels},
    }
