"""The words of ``iwanfe update``: the terminal text (:func:`format_text`) and
``report.md`` (:func:`markdown`) of :func:`feloop.update_report.summary`."""
from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

from feloop.digits import fmt, fmt_interval

__all__ = ["LABEL", "format_text", "markdown", "plausibility_lines"]

#: the parameters' names in the text and the figures
LABEL = {"chi": "chi", "ln_dc1": "ln |kappa1|B~ (level 1)", "zeta_v": "zeta_v",
          "f0_hz": "f0 [Hz]", "ln_phimax": "ln(phi_max/a_ref)", "log10_kt": "log10 K_T [N/m]",
          "ln_slip": "ln(slip scale/a_ref)", "alpha": "alpha (gross-slip stiffness)"}


def _fmt(v, digits=6):
    if v is None:
        return "open"
    return f"{v:.{digits}g}"


def plausibility_lines(checks: list) -> list:
    """A line per check of :func:`casefile.plausibility.joint_plausibility`."""
    return [f"plausibility: {c['parameter']} = {c['value']:.4g} ({c['kind']}): "
            f"{c['verdict']} (range "
            f"{_fmt(c['low'], 3)} .. {_fmt(c['high'], 3)}: {c['source']})" for c in checks]


def _head_lines(s: dict) -> list:
    """The verdict (held-out misses first), the model, the noise and the checks."""
    n, ft = s["noise"], s["fit_test"]
    return [f"iwanfe update --case {s['case']}  ({s['source']}, mode {s['mode']}, fit levels "
            f"{s['fit_levels'][0]}-{s['fit_levels'][-1]})",
            *s["verdict"]["lines"],
            f"model: {s['model']} fitted to the fit levels (the one judge, as diagnose "
            f"--case; fit test p = {_fmt(ft['p_value'], 2)}, {ft['test']})",
            f"noise: sigma_omega2 = {n['sigma_omega2'][0]:.3g} rad^2/s^2, sigma_zeta = "
            f"{n['sigma_zeta'][0]:.3g} ({n['source']})",
            f"check: {s['engagement_text']}",
            *plausibility_lines(s.get("plausibility", [])),
            *(f"note: {t}" for t in s.get("notes", []))]


def _parameter_lines(s: dict) -> list:
    """The parameter table (to the digits each interval supports) and the joint."""
    lines = [f"{'parameter':26s} {'value':>14s}  {int(100 * s['confidence'])}% profile "
             f"interval          status / kind"]
    for name, p in s["parameters"].items():
        iv = p.get("interval")
        # to the digits the interval supports (feloop.digits); JSON keeps them all
        value, lo, hi = fmt_interval(p["value"], *(iv or (None, None)), fallback=".7g",
                                     z=NormalDist().inv_cdf(0.5 + s["confidence"] / 2))
        ivs = f"{lo} .. {hi}" if iv else ""
        ab = f" / at {p['at_bound']} bound" if p.get("at_bound") else ""
        start = f" from {p['start']:.4g}" if "start" in p else ""
        scale = f"; rests on {p['rests_on']}" if "rests_on" in p else ""
        lines.append(f"{LABEL.get(name, name):26s} {value:>14s}  {ivs:28s} "
                     f"{p.get('status', '')} / {p['kind']}{start}{ab}{scale}")
    d = s["derived"]
    lines.append(f"joint: {d['joint_text']}, K_T = {d['K_T_N_per_m']:.3g} "
                 f"N/m, {d['structure']}; force scale "
                 f"{d['force_scale_N_per_unit']:g} N/V assumed (omega2, zeta invariant to it)")
    return lines


def _level_lines(s: dict) -> list:
    """Every level, measured and modelled (``*``: held out)."""
    scale = f"slip/{s['derived'].get('slip_scale_name', 'phi_max')}"
    return ["level held  f meas [Hz]  f model [Hz]  err [Hz]   zeta meas   zeta model  "
            f"err [%]  {scale:>12s}"] + [
        f"{row['level']:5d} {'*' if row['held_out'] else ' ':>4s} "
        f"{row['measured']['frequency_hz']:12.5f} {row['model']['frequency_hz']:13.5f} "
        f"{row['error_hz']:+9.4f} {row['measured']['zeta']:11.6f} "
        f"{row['model']['zeta']:12.6f} {100 * row['error_zeta_rel']:+8.3f} "
        f"{row['slip_over_phi_max']:11.3g}" for row in s["levels"]]


def _fit_state_lines(s: dict) -> list:
    """What was not tested, how the fit started, failed and converged."""
    lines = [f"not tested: {c} ({why})" for c, why in s["untested"].items()]
    if s.get("estimator_start", "used") != "used":
        lines.append(f"base fit started without the paper's estimator: {s['estimator_start']}")
    flat = s["fit"].get("flat") or []
    if flat:                  # inverse.decrement.FLAT_EFFECT: no effect where it stopped
        lines.append(f"flat at the optimum (no effect there, not determined): "
                     f"{', '.join(LABEL.get(n, n) for n in flat)}")
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
    return lines


