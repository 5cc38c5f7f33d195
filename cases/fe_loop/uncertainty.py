"""Monte Carlo of any case's FE predictions over the identified joint (exact-DF route).

The estimator's fit of the fit levels (``exact``, paper eq. 33-35,
:func:`inverse.estimate.estimate`) gives ``(p, ln Kt)`` = ``(chi + 1, ln((chi+1)
|kappa1| B))`` with its covariance; :mod:`inverse.uncertainty` draws from it (Student t
with the fit's dof or normal, truncated to -1 < chi < 0, one executor task and one seed
stream per sample, resumable store). Each sample is put into the case's FE-levels model
(:class:`cases.fe_loop.levels.FELevels`: one Iwan element per joint element, ``beta =
0``, ``chi = p - 1``, ``|kappa1| B~ = Kt / p`` at level 1, eq. 36-37) with the stuck
frequency and the viscous damping matched to the measured level 1
(:func:`cases.fe_loop.backbone.estimated_joint`) and simulated at every level by
first-harmonic balance at phase resonance with the exact describing function
(:func:`fe.hb_resonance.resonance_levels`, from a cold start: a few ms per sample). The report gives per level the measured value, the nominal prediction (the
estimate itself) and the samples' median and central interval; failed samples are
counted with their reason and left out of the quantiles. (The double beam's own
Monte Carlo, a Jenkins-bank stepped sine per sample, is
:mod:`cases.double_beam.uncertainty`.)

SI units: Hz, rad^2/s^2; damping ratios as fractions.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cases.fe_loop.backbone import estimated_joint
from ident.measured import read_measured
from inverse.estimate import estimate, parse_levels
from inverse.sample_store import SampleStore, describe
from inverse.uncertainty import ParameterDistribution, SweepInputs, run_samples, sweep_hash
from runs.executor import ExecutorSpec

__all__ = ["LevelsStudy", "LevelsSweepInputs", "simulate_levels", "run_fe_uncertainty"]


@dataclass(frozen=True)
class LevelsStudy:
    """What a sample depends on besides the data and the FE model (hashed into the
    store's name): the data file, mode label, fit levels, force scale (N per excitation
    unit, assumed), the case's name."""

    data_path: str | None
    mode_label: int
    fit_levels: str
    force_scale: float = 1.0
    case: str = ""


@dataclass(frozen=True)
class LevelsSweepInputs(SweepInputs):
    """:class:`inverse.uncertainty.SweepInputs` with the case's FE-levels builder
    ``levels(data, force_scale=)`` (picklable)."""

    levels: object = None


_CACHE: dict = {}      # per process: the FE-levels model and estimate of one sweep


def _prepared(inputs: LevelsSweepInputs):
    key = (id(inputs), inputs.study)
    if _CACHE.get("key") != key:
        st = inputs.study
        est = estimate(inputs.data, fit_levels=parse_levels(st.fit_levels), method="exact")
        _CACHE.update(key=key, est=est,
                      fe=inputs.levels(inputs.data, force_scale=st.force_scale))
    return _CACHE["fe"], _CACHE["est"]


def simulate_levels(inputs: LevelsSweepInputs, p=None, ln_kt=None) -> dict:
    """One sample (module docstring); ``p = ln_kt = None``: the estimate itself.
    Returns ``frequency_hz``, ``zeta``, ``slip_over_phi_max`` (n_levels,) and ``chi``,
    ``R``, ``phi_max``, ``zeta_viscous``."""
    fe, est = _prepared(inputs)
    chi, dc1 = (est.chi, est.kappa1_B) if p is None else (p - 1.0, math.exp(ln_kt) / p)
    values = estimated_joint(chi, dc1, inputs.data.omega2[0], inputs.data.zeta[0])
    fe.reset()             # no warm start: a sample's bits do not depend on the executor
    pred = fe.predict(values)
    return {"frequency_hz": pred.frequency_hz, "zeta": pred.zeta,
            "slip_over_phi_max": pred.slip_over_phi_max, "chi": chi, "R": pred.joint["R"],
            "phi_max": pred.joint["phi_max"], "zeta_viscous": values["zeta_v"]}


def _quantiles(rows, q) -> dict:
    a = np.asarray(rows, dtype=float)
    if a.size == 0:
        return {"median": None, "lo": None, "hi": None}
    lo, med, hi = np.quantile(a, [q[0], 0.5, q[1]], axis=0)
    return {"median": med.tolist(), "lo": lo.tolist(), "hi": hi.tolist()}


