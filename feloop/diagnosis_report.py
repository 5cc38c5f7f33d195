"""Wording and files of the FE-level diagnosis (``iwanfe diagnose FILE --case NAME|FILE``).

:func:`add_fe_diagnosis` runs :func:`feloop.diagnosis.fe_diagnosis` on the
diagnosed mode and puts ``fe_levels`` and ``fe`` into the diagnosis result;
:func:`format_fe` gives its text lines, :func:`write_fe_files` its markdown section and
the figure ``fe_levels.png`` (measured vs base FE vs extended FE per level).
"""
from __future__ import annotations

import copy
import hashlib
import math
from pathlib import Path

import numpy as np

from feloop.digits import fmt_interval
from feloop.update_text import plausibility_lines
from inverse.diagnosis.report import own_scatter_sentence

__all__ = ["add_fe_diagnosis", "format_fe", "write_fe_files"]

_DONE: dict = {}   # FE diagnoses of this process, by a digest of their data


def _digest(d) -> str:
    h = hashlib.sha256()
    for a in (d.level, d.excitation, d.omega2, d.zeta, d.run_order, d.omega2_std, d.zeta_std):
        h.update(b"-" if a is None else np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr(d.rig_repeatability).encode())
    return h.hexdigest()


def add_fe_diagnosis(result: dict, data, out=None, levels=None, model_key: str = "") -> dict:
    """Add ``fe_levels`` and ``fe`` (FE cause, gains, held-out errors) to ``result``;
    with ``out`` also write :func:`write_fe_files`. ``levels``: the FE-levels model of
    :func:`feloop.diagnosis.fe_diagnosis`, ``model_key`` names it (for the
    reuse of a finished diagnosis). Returns ``result``."""
    from feloop.diagnosis import fe_diagnosis

    mode = result.get("mode")
    d = data.for_mode(int(mode)) if mode is not None else data
    key = (_digest(d), model_key)
    if key not in _DONE:                     # the same data diagnosed again: reuse
        _DONE[key] = fe_diagnosis(d, levels=levels)
    result.update(copy.deepcopy(_DONE[key]))
    if "cause" in result:                   # one report: both verdicts, reconciled
        from feloop.verdict import one_mode_agreement

        result["fe"]["one_mode_agreement"] = one_mode_agreement(result, result["fe"])
    if out is not None:
        write_fe_files(result, Path(out))
    return result


def _g(v, spec=".3g"):
    return "n/a" if v is None else format(v, spec)


def format_fe(fe: dict) -> list:
    """Text lines of the FE-level diagnosis."""
    ft = fe["fit_test"]
    lines = [f"FE level ({fe.get('model', 'FE model')} refitted; fit levels "
             f"{fe['fit_levels']}, held out {fe['held_out_levels']}; judged by {fe['rule']}):",
             *(f"  {t}" for t in fe["verdict"]["lines"]),
             *([f"  {fe['one_mode_agreement']}"] if "one_mode_agreement" in fe else []),
             *(f"  note: {t}" for t in fe.get("notes", [])),
             f"  fit of {fe['candidate']}: rms {ft['rms_standardized']:.3g} noise sd, p = "
             f"{_g(ft['p_value'], '.2g')} ({ft['test']})",
             "  noise: " + "; ".join(f"{c}: {n['source']}" for c, n in fe["noise"].items()),
             *([f"  check: {fe['engagement_text']}"] if "engagement_text" in fe else []),
             *(f"  {t}" for t in plausibility_lines(fe.get("plausibility", []))),
             *_own_scatter_lines(fe),
             f"  cross-validated: base error {_g(fe['base_error'])}, extended "
             f"{_g(fe['extended_error'])}, gain {_g(fe['gain'])}",
             f"  held out: base error {_g(fe['base_error_held_out'])}, extended "
             f"{_g(fe['extended_error_held_out'])}, gain_held_out {_g(fe['gain_held_out'])} "
             f"({fe['error_measure']})"]
    for c, e in fe["evidence"].items():
        chi2 = _g(e["chi2"], "8.2f")
        lines.append(f"  {c:40s} chi2 {chi2:>8s}, w {e['weight']:.3f}, p "
                     f"{_g(e['fit_test']['p_value'], '.2g'):>7s}, gain {_g(e['gain'])}"
                     + (f"  ({e['why_not']})" if e["why_not"] else ""))
    for c, why in fe["untested"].items():
        lines.append(f"  not tested: {c} ({why})")
    if fe.get("estimator_start", "used") != "used":
        lines.append(f"  base fit started without the paper's estimator: "
                     f"{fe['estimator_start']}")
    fl = fe["failures"]
    names = fl.get("unconverged_fit_names") or []
    lines.append(f"  failures: {fl['simulations']} simulations, {fl['folds']} folds, "
                 f"{fl['fits']} fits, {fl['profile_points']} profile points; not converged: "
                 f"{fl.get('unconverged_fits', 0)} fits"
                 + (f" ({', '.join(names)})" if names else "")
                 + f", {fl.get('unconverged_folds', 0)} folds, "
                 f"{fl.get('unconverged_profile_points', 0)} profile points")
    lines.append("  steady states reached by a fallback: " + "; ".join(
        f"{name} model {', '.join(fb) or 'none'}" for name, fb in fl["fallbacks"].items()))
    lines.append("  parameters (fitted; interval 95 %):")
    for n, p in fe["parameters"].items():
        iv = p["interval"]
        ab = f", at its {p['at_bound']} bound" if p["at_bound"] else ""
        value, lo, hi = fmt_interval(p["value"], *iv)     # the digits the interval supports
        lines.append(f"    {n:10s} {value} [{'n/a' if iv[0] is None else lo} .. "
                     f"{'n/a' if iv[1] is None else hi}] "
                     f"({p['interval_kind']}{ab}"
                     + (f"; rests on {p['rests_on']}" if "rests_on" in p else "") + ")")
    if fe["reading"]:
        lines.append("  extended FE parameters: " + ", ".join(
            f"{k} = {v:.4g}" for k, v in fe["reading"].items()))
    lines.append("  level  base err [Hz]  ext err [Hz] (95 % PI)  ext err zeta [%] (95 % PI)  "
                 "z f / z zeta")
    for r in fe["held_out"]:
        lines.append(f"  {r['level']:5d} {r['base_error_hz']:+14.4f} {r['error_hz']:+13.4f} "
                     f"(+/-{r['pi95_half_width_hz']:.4f}) {100 * r['error_zeta_rel']:+16.3f} "
                     f"(+/-{100 * r['pi95_half_width_zeta_rel']:.3f}) "
                     f"{r['z_frequency']:+6.1f} / {r['z_zeta']:+.1f}")
    lines.append("  " + acceptance_text(fe))
    return lines


