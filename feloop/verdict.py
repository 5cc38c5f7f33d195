"""One FE verdict from all levels: the top levels are evidence, never only a test.

The FE model choice (:func:`feloop.select.fe_select`) on the fit levels predicts the
held-out ones; a cause whose effect shows only at the top (a hardening, a slip onset)
is invisible to it, and its held-out levels miss. So the FE cause is judged again with
*every* level fitted (:func:`all_levels_choice`: the same candidates, the same judge,
its leave-one-level-out gain over the interior levels, now the held-out ones among
them), and the answer keeps the leave-top-out gain of that cause: the candidate fitted
to the fit levels alone, its rms error at the held-out levels against the base
model's (:func:`leave_top_out_gain`). :func:`one_verdict` words both choices, says
first which held-out levels miss their 95 % prediction intervals and, where the two
choices differ, why.

The model a command reports for the held-out levels is the cause named with all levels,
fitted to the fit levels (:func:`model_of`): its errors there are predictions.
"""
from __future__ import annotations

import math

import numpy as np

from feloop.select import fe_select
from inverse.fe_selection import held_out_errors

__all__ = ["verdict_of", "judged_model", "all_levels_choice", "leave_top_out_gain", "model_of",
           "one_verdict", "misses_text", "agreement_text", "one_mode_agreement"]


def verdict_of(choice: dict) -> dict:
    """The verdict of a :func:`fe_select` result: ``cause``, ``also``, ``candidate`` (the
    one named, the closest when unexplained), ``unexplained``, ``closest_miss``,
    ``rivals``, ``fit_test`` and ``gain`` (cross-validated; None for ``none``)."""
    sel, ev = choice["judged"]["selection"], choice["judged"]["evidence"]
    name = choice["chosen"]
    return {"cause": sel.cause, "also": sel.also, "candidate": name,
            "unexplained": sel.unexplained, "closest_miss": sel.closest_miss,
            "rivals": sel.rivals, "fit_test": sel.tests[name].to_json(),
            "gain": ev[name]["gain"] if name != "none" else None}


def leave_top_out_gain(fit_choice: dict, name: str) -> float | None:
    """Base error / error of candidate ``name`` at the held-out levels, both fitted to
    the fit levels of ``fit_choice`` (a :func:`fe_select` result); None when the
    candidate was not fitted there (or its fit failed), 1.0 for ``none``."""
    if name == "none":
        return 1.0
    entry = fit_choice["extensions"].get(name)
    base = fit_choice["base"]
    if entry is None or entry[1].fit is None:
        return None
    c = entry[1]
    e_b = held_out_errors(base.problem, base.fit.values)
    e_x = held_out_errors(c.problem, c.fit.values)
    if e_b is None or e_x is None or not (math.isfinite(e_b) and math.isfinite(e_x)):
        return None
    return e_b / e_x if e_x > 0 else math.inf


def all_levels_choice(data, mask, fe, fit_choice: dict, causes=None,
                      progress=None) -> dict | None:
    """The FE model choice with every level fitted (module docstring), or None when
    ``mask`` holds every level already. Returns the verdict (``cause``, ``also``,
    ``candidate``, ``unexplained``, ``closest_miss``, ``rivals``, ``fit_test``), ``gain``
    (cross-validated over all levels, None for ``none``), ``gain_leave_top_out``
    (:func:`leave_top_out_gain` on ``fit_choice``), ``evidence`` and ``choice`` (the
    :func:`fe_select` result)."""
    mask = np.asarray(mask, dtype=bool)
    if mask.all():
        return None
    say = progress or (lambda m: None)
    s = fe_select(data, np.ones_like(mask), fe, causes, lambda m: say(f"all levels: {m}"),
                  earlier=fit_choice)
    return {**verdict_of(s), "gain_leave_top_out": leave_top_out_gain(fit_choice, s["chosen"]),
            "levels": [int(v) for v in data.level], "evidence": s["judged"]["evidence"],
            "choice": s}


def judged_model(data, mask, fe, fit_choice: dict, causes=None, progress=None) -> tuple:
    """(:func:`all_levels_choice`, candidate of the model, note of :func:`model_of`): what
    every FE command does after its fit-level choice."""
    every = all_levels_choice(data, mask, fe, fit_choice, causes, progress)
    return (every, *model_of(fit_choice, every))


def model_of(fit_choice: dict, all_levels: dict | None) -> tuple[str, str | None]:
    """(candidate whose fit to the fit levels is the model, note): the candidate the
    judge chose with all levels when the fit-level choice fitted it (its errors at the
    held-out levels are then predictions of the cause named), else the fit-level
    choice, with why."""
    own = fit_choice["chosen"]
    if all_levels is None or all_levels["candidate"] == own:
        return own, None
    name = all_levels["candidate"]
    if name == "none":
        return name, None
    entry = fit_choice["extensions"].get(name)
    if entry is not None and entry[1].fit is not None:
        return name, None
    why = "not fitted" if entry is None else (entry[1].excluded or "its fit failed")
    return own, (f"{name} (chosen with all levels) on the fit levels alone: {why}; "
                 f"the model is the fit-level choice {own}")


