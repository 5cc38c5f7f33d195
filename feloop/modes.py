"""One joint, several modes: the joint parameters fitted to every given mode at once, and
the joint fitted on some modes predicting the others.

A joint is one physical object that a test sees through several modes. Here every mode
of the measured table has its own FE-levels model (:class:`feloop.levels.FELevels`, its
levels at their own forces, its amplitude in its own modal coordinate, the joints' slips
from its FE mode shape), and all of them take the joints of the *reference* mode (the
first fitted; :attr:`feloop.levels.FELevels.joint_source`): the joint parameters
(:mod:`feloop.joint_forms`, e.g. ``chi``, ``ln_dc1`` for Iwan joints; ``ln_dc1`` and a
slip scale refer to the reference mode's level-1 slips) are one set, the physical joint
(``R``, ``phi_max``, ``F_S``, ``K_T``) the same on every mode. Each mode keeps its own
viscous damping ``zeta_v@m`` and stuck frequency ``f0_hz@m`` (a model's frequency
error differs from mode to mode); ``f0_hz@m`` scales mode ``m``'s stiffness, its joints'
included, so the joint mode ``m`` sees differs from the reference's by the ratio of their
stiffness scales (reported, ``stiffness_scale``).

* :func:`fit_modes` (``update --modes 1,2``): one joint and the per-mode nuisance
  parameters fitted to the fit levels of every mode with one noise model (each mode's
  :func:`feloop.select.fe_noise`), from starts made by the reference mode's own base fit;
  the per-mode fit tests (chi2 of each mode's levels against its residual count), and the
  one-joint test: every mode fitted alone (its own joint) against the one joint,
  ``D = chi2(one joint) - sum chi2(alone)`` against chi2 with ``q = (M - 1) k`` degrees
  of freedom (``k`` joint parameters, ``M`` modes; a likelihood-ratio test), or ``D / q``
  against ``F(q, nu)`` when the noise's repeatability is estimated (``nu`` its degrees
  of freedom, the fewest of the modes'), as the judge's fit test.
* :func:`feloop.mode_prediction.predict_mode` (``loop --fit-modes 2 --predict-modes 1``): a mode the fit never
  saw, predicted at every level from the fitted joint; its ``zeta_v@m`` and ``f0_hz@m``
  are *calibrated* to its lowest level (two numbers from two measured ones), so what is
  predicted is the amplitude dependence: the frequency drop and the damping growth. The
  prediction sd (delta method, :func:`feloop.mode_prediction.prediction_sd`): the joint's covariance (misfit
  scaled) and the noise of the calibration level through the recalibrated prediction,
  and the level's own noise. A level is a miss outside the 95 % interval; the gain is
  the chi2 of the prediction "no amplitude dependence" (each level at the calibration
  level's values) over the joint's, on the predicted levels.

SI units: omega^2 in rad^2/s^2, frequencies in Hz.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from feloop.levels import FELevels, Simulator
from feloop.select import fe_noise, fit_base
from feloop.starts import base_parameters
from inverse.decrement import central_jacobian
from inverse.judge.selection import effective_dof, fit_test
from inverse.update import Fit, NoiseModel, Parameter, UpdateProblem, fit

__all__ = ["MODE_NUISANCE", "ModeSeries", "ModeSet", "ModesFit", "mode_series",
           "nuisance_name", "fit_modes", "calibrate", "covariance_at"]

#: The parameters each mode keeps of its own (module docstring).
MODE_NUISANCE = ("zeta_v", "f0_hz")
#: Test size of the per-mode fit tests and of the one-joint test.
TEST_SIZE = 0.05


def nuisance_name(name: str, label: int) -> str:
    """Mode ``label``'s own copy of a nuisance parameter: ``f0_hz@2``."""
    return f"{name}@{int(label)}"


@dataclass
class ModeSeries:
    """One measured mode: its ``label`` in the table, its levels ``data`` (one mode,
    sorted; :class:`ident.modal_data.MeasuredData`), the fit ``mask``, its FE-levels model
    ``fe`` and its noise (:func:`feloop.select.fe_noise`)."""

    label: int
    data: object
    mask: np.ndarray
    fe: FELevels
    noise: NoiseModel = None
    judge_noise: object = None

    def __post_init__(self):
        self.mask = np.asarray(self.mask, dtype=bool)
        if self.noise is None:
            self.judge_noise, self.noise = fe_noise(self.data)