def run_fe_uncertainty(levels, model, study: LevelsStudy, n_samples: int = 200,
                       seed: int = 1, confidence: float = 0.9, distribution: str = "t",
                       out=None, executor="serial", progress: bool = False) -> dict:
    """The Monte Carlo of the module docstring.

    Parameters
    ----------
    levels : callable(data, force_scale=) -> FELevels (the case's ``fe_levels``).
    model : the case's FE model (hashed into the store's name).
    study : LevelsStudy
    out : directory of the resumable sample store ``samples-<hash12>/`` (None: none).

    Returns
    -------
    dict: ``estimate`` (chi with its t-interval, ``|kappa1| B``, dof), ``distribution``,
    ``chi`` (quantiles of the admitted draws), ``levels`` (per level: ``held_out``,
    measured, nominal, ``mc`` median/lo/hi of frequency (Hz) and zeta, whether the
    measured value lies inside; None at level 1, matched by every sample),
    ``n_failed`` and ``failures``, ``computed`` (samples not loaded from the store),
    ``store``, ``timing_s``.
    """
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
    if study.data_path is None:
        raise ValueError("no measured data: give FILE (the case names none)")
    t0 = time.perf_counter()
    data = read_measured(study.data_path).for_mode(study.mode_label)
    fit = parse_levels(study.fit_levels)
    missing = sorted(set(fit) - set(map(int, data.level)))
    if missing:
        raise ValueError(f"--fit-levels: level(s) {missing} not in the data "
                         f"(levels {list(map(int, data.level))})")
    est = estimate(data, fit_levels=fit, method="exact", confidence=confidence)
    dist = ParameterDistribution.from_fit(est.fit, distribution)
    inputs = LevelsSweepInputs(model=model, data=data, study=study, distribution=dist,
                               simulate=simulate_levels, levels=levels)
    digest = sweep_hash(inputs, seed)
    store = None if out is None else SampleStore(
        Path(out) / f"samples-{digest[:12]}", digest,
        {"seed": seed, "distribution": distribution, "study": describe(study)})
    nominal, samples = run_samples(inputs, n_samples, seed, store, executor, progress)
    if nominal.status != "ok":
        raise ValueError(f"the estimate's own joint could not be simulated ({nominal.status})")
    ok = [s for s in samples if s.status == "ok"]
    q = (0.5 * (1 - confidence), 0.5 * (1 + confidence))
    mc_f = _quantiles([s.values["frequency_hz"] for s in ok], q)
    mc_z = _quantiles([s.values["zeta"] for s in ok], q)
    f_meas = np.sqrt(data.omega2) / (2 * math.pi)
    rows = []
    for i, lv in enumerate(data.level):
        row = {"level": int(lv), "held_out": int(lv) not in fit,
               "measured_frequency_hz": float(f_meas[i]), "measured_zeta": float(data.zeta[i]),
               "nominal_frequency_hz": float(nominal.values["frequency_hz"][i]),
               "nominal_zeta": float(nominal.values["zeta"][i])}
        for name, mc, meas in (("frequency_hz", mc_f, f_meas[i]), ("zeta", mc_z, data.zeta[i])):
            row[f"mc_{name}"] = {k: (None if v is None else v[i]) for k, v in mc.items()}
            row[f"measured_{name}_inside"] = None if mc["lo"] is None or i == 0 else \
                bool(mc["lo"][i] <= meas <= mc["hi"][i])      # level 1: matched (None)
        rows.append(row)
    chis = [float(s.values["chi"]) for s in ok]
    return {
        "case": study.case, "source": str(study.data_path), "mode": study.mode_label,
        "route": "exact describing function, phase resonance (FE-levels model)",
        "estimate": {"chi": est.chi, "chi_interval": list(est.chi_interval),
                     "kappa1_B": est.kappa1_B, "dof": est.dof, "method": "exact",
                     "fit_levels": list(fit), "kind": "fitted"},
        "distribution": dist.to_dict(), "n_samples": int(n_samples), "seed": int(seed),
        "confidence": confidence,
        "chi": {"median": float(np.median(chis)), "lo": float(np.quantile(chis, q[0])),
                "hi": float(np.quantile(chis, q[1]))} if chis else None,
        "levels": rows, "n_failed": len(samples) - len(ok),
        "failures": [{"index": s.index, "chi": s.p - 1.0, "status": s.status}
                     for s in samples if s.status != "ok"],
        "store": None if store is None else str(store.path),
        "executor": executor.describe() if isinstance(executor, ExecutorSpec) else str(executor),
        "computed": sum(not s.loaded for s in [nominal, *samples]),
        "timing_s": {"total": time.perf_counter() - t0}}
