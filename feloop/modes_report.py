"""The report of one joint over several modes (:func:`feloop.modes_run.run_modes`): the
JSON summary (:func:`summary`), the text (:func:`format_text`), the page and figures
(:func:`write_modes`). Every number says what it is: ``fitted`` (the joint, each fit
mode's ``zeta_v`` and ``f0_hz``), ``calibrated`` (a predicted mode's ``zeta_v`` and
``f0_hz``, to its lowest level), ``derived`` (the physical joint), ``measured`` or
``predicted``."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from feloop.digits import Z95, fmt, fmt_interval
from feloop.modes import MODE_NUISANCE, TEST_SIZE, nuisance_name
from runs.jsonio import to_jsonable

__all__ = ["summary", "format_text", "write_modes"]


def _parameters(mf) -> dict:
    f, P = mf.fit, mf.problem.parameters
    out = {}
    for n in f.free:
        se = f.std_error(n)
        out[n] = {"value": f.values[n], "unit": P[n].unit, "kind": "fitted",
                  "at_bound": f.at_bound.get(n, False), "std_error": se,
                  "interval": [f.values[n] - Z95 * se, f.values[n] + Z95 * se]
                  if math.isfinite(se) else [None, None],
                  "interval_kind": "linearized 95 % (misfit-scaled covariance)",
                  "description": P[n].description}
    return out


def _one_joint_words(mf) -> str:
    t, labels = mf.one_joint, [s.label for s in mf.series]
    if t["dof"] == 0:
        return "one mode fitted: nothing to compare"
    modes = ", ".join(map(str, labels))
    if t["passes"]:
        return (f"one joint explains modes {modes}: each mode fitted alone lowers chi2 by "
                f"D = {t['D']:.3g} together, {t['dof']} degree(s) of freedom ({t['test']}, "
                f"p = {t['p_value']:.2g} >= {TEST_SIZE:g})")
    alone = "; ".join(f"mode {lb} alone: F_S = {j['F_S']:.4g} N, slip scale "
                      f"{j['slip_scale']:.4g} m" for lb, j in mf.alone_joint.items())
    return (f"the modes disagree on the joint: one joint for modes {modes} costs D = "
            f"{t['D']:.3g} in chi2 over each mode fitted alone ({t['dof']} degree(s) of "
            f"freedom, {t['test']}, p = {t['p_value']:.2g} < {TEST_SIZE:g}); {alone}. A joint law or "
            "distribution over the interface that the modes load differently, or a second "
            "joint that one mode works: unexplained (no mode-dependent cause is tested at the "
            "FE level)")


def _prediction_words(lb: int, p, fit_labels) -> str:
    c = p.change
    src = ", ".join(map(str, fit_labels))
    change = (f"frequency drop {c['measured_frequency_drop_pct']:.3g} % measured, "
              f"{c['predicted_frequency_drop_pct']:.3g} % predicted; damping growth x"
              f"{c['measured_zeta_growth']:.4g} measured, x{c['predicted_zeta_growth']:.4g} "
              f"predicted; gain {p.gain:.3g} over no amplitude dependence")
    if p.inside:
        return (f"mode {lb}, predicted from the joint of mode(s) {src}: within its 95 % "
                f"intervals at every level ({change})")
    miss = "; ".join(f"level {m['level']}: frequency {m['z_frequency']:+.1f} sd, zeta "
                     f"{m['z_zeta']:+.1f} sd" for m in p.misses)
    return (f"mode {lb}, predicted from the joint of mode(s) {src}: MISSED at "
            f"{len(p.misses)} of {len(p.rows) - 1} levels ({miss}; {change}): the joint "
            f"fitted on mode(s) {src} fails on mode {lb}; cause unexplained (a second joint "
            f"that mode {lb} works, or a joint distributed otherwise over the interface; not "
            "tested at the FE level)")


def summary(r: dict) -> dict:
    """The JSON document of ``update --modes`` / ``loop --fit-modes`` (module docstring)."""
    mf, st = r["fit"], r["settings"]
    j = mf.joint()
    per_mode = {}
    for s in mf.series:
        pred = s.fe.predict({**mf.joint_values, **{n: mf.fit.values[nuisance_name(n, s.label)]
                                                   for n in MODE_NUISANCE}})
        per_mode[str(s.label)] = {
            **mf.per_mode[s.label], "fe_mode": int(pred.joint["fe_mode"]),
            "stiffness_scale": float(pred.joint["stiffness_scale"]),
            "fit_levels": [int(v) for v in s.data.level[s.mask]],
            "alone": {"chi2": mf.alone[s.label].chi2,
                      "joint": {k: mf.alone_joint[s.label][k] for k in ("F_S", "slip_scale")},
                      "values": mf.alone[s.label].values}}
    predicted = {}
    for lb, p in r["predicted"].items():
        predicted[str(lb)] = {
            "calibrated": {n: {"value": p.values[n], "kind": "calibrated to level "
                               f"{p.rows[0]['level']}"} for n in MODE_NUISANCE},
            "stiffness_scale": p.stiffness_scale, "rows": p.rows, "misses": p.misses,
            "inside_pi95": p.inside, "gain": p.gain, "change": p.change,
            "verdict": _prediction_words(lb, p, st.fit_modes)}
    lines = ([_one_joint_words(mf)] if mf.one_joint["dof"] else []) \
        + [v["verdict"] for v in predicted.values()]
    f = mf.fit
    for lb, t in mf.per_mode.items():
        if not t["passes"]:
            lines.insert(0, f"mode {lb}'s fit levels are not fitted within their noise (chi2 "
                            f"{t['chi2']:.3g} over {t['residuals']} residuals, {t['test']}, "
                            f"p = {t['p_value']:.2g}): the joint model misfits a mode it was "
                            "fitted to, and what is predicted from it rests on that fit")
    if not (f.success and f.converged):
        lines.insert(0, f"the joint fit did NOT converge (decrement {f.decrement:.3g}, "
                        f"{f.message})")
    bound = [n for n in f.free if f.at_bound.get(n)]
    if bound:
        lines.insert(0, f"on a bound: {', '.join(bound)} (its interval is not determined)")
    return {"case": r["case"], "data": st.data_path, "fit_modes": list(st.fit_modes),
            "reference_mode": int(st.fit_modes[0]), "predict_modes": list(st.predict_modes),
            "force_scale": {"value": st.force_scale, "kind": "assumed", "unit": "N per unit"},
            "parameters": _parameters(mf),
            "joint": {**{k: v for k, v in j.items()}, "kind": "derived from the fitted "
                      "parameters (F_S and the slip scale scale with the force scale)"},
            "fit": {"chi2": f.chi2, "residuals": f.n, "success": f.success,
                    "converged": f.converged, "decrement": f.decrement,
                    "flat": list(f.flat), "at_bound": bound},
            "noise": mf.problem.noise.source, "per_mode": per_mode,
            "one_joint": mf.one_joint, "predicted": predicted, "verdict": lines,
            "timing_s": r["timing_s"]}


def format_text(s: dict) -> str:
    """The text of :func:`summary`."""
    out = [f"one joint, modes {', '.join(map(str, s['fit_modes']))} fitted (reference mode "
           f"{s['reference_mode']}), case {s['case']}"]
    for n, e in s["parameters"].items():
        v, lo, hi = fmt_interval(e["value"], *e["interval"])
        unit = "" if e["unit"] in ("", "1") else f" {e['unit']}"
        iv = f" ({lo} .. {hi})" if e["interval"][0] is not None else " (no interval)"
        out.append(f"  {n} = {v}{unit}{iv}, fitted"
                   + (f", AT {e['at_bound'].upper()} BOUND" if e["at_bound"] else ""))
    j = s["joint"]
    out.append(f"  joint ({j['law']}): F_S = {j['F_S']:.4g} N, slip scale "
               f"{j['slip_scale']:.4g} m, K_T = {j['K_T']:.4g} N/m (derived; force scale "
               f"{s['force_scale']['value']:g} N/unit assumed)")
    for lb, m in s["per_mode"].items():
        out.append(f"  mode {lb} (FE mode {m['fe_mode']}): chi2 {m['chi2']:.3g} over "
                   f"{m['residuals']} residuals, {m['test']}, p = {m['p_value']:.2g} "
                   f"({'passes' if m['passes'] else 'FAILS'}); alone: chi2 "
                   f"{m['alone']['chi2']:.3g}, F_S {m['alone']['joint']['F_S']:.4g} N")
    for lb, p in s["predicted"].items():
        out.append(f"  mode {lb} predicted (zeta_v, f0_hz calibrated to level "
                   f"{p['rows'][0]['level']}):")
        for row in p["rows"][1:]:
            out.append(f"    level {row['level']}: {row['measured_hz']:.6g} Hz measured, "
                       f"{fmt(row['predicted_hz'], row['sd_hz'])} +- "
                       f"{Z95 * row['sd_hz']:.2g} predicted "
                       f"({row['z_frequency']:+.1f} sd); zeta {row['measured_zeta']:.4g} / "
                       f"{row['predicted_zeta']:.4g} +- {Z95 * row['sd_zeta']:.2g} "
                       f"({row['z_zeta']:+.1f} sd)")
    out.append(f"  noise: {s['noise']}")
    out += [f"verdict: {v}" for v in s["verdict"]]
    return "\n".join(out)


def write_modes(r: dict, out, name: str = "modes") -> list:
    """``DIR/<name>.json``, ``DIR/report.md`` and a figure per predicted mode."""
    from viz.level_models import plot_level_models

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    s = summary(r)
    files = [out / f"{name}.json", out / "report.md"]
    files[0].write_text(json.dumps(to_jsonable(s), indent=2) + "\n", encoding="utf-8")
    page = ["# One joint, several modes", "", "```", format_text(s), "```", ""]
    for lb, p in r["predicted"].items():
        rows = p.rows
        fig = out / f"mode{lb}_predicted.png"
        plot_level_models([q["level"] for q in rows], [q["measured_hz"] for q in rows],
                          [q["measured_zeta"] for q in rows], [q["sd_hz"] for q in rows],
                          [q["sd_zeta"] for q in rows],
                          {f"from mode(s) {', '.join(map(str, s['fit_modes']))}":
                           (np.array([q["predicted_hz"] for q in rows]),
                            np.array([q["predicted_zeta"] for q in rows]))},
                          np.ones(len(rows), bool),
                          title=f"mode {lb} predicted from the joint of the fit modes "
                                "(error bars: prediction sd)", path=fig)
        page += [f"![mode {lb}]({fig.name})", ""]
        files.append(fig)
    files[1].write_text("\n".join(page), encoding="utf-8")
    return files
