"""The diagnosis at the FE level: base and extended FE models of a case refitted to the
measured levels, judged by the one judge, their errors on levels they never saw.

:func:`fe_diagnosis` runs :func:`feloop.select.fe_select` on the fit levels
(default: all but the top three): the base FE model and each testable cause's FE
realization, judged by :func:`inverse.judge.select` (fit test, so the answer can be
``unexplained``; cost per cause; held-out gain > 1), then reports the chosen model:

* ``gain``: base / extended leave-one-level-out error over the interior fit levels
  (folds refitted from the original starts; ``None`` over failed folds);
* ``gain_held_out``: base / extended error at the levels above the fit levels (the
  paper's protocol: fit 1-7, predict 8-10);
* ``parameters``: every fitted parameter with ``at_bound``; its interval is a profile
  (:mod:`inverse.profile`) when it sits on a bound, else linearized (covariance);
* ``held_out``: per held-out level the errors in Hz and in % of zeta and the 95 %
  prediction interval (the fit's delta-method sd with bound parameters held there,
  plus the noise of the level), whether the level lies inside it, and if not by how
  many sd (``misses``, with the reason);
* ``failures``: failed simulations, folds (a fold whose fit did not converge is a failed
  fold), fits and profile points, and what did not converge, counted and named
  (``unconverged_fits``, ``unconverged_fit_names``, ``unconverged_folds``,
  ``unconverged_profile_points``; :attr:`inverse.update.Fit.converged`);
* ``verdict_own_scatter``: where a channel's scatter far above the assumed rig
  repeatability was judged against it (:mod:`inverse.judge.prior`), the verdict with
  that scatter as the noise (every candidate and fold again) and its failures, as the
  one-mode diagnosis reports it; None otherwise.
"""
from __future__ import annotations

import math

import numpy as np

from feloop.causes import force_scale_power
from feloop.select import chosen_model, fe_select
from feloop.verdict import judged_model, one_verdict, verdict_of
from inverse.fe_selection import held_out_errors, prediction_sd
from inverse.profile import bounded_interval, linear_grid, run_profiles

__all__ = ["FIT_RULE", "default_fit_mask", "fe_diagnosis", "own_scatter_verdict",
           "unconverged_fits", "parameter_table", "held_out_table", "level_entries"]

FIT_RULE = "all levels but the top three (at least 5 fitted)"
#: The acceptance tolerances of issue 13 on held-out levels.
TOLERANCE_HZ = 0.02
TOLERANCE_ZETA_REL = 0.005
Z95 = 1.959963984540054


def default_fit_mask(levels) -> np.ndarray:
    """:data:`FIT_RULE`: the lowest ``max(5, n - 3)`` levels."""
    n = len(levels)
    order = np.argsort(levels)
    mask = np.zeros(n, dtype=bool)
    mask[order[:max(5, n - 3)]] = True
    return mask


def parameter_table(problem, f, profiles: dict | None = None,
                    force_scale: float = 1.0) -> dict:
    """Every fitted parameter of fit ``f``: value, unit, ``at_bound`` (False or the
    bound's side), interval and its kind (profile at a bound, covariance inside), and
    ``rests_on`` where the value scales with the assumed ``force_scale`` (N per
    excitation unit; :func:`feloop.causes.force_scale_power`)."""
    out = {}
    for name in f.free:
        p = problem.parameters[name]
        side = f.at_bound.get(name, False)
        entry = {"value": f.values[name], "unit": p.unit, "kind": "fitted",
                 "lower_bound": p.lower, "upper_bound": p.upper, "at_bound": side}
        if profiles and name in profiles:
            pr = profiles[name]
            entry.update(interval=list(bounded_interval(pr, p.lower, p.upper, side)),
                         interval_kind="profile likelihood 95 %", status=pr.status)
        else:
            se = f.std_error(name)
            entry.update(std_error=se, interval=[f.values[name] - Z95 * se,
                                                 f.values[name] + Z95 * se]
                         if math.isfinite(se) else [None, None],
                         interval_kind="linearized 95 % (misfit-scaled covariance)")
        if force_scale_power(name):
            entry["rests_on"] = (f"the force scale {force_scale:g} N per excitation unit "
                                 f"(assumed): it scales as s^{force_scale_power(name)}")
        out[name] = entry
    return out


