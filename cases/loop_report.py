"""The main job: the whole loop on one page (``iwanfe loop``, ``make run``).

Measured levels -> the FE model updated to the fit levels (:func:`run_update`, the one
judge of :mod:`inverse.judge` choosing between the base model and its extensions) ->
what the updated base model (no cause) gets wrong, with numbers -> the cause named ->
the extended model -> its gain at the levels the fit never saw.

Scores at the held-out levels (both channels, in noise units of the judge's noise model,
``err = sqrt(mean r^2)`` with ``r = (model - measured) / sigma``):
``gain_held_out = err_base / err_extended`` (> 1: the extension predicts better).

Writes ``report.md`` (one page, with ``update_levels.png``), ``loop.json`` and, in
``update/``, every file of ``iwanfe update``; returns the JSON-ready summary.

``loop --model DIR/updated_model.json`` (a model ``update`` wrote for the same case and
data): the loop is run as without it (its fits start from the data, the estimator and
fixed chi starts, never from the case file's nominal joint, so a given model has nothing
to start), and beside it the report says what the given model gets wrong at every level
(its predictions against the measured values, in the noise sd of the judge's noise
model, rms at its fit levels and at the others) next to the loop's own updated model
(:func:`given_model_check`, ``given_model`` in ``loop.json``).
"""
from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np

from runs.jsonio import to_jsonable

__all__ = ["held_out_scores", "given_model_check", "run_loop", "format_summary",
           "markdown"]


def held_out_scores(data, mask, noise, prediction) -> dict:
    """Errors of one model at the held-out levels: per level in Hz and in % of zeta,
    and the rms over both channels in noise units (module docstring)."""
    held = ~np.asarray(mask, dtype=bool)
    f_meas = np.sqrt(data.omega2) / (2 * math.pi)
    r = np.concatenate([(prediction.omega2[held] - data.omega2[held]) / noise.sigma_omega2[held],
                        (prediction.zeta[held] - data.zeta[held]) / noise.sigma_zeta[held]])
    rows = [{"level": int(data.level[i]),
             "error_hz": float(prediction.frequency_hz[i] - f_meas[i]),
             "error_zeta_percent": float(100 * (prediction.zeta[i] / data.zeta[i] - 1))}
            for i in np.flatnonzero(held)]
    return {"rms_noise_units": float(np.sqrt(np.mean(r * r))) if r.size else math.nan,
            "levels": rows}


def given_model_check(r: dict, given) -> dict:
    """What the given model (:class:`feloop.given_model.GivenModel`, ``loop --model``)
    gets wrong at every level of the loop's data, beside the loop's own updated model:
    both simulated by the loop's FE-levels model, errors in the noise sd of the loop's
    noise model; InputError (one line) for a model of other data."""
    from feloop.given_model import level_errors

    data, mask, noise = r["data"], r["fit_mask"], r["noise"]
    given.check_data(data, r["settings"].mode_label, r["settings"].force_scale)
    fe = r["selection"]["fe"]
    fe.reset()                                 # a cold start, as the Monte Carlo's
    pred = fe.predict(given.fit.values, given.extension)
    fitted = np.isin(data.level, given.fit_levels)
    return {"path": given.path, "model": given.candidate, "cause": given.cause,
            "fit_levels": list(given.fit_levels), "values": dict(given.fit.values),
            "errors": level_errors(data, noise, pred, fitted),
            "loop_errors": level_errors(data, noise, r["prediction"], mask),
            "same_fit_levels": bool(np.array_equal(fitted, mask))}


