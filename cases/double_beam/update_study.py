"""Model updating of the FE double beam: the glue joint, the damping and the frequency
fitted to the measured levels by the nonlinear FE simulation itself.

:func:`run_update` (``iwanfe update --case double-beam``):

1. the measured mode's levels (:func:`cases.double_beam.settings.measured_levels`), the
   fit levels (default 1-7) and the noise model (:func:`inverse.update.noise_model`);
2. the base FE model (:mod:`cases.double_beam.fe_levels`: one continuous Iwan element
   per glue node, viscous modal damping, first-harmonic balance at phase resonance)
   fitted in ``chi``, ``ln_dc1`` (the glue's modal damping at level 1, ``|kappa1| B~``),
   ``zeta_v`` and ``f0_hz`` at the assumed ``K_T = 1e8 N/m`` and ``beta = 0``
   (:func:`inverse.update.fit`, several starts: the paper's estimator
   :func:`inverse.estimate.estimate` is one of them, not the answer);
3. profile likelihoods (:mod:`inverse.profile`) of those four and of ``log10_kt`` (each
   K_T its own model, grip re-calibrated to 252.0 Hz) and ``ln_phimax`` (where macro-slip
   starts; ``beta = 0`` at and above its micro-slip limit), run as
   executor tasks; a K_T or beta whose profile has a better optimum than the assumed
   value is refitted there (it is then *fitted*);
4. which parameters the data determine, and along the profiles of those they do not,
   the range of every headline figure: predicted frequency and damping at the
   held-out levels and the top slip over ``phi_max``;
5. the same figures after refitting with each assumed property changed
   (:mod:`cases.double_beam.update_assumptions`).

The force scale (N per excitation unit) is not a parameter: every simulated omega^2 and
zeta is exactly invariant to it (:mod:`cases.double_beam.joint_setup`); R~, phi_max and
F_S are stated at the assumed 1 N/V and scale as ``s^-(chi+1)``, ``s``, ``s``.
"""
from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from cases.double_beam.fe_causes import MacroSlip
from cases.double_beam.fe_levels import BASE_PARAMETERS, DEFAULT_KT, DoubleBeamLevels, Simulator
from cases.double_beam.model import DoubleBeamConfig
from cases.double_beam.settings import DEFAULT_DATA
from ident.measured import read_measured
from inverse.estimate import estimate, parse_levels
from inverse.profile import linear_grid, run_profiles
from inverse.update import Parameter, UpdateProblem, fit, noise_model

__all__ = ["UpdateSettings", "base_parameters", "base_fit", "headline", "run_update"]

#: Fitted by ``update``: the base parameters and phi_max (macro-slip onset, via beta).
UPDATED_PARAMETERS = BASE_PARAMETERS + ("ln_phimax",)
KT_GRID = tuple(np.round(np.arange(6.0, 11.01, 0.5), 6))


@dataclass(frozen=True)
class UpdateSettings:
    """What ``iwanfe update`` fits: the data (default the shipped paper data, mode label
    2), the fit levels, the force scale (N per excitation unit, assumed), the profile
    confidence, the K_T grid (log10 N/m) and the step of the phi_max scan (ln units)."""

    data_path: str | None = None
    mode_label: int = 2
    fit_levels: str = "1-7"
    force_scale: float = 1.0
    confidence: float = 0.95
    kt_grid: tuple = KT_GRID
    phimax_step: float = 0.5
    profile_points: int = 4
    assumptions: bool = True

    def __post_init__(self):
        if not (math.isfinite(self.force_scale) and self.force_scale > 0):
            raise ValueError(f"force scale must be a positive number, got {self.force_scale!r}")
        if not 0 < self.confidence < 1:
            raise ValueError(f"confidence must be in (0, 1), got {self.confidence!r}")
        parse_levels(self.fit_levels)


def load_levels(settings: UpdateSettings):
    """The measured levels, the fit mask and the noise model."""
    data = read_measured(settings.data_path or DEFAULT_DATA).for_mode(settings.mode_label)
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
    mask = np.isin(data.level, fit_levels)
    return data, mask, noise_model(data, mask)


def base_fit(problem: UpdateProblem, starts, free=BASE_PARAMETERS):
    """The best of the fits from every start."""
    best = None
    for s in starts:
        f = fit(problem, free, start=s)
        if best is None or f.chi2 < best.chi2:
            best = f
    return best


def _ranges(items: list) -> dict:
    """Elementwise min/max over a list of headline dicts."""
    out = {}
    for k in items[0]:
        a = np.array([it[k] for it in items], dtype=float)
        out[k] = {"min": a.min(axis=0).tolist(), "max": a.max(axis=0).tolist()}
    return out


def problem_digest(data, mask, settings: UpdateSettings) -> str:
    """SHA-256 of everything a profile branch depends on besides its task: the data,
    the fit levels, the settings and the FE model's configuration."""
    h = hashlib.sha256(b"iwanfe-update/1")
    for a in (data.level, data.excitation, data.omega2, data.zeta, data.run_order, mask):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr((settings, DoubleBeamConfig())).encode())
    return h.hexdigest()


