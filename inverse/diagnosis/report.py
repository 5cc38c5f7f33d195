"""The JSON object of a diagnosis (``docs/formats/diagnosis.md`` v2), from the pieces
:func:`inverse.diagnose.diagnose` computed.

Keys: ``cause``, ``also``, ``alternatives`` (each with ``gain_untestable``: why no
held-out gain can be measured on these levels, or None), ``ambiguous`` (+ ``ambiguity``:
who ties and what measurement separates them), ``contradictions`` (plain strings) and
``contradiction_details``, ``parameters`` (model, chi, ...; fitted),
``base_parameters``, ``base_error``, ``extended_error``, ``gain``, ``gain_held_out``,
``error_measure``, ``evidence`` (per candidate, with whether its fit ``converged`` and
in how many ``iterations``), ``fit_test`` (the named or closest model against the
noise), ``noise`` (per channel: source, identification and repeatability parts, dof),
``verdict_identification_only`` (the verdict with the identification's noise alone,
its failed and unconverged fits counted; its held-out gains are those of the folds
with the total noise), ``verdict_own_scatter`` (where a scatter far above the assumed
rig repeatability was judged against it: the verdict with that scatter as the noise,
with its failed and unconverged fits and folds; else None), ``closest_miss`` (when
``unexplained``), ``parameter_bounds`` (every fitted parameter of the named model with
``at_bound``), ``at_bound`` (names), ``held_out_predictions``, ``failures`` (fits,
folds, held-out fits and profile points that failed or did not converge, counted and
named: :func:`_failures`), ``untestable``, ``separability``, ``data_warnings``,
``summary``, ``mode``, ``control``, ``levels`` (data, fits and residuals per row, for
the plots).
"""
from __future__ import annotations

import numpy as np

from inverse.diagnosis.cv import untestable_gain
from inverse.diagnosis.separability import separating_measurement
from inverse.diagnosis.text import describe, extrapolation_note
from inverse.judge import P_UNEXPLAINED, T_CAUSE, W_AMBIGUOUS, Bounded, at_bound
from inverse.judge.prior import CAP_FACTOR

__all__ = ["assemble", "ERROR_MEASURE", "own_scatter_sentence"]

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


def _evidence(fits, unavailable, sel):
    none = fits["none"]
    ev = {}
    for name, reason in unavailable.items():
        ev[name] = {"causes": name.split("+"), "available": False, "reason": reason,
                    "weight": 0.0}
    for name, f in fits.items():
        e = {"causes": list(f.model.causes) or ["none"], "available": True,
             "chi2": f.chi2, "n_params": f.n_params, "n_data": f.n_data, "aic": f.aic,
             "aicc": f.aicc, "bic": f.bic, "delta_bic": none.bic - f.bic,
             "converged": f.converged, "iterations": f.iterations,
             "weight": sel.weights[name], "p_value": sel.tests[name].p_value,
             "eligible": name in sel.eligible, "why_not": sel.why_not.get(name)}
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


def parameter_bounds(fit, obs, profiles=None, rtol: float = 1e-3) -> dict:
    """Every fitted parameter of ``fit`` as :class:`inverse.judge.Bounded` JSON: the
    nonlinear ones with their box (``p`` reported as ``chi = p - 1``) and, for those on
    a bound, the profile interval of ``profiles`` (``{index: (lo, hi)}``); the linear
    ones with ``[0, inf)`` when non-negative, else unbounded."""
    out = {}
    profiles = profiles or {}
    for j, (v, (name, lo, hi, _)) in enumerate(zip(fit.theta, fit.model.nonlinear)):
        shift = -1.0 if name == "p" else 0.0
        on, which = at_bound(v, lo, hi, rtol)
        iv = profiles.get(j)
        out["chi" if name == "p" else name] = Bounded(
            "chi" if name == "p" else name, float(v + shift), lo + shift, hi + shift,
            on, which, None if iv is None else (iv[0] + shift, iv[1] + shift),
            None if iv is None else "profile (95 %)").to_json()
    nonneg = fit.model.nonneg(obs.log_r is not None)
    for j, (name, x) in enumerate(zip(fit.model.linear_names(obs.log_r is not None),
                                      fit.linear)):
        lo = 0.0 if j in nonneg else -np.inf
        on = bool(j in nonneg and x <= 0.0)
        out[name] = Bounded(name, float(x), lo, np.inf, on, "lower" if on else None).to_json()
    return out