def run_loop(case, out, executor="serial", progress: bool = True, model=None) -> dict:
    """Run the loop on ``case`` (a :class:`cases.case.Case` with the ``update``
    capability) and write its files into ``out``; the summary dict. ``model``: an
    ``updated_model.json`` of ``update`` on the case, checked at every level beside
    the loop's update (:func:`given_model_check`; the loop's fits start from the data,
    never from a nominal joint, so the model cannot start them)."""
    from feloop.given_model import read_given
    from feloop.update_report import summary, write_update

    update = case.require("update")
    given = None if model is None else read_given(model, case.name)   # before the fits
    out = Path(out)
    r = update(executor=executor, progress=progress, store=str(out / "update" / "profiles"))
    write_update(r, out / "update")
    s = summary(r)
    data, mask, noise = r["data"], r["fit_mask"], r["noise"]
    base = held_out_scores(data, mask, noise, r["base_prediction"])
    extended = held_out_scores(data, mask, noise, r["prediction"])
    named = s["cause"] not in ("none", "unexplained")
    gain = base["rms_noise_units"] / extended["rms_noise_units"] if named else None
    evidence = s["evidence"]
    loop = {
        "case": case.name, "data": s["source"], "mode": s["mode"],
        "fit_levels": s["fit_levels"], "held_out_levels": s["held_out_levels"],
        "noise": s["noise"]["source"] if isinstance(s["noise"], dict) else str(s["noise"]),
        "base": {"chi2": evidence["none"]["chi2"], "fit_test": evidence["none"]["fit_test"],
                 "held_out": base,
                 "parameters": {n: p for n, p in s["parameters"].items()
                                if n in r["base_fit"].values}},
        "tie": s["tie"], "cause": s["cause"], "also": s["also"],
        "unexplained": s["unexplained"], "untested": s["untested"],
        "judged_on": s["verdict"]["judged_on"], "misses": s["verdict"]["misses_text"],
        "agreement": s["verdict"]["agreement"], "verdict": s["verdict"]["lines"],
        "extended": {"model": s["model"], "fit_test": s["fit_test"], "held_out": extended,
                     "parameters": s["parameters"]},
        "gain_held_out": gain,
        "error_measure": "rms of (model - measured)/sigma over omega2 and zeta at the "
                         "held-out levels; sigma from the judge's noise model",
        "statements": s["misfit"],
        "plausibility": s.get("plausibility", []),
        "still_wrong": [m for m in s["misfit"]
                        if m.startswith("level ") or " sits on its " in m]
        + [f"{c['parameter']} = {c['value']:.4g} ({c['kind']}) is implausible: {c['source']}"
           for c in s.get("plausibility", []) if c["verdict"] == "implausible"],
    }
    if given is not None:
        loop["given_model"] = given_model_check(r, given)
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(out / "update" / "update_levels.png", out / "update_levels.png")
    (out / "loop.json").write_text(json.dumps(to_jsonable(loop), indent=2) + "\n",
                                   encoding="utf-8")
    (out / "report.md").write_text(markdown(loop), encoding="utf-8")
    return loop


def _kind(p: dict) -> str:
    kind = p["kind"]
    if p.get("at_bound"):
        kind += f", at its {p['at_bound']} bound"
    return kind


def _errors(rows: list) -> str:
    return ", ".join(f"level {r['level']}: {r['error_hz']:+.4f} Hz / "
                     f"{r['error_zeta_percent']:+.2f} % zeta" for r in rows)


def format_summary(s: dict) -> str:
    """The short terminal summary."""
    b, e = s["base"], s["extended"]
    lines = [f"iwanfe loop --case {s['case']}: mode {s['mode']}, levels "
             f"{s['fit_levels'][0]}-{s['fit_levels'][-1]} fitted, "
             f"{', '.join(map(str, s['held_out_levels']))} held out (measured data: {s['data']})",
             f"1. updated FE model (no cause): chi2 {b['chi2']:.1f}, fit test p = "
             f"{b['fit_test']['p_value']:.2g}; at the held-out levels "
             f"{_errors(b['held_out']['levels'])}",
             f"2. what it gets wrong: {s['tie']['text']}",
             f"3. cause ({s['judged_on']} fitted): {s['cause']}"
             + (f" + {', '.join(s['also'])}" if s["also"] else "")
             + (" (no candidate brings the data within their noise)" if s["unexplained"] else "")
             + (f"; {s['agreement']}" if s["agreement"] else ""),
             f"4. extended model ({e['model']} fitted to levels {s['fit_levels'][0]}-"
             f"{s['fit_levels'][-1]}): fit test p = {e['fit_test']['p_value']:.2g}; "
             f"held out {_errors(e['held_out']['levels'])}"]
    if s["misses"]:                     # what the held-out levels show comes first
        lines.insert(1, s["misses"])
    gain = s["gain_held_out"]
    lines.append(f"5. gain at the held-out levels: {gain:.2f} (rms error "
                 f"{b['held_out']['rms_noise_units']:.1f} -> "
                 f"{e['held_out']['rms_noise_units']:.1f} noise units)" if gain is not None
                 else "5. gain at the held-out levels: n/a (no cause named)")
    lines += [f"   still wrong: {m}" for m in s["still_wrong"]]
    if s.get("given_model"):
        lines.append(given_line(s["given_model"]))
    return "\n".join(lines)