def run_update(settings: UpdateSettings = UpdateSettings(), executor="serial",
               progress: bool = False, store=None) -> dict:
    """Fit, profile and assess the base FE model (module docstring). ``store``: a
    directory where finished profile branches are kept (a rerun loads them). Returns a
    dict (rendered by :mod:`cases.double_beam.update_report`)."""
    t0 = time.perf_counter()
    data, mask, noise = load_levels(settings)
    fe = DoubleBeamLevels.from_data(data, force_scale=settings.force_scale)
    P, starts = base_parameters(data, mask, fe)
    problem = UpdateProblem(Simulator(fe), data.omega2, data.zeta, noise, mask, P,
                            describe=Headline(fe, ~mask))
    micro = base_fit(problem, starts)                       # beta = 0
    # macro-slip may fit better: scan phi_max down from the micro-slip limit (the others
    # refitted) to the level-1 slip, then fit all from the best point
    pm0 = MacroSlip.micro_limit(fe, micro.values)
    top = math.log(float(data.excitation[mask].max() / data.excitation[0]))
    first = min(pm0, top + 2.0)
    scan_grid = list(np.arange(first, -1e-9, -settings.phimax_step))
    seed = replace(micro, values=dict(micro.values, ln_phimax=pm0 + 1e-9))
    half = (len(scan_grid) + 1) // 2                       # two tasks of the executor
    t_micro = time.perf_counter() - t0
    scan = run_profiles(problem, seed, {"ln_phimax": (scan_grid[:half], scan_grid[half:])},
                        BASE_PARAMETERS, settings.confidence, stop_factor=math.inf,
                        executor=executor)
    low = min(scan["ln_phimax"].points, key=lambda p: p.chi2)
    best = micro
    if low.values is not None and low.chi2 < micro.chi2 - 1e-6:
        best = fit(problem, UPDATED_PARAMETERS, start=low.values)
    t_scan = time.perf_counter() - t0 - t_micro
    macro = best is not micro
    free = UPDATED_PARAMETERS if macro else BASE_PARAMETERS
    store = None if store is None else (store, problem_digest(data, mask, settings))
    # K_T first (each value its own calibrated model): a better optimum there is adopted
    # before the other profiles are taken around the final optimum
    kt = best.values["log10_kt"]
    kt_grid = {"log10_kt": ([g for g in sorted(settings.kt_grid, reverse=True) if g < kt],
                            [g for g in sorted(settings.kt_grid) if g > kt])}
    t_fit = time.perf_counter() - t0
    profiles = run_profiles(problem, best, kt_grid, free, settings.confidence,
                            executor=executor, progress=progress, store=store)
    low = min(profiles["log10_kt"].points, key=lambda p: p.chi2)
    if low.values is not None and low.chi2 < best.chi2 - 1e-6:
        again = fit(problem, free, start=low.values)        # K_T stays at that grid value
        best = again if again.chi2 <= low.chi2 else fit(problem, (), start=low.values)
    grids = {n: linear_grid(best, n, P[n], settings.profile_points) for n in free}
    profiles.update(run_profiles(problem, best, grids, free, settings.confidence,
                                 executor=executor, progress=progress, store=store))
    if not macro:
        profiles["ln_phimax"] = scan["ln_phimax"]
    for pr in profiles.values():           # a profile found a better optimum: adopt it
        low = min(pr.points, key=lambda p: p.chi2)
        if low.values is not None and low.chi2 < best.chi2 - 1e-6:
            again = fit(problem, free, start=low.values)
            best = again if again.chi2 <= low.chi2 else fit(problem, (), start=low.values)
    t_prof = time.perf_counter() - t0
    assumed = []
    if settings.assumptions:
        from cases.double_beam.update_assumptions import assumption_sensitivity

        assumed = assumption_sensitivity(data, mask, noise, P, best, settings.force_scale,
                                         Headline, executor)
    sens = {}
    for name, pr in profiles.items():
        if pr.status != "determined":
            inside = [p for p in pr.inside() if p.extra is not None]
            sens[name] = _ranges([p.extra for p in inside])
            sens[name]["grid_inside"] = [p.value for p in inside]
    return {
        "settings": settings, "data": data, "fit_mask": mask, "noise": noise,
        "parameters": P, "fit": best, "micro_slip_fit": micro, "profiles": profiles,
        "micro_limit": MacroSlip.micro_limit(fe, best.values), "scan": scan["ln_phimax"],
        "prediction": fe.predict(best.values), "micro_slip_prediction": fe.predict(micro.values),
        "nominal": problem.describe(best.values), "sensitivity": sens,
        "executor": executor if isinstance(executor, str) else executor.describe(),
        "assumptions": assumed,
        "timing_s": {"base fit": t_micro, "phi_max scan and fit": t_scan,
                     "profiles and refit": t_prof - t_fit,
                     "assumptions": time.perf_counter() - t0 - t_prof,
                     "total": time.perf_counter() - t0},
    }
