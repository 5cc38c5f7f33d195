"""The report of ``iwanfe update --case NAME|FILE``: JSON, text, markdown, figures.

:func:`summary` turns :func:`feloop.update.run_update`'s result into
one JSON-ready dict; :func:`format_text` and :func:`markdown` word it;
:func:`write_update` writes ``updated_model.json`` (the model: every parameter with
its kind and interval, the joint it makes), ``update.json`` (everything),
``report.md``, ``update_levels.png`` and ``update_profiles.png``.
"""
from __future__ import annotations

import json
import math
from pathlib import Path
from statistics import NormalDist

import numpy as np

from feloop.causes import force_scale_power
from feloop.diagnosis import unconverged_fits
from feloop.digits import fmt, fmt_interval
from feloop.levels import BASE_PARAMETERS, level_entries
from feloop.tie import tie_statement
from inverse.fe_selection import fit_test_of
from inverse.iwan_modal import kappa_ratio
from inverse.profile import bounded_interval
from runs.jsonio import to_jsonable

__all__ = ["summary", "format_text", "markdown", "write_update"]

_LABEL = {"chi": "chi", "ln_dc1": "ln |kappa1|B~ (level 1)", "zeta_v": "zeta_v",
          "f0_hz": "f0 [Hz]", "ln_phimax": "ln(phi_max/a_ref)", "log10_kt": "log10 K_T [N/m]"}


def _fmt(v, digits=6):
    if v is None:
        return "open"
    return f"{v:.{digits}g}"


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