def _failures(fits, cv, held, profile_failures, profile_unconverged=0, separability=None):
    """Every fit that failed or did not converge (:mod:`inverse.diagnosis.lm`), counted
    and named. A fold that did not converge is a failed fold (``folds``; of them
    ``unconverged_folds``), as is a held-out fit (``held_out``); a fit to all levels
    that did not converge keeps its candidate but is named (``unconverged_fits``);
    ``total`` counts them all."""
    fits_failed = [k for k, f in fits.items() if f.failed]
    unconverged = [k for k, f in fits.items() if not f.failed and not f.converged]
    folds = {k: v[3] for k, v in cv.items() if v[3]}
    folds_unconverged = {k: v.unconverged for k, v in cv.items() if v.unconverged}
    held_failed = [k for k, v in held.items() if v[2] is not None and v[2].failed]
    held_unconverged = [k for k, v in held.items() if v[2] is not None
                        and not v[2].failed and not v[2].converged]
    profile_total = profile_failures + profile_unconverged
    return {"fits": len(fits_failed), "folds": sum(folds.values()),
            "held_out": len(held_failed) + len(held_unconverged),
            "profile_points": profile_total,
            "total": len(fits_failed) + len(unconverged) + sum(folds.values())
            + len(held_failed) + len(held_unconverged) + profile_total,
            "failed_fits": fits_failed, "failed_folds": folds,
            "unconverged_fits": len(unconverged), "unconverged_folds":
            sum(folds_unconverged.values()), "unconverged_held_out": len(held_unconverged),
            "unconverged_profile_points": profile_unconverged,
            "unconverged_separability_fits": (separability or {}).get("unconverged_fits",
                                                                      0),
            "unconverged": {"fits": unconverged, "folds": folds_unconverged,
                            "held_out": held_unconverged},
            "convergence": "Gauss-Newton decrement below 1e-4 chi2 units "
                           "(inverse.diagnosis.lm)"}


#: What the held-out prediction intervals hold (``held_out_predictions.interval``).
_INTERVAL_NOTE = ("nominal 95 % prediction interval, model-averaged over the eligible "
                  "candidates: the noise (scaled up where the training fit misses it), the "
                  "linear parameters' uncertainty, the nonlinear parameters integrated over "
                  "their bounded grid, the spread of the candidates' predictions; Student t "
                  "with each channel's dof (docs/coverage.md)")


def _alternatives(fits, cv, sel, refuted) -> list:
    """Every candidate with its weight, gain and fit test, the heaviest first."""
    base_err = cv["none"][0]
    alternatives = []
    for name, f in fits.items():
        err = cv[name][0]
        alternatives.append({
            "causes": list(f.model.causes) or ["none"], "weight": sel.weights[name],
            "gain": _ratio(base_err, err) if name != "none" else 1.0,
            "gain_untestable": None if name == "none" else untestable_gain(cv[name],
                                                                          cv["none"]),
            "within_noise": sel.tests[name].passes(),
            "refuted": bool(refuted and name == "none")})
    alternatives.sort(key=lambda a: -a["weight"])
    return alternatives


def _ambiguity(sel, fits) -> dict | None:
    """Who ties with the named model and what measurement separates them, or None."""
    best, rivals = sel.best, sel.rivals
    if not rivals:
        return None
    return {"between": [best] + rivals,
            "weights": [sel.weights[best]] + [sel.weights[r] for r in rivals],
            "measurement": [separating_measurement(fits[best].model.causes,
                                                   fits[r].model.causes)
                            for r in rivals]}


