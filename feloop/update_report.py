"""The report of ``iwanfe update --case NAME|FILE``: JSON, text, markdown, figures.

:func:`summary` turns :func:`feloop.update.run_update`'s result into
one JSON-ready dict; :func:`format_text` and :func:`markdown` word it;
:func:`write_update` writes ``updated_model.json`` (the model: every parameter with
its kind and interval, the joint it makes, the fit's values and covariance and the data
it was fitted to, :mod:`feloop.given_model`), ``update.json`` (everything),
``report.md``, ``update_levels.png`` and ``update_profiles.png``.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from feloop.causes import force_scale_power
from feloop.diagnosis import level_entries, unconverged_fits
from feloop.given_model import data_block, fit_block
from feloop.tie import tie_statement
from feloop.update_text import LABEL, format_text, markdown
from inverse.fe_selection import fit_test_of
from inverse.profile import bounded_interval
from runs.jsonio import to_jsonable

__all__ = ["summary", "format_text", "markdown", "write_update"]

def _levels(data, mask, pred, noise) -> list:
    rows = level_entries(data, mask, {"model": pred})
    for i, row in enumerate(rows):
        f, fm = row["measured"]["frequency_hz"], row["model"]["frequency_hz"]
        sig_f = noise.sigma_omega2[i] / (2 * (2 * math.pi) ** 2 * f)
        row.update(error_hz=fm - f, error_zeta_rel=float(pred.zeta[i] / data.zeta[i] - 1.0),
                   error_sigma=[(fm - f) / sig_f,
                                float((pred.zeta[i] - data.zeta[i]) / noise.sigma_zeta[i])],
                   slip_over_phi_max=float(pred.slip_over_phi_max[i]))
    return rows


def linearized_interval(value, se, lower, upper) -> dict:
    """The 95 % interval ``value +- 1.96 se`` of a fitted parameter from the linearized
    (misfit-scaled) covariance, cut at the parameter's bounds: a parameter whose interval
    crosses a bound is "not determined" (its likelihood is not the quadratic that the
    interval assumes there), as is one without a finite ``se``."""
    kind = "linearized (misfit-scaled covariance)"
    if not math.isfinite(se):
        return {"interval": [None, None], "status": "not determined", "interval_kind": kind}
    lo, hi = value - 1.96 * se, value + 1.96 * se
    inside = lower <= lo and hi <= upper
    return {"interval": [max(lo, lower), min(hi, upper)],
            "status": "determined" if inside else "not determined",
            "interval_kind": kind + ("" if inside else ", cut at the bounds it crosses")}


def _convergence(r: dict) -> dict:
    """Which fits of an update converged (:attr:`inverse.update.Fit.converged`): the
    updated model's, the base model's, every candidate's of the model choice (named when
    not), its folds and the profile points."""
    cands = r["selection"]["judged"]["candidates"].values()
    return {"fit": r["fit"].converged, "base_fit": r["base_fit"].converged,
            "unconverged_fits": unconverged_fits(r["selection"]),
            "unconverged_folds": sum(c.cv_unconverged for c in cands),
            "unconverged_profile_points": sum(p.unconverged_points
                                              for p in r["profiles"].values()),
            "criterion": "Gauss-Newton decrement below 1e-4 chi2 units (inverse.decrement)"}


def _parameter_entry(r: dict, name: str, p) -> dict:
    """One parameter of the update: value, kind (fitted, assumed, profile minimum),
    bounds, interval and what it rests on."""
    best, pr = r["fit"], r["profiles"].get(name)
    value = best.values[name]
    kind = "fitted" if name in best.free else "assumed"
    side = best.at_bound.get(name, False)
    entry = {"value": value, "unit": p.unit, "description": p.description, "kind": kind}
    if kind == "fitted":       # the start: the case's value (a file's given chi, too)
        entry.update(at_bound=side, lower_bound=p.lower, upper_bound=p.upper, start=p.start)
    if pr is not None:
        lo, hi = bounded_interval(pr, p.lower, p.upper, side)
        entry.update(interval=[lo, hi], status=pr.status, interval_kind="profile likelihood")
    elif kind == "fitted":
        entry.update(linearized_interval(value, best.std_error(name), p.lower, p.upper))
    if kind == "assumed" and abs(value - p.start) > 1e-9:
        entry["kind"] = "profile minimum (grid)"
        entry["assumed_value"] = p.start
    if name == "ln_phimax" and value >= r["micro_limit"]:
        entry.update(value=r["micro_limit"], kind="at the micro-slip limit (beta = 0)")
    power = force_scale_power(name)
    if power:
        entry["rests_on"] = (f"the force scale {r['settings'].force_scale:g} N per "
                             f"excitation unit (assumed): it scales as s^{power}")
    return entry


def _derived(r: dict) -> dict:
    """The joint the fitted model makes (SI units; its law's figures,
    :meth:`feloop.joint_forms.JointForm.derived`) and the modal figures behind it."""
    j, best, form = r["prediction"].joint, r["fit"], r["selection"]["fe"].form
    own = form.derived(j, best.values)
    return {**own, "K_T_N_per_m": j["K_T"], "grip_m": j["grip"],
            "structure": j["structure"], "fe_mode": j["fe_mode"],
            "stiffness_scale": j["stiffness_scale"], "zeta_v": best.values["zeta_v"],
            **(form.modal(best.values) if hasattr(form, "modal") else {}),
            "force_scale_N_per_unit": r["settings"].force_scale,
            "law": form.law, "slip_scale_name": form.scale_name, "joint_text": form.words(own), "joint_element": form.element,
            "force_scale_scaling": form.scaling}


def _tie(r: dict) -> dict:
    """The Iwan tie of the data (:func:`feloop.tie.tie_statement`) for Iwan joints; for
    another law, what its base model leaves over the fit levels (the tie is Iwan's)."""
    data, mask, base = r["data"], r["fit_mask"], r["base_fit"]
    law = r["selection"]["fe"].form.law
    if law == "iwan4":
        return tie_statement(data, mask)
    lv = [int(v) for v in data.level[mask]]
    return {"law": law, "text": f"levels {lv[0]}->{lv[-1]}: the base model of {law} joints "
                                f"leaves chi2 = {base.chi2:.1f} on {base.dof} degrees of "
                                f"freedom (the Iwan tie does not apply to {law} joints)"}


def _statements(r: dict, test) -> list:
    """What the updated model gets wrong, worded: the model, its fit, the base model,
    the Iwan tie, parameters on a bound, every held-out level's miss (in the prediction's
    sd: parameters and the judge's noise)."""
    best, base, v = r["fit"], r["base_fit"], r["verdict"]
    out = [f"model: {r['candidate']} fitted to the fit levels (cause {v['cause']}, judged "
           f"with {v['judged_on']} fitted"
           + (", unexplained: no candidate brings the levels within their noise; the "
              "closest one is kept" if v["unexplained"] else "") + ")",
           f"chi2 = {best.chi2:.1f} on {best.dof} degrees of freedom, fit test p = "
           f"{test.p_value:.2g} ({test.test})" if test.p_value is not None else
           f"chi2 = {best.chi2:.1f} ({test.test})",
           f"base model (no cause): chi2 = {base.chi2:.1f} on {base.dof} degrees of freedom"]
    if r["selection"]["fe"].form.law == "iwan4":        # the tie is the Iwan joint's
        out.append(tie_statement(r["data"], r["fit_mask"])["text"])
    out += [f"{n} sits on its {best.at_bound[n]} bound ({best.values[n]:.4g}); its interval "
            f"is a profile, and the predictions hold it there"
            for n in best.free if best.at_bound.get(n)]
    out += [f"level {row['level']} (held out): frequency {row['error_hz']:+.4f} Hz, zeta "
            f"{100 * row['error_zeta_rel']:+.2f} % ({row['z_frequency']:+.1f} / "
            f"{row['z_zeta']:+.1f} sd)" for row in r["held_out"]]
    return out


def _assumption_rows(r: dict) -> list:
    """Each refit under a changed assumed property: its chi2 change and the shift of the
    top held-out level."""
    base_head, best = r["nominal"], r["fit"]
    return [{"assumption": a["assumption"], "changes": a["changes"],
             "delta_chi2": a["chi2"] - best.chi2,
             "held_out_frequency_hz": a["headline"]["frequency_hz"],
             "held_out_zeta": a["headline"]["zeta"],
             "top_slip_over_phi_max": a["headline"]["top_slip_over_phi_max"],
             "shift_top_frequency_hz": (a["headline"]["frequency_hz"][-1]
                                        - base_head["frequency_hz"][-1])
             if base_head["frequency_hz"] else None,
             "shift_top_zeta_rel": (a["headline"]["zeta"][-1] / base_head["zeta"][-1] - 1)
             if base_head["zeta"] else None}
            for a in r.get("assumptions", [])]


def summary(r: dict) -> dict:
    """One JSON-ready dict of an update (module docstring)."""
    data, mask, best, pred = r["data"], r["fit_mask"], r["fit"], r["prediction"]
    levels = _levels(data, mask, pred, r["noise"])
    sel = r["selection"]["judged"]["selection"]
    test = fit_test_of(best, r["selection"]["judge_noise"])
    return {"case": r["case"], "source": str(data.source),
            "mode": r["settings"].mode_label,
            "fit_levels": [int(v) for v in data.level[mask]],
            "held_out_levels": [row["level"] for row in levels if row["held_out"]],
            "noise": r["noise"].to_dict(), "fit": best.to_dict(),
            "parameters": {n: _parameter_entry(r, n, p) for n, p in r["parameters"].items()},
            "derived": _derived(r), "levels": levels, "misfit": _statements(r, test),
            "notes": list(r.get("notes", [])),
            "engagement": r["selection"]["engagement"].to_json(),
            "engagement_text": r["selection"]["engagement"].line(),
            "plausibility": r.get("plausibility", []),
            "tie": _tie(r), "base_chi2": r["base_fit"].chi2,
            "cause": r["verdict"]["cause"], "also": r["verdict"]["also"],
            "model": r["candidate"], "unexplained": r["verdict"]["unexplained"],
            "verdict": r["verdict"], "fit_levels_verdict": sel.verdict_json(),
            "all_levels": _all_levels_json(r["all_levels"]), "held_out": r["held_out"],
            "misses": r["misses"], "fit_test": test.to_json(),
            "evidence": r["selection"]["judged"]["evidence"],
            "untested": r["selection"]["untested"], "rule": "inverse.judge.select",
            "estimator_start": r["selection"]["estimator_start"],
            "failed_simulations": best.failed_simulations,
            "convergence": _convergence(r),
            "fallbacks": pred.fallback_lines(data.level),
            "sensitivity": dict(r["sensitivity"]), "assumptions": _assumption_rows(r),
            "profiles": {n: p.to_dict() for n, p in r["profiles"].items()},
            "confidence": r["settings"].confidence, "executor": r["executor"],
            "timing_s": r["timing_s"]}


def _all_levels_json(a: dict | None) -> dict | None:
    """The all-levels choice without its objects (the evidence stays)."""
    return None if a is None else {k: v for k, v in a.items() if k != "choice"}


def write_update(r: dict, out) -> list:
    """Write the files of the module docstring into ``out``; returns their paths."""
    from viz.level_models import plot_level_models, plot_profiles

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    s = summary(r)
    data, mask, noise = r["data"], r["fit_mask"], r["noise"]
    f = np.sqrt(data.omega2) / (2 * math.pi)
    models = {"updated FE model": (r["prediction"].frequency_hz, r["prediction"].zeta)}
    if r["base_fit"] is not r["fit"]:
        mp = r["base_prediction"]
        models["base FE model (no cause)"] = (mp.frequency_hz, mp.zeta)
    plot_level_models(data.level, f, data.zeta, noise.sigma_omega2 / (8 * math.pi ** 2 * f),
                      noise.sigma_zeta, models, ~mask, title=f"FE model updating, {s['case']}",
                      path=out / "update_levels.png")
    plot_profiles({LABEL.get(n, n): ([q.value for q in p.points], p.delta, p.threshold, p.best)
                   for n, p in r["profiles"].items()}, title="profile likelihoods",
                  path=out / "update_profiles.png")
    model = {"case": s["case"], "cause": s["cause"], "also": s["also"],
             "model": s["model"], "unexplained": s["unexplained"],
             "fit_test": s["fit_test"], "parameters": s["parameters"], "joint": s["derived"],
             "fit_levels": s["fit_levels"], "noise": s["noise"],
             "base_parameters": list(r["selection"]["fe"].base_parameters),
             "fit": fit_block(r["fit"], r["parameters"]),
             "data": data_block(data, r["settings"].mode_label, r["settings"].force_scale)}
    files = {"updated_model.json": model, "update.json": s}
    for name, obj in files.items():
        (out / name).write_text(json.dumps(to_jsonable(obj), indent=2) + "\n", encoding="utf-8")
    (out / "report.md").write_text(markdown(s), encoding="utf-8")
    return [out / n for n in ("updated_model.json", "update.json", "report.md",
                              "update_levels.png", "update_profiles.png")]