def bound_profiles(problem, f, points: int = 4) -> dict:
    """Profiles of the parameters of ``f`` that sit on a bound (inward branch only)."""
    names = [n for n in f.free if f.at_bound.get(n)]
    if not names:
        return {}
    grids = {n: linear_grid(f, n, problem.parameters[n], points) for n in names}
    return run_profiles(problem, f, grids, f.free)


def _miss_reason(row, fit_ok: bool, bound: list) -> str:
    why = ("the fit levels lie within their noise, so the model form fails only beyond "
           "them (an extrapolation past the fitted amplitudes)" if fit_ok else
           "the model already misfits the fit levels")
    if bound:
        why += (f"; {', '.join(bound)} held at its bound (the interval does not include "
                f"what the model would do past it)")
    return why


def held_out_table(data, mask, pred, problem, f, fit_ok: bool) -> tuple:
    """Per held-out level: errors, prediction sd and 95 % interval (module docstring);
    and the list of levels outside it, with sd and reason."""
    held = ~np.asarray(mask, dtype=bool)
    sd = prediction_sd(problem, f, held)
    f_meas = np.sqrt(data.omega2) / (2 * math.pi)
    noise = problem.noise
    bound = [n for n in f.free if f.at_bound.get(n)]
    rows, misses = [], []
    # a singular covariance gives no parameter sd: the noise alone, and the row says so
    known = all(math.isfinite(v) for v in (*sd["frequency_hz"], *sd["zeta"]))
    for j, i in enumerate(np.flatnonzero(held)):
        s_nf = float(noise.sigma_omega2[i]) / (8 * math.pi ** 2 * f_meas[i])
        s_nz = float(noise.sigma_zeta[i])
        m_f, m_z = (sd["frequency_hz"][j], sd["zeta"][j]) if known else (0.0, 0.0)
        tot_f = math.hypot(m_f, s_nf)
        tot_z = math.hypot(m_z, s_nz)
        e_f = float(pred.frequency_hz[i] - f_meas[i])
        e_z = float(pred.zeta[i] - data.zeta[i])
        row = {"level": int(data.level[i]), "error_hz": e_f,
               "error_zeta_rel": float(pred.zeta[i] / data.zeta[i] - 1.0),
               "model_sd_hz": sd["frequency_hz"][j], "noise_sd_hz": s_nf,
               "pi95_half_width_hz": Z95 * tot_f,
               "model_sd_zeta_rel": sd["zeta"][j] / float(data.zeta[i]),
               "pi95_half_width_zeta_rel": Z95 * tot_z / float(data.zeta[i]),
               "z_frequency": e_f / tot_f, "z_zeta": e_z / tot_z,
               "sd_kind": ("parameters (delta method) and noise" if known else
                           "noise alone: the fit's covariance is singular")}
        row["inside_pi95"] = bool(abs(row["z_frequency"]) <= Z95 and abs(row["z_zeta"]) <= Z95)
        rows.append(row)
        if not row["inside_pi95"]:
            ch = [f"frequency {row['z_frequency']:+.1f} sd" if abs(row["z_frequency"]) > Z95
                  else None, f"zeta {row['z_zeta']:+.1f} sd" if abs(row["z_zeta"]) > Z95
                  else None]
            misses.append({"level": row["level"], "by": ", ".join(c for c in ch if c),
                           "z_frequency": row["z_frequency"], "z_zeta": row["z_zeta"],
                           "why": _miss_reason(row, fit_ok, bound)})
    return rows, misses