def summary(r: dict) -> dict:
    """One JSON-ready dict of an update (module docstring)."""
    data, mask, best, pred = r["data"], r["fit_mask"], r["fit"], r["prediction"]
    fit_levels = [int(v) for v in data.level[mask]]
    params = {}
    for name, p in r["parameters"].items():
        pr = r["profiles"].get(name)
        value = best.values[name]
        kind = "fitted" if name in best.free else "assumed"
        side = best.at_bound.get(name, False)
        entry = {"value": value, "unit": p.unit, "description": p.description, "kind": kind}
        if kind == "fitted":       # the start: the case's value (a file's given chi, too)
            entry.update(at_bound=side, lower_bound=p.lower, upper_bound=p.upper,
                         start=p.start)
        if pr is not None:
            lo, hi = bounded_interval(pr, p.lower, p.upper, side)
            entry.update(interval=[lo, hi], status=pr.status,
                         interval_kind="profile likelihood")
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
        params[name] = entry
    j = pred.joint
    derived = {"R_tilde": j["R"], "phi_max_m": j["phi_max"], "F_S_N": j["F_S"],
               "beta": j["beta"], "K_T_N_per_m": j["K_T"], "grip_m": j["grip"],
               "structure": j["structure"], "fe_mode": j["fe_mode"],
               "stiffness_scale": j["stiffness_scale"], "zeta_v": best.values["zeta_v"],
               "kappa1_B_level1": math.exp(best.values["ln_dc1"]),
               "kappa2_over_kappa1": kappa_ratio(best.values["chi"], "exact"),
               "force_scale_N_per_unit": r["settings"].force_scale}
    levels = _levels(data, mask, pred, r["noise"])
    held = [row for row in levels if row["held_out"]]
    sel = r["selection"]["judged"]["selection"]
    test = fit_test_of(best, r["selection"]["judge_noise"])
    base = r["base_fit"]
    statements = [f"model: {r['candidate']} (the one judge's choice"
                  + (", unexplained: no candidate brings the fit levels within their noise; "
                     "the closest one is kept" if sel.unexplained else "") + ")",
                  f"chi2 = {best.chi2:.1f} on {best.dof} degrees of freedom, fit test p = "
                  f"{test.p_value:.2g} ({test.test})" if test.p_value is not None else
                  f"chi2 = {best.chi2:.1f} ({test.test})",
                  f"base model (no cause): chi2 = {base.chi2:.1f} on {base.dof} degrees of "
                  f"freedom", tie_statement(data, mask)["text"]]
    for n in best.free:
        if best.at_bound.get(n):
            statements.append(f"{n} sits on its {best.at_bound[n]} bound "
                              f"({best.values[n]:.4g}); its interval is a profile, and the "
                              f"predictions hold it there")
    for row in r["held_out"]:      # sd: the prediction's (parameters and the judge's noise)
        statements.append(f"level {row['level']} (held out): frequency {row['error_hz']:+.4f} Hz"
                          f", zeta {100 * row['error_zeta_rel']:+.2f} % "
                          f"({row['z_frequency']:+.1f} / {row['z_zeta']:+.1f} sd)")
    sens = {}
    for name, s in r["sensitivity"].items():
        sens[name] = s
    base_head = r["nominal"]
    assumptions = [{"assumption": a["assumption"], "changes": a["changes"],
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
    return {"case": r["case"], "source": str(data.source),
            "mode": r["settings"].mode_label,
            "fit_levels": fit_levels, "held_out_levels": [row["level"] for row in held],
            "noise": r["noise"].to_dict(), "fit": best.to_dict(), "parameters": params,
            "derived": derived, "levels": levels, "misfit": statements,
            "notes": list(r.get("notes", [])),
            "engagement": r["selection"]["engagement"].to_json(),
            "engagement_text": r["selection"]["engagement"].line(),
            "plausibility": r.get("plausibility", []),
            "tie": tie_statement(data, mask), "base_chi2": base.chi2,
            "cause": r["verdict"]["cause"], "also": r["verdict"]["also"],
            "model": r["candidate"], "unexplained": r["verdict"]["unexplained"],
            "verdict": r["verdict"], "fit_levels_verdict": _verdict_json(sel),
            "all_levels": _all_levels_json(r["all_levels"]), "held_out": r["held_out"],
            "misses": r["misses"], "fit_test": test.to_json(),
            "evidence": r["selection"]["judged"]["evidence"],
            "untested": r["selection"]["untested"], "rule": "inverse.judge.select",
            "estimator_start": r["selection"]["estimator_start"],
            "failed_simulations": best.failed_simulations,
            "convergence": _convergence(r),
            "fallbacks": pred.fallback_lines(data.level),
            "sensitivity": sens, "assumptions": assumptions,
            "profiles": {n: p.to_dict() for n, p in r["profiles"].items()},
            "confidence": r["settings"].confidence, "executor": r["executor"],
            "timing_s": r["timing_s"]}


def _verdict_json(sel) -> dict:
    return {"cause": sel.cause, "also": sel.also, "model": sel.best,
            "unexplained": sel.unexplained}


def _all_levels_json(a: dict | None) -> dict | None:
    """The all-levels choice without its objects (the evidence stays)."""
    return None if a is None else {k: v for k, v in a.items() if k != "choice"}


def _plausibility_lines(checks: list) -> list:
    """A line per check of :func:`casefile.plausibility.joint_plausibility`."""
    return [f"plausibility: {c['parameter']} = {c['value']:.4g} ({c['kind']}): "
            f"{c['verdict']} (range "
            f"{_fmt(c['low'], 3)} .. {_fmt(c['high'], 3)}: {c['source']})" for c in checks]


def format_text(s: dict) -> str:
    """Readable summary (the command's default output)."""
    n = s["noise"]
    ft = s["fit_test"]
    lines = [f"iwanfe update --case {s['case']}  ({s['source']}, mode {s['mode']}, fit levels "
             f"{s['fit_levels'][0]}-{s['fit_levels'][-1]})",
             *s["verdict"]["lines"],
             f"model: {s['model']} fitted to the fit levels (the one judge, as diagnose "
             f"--case; fit test p = {_fmt(ft['p_value'], 2)}, {ft['test']})",
             f"noise: sigma_omega2 = {n['sigma_omega2'][0]:.3g} rad^2/s^2, sigma_zeta = "
             f"{n['sigma_zeta'][0]:.3g} ({n['source']})",
             f"check: {s['engagement_text']}",
             *_plausibility_lines(s.get("plausibility", [])),
             *(f"note: {t}" for t in s.get("notes", [])),
             f"{'parameter':26s} {'value':>14s}  {int(100 * s['confidence'])}% profile interval"
             f"          status / kind"]
    for name, p in s["parameters"].items():
        iv = p.get("interval")
        # to the digits the interval supports (feloop.digits); JSON keeps them all
        value, lo, hi = fmt_interval(p["value"], *(iv or (None, None)), fallback=".7g",
                                     z=NormalDist().inv_cdf(0.5 + s["confidence"] / 2))
        ivs = f"{lo} .. {hi}" if iv else ""
        ab = f" / at {p['at_bound']} bound" if p.get("at_bound") else ""
        start = f" from {p['start']:.4g}" if "start" in p else ""
        scale = f"; rests on {p['rests_on']}" if "rests_on" in p else ""
        lines.append(f"{_LABEL.get(name, name):26s} {value:>14s}  {ivs:28s} "
                     f"{p.get('status', '')} / {p['kind']}{start}{ab}{scale}")
    d = s["derived"]
    lines.append(f"joint: R~ = {d['R_tilde']:.4g} N/m^(chi+2), phi_max = {d['phi_max_m']:.4g} m, "
                 f"F_S = {d['F_S_N']:.4g} N, beta = {d['beta']:.4g}, K_T = {d['K_T_N_per_m']:.3g} "
                 f"N/m, {d['structure']}; force scale "
                 f"{d['force_scale_N_per_unit']:g} N/V assumed (omega2, zeta invariant to it)")
    lines.append("level held  f meas [Hz]  f model [Hz]  err [Hz]   zeta meas   zeta model  "
                 "err [%]  slip/phi_max")
    for row in s["levels"]:
        lines.append(f"{row['level']:5d} {'*' if row['held_out'] else ' ':>4s} "
                     f"{row['measured']['frequency_hz']:12.5f} "
                     f"{row['model']['frequency_hz']:13.5f} "
                     f"{row['error_hz']:+9.4f} {row['measured']['zeta']:11.6f} "
                     f"{row['model']['zeta']:12.6f} {100 * row['error_zeta_rel']:+8.3f} "
                     f"{row['slip_over_phi_max']:11.3g}")
    for c, why in s["untested"].items():
        lines.append(f"not tested: {c} ({why})")
    if s.get("estimator_start", "used") != "used":
        lines.append(f"base fit started without the paper's estimator: {s['estimator_start']}")
    if s["failed_simulations"] or s["fallbacks"]:
        lines.append(f"failed simulations in the fit: {s['failed_simulations']}; steady states "
                     f"reached by a fallback: {', '.join(s['fallbacks']) or 'none'}")
    cv = s["convergence"]
    lines.append(f"converged: updated fit {'yes' if cv['fit'] else 'NO'}, base fit "
                 f"{'yes' if cv['base_fit'] else 'NO'}; not converged: "
                 f"{len(cv['unconverged_fits'])} candidate fits"
                 + (f" ({', '.join(cv['unconverged_fits'])})" if cv["unconverged_fits"]
                    else "")
                 + f", {cv['unconverged_folds']} folds, {cv['unconverged_profile_points']} "
                 f"profile points")
    lines.append("misfit:")
    lines.extend(f"  - {t}" for t in s["misfit"])
    for name, sv in s["sensitivity"].items():
        f, z = sv["frequency_hz"], sv["zeta"]
        lines.append(f"not determined: {_LABEL.get(name, name)} (inside the interval: "
                     f"{_fmt(min(sv['grid_inside']), 4)} .. {_fmt(max(sv['grid_inside']), 4)}); "
                     f"top held-out level moves {f['min'][-1]:.4f}..{f['max'][-1]:.4f} Hz, "
                     f"zeta {z['min'][-1]:.5f}..{z['max'][-1]:.5f}, top slip/phi_max "
                     f"{sv['top_slip_over_phi_max']['min']:.3g}.."
                     f"{sv['top_slip_over_phi_max']['max']:.3g}")
    if s["assumptions"]:
        lines.append("assumed properties changed (refitted): dchi2, top held-out level shift "
                     "[Hz], [% zeta], top slip/phi_max")
        # the shifts to one digit of the top level's noise sd: a shift is read against it,
        # and below a tenth of it it is the refits' convergence (1e-6 Hz, 1e-3 % that move
        # with the BLAS kernel), not the assumption's effect
        top = s["levels"][-1]["measured"]
        sd_f = n["sigma_omega2"][-1] / (2 * (2 * math.pi) ** 2 * top["frequency_hz"])
        sd_z = 100 * n["sigma_zeta"][-1] / top["zeta"]
        for a in s["assumptions"]:
            zeta_shift = (None if a['shift_top_zeta_rel'] is None
                          else 100 * a['shift_top_zeta_rel'])
            lines.append(f"  {a['assumption']:28s} {a['delta_chi2']:+9.2f} "
                         f"{fmt(a['shift_top_frequency_hz'], sd_f, '.3g', 1):>10s} "
                         f"{fmt(zeta_shift, sd_z, '.3g', 1):>8s}"
                         f" {a['top_slip_over_phi_max']:9.3g}")
    t = s["timing_s"]
    lines.append(f"time: {t['total']:.1f} s ({s['executor']})")
    return "\n".join(lines)


def markdown(s: dict) -> str:
    """report.md."""
    rows = "\n".join(f"| {_LABEL.get(n, n)} | {p['value']:.7g} | "
                     f"{_fmt((p.get('interval') or [None, None])[0])} .. "
                     f"{_fmt((p.get('interval') or [None, None])[1])} | {p.get('status', '')} | "
                     f"{p['kind']}"
                     f"{' (at ' + p['at_bound'] + ' bound)' if p.get('at_bound') else ''} | "
                     f"{p['description']} |" for n, p in s["parameters"].items())
    lv = "\n".join(f"| {r['level']}{'*' if r['held_out'] else ''} | "
                   f"{r['measured']['frequency_hz']:.5f} | {r['model']['frequency_hz']:.5f} | "
                   f"{r['error_hz']:+.4f} | {r['measured']['zeta']:.6f} | "
                   f"{r['model']['zeta']:.6f} | "
                   f"{100 * r['error_zeta_rel']:+.3f} | {r['slip_over_phi_max']:.3g} |"
                   for r in s["levels"])
    sens = "\n".join(f"- **{_LABEL.get(n, n)}** not determined: over its likelihood region the "
                     f"held-out frequencies span {np.round(v['frequency_hz']['min'], 4).tolist()}"
                     f" .. {np.round(v['frequency_hz']['max'], 4).tolist()} Hz, zeta "
                     f"{np.round(v['zeta']['min'], 6).tolist()} .. "
                     f"{np.round(v['zeta']['max'], 6).tolist()}, top slip/phi_max "
                     f"{v['top_slip_over_phi_max']['min']:.3g} .. "
                     f"{v['top_slip_over_phi_max']['max']:.3g}, R~ {v['R']['min']:.3g} .. "
                     f"{v['R']['max']:.3g}" for n, v in s["sensitivity"].items()) or "- none"
    assumed = "\n".join(
        f"| {a['assumption']} | {a['delta_chi2']:+.2f} | {_fmt(a['shift_top_frequency_hz'], 3)} | "
        f"{_fmt(None if a['shift_top_zeta_rel'] is None else 100 * a['shift_top_zeta_rel'], 3)} | "
        f"{a['top_slip_over_phi_max']:.3g} |" for a in s["assumptions"]) or "| (not run) | | | | |"
    d = s["derived"]
    return f"""# FE model updating: {s['case']}

Data: `{s['source']}`, mode {s['mode']}; fitted levels {s['fit_levels']}, held out
{s['held_out_levels']}. The nonlinear FE model (one continuous four-parameter Iwan
element per joint node, first-harmonic balance with the exact describing function at the
phase resonance of the mode) is fitted by weighted least squares to omega^2 and zeta of
the fit levels. Noise: {s['noise']['source']}: sigma_omega2 =
{s['noise']['sigma_omega2'][0]:.3g} rad^2/s^2, sigma_zeta = {s['noise']['sigma_zeta'][0]:.3g}.
Model: **{s['model']}** (cause `{s['cause']}`), chosen by the one judge as in `diagnose
--case` (fit test p = {s['fit_test']['p_value']:.2g}, {s['fit_test']['test']}).
Intervals at {int(100 * s['confidence'])} %: profile likelihood for a parameter on its
bound (the bound then ends the interval) or with `--profiles all`, else linearized;
widened by the misfit (chi2/dof) when the model misfits.

## Parameters

| parameter | value | interval | status | kind (at_bound) | meaning |
| --- | --- | --- | --- | --- | --- |
{rows}

The joint they make: R~ = {d['R_tilde']:.4g} N/m^(chi+2), phi_max = {d['phi_max_m']:.4g} m,
F_S = {d['F_S_N']:.4g} N, beta = {d['beta']:.4g}, K_T = {d['K_T_N_per_m']:.3g} N/m;
{d['structure']}, force scale {d['force_scale_N_per_unit']:g} N/V (assumed; omega^2 and zeta are exactly invariant
to it, R~ scales as its -(chi+1) power, phi_max and F_S as its first power).

## Levels (* = held out)

| level | f measured [Hz] | f model [Hz] | error [Hz] | zeta measured | zeta model | error [%] | slip/phi_max |
| --- | --- | --- | --- | --- | --- | --- | --- |
{lv}

![levels](update_levels.png)

## What the base model gets wrong

{chr(10).join('- ' + t for t in s['misfit'])}

## What the data do not determine, and what it changes

{sens}

![profiles](update_profiles.png)

## What the assumed properties change (each changed, the model refitted)

| assumption | delta chi2 | top held-out frequency shift [Hz] | top held-out zeta shift [%] | top slip/phi_max |
| --- | --- | --- | --- | --- |
{assumed}
"""


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
    plot_profiles({_LABEL.get(n, n): ([q.value for q in p.points], p.delta, p.threshold, p.best)
                   for n, p in r["profiles"].items()}, title="profile likelihoods",
                  path=out / "update_profiles.png")
    model = {"case": s["case"], "cause": s["cause"], "also": s["also"],
             "model": s["model"], "unexplained": s["unexplained"],
             "fit_test": s["fit_test"], "parameters": s["parameters"], "joint": s["derived"],
             "fit_levels": s["fit_levels"], "noise": s["noise"],
             "base_parameters": list(BASE_PARAMETERS)}
    files = {"updated_model.json": model, "update.json": s}
    for name, obj in files.items():
        (out / name).write_text(json.dumps(to_jsonable(obj), indent=2) + "\n", encoding="utf-8")
    (out / "report.md").write_text(markdown(s), encoding="utf-8")
    return [out / n for n in ("updated_model.json", "update.json", "report.md",
                              "update_levels.png", "update_profiles.png")]