def _verdict(selection, failures) -> dict | None:
    """The JSON verdict of another selection (None when it was not made)."""
    return None if selection is None else selection.verdict_json(failures)


def _identification_only(selection, failures, verdict) -> tuple[dict | None, bool | None]:
    """The verdict with the identification's noise alone and whether it differs from
    ``verdict`` ((cause, also)); (None, None) when it was not made."""
    id_only = _verdict(selection, failures)
    if id_only is None:
        return None, None
    id_only["gains"] = "the held-out gains of the folds with the total noise"
    return id_only, (id_only["cause"], id_only["also"]) != verdict


def _fit_notes(ext, best: str, on_bound: list) -> str:
    """Sentences on the named fit: not converged, parameters on a bound."""
    text = ""
    if not ext.converged and not ext.failed:
        text += (f" The {best} fit did not converge in {ext.iterations} steps (Gauss-"
                 f"Newton decrement {ext.decrement:.2g}): its numbers may move with "
                 f"the optimizer.")
    if on_bound:
        text += (f" On a bound in the {best} fit: {', '.join(on_bound)} (not treated as "
                 f"free: the prediction intervals integrate the nonlinear parameters "
                 f"over their bounded range).")
    return text


def _levels_json(obs, d, raw, fits, cv, best: str) -> dict:
    """Data, fits and residuals per row, for the plots."""
    bo, bz, br = _predictions(fits["none"], obs)
    eo, ez, er = _predictions(fits[best], obs)
    n = obs.n
    ch = len(obs.channels)

    def stdres(f):
        return f.residual.reshape(ch, n).T

    return {
        "level": obs.levels, "abscissa": raw, "s": obs.s, "run_order": d.run_order,
        "omega2": obs.omega2, "zeta": obs.zeta,
        "response_amplitude": d.response_amplitude,
        "base_omega2": bo, "base_zeta": bz, "base_response": br,
        "extended_omega2": eo, "extended_zeta": ez, "extended_response": er,
        "base_residual": stdres(fits["none"]), "extended_residual": stdres(fits[best]),
        "base_cv_residual": cv["none"][1], "extended_cv_residual": cv[best][1],
        "channels": obs.channels}


def assemble(*, obs, d, raw, fits, params, selection, cv, held, n_top, noise, averaged,
             unavailable, untestable, contradictions, refuted, separability, warnings,
             predictions, selection_id_only, why_id_only, profiles,
             id_only_failures=None,
             profile_failures, profile_unconverged=0, selection_own_scatter=None,
             own_scatter_failures=None) -> dict:
    """The diagnosis as one JSON-ready dict (module doc)."""
    sel = selection
    cause, also, best, rivals = sel.cause, sel.also, sel.best, sel.rivals
    base_err, ext_err = cv["none"][0], cv[best][0]
    ext = fits[best]
    held_base, held_ext = held["none"][0], held[best][0]
    named_gain = _ratio(base_err, ext_err)
    unfit = [k for k, f in fits.items() if f.aic is None]
    bounds = parameter_bounds(ext, obs, profiles)
    on_bound = [k for k, b in bounds.items() if b["at_bound"]]
    noise_json = noise.to_json({"omega2": obs.omega2, "zeta": obs.zeta, "response": obs.log_r})
    id_only, changes = _identification_only(selection_id_only, id_only_failures, (cause, also))
    summary = describe(cause, also, params[best], named_gain, sel.tests[best].to_json(),
                       contradictions, best, rivals, np.unique(obs.levels).size,
                       separability["inseparable"], unfit)
    summary += _noise_sentence(noise_json, id_only, changes, why_id_only)
    own = _verdict(selection_own_scatter, own_scatter_failures)
    summary += own_scatter_sentence(noise.capped(), own, (cause, also))
    summary += extrapolation_note("+".join([cause] + also), _ratio(held_base, held_ext),
                                  n_top)
    summary += _fit_notes(ext, best, on_bound)
    return {
        "cause": cause, "also": also, "mode": int(d.mode[0]),
        "control": "response" if obs.response_controlled else "force",
        "alternatives": _alternatives(fits, cv, sel, refuted), "ambiguous": bool(rivals),
        "ambiguity": _ambiguity(sel, fits),
        "unexplained": sel.unexplained, "closest_miss": sel.closest_miss,
        "contradictions": [c.statement for c in contradictions],
        "contradiction_details": [{"kind": c.kind, **c.numbers} for c in contradictions],
        "parameters": dict(params[best], model=best),
        "parameter_bounds": bounds, "at_bound": on_bound,
        "base_parameters": params["none"],
        "base_error": base_err, "extended_error": ext_err, "gain": named_gain,
        "cv_note": cv["none"][2] or cv[best][2],
        "gain_held_out": _ratio(held_base, held_ext),
        "held_out_errors": {"base": held_base, "extended": held_ext,
                            "note": held["none"][1] or held[best][1]},
        "held_out_predictions": {"model": best, "levels": predictions,
                                 "averaged_over": averaged, "interval": _INTERVAL_NOTE},
        "error_measure": ERROR_MEASURE.format(top=n_top),
        "evidence": _evidence(fits, unavailable, sel),
        "criterion": {"t_cause": T_CAUSE, "w_ambiguous": W_AMBIGUOUS,
                      "p_unexplained": P_UNEXPLAINED, "gain_min": 1.0},
        "fit_test": dict(sel.tests[best].to_json(), model=best),
        "noise": noise_json,
        "verdict_identification_only": id_only,
        "verdict_changes_with_identification_only": changes,
        "identification_only_note": why_id_only,
        "verdict_own_scatter": own,
        "failures": _failures(fits, cv, held, profile_failures, profile_unconverged,
                              separability),
        "untestable": untestable,
        "separability": separability,
        "summary": summary,
        "data_warnings": warnings,
        "levels": _levels_json(obs, d, raw, fits, cv, best),
    }