def fe_diagnosis(data, mask=None, force_scale: float = 1.0, causes=None,
                 progress=None, levels=None) -> dict:
    """FE-level diagnosis of one mode's levels (module docstring).

    Parameters
    ----------
    data : ident.modal_data.MeasuredData, one mode, levels sorted.
    mask : (L,) bool, optional
        Fit levels (default :func:`default_fit_mask`); the others are held out.
    force_scale : float, N per excitation unit (every omega^2, zeta is invariant to it).
    causes : iterable of cause ids (default: every FE extension).
    progress : callable(str) or None, told what is being fitted.
    levels : callable(data, force_scale=) -> FE-levels model (the case's ``fe_levels``
        capability, a :class:`feloop.levels.FELevels`).

    Returns
    -------
    dict with ``fe_levels``, ``fe`` (cause, also, fit test, gains, errors, parameters).
    """
    mask = default_fit_mask(data.level) if mask is None else np.asarray(mask, dtype=bool)
    if mask.sum() < 5:
        raise ValueError(f"the FE diagnosis needs at least 5 fit levels, got {int(mask.sum())}")
    fe = levels(data, force_scale=force_scale)
    s = fe_select(data, mask, fe, causes, progress)
    every = judged_model(data, mask, fe, s, causes, progress)   # the top judged too
    own = None
    if s["judge_noise"].capped():
        say = progress or (lambda m: None)
        own = own_scatter_verdict(fe_select(data, mask, fe, causes,
                                            lambda m: say(f"own scatter: {m}"), cap=False))
    return report(data, mask, s, own, every)


def own_scatter_verdict(s: dict) -> dict:
    """The verdict of a :func:`fe_select` result judged with the data's own scatter
    (``cap=False``): cause, also, candidate, unexplained, fit test, failures."""
    cands = s["judged"]["candidates"].values()
    return s["judged"]["selection"].verdict_json(
        {"fits": sum(c.fit is None for c in cands), "folds": sum(c.cv_failed for c in cands),
         "unconverged_fits": len(unconverged_fits(s))})


def unconverged_fits(s: dict) -> list:
    """Names of the fits of a :func:`fe_select` result (base and candidates) that gave a
    chi2 but did not converge (:attr:`inverse.update.Fit.converged`)."""
    return [c.name for c in s["judged"]["candidates"].values()
            if c.fit is not None and not c.fit.converged]


def _failures(s: dict, profiles: dict, levels, base_pred, ext_pred) -> dict:
    """Failed simulations, folds, fits and profile points of a :func:`fe_select` result,
    what did not converge, and the levels reached by a fallback (module docstring)."""
    cands = s["judged"]["candidates"].values()
    return {"simulations": sum(c.fit.failed_simulations for c in cands if c.fit is not None),
            "folds": sum(c.cv_failed for c in cands),
            "fits": sum(c.fit is None for c in cands),
            "profile_points": sum(p.failed_points for p in profiles.values()),
            "unconverged_fits": len(unconverged_fits(s)),
            "unconverged_fit_names": unconverged_fits(s),
            "unconverged_folds": sum(c.cv_unconverged for c in cands),
            "unconverged_profile_points": sum(p.unconverged_points for p in profiles.values()),
            "convergence": "Gauss-Newton decrement below 1e-4 chi2 units (inverse.decrement)",
            "fallbacks": {n: p.fallback_lines(levels) for n, p in
                          (("base", base_pred), ("extended", ext_pred))}}


