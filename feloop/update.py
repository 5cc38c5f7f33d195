"""Model updating of any case's FE model: the joints, the damping and the frequency
fitted to the measured levels by the nonlinear FE simulation itself, in the form the one
judge selects.

:func:`run_update` (``iwanfe update --case NAME|FILE``; the case gives its FE-levels
model, :class:`feloop.levels.FELevels`, and its data):

1. the measured mode's levels and the fit levels;
2. the model choice of :func:`feloop.select.fe_select`, the same as
   ``diagnose --case``: the base FE model (one continuous Iwan element per joint
   element, viscous modal damping, first-harmonic balance at phase resonance; ``chi``,
   ``ln_dc1`` = ``|kappa1| B~`` at level 1, ``zeta_v``, ``f0_hz`` fitted at the case's
   assumed ``K_T``) and each testable cause's FE realization, judged by
   :func:`inverse.judge.select` (fit test, cost per cause, held-out gain > 1, noise of
   :func:`inverse.judge.noise_model`). The updated model is the selected one (the
   closest candidate when the answer is ``unexplained``, and the report says so);
3. profile likelihoods (:mod:`inverse.profile`) of the fitted parameters on a bound,
   as executor tasks; the others get linearized intervals. With ``--profiles all``:
   of every fitted parameter, and of ``log10_kt`` (each K_T its own model, calibrated
   again as the case calibrates; a grid value is adopted only when it lowers chi2 by more
   than the cost of one parameter, :data:`FREE_COST`; K_T is then *fitted* on the grid);
4. along the profiles of what the data do not determine, the range of every headline
   figure: predicted frequency and damping at the held-out levels, top slip over
   ``phi_max``;
5. with ``--assumptions``, the same figures after refitting with each assumed
   property of the case changed (:mod:`feloop.assumptions`; the changes are the
   case's ``assumptions`` capability).

The force scale (N per excitation unit) is not a parameter: every simulated omega^2 and
zeta is exactly invariant to it (:mod:`feloop.levels`); R~, phi_max and
F_S are stated at the assumed 1 N/V and scale as ``s^-(chi+1)``, ``s``, ``s``.
"""
from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass

import numpy as np

from feloop.causes import MacroSlip
from feloop.engagement import KT_GRID
from feloop.levels import BASE_PARAMETERS, abscissa_of
from feloop.diagnosis import held_out_table
from feloop.select import chosen_model, fe_select
from feloop.verdict import judged_model, one_verdict, verdict_of
from ident.measured import read_measured
from inverse.estimate import parse_levels
from inverse.profile import linear_grid, run_profiles
from inverse.update import fit

__all__ = ["UpdateSettings", "load_levels", "problem_digest", "run_update"]

#: Parameters ``update`` may fit: the base ones and those of the FE causes.
UPDATED_PARAMETERS = BASE_PARAMETERS + ("ln_phimax", "drag_cd", "k3", "drift", "inv_e_sat")


@dataclass(frozen=True)
class UpdateSettings:
    """What ``iwanfe update`` fits: the data (the case's table, its mode label), the fit
    levels, the force scale (N per excitation unit, assumed), the profile
    confidence, the K_T grid (log10 N/m), the points per profile branch, whether to
    refit under changed assumptions, which parameters to profile (``bound``: those on a
    bound; ``all``), what the user states of the rig's repeatability
    (:attr:`ident.modal_data.MeasuredData.rig_repeatability`)."""

    data_path: str | None = None
    mode_label: int = 2
    fit_levels: str = "1-7"
    force_scale: float = 1.0
    confidence: float = 0.95
    kt_grid: tuple = KT_GRID
    profile_points: int = 3
    assumptions: bool = False
    profiles: str = "bound"
    rig_repeatability: tuple | None = None

    def __post_init__(self):
        if not (math.isfinite(self.force_scale) and self.force_scale > 0):
            raise ValueError(f"force scale must be a positive number, got {self.force_scale!r}")
        if not 0 < self.confidence < 1:
            raise ValueError(f"confidence must be in (0, 1), got {self.confidence!r}")
        parse_levels(self.fit_levels)
        if self.profiles not in ("bound", "all"):
            raise ValueError(f"profiles must be 'bound' or 'all', got {self.profiles!r}")


def load_levels(settings: UpdateSettings):
    """The measured levels and the fit mask."""
    if settings.data_path is None:
        raise ValueError("no measured data: give --data (the case names none)")
    data = read_measured(settings.data_path).for_mode(settings.mode_label)
    data.rig_repeatability = settings.rig_repeatability
    abscissa_of(data)                      # a series no FE route models: one line
    if len(data) < 5:
        raise ValueError(f"mode {settings.mode_label}: {len(data)} levels in the data, "
                         f"need at least 5")
    fit_levels = parse_levels(settings.fit_levels)
    missing = sorted(set(fit_levels) - set(map(int, data.level)))
    if missing:
        raise ValueError(f"--fit-levels: level(s) {missing} not in the data "
                         f"(levels {list(map(int, data.level))})")
    if len(fit_levels) < 5:
        raise ValueError(f"--fit-levels: need at least 5 levels, got {len(fit_levels)}")
    return data, np.isin(data.level, fit_levels)


def _ranges(items: list) -> dict:
    """Elementwise min/max over a list of headline dicts."""
    out = {}
    for k in items[0]:
        a = np.array([it[k] for it in items], dtype=float)
        out[k] = {"min": a.min(axis=0).tolist(), "max": a.max(axis=0).tolist()}
    return out