def misses_text(misses: list, model: str, fit_levels: list) -> str | None:
    """The held-out levels outside their 95 % prediction intervals, in one sentence
    (None when every held-out level is inside)."""
    if not misses:
        return None
    span = f"{fit_levels[0]}-{fit_levels[-1]}" if fit_levels else "the fit levels"
    return (f"held-out levels outside their 95 % prediction intervals ({model} fitted to "
            f"levels {span}): " + "; ".join(f"level {m['level']} by {m['by']}"
                                           for m in misses))


def _name(cause: str, also: list) -> str:
    return cause + "".join(f" + {a}" for a in also)


def agreement_text(fit_verdict: dict, all_levels: dict) -> str:
    """Whether the choice on the fit levels and the one with all levels agree; why not
    when they differ (the all-levels judge's reason against the fit-level answer)."""
    a = _name(all_levels["cause"], all_levels["also"])
    f = _name(fit_verdict["cause"], fit_verdict["also"])
    if a == f:
        return f"the fit levels alone give the same answer ({f})"
    why = all_levels["evidence"].get(fit_verdict["candidate"], {}).get("why_not")
    top = all_levels["gain_leave_top_out"]
    lines = [f"the fit levels alone give {f}"]
    if all_levels["candidate"] != "none" and fit_verdict["candidate"] == "none":
        lines.append(f"the top levels show what the fit levels do not: {a} predicts the "
                     f"held-out levels from the fit levels with gain "
                     + ("n/a" if top is None else f"{top:.3g}")
                     + " and explains them once they are fitted")
    elif why:
        lines.append(f"with all levels, {f}: {why}")
    return "; ".join(lines)


def one_verdict(fit_verdict: dict, all_levels: dict | None, misses: list,
                model: str, fit_levels: list) -> dict:
    """The FE verdict of a command (module docstring): ``cause``, ``also``,
    ``unexplained`` (judged with all levels when there are held-out levels),
    ``judged_on`` ("all levels" or "fit levels"), ``misses_text`` (first),
    ``agreement`` and ``lines`` (the words, in order)."""
    v = all_levels or fit_verdict
    out = {"cause": v["cause"], "also": v["also"], "unexplained": v["unexplained"],
           "judged_on": "all levels" if all_levels else "fit levels",
           "misses_text": misses_text(misses, model, fit_levels),
           "agreement": agreement_text(fit_verdict, all_levels) if all_levels else None}
    gain = v.get("gain")
    head = (f"FE cause ({out['judged_on']} fitted): {_name(v['cause'], v['also'])}"
            + (f" (closest candidate {v['candidate']}: {v['closest_miss']['why']})"
               if v["unexplained"] and v.get("closest_miss") else "")
            + (f", cross-validated gain {gain:.3g}" if gain is not None else ""))
    if all_levels and all_levels["candidate"] != "none":
        top = all_levels["gain_leave_top_out"]
        head += ("; leave-top-out gain " + ("n/a" if top is None else f"{top:.3g}")
                 + " (fitted to the fit levels, predicting the held-out ones)")
    out["lines"] = [t for t in (out["misses_text"], head, out["agreement"]) if t]
    return out


def one_mode_agreement(one_mode: dict, fe: dict) -> str:
    """The one-mode diagnosis's verdict beside the FE one (``fe``: the ``fe`` dict of
    :func:`feloop.diagnosis.report`): the same, or why they differ, from what the FE
    level says of the one-mode cause (not tested there and why, or the judge's reason
    against its FE realization) and the causes the FE level named."""
    a = _name(one_mode["cause"], one_mode["also"])
    f = _name(fe["cause"], fe["also"])
    if a == f:
        return f"one-mode and FE diagnoses agree: {a}"
    words = [f"one-mode diagnosis: {a}; FE level: {f}"]
    ev = (fe.get("all_levels") or {}).get("evidence") or fe["evidence"]
    for cause in [one_mode["cause"], *one_mode["also"]]:
        if cause in ("none", "unexplained"):
            continue
        if cause in fe["untested"]:
            words.append(f"{cause} is not tested at the FE level ({fe['untested'][cause]})")
        elif cause in ev:
            why = ev[cause].get("why_not")
            words.append(f"at the FE level {cause} " + (f"is not named: {why}" if why else
                                                        "is eligible but outweighed"))
    for cause in [fe["cause"], *fe["also"]]:
        if cause not in ("none", "unexplained") and cause not in (one_mode["cause"],
                                                                   *one_mode["also"]):
            e = (one_mode.get("evidence") or {}).get(cause, {})
            why = e.get("why_not") or e.get("reason")
            words.append(f"in the one-mode diagnosis {cause} " + (
                f"is not named: {why}" if why else "is eligible but outweighed"))
    if len(words) == 1:
        words.append("why they differ is unexplained by the evidence of either")
    return "; ".join(words)