def report(data, mask, s: dict, own: dict | None = None, every: tuple | None = None) -> dict:
    """``fe_levels`` and ``fe`` of a :func:`fe_select` result (module docstring);
    ``own``: :func:`own_scatter_verdict` of the uncapped selection, or None; ``every``:
    :func:`feloop.verdict.judged_model` (the choice with all levels fitted names the FE
    cause; the model is that cause fitted to the fit levels), or None."""
    fe, base = s["fe"], s["base"]
    sel, judged = s["judged"]["selection"], s["judged"]
    every, name, note = every or (None, s["chosen"], None)
    ext, chosen = chosen_model(s, name)
    f, prob = chosen.fit, chosen.problem
    base_pred = fe.predict(base.fit.values)
    ext_pred = fe.predict(f.values, ext)
    test = sel.tests[chosen.name]
    profiles = bound_profiles(prob, f)
    rows, misses = held_out_table(data, mask, ext_pred, prob, f, test.passes())
    errs_b = held_out_errors(base.problem, base.fit.values)
    errs_e = held_out_errors(prob, f.values)
    base_cv = judged["base_cv_error"]
    ext_cv = chosen.cv_error if chosen.causes else base_cv

    def ratio(a, b):
        return (a / b if b else math.inf) if a is not None and b is not None else None

    base_err = {r["level"]: float(base_pred.frequency_hz[i] - math.sqrt(data.omega2[i])
                                  / (2 * math.pi))
                for i, r in zip(np.flatnonzero(~mask), rows)}
    for r in rows:                                 # the base model's errors beside them
        r["base_error_hz"] = base_err[r["level"]]
        r["extended_error_hz"] = r["error_hz"]
    met = bool(rows) and all(abs(r["error_hz"]) <= TOLERANCE_HZ and
                             abs(r["error_zeta_rel"]) <= TOLERANCE_ZETA_REL for r in rows)
    reading = ext.reading(f.values, fe, fe.linear(10 ** f.values["log10_kt"]), ext_pred) \
        if ext is not None else {}
    failures = _failures(s, profiles, data.level, base_pred, ext_pred)
    verdict = one_verdict(verdict_of(s), every, misses, name,
                          [int(v) for v in data.level[mask]])
    judged_on = every or verdict_of(s)
    summary = {
        "model": fe.label, "cause": verdict["cause"], "also": verdict["also"],
        "candidate": chosen.name, "verdict": verdict, "notes": [note] if note else [],
        "fit_levels_verdict": sel.verdict_json(),
        "all_levels": None if every is None else {k: v for k, v in every.items()
                                                  if k != "choice"},
        "fit_levels": [int(v) for v in data.level[mask]],
        "held_out_levels": [int(v) for v in data.level[~mask]],
        "noise": s["judge_noise"].to_json({"omega2": data.omega2, "zeta": data.zeta}),
        "noise_sigma": s["noise"].to_dict(), "fit_test": test.to_json(),
        "unexplained": verdict["unexplained"],
        "closest_miss": judged_on["closest_miss"], "ambiguous": bool(judged_on["rivals"]),
        "rivals": judged_on["rivals"],
        "untested": s["untested"], "estimator_start": s["estimator_start"],
        "engagement": s["engagement"].to_json(), "engagement_text": s["engagement"].line(),
        "base_fit": base.fit.to_dict(), "extended_fit": f.to_dict(),
        "parameters": parameter_table(prob, f, profiles, fe.force_scale),
        "profiles": {n: p.to_dict() for n, p in profiles.items()},
        "evidence": judged["evidence"], "rule": "inverse.judge.select",
        "base_error": base_cv, "extended_error": ext_cv, "gain": ratio(base_cv, ext_cv),
        "base_error_held_out": errs_b, "extended_error_held_out": errs_e,
        "gain_held_out": ratio(errs_b, errs_e),
        "held_out": rows, "misses": misses, "verdict_own_scatter": own,
        "acceptance": {"tolerance_hz": TOLERANCE_HZ, "tolerance_zeta_rel": TOLERANCE_ZETA_REL,
                       "met": met},
        "failures": failures,
        "reading": reading, "joint": {k: v for k, v in ext_pred.joint.items()},
        "error_measure": "rms residual in noise units over both channels (omega2, zeta)",
    }
    fe_rows = level_entries(data, mask, {"base": base_pred, "extended": ext_pred})
    return {"fe_levels": fe_rows, "fe": summary}


def level_entries(data, mask, models: dict) -> list:
    """One dict per level of ``data``: ``level``, ``held_out`` (not in ``mask``), ``measured``
    and each of ``models`` (name -> LevelPrediction), each as ``{frequency_hz, zeta}``."""
    f_meas = np.sqrt(data.omega2) / (2 * math.pi)
    rows = []
    for i, lv in enumerate(data.level):
        row = {"level": int(lv), "held_out": bool(not mask[i]),
               "measured": {"frequency_hz": float(f_meas[i]), "zeta": float(data.zeta[i])}}
        for name, pred in models.items():
            row[name] = {"frequency_hz": float(pred.frequency_hz[i]), "zeta": float(pred.zeta[i])}
        rows.append(row)
    return rows
