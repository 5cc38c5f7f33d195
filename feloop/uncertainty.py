"""Monte Carlo of any case's FE predictions over ``update``'s selected model, or over
a given one (``uncertainty --model DIR/updated_model.json``, :mod:`feloop.given_model`:
its values the nominal, its stored fit the distribution, no model choice run).

The nominal model is the one ``iwanfe update`` writes for the same fit levels
(:func:`feloop.update.run_update` without ``--assumptions``: the model the one
judge selects, the base FE model or the cause it names, the closest candidate when the
answer is ``unexplained``; its parameters fitted by weighted least squares to omega^2
and zeta of the fit levels, :mod:`inverse.update`). Its free parameters not on a bound
are drawn from the fit's linearized distribution (:class:`inverse.uncertainty.
FitDistribution`: Student t with the fit's residual dof or normal, the covariance
widened by the misfit, truncated to the parameters' bounds; parameters on a bound are
held, as in the fit's prediction intervals), one executor task and one seed stream per
sample, resumable store. Each sample is simulated at every level by the case's FE-levels
model (:class:`feloop.levels.FELevels`: first-harmonic balance at phase
resonance with the exact describing function, from a cold start: a few ms per sample).

A sample must be physical, else it is counted failed with its reason and left out of
the quantiles (:func:`physical_check`): its joints have a positive strength (``F_S``,
``phi_max`` > 0) and, unless the model's cause stiffens (:attr:`feloop.causes.
Extension.stiffens`), no level's frequency lies above the stuck-joint frequency
``f0_hz`` and no damping ratio below the viscous ``zeta_v`` (an Iwan joint softens
and dissipates). The report gives per level the measured value, the nominal prediction
and the samples' median and central interval, and how far the nominal misses its fit
levels (rms in noise sd, the fit test). (The double beam's own Monte Carlo, a
Jenkins-bank stepped sine per sample, is :mod:`cases.double_beam.uncertainty`.)

SI units: Hz, rad^2/s^2; damping ratios as fractions.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from feloop.update import UpdateSettings, load_levels, run_update
from ident.errors import InputError
from inverse.fe_selection import fit_test_of
from inverse.sample_store import SampleStore, describe
from inverse.uncertainty import FitDistribution, SweepInputs, run_samples, sweep_hash
from runs.executor import ExecutorSpec

__all__ = ["LevelsStudy", "LevelsSweepInputs", "physical_check", "simulate_levels",
           "run_fe_uncertainty"]

#: Round-off allowed in the physical checks (relative).
PHYSICAL_RTOL = 1e-6


@dataclass(frozen=True)
class LevelsStudy:
    """What a sample depends on besides the data and the FE model (hashed into the
    store's name): the data file, mode label, fit levels, force scale (N per excitation
    unit, assumed), the case's name and the selected candidate (set by
    :func:`run_fe_uncertainty`)."""

    data_path: str | None
    mode_label: int
    fit_levels: str
    force_scale: float = 1.0
    case: str = ""
    candidate: str = ""


@dataclass(frozen=True)
class LevelsSweepInputs(SweepInputs):
    """:class:`inverse.uncertainty.SweepInputs` with the case's FE-levels builder
    ``levels(data, force_scale=)`` and the selected model's extension (None: the base
    model); picklable."""

    levels: object = None
    extension: object = None


_CACHE: dict = {}      # per process: the FE-levels model of one sweep


def _prepared(inputs: LevelsSweepInputs):
    key = (id(inputs), inputs.study)
    if _CACHE.get("key") != key:
        _CACHE.update(key=key, fe=inputs.levels(inputs.data,
                                                force_scale=inputs.study.force_scale))
    return _CACHE["fe"]


def physical_check(pred, values: dict, stiffens: bool = False) -> None:
    """ValueError (one line, the first level that fails) unless prediction ``pred``
    (:class:`feloop.levels.LevelPrediction`) of parameter set ``values`` is
    physical (module docstring)."""
    fs, pm = pred.joint["F_S"], pred.joint["slip_scale"]
    if not (math.isfinite(fs) and fs > 0 and math.isfinite(pm) and pm > 0):
        raise ValueError(f"no joint: strength F_S = {fs:.3g} N, slip scale {pm:.3g} m")
    f, z = pred.frequency_hz, pred.zeta
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(z))):
        raise ValueError("a level's frequency or damping ratio is not finite")
    if stiffens:
        return
    f0, zv = float(values["f0_hz"]), float(values["zeta_v"])
    for i in range(f.size):
        if f[i] > f0 * (1 + PHYSICAL_RTOL):
            raise ValueError(f"level index {i}: frequency {f[i]:.6g} Hz above the "
                             f"stuck-joint frequency {f0:.6g} Hz")
        if z[i] < zv * (1 - PHYSICAL_RTOL):
            raise ValueError(f"level index {i}: damping ratio {z[i]:.4g} below the "
                             f"viscous one {zv:.4g}")


def simulate_levels(inputs: LevelsSweepInputs, values: dict) -> dict:
    """One sample (module docstring): the parameter set ``values`` simulated from a cold
    start and checked. Returns ``frequency_hz``, ``zeta``, ``slip_over_phi_max``
    (n_levels,) and ``chi``, ``R``, ``phi_max``, ``F_S``, ``zeta_viscous``, ``f0_hz``,
    ``fallback_levels`` (levels whose steady state needed a fallback,
    :attr:`feloop.levels.LevelPrediction.fallbacks`)."""
    fe = _prepared(inputs)
    fe.reset()             # no warm start: a sample's bits do not depend on the executor
    ext = inputs.extension
    pred = fe.predict(values, ext)
    physical_check(pred, values, bool(getattr(ext, "stiffens", False)))
    return {"frequency_hz": pred.frequency_hz, "zeta": pred.zeta,
            "slip_over_phi_max": pred.slip_over_phi_max, "chi": values.get("chi", math.nan),
            "R": pred.joint.get("R", math.nan), "phi_max": pred.joint["slip_scale"],
            "F_S": pred.joint["F_S"], "zeta_viscous": values["zeta_v"],
            "f0_hz": values["f0_hz"], "fallback_levels": float(len(pred.fallback_lines()))}


def _quantiles(rows, q) -> dict:
    a = np.asarray(rows, dtype=float)
    if a.size == 0:
        return {"median": None, "lo": None, "hi": None}
    lo, med, hi = np.quantile(a, [q[0], 0.5, q[1]], axis=0)
    return {"median": med.tolist(), "lo": lo.tolist(), "hi": hi.tolist()}


def _model(u: dict) -> dict:
    """The nominal model (``update``'s result ``u``) and how far it misses its fit
    levels."""
    f, judged = u["fit"], u["selection"]["judged"]["selection"]
    return {"candidate": u["candidate"], "cause": judged.cause,
            "unexplained": judged.unexplained,
            "fit_levels": [int(v) for v in u["data"].level[u["fit_mask"]]],
            "values": dict(f.values), "free": list(f.free),
            "at_bound": {n: f.at_bound.get(n, False) for n in f.free},
            "std_error": {n: f.std_error(n) for n in f.free}, "chi2": f.chi2,
            "n_residuals": f.n, "rms_misfit_sd": math.sqrt(f.chi2 / f.n),
            "fit_test": fit_test_of(f, u["selection"]["judge_noise"]).to_json(),
            "kind": "fitted", "rule": "feloop.update.run_update"}


def _rows(data, mask, nominal, mc_f: dict, mc_z: dict) -> list:
    """Per level: measured, nominal and the samples' quantiles (:func:`run_fe_uncertainty`)."""
    f_meas = np.sqrt(data.omega2) / (2 * math.pi)
    rows = []
    for i, lv in enumerate(data.level):
        row = {"level": int(lv), "held_out": bool(not mask[i]),
               "measured_frequency_hz": float(f_meas[i]), "measured_zeta": float(data.zeta[i]),
               "nominal_frequency_hz": float(nominal.values["frequency_hz"][i]),
               "nominal_zeta": float(nominal.values["zeta"][i])}
        for name, mc, meas in (("frequency_hz", mc_f, f_meas[i]), ("zeta", mc_z, data.zeta[i])):
            row[f"mc_{name}"] = {k: (None if v is None else v[i]) for k, v in mc.items()}
            row[f"measured_{name}_inside"] = None if mc["lo"] is None else \
                bool(mc["lo"][i] <= meas <= mc["hi"][i])
        rows.append(row)
    return rows


def _source(study: LevelsStudy, levels, executor, distribution: str, given):
    """(the update-like dict, the nominal model's report, the FitDistribution) of
    ``update``'s model choice or of the ``given`` model (:func:`run_fe_uncertainty`)."""
    settings = UpdateSettings(study.data_path, study.mode_label, study.fit_levels,
                              study.force_scale)
    if given is None:
        u = run_update(settings, levels, executor=executor, case_name=study.case)
        return u, _model(u), FitDistribution.from_fit(u["fit"], u["parameters"], distribution)
    data, mask = load_levels(settings)    # the given model: its values, its fit's covariance
    given.check_data(data, study.mode_label, study.force_scale, mask)
    u = {"data": data, "fit_mask": mask, "extension": given.extension,
         "fit": given.fit, "parameters": given.bounds, "candidate": given.candidate}
    try:
        dist = FitDistribution.from_fit(given.fit, given.bounds, distribution)
    except ValueError as exc:
        raise InputError(f"{given.path}: {exc}") from None
    return u, given.summary(), dist


def run_fe_uncertainty(levels, model, study: LevelsStudy, n_samples: int = 200,
                       seed: int = 1, confidence: float = 0.9, distribution: str = "t",
                       out=None, executor="serial", progress: bool = False,
                       given=None) -> dict:
    """The Monte Carlo of the module docstring.

    Parameters
    ----------
    levels : callable(data, force_scale=) -> FELevels (the case's ``fe_levels``).
    model : the case's FE model (hashed into the store's name).
    study : LevelsStudy
    out : directory of the resumable sample store ``samples-<hash12>/`` (None: none).
    given : a :class:`feloop.given_model.GivenModel` (``uncertainty --model``): the
        nominal and the distribution are its fit instead of ``update``'s model choice
        (its data and fit levels must be the study's: one line otherwise).

    Returns
    -------
    dict: ``model`` (the selected candidate, its fitted values, ``at_bound``, misfit in
    noise sd and fit test), ``distribution``, ``chi`` (quantiles of the physical
    samples), ``levels`` (per level: ``held_out``, measured, nominal, ``mc``
    median/lo/hi of frequency (Hz) and zeta, whether the measured value lies inside),
    ``n_failed`` and ``failures`` (with the reason), ``n_with_fallback`` (physical
    samples with a level whose steady state needed a fallback), ``computed`` (samples
    not loaded from the store), ``store``, ``timing_s``.
    """
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
    if study.data_path is None:
        raise ValueError("no measured data: give FILE (the case names none)")
    t0 = time.perf_counter()
    u, nominal_model, dist = _source(study, levels, executor, distribution, given)
    data, mask, ext = u["data"], u["fit_mask"], u["extension"]
    t_sel = time.perf_counter() - t0
    study = replace(study, candidate=u["candidate"])
    inputs = LevelsSweepInputs(model=model, data=data, study=study, distribution=dist,
                               simulate=simulate_levels, levels=levels, extension=ext)
    digest = sweep_hash(inputs, seed)
    store = None if out is None else SampleStore(
        Path(out) / f"samples-{digest[:12]}", digest,
        {"seed": seed, "distribution": distribution, "study": describe(study)})
    nominal, samples = run_samples(inputs, n_samples, seed, store, executor, progress)
    if nominal.status != "ok":
        who = "update's selected model" if given is None else f"the given model {given.path}"
        raise ValueError(f"{who} ({u['candidate']}) is not physical at its fit: "
                         f"{nominal.status}")
    ok = [s for s in samples if s.status == "ok"]
    q = (0.5 * (1 - confidence), 0.5 * (1 + confidence))
    mc_f = _quantiles([s.values["frequency_hz"] for s in ok], q)
    mc_z = _quantiles([s.values["zeta"] for s in ok], q)
    rows = _rows(data, mask, nominal, mc_f, mc_z)
    chis = [float(s.values["chi"]) for s in ok if math.isfinite(s.values["chi"])]
    draws = sum(s.n_draws for s in samples)
    return {
        "case": study.case, "source": str(study.data_path), "mode": study.mode_label,
        "route": "exact describing function, phase resonance (FE-levels model)",
        "model": nominal_model,
        "distribution": {**dist.to_dict(),
                         "kept_fraction": len(samples) / draws if draws else None},
        "n_samples": int(n_samples), "seed": int(seed), "confidence": confidence,
        "chi": {"median": float(np.median(chis)), "lo": float(np.quantile(chis, q[0])),
                "hi": float(np.quantile(chis, q[1]))} if chis else None,
        "levels": rows, "n_failed": len(samples) - len(ok),
        "n_with_fallback": int(sum(s.values.get("fallback_levels", 0) > 0 for s in ok)),
        "failures": [{"index": s.index, "chi": None if math.isnan(s.p) else s.p - 1.0,
                      "status": s.status}
                     for s in samples if s.status != "ok"],
        "store": None if store is None else str(store.path),
        "executor": executor.describe() if isinstance(executor, ExecutorSpec) else str(executor),
        "computed": sum(not s.loaded for s in [nominal, *samples]),
        "timing_s": {"model choice (as update)" if given is None else "given model": t_sel, "total": time.perf_counter() - t0}}