def given_line(g: dict) -> str:
    """One line of what the given model (``--model``) gets wrong, beside the loop's."""
    e, le = g["errors"], g["loop_errors"]

    def sd(v):
        return "n/a" if v is None else f"{v:.2f}"

    worst = max(e["levels"], key=lambda r: max(abs(r["z_frequency"]), abs(r["z_zeta"])))
    return (f"6. given model {g['path']} ({g['model']}, fitted to levels "
            f"{g['fit_levels'][0]}-{g['fit_levels'][-1]}): rms error {sd(e['rms_fitted_sd'])} "
            f"noise sd at its fit levels, {sd(e['rms_others_sd'])} at the others (the loop's "
            f"updated model: {sd(le['rms_fitted_sd'])} / {sd(le['rms_others_sd'])} at its "
            f"own); worst level {worst['level']}: {worst['error_hz']:+.4f} Hz "
            f"({worst['z_frequency']:+.1f} sd) / {worst['error_zeta_percent']:+.2f} % zeta "
            f"({worst['z_zeta']:+.1f} sd)")


def _given_markdown(g: dict | None) -> str:
    """The report's section on the given model (``--model``), or nothing."""
    if not g:
        return ""
    rows = "\n".join(
        f"| {a['level']}{'' if a['fitted'] else '*'} | {a['error_hz']:+.4f} | "
        f"{a['z_frequency']:+.1f} | {a['error_zeta_percent']:+.2f} | {a['z_zeta']:+.1f} | "
        f"{b['z_frequency']:+.1f} | {b['z_zeta']:+.1f} |"
        for a, b in zip(g["errors"]["levels"], g["loop_errors"]["levels"]))
    return f"""
## The given model `{g['path']}`

{given_line(g)[3:]}. Simulated by the loop's FE-levels model at every level; errors of
the given model (Hz, % of zeta and in noise sd) beside the loop's updated model's (in
noise sd); * = not among the given model's fit levels.

| level | error [Hz] | sd | error [% zeta] | sd | loop's model, frequency sd | loop's model, zeta sd |
| --- | --- | --- | --- | --- | --- | --- |
{rows}
"""


def markdown(s: dict) -> str:
    """The one-page ``report.md``."""
    b, e = s["base"], s["extended"]
    params = "\n".join(f"| {n} | {p['value']:.6g} | {_kind(p)} | {p['description']} |"
                       for n, p in e["parameters"].items())
    rows = "\n".join(
        f"| {rb['level']} | {rb['error_hz']:+.4f} | {re['error_hz']:+.4f} | "
        f"{rb['error_zeta_percent']:+.2f} | {re['error_zeta_percent']:+.2f} |"
        for rb, re in zip(b["held_out"]["levels"], e["held_out"]["levels"]))
    gain = s["gain_held_out"]
    gain_text = (f"**{gain:.2f}** (rms error {b['held_out']['rms_noise_units']:.1f} -> "
                 f"{e['held_out']['rms_noise_units']:.1f} noise units)" if gain is not None
                 else "n/a (no cause named)")
    still = "\n".join(f"   - {m}" for m in s["still_wrong"]) or "   - nothing beyond the noise"
    untested = "; ".join(f"{c}: {why}" for c, why in s["untested"].items()) or "none"
    misses = f"\n**{s['misses']}.**\n" if s["misses"] else ""
    agree = f"; {s['agreement']}" if s["agreement"] else ""
    return f"""# The loop on case `{s['case']}`

Measured data `{s['data']}` (mode {s['mode']}): levels {s['fit_levels']} fitted, levels
{s['held_out_levels']} held out (never seen by the fit of the extended model). Noise:
{s['noise']}.
{misses}

1. **Updated FE model (no cause)**: chi2 = {b['chi2']:.1f}, fit test p =
   {b['fit_test']['p_value']:.2g} ({b['fit_test']['test']}).
2. **What it gets wrong**: {s['tie']['text']}.
3. **Cause named** ({s['judged_on']} fitted): `{s['cause']}`{' + ' + ', '.join(s['also']) if s['also'] else ''}
   (one judge: fit test, complexity cost, held-out gain > 1; not tested: {untested}){agree}.
4. **Extended model** `{e['model']}` fitted to levels {s['fit_levels']}: fit test p =
   {e['fit_test']['p_value']:.2g}.
5. **Gain at the held-out levels**: {gain_text}.
6. **What the extended model still gets wrong** (sigma: the judge's noise):
{still}

![measured vs base vs extended FE model](update_levels.png)

| level | base error [Hz] | extended error [Hz] | base error [% zeta] | extended error [% zeta] |
| --- | --- | --- | --- | --- |
{rows}

Parameters of the extended model (kind: fitted, assumed, calibrated):

| parameter | value | kind | meaning |
| --- | --- | --- | --- |
{params}

Error measure: {s['error_measure']}. Details (profiles, intervals, every level):
`update/report.md`.
{_given_markdown(s.get('given_model'))}"""