def mode_series(data_by_mode: dict, masks: dict, levels) -> list[ModeSeries]:
    """The :class:`ModeSeries` of every mode (label -> one-mode data and fit mask; the
    first is the reference), each with its FE-levels model ``levels(data)`` taking the
    reference's joints. ValueError (one line) when two measured modes tie to one FE mode."""
    out = []
    for label, data in data_by_mode.items():
        fe = levels(data)
        if out:
            fe.joint_source = out[0].fe
        out.append(ModeSeries(int(label), data, masks[label], fe))
    tied = {}
    for s in out:
        fe_mode = s.fe.linear(s.fe.default_kt).fe_mode
        if fe_mode in tied:
            raise ValueError(f"measured modes {tied[fe_mode]} and {s.label} both tie to FE "
                             f"mode {fe_mode} (nearest in frequency): they are one mode of "
                             "the model")
        tied[fe_mode] = s.label
    return out


def _own(values: dict, s: ModeSeries, names: tuple) -> dict:
    """Mode ``s``'s parameter set from the set of all modes."""
    v = {n: values[n] for n in names if n in values}
    v.update({n: values[nuisance_name(n, s.label)] for n in MODE_NUISANCE})
    if "log10_kt" in values:
        v["log10_kt"] = values["log10_kt"]
    return v


@dataclass
class ModeSet:
    """``simulate(values) -> (omega2, zeta)`` of :mod:`inverse.update` over several modes:
    every mode's levels in the order of ``series``, one after the other; ``names``: the
    joint parameters (the reference's form)."""

    series: list
    names: tuple

    def __call__(self, values: dict):
        out = self.batch([values])[0][0]
        if isinstance(out, Exception):
            raise out
        return out

    def batch(self, values: list, warm=None) -> tuple:
        """Per set ``(omega2, zeta)`` over every mode's levels, or the first failure, and
        its warm starts after it (``warm[i]``: label -> the mode's warm starts, ``{}``
        cold, None: the models' own; :meth:`feloop.levels.FELevels.predict_batch`)."""
        warm = list(warm or [None] * len(values))
        parts, after = [], [{} for _ in values]
        for s in self.series:
            w = [None if x is None else x.get(s.label, {}) for x in warm]
            preds, new = s.fe.predict_batch([_own(v, s, self.names) for v in values], None, w)
            parts.append(preds)
            for a, n in zip(after, new):
                a[s.label] = n
        out = []
        for per_mode in zip(*parts):
            bad = next((p for p in per_mode if isinstance(p, Exception)), None)
            out.append(bad if bad is not None else (
                np.concatenate([p.omega2 for p in per_mode]),
                np.concatenate([p.zeta for p in per_mode])))
        return out, after

    def reset(self) -> None:
        for s in self.series:
            s.fe.reset()


def _stacked(series, simulate, parameters) -> UpdateProblem:
    """The update problem of every mode's levels together (one noise model: each mode's)."""
    cat = np.concatenate
    noise = NoiseModel(cat([s.noise.sigma_omega2 for s in series]),
                       cat([s.noise.sigma_zeta for s in series]),
                       "; ".join(f"mode {s.label}: {s.noise.source}" for s in series))
    return UpdateProblem(simulate, cat([s.data.omega2 for s in series]),
                         cat([s.data.zeta for s in series]), noise,
                         cat([s.mask for s in series]), parameters)


def _slices(series) -> list[slice]:
    ends = np.cumsum([0] + [s.data.omega2.size for s in series])
    return [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:])]