def own_scatter_sentence(capped, own, verdict) -> str:
    """What the verdict would be with the data's own scatter where it was capped
    (``capped``: the channels; ``own``: the verdict's JSON with ``cause``, ``also`` and
    ``failures``; ``verdict``: (cause, also) judged against the capped noise)."""
    if not capped or own is None:
        return ""
    text = (f" The scatter of {' and '.join(capped)} is far above what a rig repeats and "
            f"was judged against {CAP_FACTOR:g} times the assumed repeatability: ")
    fl = own.get("failures") or {}
    failed = sum(fl.get(k, 0) for k in ("fits", "folds", "unconverged_fits"))
    lost = (f" ({failed} of its fits and folds failed or did not converge)" if failed
            else "")
    if (own["cause"], own["also"]) == tuple(verdict):
        return text + f"with that scatter as the noise the verdict is the same{lost}."
    name = own["cause"] + (f" + {', '.join(own['also'])}" if own["also"] else "")
    return text + (f"with that scatter as the noise the verdict would be {name}{lost}; "
                   f"a repeated level tells which holds.")


def _noise_sentence(noise_json, id_only, changes, why) -> str:
    parts = [f"{c} {100 * v['total_rel']:.3g} % ({v['source']})" if v["relative"]
             else f"{c} {v['total_rel']:.3g} ({v['source']})" for c, v in noise_json.items()]
    text = " Judged against the noise: " + "; ".join(parts) + "."
    if id_only is None:
        return text + f" With the identification's noise alone: not judged ({why})."
    fl = id_only.get("failures") or {}
    failed, unconverged = fl.get("fits"), fl.get("unconverged_fits")
    if failed:
        text += (f" With the identification's noise alone {failed} fit(s) failed and were "
                 f"left out.")
    if unconverged:
        text += (f" With the identification's noise alone {unconverged} fit(s) did not "
                 f"converge.")
    if changes:
        return text + (f" With the identification's noise alone the verdict would be "
                       f"{id_only['cause']}" + (f" + {', '.join(id_only['also'])}"
                                                 if id_only["also"] else "")
                       + ": it follows from the repeatability.")
    return text + " The verdict is the same with the identification's noise alone."