def _sensitivity_lines(s: dict) -> list:
    """What the data do not determine, and what the assumed properties move."""
    lines, scale = [], s["derived"].get("slip_scale_name", "phi_max")
    for name, sv in s["sensitivity"].items():
        f, z = sv["frequency_hz"], sv["zeta"]
        lines.append(f"not determined: {LABEL.get(name, name)} (inside the interval: "
                     f"{_fmt(min(sv['grid_inside']), 4)} .. {_fmt(max(sv['grid_inside']), 4)}); "
                     f"top held-out level moves {f['min'][-1]:.4f}..{f['max'][-1]:.4f} Hz, "
                     f"zeta {z['min'][-1]:.5f}..{z['max'][-1]:.5f}, top slip/{scale} "
                     f"{sv['top_slip_over_phi_max']['min']:.3g}.."
                     f"{sv['top_slip_over_phi_max']['max']:.3g}")
    if s["assumptions"]:
        lines.append("assumed properties changed (refitted): dchi2, top held-out level shift "
                     f"[Hz], [% zeta], top slip/{scale}")
        # the shifts to one digit of the top level's noise sd: a shift is read against it,
        # and below a tenth of it it is the refits' convergence (1e-6 Hz, 1e-3 % that move
        # with the BLAS kernel), not the assumption's effect
        n, top = s["noise"], s["levels"][-1]["measured"]
        sd_f = n["sigma_omega2"][-1] / (2 * (2 * math.pi) ** 2 * top["frequency_hz"])
        sd_z = 100 * n["sigma_zeta"][-1] / top["zeta"]
        for a in s["assumptions"]:
            zeta_shift = (None if a['shift_top_zeta_rel'] is None
                          else 100 * a['shift_top_zeta_rel'])
            lines.append(f"  {a['assumption']:28s} {a['delta_chi2']:+9.2f} "
                         f"{fmt(a['shift_top_frequency_hz'], sd_f, '.3g', 1):>10s} "
                         f"{fmt(zeta_shift, sd_z, '.3g', 1):>8s}"
                         f" {a['top_slip_over_phi_max']:9.3g}")
    return lines


def format_text(s: dict) -> str:
    """Readable summary (the command's default output)."""
    return "\n".join([*_head_lines(s), *_parameter_lines(s), *_level_lines(s),
                      *_fit_state_lines(s), "misfit:", *(f"  - {t}" for t in s["misfit"]),
                      *_sensitivity_lines(s),
                      f"time: {s['timing_s']['total']:.1f} s ({s['executor']})"])


def markdown(s: dict) -> str:
    """report.md."""
    rows = "\n".join(f"| {LABEL.get(n, n)} | {p['value']:.7g} | "
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
    sens = "\n".join(f"- **{LABEL.get(n, n)}** not determined: over its likelihood region the "
                     f"held-out frequencies span {np.round(v['frequency_hz']['min'], 4).tolist()}"
                     f" .. {np.round(v['frequency_hz']['max'], 4).tolist()} Hz, zeta "
                     f"{np.round(v['zeta']['min'], 6).tolist()} .. "
                     f"{np.round(v['zeta']['max'], 6).tolist()}, top slip/phi_max "
                     f"{v['top_slip_over_phi_max']['min']:.3g} .. "
                     f"{v['top_slip_over_phi_max']['max']:.3g}"
                     + (f", R~ {v['R']['min']:.3g} .. {v['R']['max']:.3g}"
                        if math.isfinite(v['R']['min']) else "")
                     for n, v in s["sensitivity"].items()) or "- none"
    assumed = "\n".join(
        f"| {a['assumption']} | {a['delta_chi2']:+.2f} | {_fmt(a['shift_top_frequency_hz'], 3)} | "
        f"{_fmt(None if a['shift_top_zeta_rel'] is None else 100 * a['shift_top_zeta_rel'], 3)} | "
        f"{a['top_slip_over_phi_max']:.3g} |" for a in s["assumptions"]) or "| (not run) | | | | |"
    d = s["derived"]
    return f"""# FE model updating: {s['case']}

Data: `{s['source']}`, mode {s['mode']}; fitted levels {s['fit_levels']}, held out
{s['held_out_levels']}. The nonlinear FE model ({d['joint_element']},
first-harmonic balance with the exact describing function at the
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

The joint they make: {d['joint_text']}, K_T = {d['K_T_N_per_m']:.3g} N/m;
{d['structure']}, force scale {d['force_scale_N_per_unit']:g} N/V (assumed; omega^2 and zeta are exactly invariant
to it, {d['force_scale_scaling']}).

## Levels (* = held out)

| level | f measured [Hz] | f model [Hz] | error [Hz] | zeta measured | zeta model | error [%] | slip/{d.get('slip_scale_name', 'phi_max')} |
| --- | --- | --- | --- | --- | --- | --- | --- |
{lv}

![levels](update_levels.png)

## What the base model gets wrong

{chr(10).join('- ' + t for t in s['misfit'])}

## What the data do not determine, and what it changes

{sens}

![profiles](update_profiles.png)

## What the assumed properties change (each changed, the model refitted)

| assumption | delta chi2 | top held-out frequency shift [Hz] | top held-out zeta shift [%] | top slip/{d.get('slip_scale_name', 'phi_max')} |
| --- | --- | --- | --- | --- |
{assumed}
"""