@dataclass
class ModesFit:
    """The one-joint fit over several modes (:func:`fit_modes`): the ``fit``
    (:class:`inverse.update.Fit`, joint and per-mode nuisance parameters), its
    ``problem``, the joint parameter ``names``, per mode its fit test (``per_mode``:
    label -> chi2, residuals, test, p-value, passes), each mode fitted alone (``alone``:
    label -> Fit of the mode's own base model; ``alone_joint``: its physical joint), and
    the one-joint test (``one_joint``: D, dof, test, p-value, passes)."""

    series: list
    problem: UpdateProblem
    fit: Fit
    names: tuple
    per_mode: dict = field(default_factory=dict)
    alone: dict = field(default_factory=dict)
    alone_joint: dict = field(default_factory=dict)
    one_joint: dict = field(default_factory=dict)

    @property
    def joint_values(self) -> dict:
        """The fitted joint parameters (and ``log10_kt``)."""
        keep = set(self.names) | {"log10_kt"}
        return {n: v for n, v in self.fit.values.items() if n in keep}

    def joint(self) -> dict:
        """The physical joint of the fit (the reference mode's, :meth:`FELevels.joint`)."""
        ref = self.series[0]
        j = ref.fe.joint(_own(self.fit.values, ref, self.names))
        return {k: v for k, v in j.items() if k not in ("params", "linear")}


def _mode_test(chi2: float, n: int, k: int, jn) -> dict:
    """The judge's fit test (:func:`inverse.judge.selection.fit_test`: chi-square with a
    known noise, F with an estimated repeatability) of one mode's ``n`` residuals under
    the ``k`` parameters that shape them (the joint's and its own two)."""
    t = fit_test(chi2, n, k, jn)
    return {"chi2": float(chi2), "residuals": int(n), "parameters": int(k),
            "p_value": t.p_value, "test": t.test,
            "passes": bool(t.p_value is None or t.p_value >= TEST_SIZE)}


def _alone(s: ModeSeries) -> tuple[Fit, dict, list, dict]:
    """Mode ``s`` fitted alone by its base model (its own joint): fit, parameters, starts
    and the physical joint of the fit."""
    solo = copy.copy(s.fe)
    solo.joint_source = None
    solo.reset()
    P, starts = base_parameters(s.data, s.mask, solo)
    problem = UpdateProblem(Simulator(solo), s.data.omega2, s.data.zeta, s.noise, s.mask, P)
    best, _, _ = fit_base(problem, starts, solo.base_parameters)
    joint = {k: v for k, v in solo.joint(best.values).items() if k not in ("params", "linear")}
    return best, P, starts, joint


def fit_modes(series: list) -> ModesFit:
    """One joint fitted to the fit levels of every mode of ``series`` (the first the
    reference; module docstring). Every mode is first fitted alone (its base model); the
    joint fit starts from the reference's optimum (and, when that fit fails or does not
    converge, from the reference's other starts too), each with every other mode's
    nuisance parameters calibrated to its own levels under that joint."""
    ref = series[0]
    names = tuple(ref.fe.form.names)
    alone = {s.label: _alone(s) for s in series}
    P_ref = alone[ref.label][1]
    P = {n: P_ref[n] for n in P_ref if n not in MODE_NUISANCE}
    for s in series:
        own = alone[s.label][1]
        for n in MODE_NUISANCE:
            p = own[n]
            P[nuisance_name(n, s.label)] = Parameter(
                nuisance_name(n, s.label), p.start, p.lower, p.upper, p.step, p.unit,
                f"{p.description} (mode {s.label})")
    problem = _stacked(series, ModeSet(series, names), P)
    free = names + tuple(nuisance_name(n, s.label) for s in series for n in MODE_NUISANCE)
    def start_of(js: dict) -> dict:
        start = {n: js[n] for n in names if n in js}
        for s in series:
            own = alone[s.label][0].values if s is ref else calibrate(
                s, {**start, **{k: v for k, v in js.items() if k == "log10_kt"}}, names,
                mask=s.mask, fallback=alone[s.label][0].values)
            start.update({nuisance_name(n, s.label): own[n] for n in MODE_NUISANCE})
        return start

    first = alone[ref.label][0].values
    best, _, _ = fit_base(problem, [start_of(first)], free)
    if not (best.success and best.converged):      # the reference's other starts too
        best, _, _ = fit_base(problem, [start_of(first)] + [
            start_of({**first, **st}) for st in alone[ref.label][2]], free)
    best.cov = covariance_at(problem, best)
    out = ModesFit(series, problem, best, names)
    for s, sl in zip(series, _slices(series)):
        only = np.zeros(problem.omega2.size, bool)
        only[sl] = s.mask
        r = problem.residuals(best.values, mask=only)
        out.per_mode[s.label] = _mode_test(float(r @ r), r.size,
                                           len(names) + len(MODE_NUISANCE), s.judge_noise)
    out.alone = {lb: a[0] for lb, a in alone.items()}
    out.alone_joint = {lb: a[3] for lb, a in alone.items()}
    D = best.chi2 - sum(f.chi2 for f in out.alone.values())
    dof = (len(series) - 1) * len(names)
    nu = min(effective_dof(s.judge_noise) for s in series)
    if dof == 0:
        p, test = math.nan, "none (one mode)"
    elif math.isinf(nu):
        p, test = float(stats.chi2.sf(max(D, 0.0), dof)), f"chi-square, {dof} dof"
    else:           # the noise's repeatability estimated: F, as the judge's fit test
        p, test = float(stats.f.sf(max(D, 0.0) / dof, dof, nu)), f"F({dof}, {nu:.3g})"
    out.one_joint = {"D": float(D), "dof": dof, "p_value": p, "test": test,
                     "passes": bool(not (p < TEST_SIZE))}
    return out