def problem_digest(data, mask, settings: UpdateSettings, model: str = "") -> str:
    """SHA-256 of everything a profile branch depends on besides its task: the data,
    the fit levels, the settings and the FE model's configuration."""
    h = hashlib.sha256(b"iwanfe-update/1")
    for a in (data.level, data.excitation, data.omega2, data.zeta, data.run_order, mask):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr((settings, model)).encode())
    return h.hexdigest()


#: chi2 drop that frees an assumed parameter (K_T): the judge's cost of one parameter
#: (AIC, :mod:`inverse.judge`).
FREE_COST = 2.0


def _adopt(problem, best, profiles):
    """A profile point better than ``best`` refitted there: a second optimum of the
    fitted parameters at any drop; a grid value of an assumed one (K_T) only when it
    lowers chi2 by more than :data:`FREE_COST` (it then costs one parameter)."""
    for name, pr in profiles.items():
        low = min(pr.points, key=lambda p: p.chi2)
        cost = 1e-6 if name in best.free else FREE_COST
        if low.values is not None and low.chi2 < best.chi2 - cost:
            again = fit(problem, best.free, start=low.values)
            best = again if again.chi2 <= low.chi2 else fit(problem, (), start=low.values)
    return best


def run_update(settings: UpdateSettings, levels, executor="serial", progress: bool = False,
               store=None, case_name: str = "", model_key: str = "", assumptions=None) -> dict:
    """Select, fit, profile and assess the FE model (module docstring). ``store``: a
    directory where finished profile branches are kept (a rerun loads them);
    ``levels(data, force_scale=)``: the case's FE-levels model
    (:class:`feloop.levels.FELevels`), ``case_name`` and ``model_key`` (what the
    model is built from, for the store's digest) go with it; ``assumptions``: name ->
    ``levels`` under a changed assumed property (:mod:`feloop.assumptions`),
    needed when ``settings.assumptions``. Returns a dict (rendered by
    :mod:`feloop.update_report`)."""
    t0 = time.perf_counter()
    data, mask = load_levels(settings)
    if settings.assumptions and not assumptions:
        raise ValueError(f"case {case_name!r} names no assumed property to change "
                         "(--assumptions)")
    fe = levels(data, force_scale=settings.force_scale)
    sel = fe_select(data, mask, fe)
    every, model_name, note = judged_model(data, mask, fe, sel)   # the top judged too
    ext, chosen = chosen_model(sel, model_name)
    problem, best, noise = chosen.problem, chosen.fit, sel["noise"]
    P, free = problem.parameters, best.free
    t_sel = time.perf_counter() - t0
    store = None if store is None else (store, problem_digest(data, mask, settings, model_key))
    profiles = {}
    if settings.profiles == "all":
        kt = best.values["log10_kt"]
        kt_grid = {"log10_kt": ([g for g in sorted(settings.kt_grid, reverse=True) if g < kt],
                                [g for g in sorted(settings.kt_grid) if g > kt])}
        profiles = run_profiles(problem, best, kt_grid, free, settings.confidence,
                                executor=executor, progress=progress, store=store)
        best = _adopt(problem, best, profiles)
    names = [n for n in free if settings.profiles == "all" or best.at_bound.get(n)
             or n in fe.form.profiled]
    grids = {n: linear_grid(best, n, P[n], settings.profile_points) for n in names}
    if grids:
        profiles.update(run_profiles(problem, best, grids, free, settings.confidence,
                                     executor=executor, progress=progress, store=store))
        best = _adopt(problem, best, profiles)
    t_prof = time.perf_counter() - t0 - t_sel
    assumed = []
    if settings.assumptions:
        from feloop.assumptions import assumption_sensitivity

        assumed = assumption_sensitivity(data, mask, noise, P, best, settings.force_scale,
                                         assumptions, executor, extension=ext)
    sens = {}
    for name, pr in profiles.items():
        if pr.status != "determined":
            inside = [p for p in pr.inside() if p.extra is not None]
            sens[name] = _ranges([p.extra for p in inside])
            sens[name]["grid_inside"] = [p.value for p in inside]
    base = sel["base"].fit
    prediction = fe.predict(best.values, ext)
    rows, misses = held_out_table(data, mask, prediction, problem, best,
                                  sel["judged"]["selection"].tests[model_name].passes())
    verdict = one_verdict(verdict_of(sel), every, misses, model_name,
                          [int(v) for v in data.level[mask]])
    return {
        "case": case_name, "settings": settings, "data": data, "fit_mask": mask, "noise": noise,
        "selection": sel, "extension": ext, "candidate": chosen.name,
        "all_levels": every, "verdict": verdict, "held_out": rows, "misses": misses,
        "notes": [note] if note else [],
        "parameters": P, "fit": best, "base_fit": base, "profiles": profiles,
        "micro_limit": MacroSlip.micro_limit(fe, best.values)
        if fe.form.law == "iwan4" else None,
        "prediction": prediction, "base_prediction": fe.predict(base.values),
        "nominal": problem.describe(best.values), "sensitivity": sens,
        "executor": executor if isinstance(executor, str) else executor.describe(),
        "assumptions": assumed,
        "timing_s": {"model choice (fits, judge)": t_sel, "profiles and refit": t_prof,
                     "assumptions": time.perf_counter() - t0 - t_sel - t_prof,
                     "total": time.perf_counter() - t0},
    }