def _own_scatter_lines(fe: dict) -> list:
    """The verdict with the data's own scatter, where a channel's was capped."""
    capped = [c for c, n in fe["noise"].items()
              if (n.get("assumed_repeatability") or {}).get("capped")]
    text = own_scatter_sentence(capped, fe.get("verdict_own_scatter"),
                                (fe["cause"], fe["also"]))
    return ["  " + text.strip()] if text else []


def acceptance_text(fe: dict) -> str:
    """Whether the extended FE model predicts the held-out levels within the issue's
    tolerances and inside its own 95 % prediction intervals; which level misses, by how
    many sd and why."""
    a = fe["acceptance"]
    if not fe["held_out"]:
        return "no held-out levels"
    if a["met"]:
        text = (f"extended FE model within {a['tolerance_hz']} Hz and "
                f"{100 * a['tolerance_zeta_rel']:.1f} % at every held-out level")
    else:
        worst = max(fe["held_out"], key=lambda r: abs(r["error_hz"]))
        text = (f"not within {a['tolerance_hz']} Hz / {100 * a['tolerance_zeta_rel']:.1f} %: "
                f"worst level {worst['level']}, {worst['error_hz']:+.4f} Hz")
        wide = [r["level"] for r in fe["held_out"] if r["pi95_half_width_hz"] > a["tolerance_hz"]]
        if wide:
            text += (f"; at level(s) {wide} the 95 % prediction half-width already exceeds "
                     f"{a['tolerance_hz']} Hz")
        else:
            text += ("; every 95 % prediction half-width is below the tolerance, so the "
                     "noise does not make it unreachable: the miss is the model's")
    if fe["misses"]:
        text += "; outside the 95 % prediction interval: " + "; ".join(
            f"level {m['level']} by {m['by']} ({m['why']})" for m in fe["misses"])
    else:
        text += "; every held-out level inside its 95 % prediction interval"
    return text


def write_fe_files(result: dict, out: Path) -> list:
    """``fe_levels.png`` and ``fe_diagnosis.md`` in ``out``."""
    from viz.level_models import plot_level_models

    out.mkdir(parents=True, exist_ok=True)
    fe, rows = result["fe"], result["fe_levels"]
    lv = np.array([r["level"] for r in rows])
    f = np.array([r["measured"]["frequency_hz"] for r in rows])
    z = np.array([r["measured"]["zeta"] for r in rows])
    s_om2 = np.asarray(fe["noise_sigma"]["sigma_omega2"], dtype=float)
    s_z = np.asarray(fe["noise_sigma"]["sigma_zeta"], dtype=float)
    models = {"base FE": ([r["base"]["frequency_hz"] for r in rows],
                          [r["base"]["zeta"] for r in rows]),
              f"extended FE ({fe['cause']})": ([r["extended"]["frequency_hz"] for r in rows],
                                               [r["extended"]["zeta"] for r in rows])}
    png = out / "fe_levels.png"
    plot_level_models(lv, f, z, s_om2 / (8 * math.pi ** 2 * f), s_z, models,
                      [r["held_out"] for r in rows],
                      title=f"measured vs base FE vs extended FE ({fe['cause']})", path=png)
    md = out / "fe_diagnosis.md"
    md.write_text(f"# FE-level diagnosis ({fe.get('model', 'FE model')})\n\n" + "\n".join(
        ("    " + ln) for ln in format_fe(fe)) + "\n\n![FE levels](fe_levels.png)\n",
        encoding="utf-8")
    return [png, md]