def covariance_at(problem: UpdateProblem, f: Fit) -> np.ndarray | None:
    """``(J^T J)^-1`` of fit ``f`` from a central-difference Jacobian of step
    :data:`inverse.decrement.CHECK_STEP` parameter steps (parameters at a bound held:
    zero rows and columns). The optimizer's own Jacobian is taken at steps of 1e-6 steps
    about where it stopped: a fit started at its optimum (the joint fit here starts at the
    reference's) stops there, and at that step the balance's round-off made ``J^T J``
    singular (a zero-width interval of ``ln_dc1``) under one BLAS kernel and not another."""
    P = [problem.parameters[n] for n in f.free]
    step = np.array([p.step for p in P])
    x = np.array([f.values[n] for n in f.free])
    lo = np.array([(p.lower - v) / s for p, v, s in zip(P, x, step)])
    hi = np.array([(p.upper - v) / s for p, v, s in zip(P, x, step)])

    def funs(us):
        return problem.residuals_many([{**f.values, **dict(zip(f.free, x + step * u))}
                                       for u in us])

    u = np.zeros(x.size)
    J, _ = central_jacobian(funs, u, problem.residuals(f.values), lo, hi)
    held = np.array([bool(f.at_bound.get(n)) for n in f.free])
    keep = np.flatnonzero(~held)
    cov = np.zeros((x.size, x.size))
    Js = J[:, keep] / step[keep]
    try:
        cov[np.ix_(keep, keep)] = np.linalg.inv(Js.T @ Js)
    except np.linalg.LinAlgError:
        return None
    return cov


def calibrate(s: ModeSeries, joint: dict, names: tuple, mask=None, fallback=None) -> dict:
    """Mode ``s``'s ``zeta_v`` and ``f0_hz`` fitted to its levels ``mask`` (default the
    lowest level alone: two numbers from two measured ones) with the joint parameters
    ``joint`` held; the mode's own parameter set."""
    m = np.zeros(s.data.omega2.size, bool)
    if mask is None:
        m[0] = True
    else:
        m = np.asarray(mask, bool)
    f1 = math.sqrt(float(s.data.omega2[0])) / (2 * math.pi)
    start = {"zeta_v": float(s.data.zeta[0]), "f0_hz": f1} if fallback is None else \
        {n: fallback[n] for n in MODE_NUISANCE}
    P = {"zeta_v": Parameter("zeta_v", start["zeta_v"], 1e-6, 0.2, 1e-5, "1",
                             "viscous modal damping ratio"),
         "f0_hz": Parameter("f0_hz", start["f0_hz"], 0.8 * f1, 1.25 * f1, 1e-3, "Hz",
                            "stuck-joint natural frequency of the mode")}
    problem = UpdateProblem(_Fixed(s.fe, joint), s.data.omega2, s.data.zeta, s.noise, m, P)
    f = fit(problem, MODE_NUISANCE, start=start, tol=1e-12)
    return {**joint, **{n: f.values[n] for n in MODE_NUISANCE}}


@dataclass
class _Fixed:
    """``simulate`` of one mode with the joint parameters ``joint`` held."""

    fe: FELevels
    joint: dict

    def __call__(self, values):
        p = self.fe.predict({**self.joint, **values})
        return p.omega2, p.zeta
