"""The model ``iwanfe update`` wrote (``DIR/updated_model.json``) as the given model of
another command, in the parametrization of the case's FE-levels model
(:class:`feloop.levels.FELevels`: ``chi``, ``ln_dc1``, ``zeta_v``, ``f0_hz``, ``log10_kt``,
``ln_phimax`` and a cause's parameters):

* ``uncertainty --case FILE --model M`` draws its samples around M: the nominal is M's
  fitted values, the distribution M's fit (its covariance ``(J^T J)^-1``, misfit scale,
  residual dof and bounds, stored by ``update`` in ``fit``), instead of re-running
  ``update``'s model choice (:func:`feloop.uncertainty.run_fe_uncertainty`);
* ``loop --case FILE --model M`` reports what M gets wrong at every level beside the
  loop's own update (:func:`level_errors`).

The parameters are relative to the data (``ln_dc1`` is the joints' damping at the first
level of the table the model was fitted to), so M is taken only with the data it was
fitted to: the same case, mode label, force scale and table (``data.digest``, SHA-256 of
the levels, excitations, omega^2, zeta and run orders), and for ``uncertainty`` the same
fit levels. Anything else, or a file of an ``update`` older than the ``fit`` and ``data``
blocks, is one line (:class:`ident.errors.InputError`, exit 2). Any candidate is taken
(the base model or a cause: its extension is rebuilt from its name,
:data:`feloop.causes.EXTENSIONS`), unlike the FE commands' case-file form of M
(:mod:`feloop.updated_model`, base model only).
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ident.errors import InputError
from inverse.update import Fit

__all__ = ["data_digest", "fit_block", "data_block", "Bounds", "GivenModel", "read_given",
           "level_errors"]


def data_digest(data) -> str:
    """SHA-256 of one mode's measured levels (:class:`ident.modal_data.MeasuredData`)."""
    h = hashlib.sha256(b"iwanfe-levels/1")
    for a in (data.level, data.excitation, data.omega2, data.zeta, data.run_order):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()


def fit_block(fit, parameters: dict) -> dict:
    """The ``fit`` block of ``updated_model.json``: what a Monte Carlo around the model
    needs (:meth:`inverse.uncertainty.FitDistribution.from_fit`)."""
    return {"values": dict(fit.values), "free": list(fit.free), "chi2": fit.chi2,
            "n_residuals": fit.n, "dof": fit.dof, "misfit_scale": fit.misfit_scale,
            "covariance": None if fit.cov is None else np.asarray(fit.cov).tolist(),
            "covariance_kind": "(J^T J)^-1 of the free parameters in noise units, not "
                               "scaled by the misfit",
            "at_bound": {n: fit.at_bound.get(n, False) for n in fit.free},
            "bounds": {n: [parameters[n].lower, parameters[n].upper] for n in fit.free},
            "bounds_kind": "[lower, upper]; null: unbounded on that side",
            "converged": fit.converged}


def data_block(data, mode: int, force_scale: float) -> dict:
    """The ``data`` block of ``updated_model.json``: the table the model was fitted to."""
    return {"source": str(data.source), "mode": int(mode), "force_scale": float(force_scale),
            "levels": [int(v) for v in data.level], "digest": data_digest(data)}


@dataclass(frozen=True)
class Bounds:
    """A parameter's bounds (what :class:`inverse.uncertainty.FitDistribution` reads of
    an :class:`inverse.update.Parameter`)."""

    lower: float
    upper: float


def _extension(name: str, where: str):
    from feloop.causes import EXTENSIONS, Combined

    if name == "none":
        return None
    parts = name.split("+")
    if not all(p in EXTENSIONS for p in parts) or len(parts) > 2:
        raise InputError(f"{where}: model {name!r} is no candidate of iwanfe update")
    return EXTENSIONS[parts[0]] if len(parts) == 1 else \
        Combined(EXTENSIONS[parts[0]], EXTENSIONS[parts[1]])


def _float(v) -> float:
    return math.nan if v is None else float(v)


@dataclass(frozen=True)
class GivenModel:
    """An ``updated_model.json`` read and checked against its case (:func:`read_given`)."""

    path: str
    case: str
    candidate: str
    cause: str
    unexplained: bool
    fit: Fit
    bounds: dict
    fit_levels: tuple
    data: dict
    fit_test: dict
    extension: object = None

    def check_data(self, data, mode: int, force_scale: float, mask=None) -> None:
        """InputError (one line) unless ``data`` (one mode's levels) are the table the
        model was fitted to, at the same mode label and force scale, and (``mask`` given)
        its fit levels are the model's."""
        d, where = self.data, self.path
        if int(mode) != d["mode"]:
            raise InputError(f"{where}: a model of mode {d['mode']}, not of mode {mode}")
        if not math.isclose(float(force_scale), d["force_scale"], rel_tol=1e-12):
            raise InputError(f"{where}: fitted at force scale {d['force_scale']:g} N per "
                             f"unit, not {force_scale:g}")
        if data_digest(data) != d["digest"]:
            raise InputError(f"{where}: fitted to other data ({d['source']}, levels "
                             f"{d['levels']}) than {data.source}")
        if mask is not None:
            levels = [int(v) for v in data.level[np.asarray(mask, dtype=bool)]]
            if levels != list(self.fit_levels):
                raise InputError(f"{where}: fitted to levels {list(self.fit_levels)}, not "
                                 f"to the run's fit levels {levels}")

    def summary(self, noise_rms: float | None = None) -> dict:
        """The nominal model as :func:`feloop.uncertainty.run_fe_uncertainty` reports it."""
        f = self.fit
        return {"candidate": self.candidate, "cause": self.cause,
                "unexplained": self.unexplained, "fit_levels": list(self.fit_levels),
                "values": dict(f.values), "free": list(f.free),
                "at_bound": {n: f.at_bound.get(n, False) for n in f.free},
                "std_error": {n: f.std_error(n) for n in f.free}, "chi2": f.chi2,
                "n_residuals": f.n, "rms_misfit_sd": math.sqrt(f.chi2 / f.n),
                "fit_test": self.fit_test, "kind": "given",
                "rule": f"given: {self.path}", "given": self.path}


def read_given(path, case_name: str) -> GivenModel:
    """The updated model at ``path`` for case ``case_name``; InputError (one line) for a
    file that is not an update's, of another case, or of an older update."""
    where = str(path)
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{where}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{where}: not a JSON file: {exc}") from None
    if not isinstance(doc, dict) or "parameters" not in doc or "case" not in doc:
        raise InputError(f"{where}: not an updated_model.json of iwanfe update")
    if doc["case"] != case_name:
        raise InputError(f"{where}: the update of case {doc['case']!r}, not of {case_name!r}")
    if not isinstance(doc.get("fit"), dict) or not isinstance(doc.get("data"), dict):
        raise InputError(f"{where}: written by an older iwanfe update (no fit covariance "
                         f"and data digest): run iwanfe update again")
    fb, db = doc["fit"], doc["data"]
    try:
        free = tuple(fb["free"])
        cov = None if fb["covariance"] is None else np.array(
            [[_float(v) for v in row] for row in fb["covariance"]], dtype=float)
        fit = Fit(values={k: _float(v) for k, v in fb["values"].items()}, free=free,
                  chi2=float(fb["chi2"]), n=int(fb["n_residuals"]), cov=cov, nfev=0,
                  seconds=0.0, success=True, at_bound=dict(fb["at_bound"]),
                  converged=bool(fb.get("converged", True)))
        bounds = {n: Bounds(-math.inf if lo is None else float(lo),     # JSON: no inf
                            math.inf if hi is None else float(hi))
                  for n, (lo, hi) in fb["bounds"].items()}
        data = {"source": str(db["source"]), "mode": int(db["mode"]),
                "force_scale": float(db["force_scale"]),
                "levels": [int(v) for v in db["levels"]], "digest": str(db["digest"])}
        fit_levels = tuple(int(v) for v in doc["fit_levels"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{where}: a damaged fit or data block ({exc!r})") from None
    if cov is not None and cov.shape != (len(free), len(free)):
        raise InputError(f"{where}: the covariance is {cov.shape}, not of the "
                         f"{len(free)} free parameters")
    name = str(doc.get("model", "none"))
    return GivenModel(where, case_name, name, str(doc.get("cause", "none")),
                      bool(doc.get("unexplained", False)), fit, bounds, fit_levels, data,
                      dict(doc.get("fit_test") or {}), _extension(name, where))


def level_errors(data, noise, pred, fitted) -> dict:
    """What prediction ``pred`` (:class:`feloop.levels.LevelPrediction`) gets wrong at
    every level: per level the measured and predicted frequency and zeta, the errors
    (Hz, % of zeta) and in noise sd (``noise.sigma_omega2``, ``sigma_zeta``), with
    ``fitted`` (bool per level) marking the levels a fit saw; the rms over both channels
    of those and of the others."""
    fitted = np.asarray(fitted, dtype=bool)
    f_meas = np.sqrt(data.omega2) / (2 * math.pi)
    z_f = (pred.omega2 - data.omega2) / noise.sigma_omega2
    z_z = (pred.zeta - data.zeta) / noise.sigma_zeta
    rows = [{"level": int(data.level[i]), "fitted": bool(fitted[i]),
             "measured_frequency_hz": float(f_meas[i]), "measured_zeta": float(data.zeta[i]),
             "frequency_hz": float(pred.frequency_hz[i]), "zeta": float(pred.zeta[i]),
             "error_hz": float(pred.frequency_hz[i] - f_meas[i]),
             "error_zeta_percent": float(100 * (pred.zeta[i] / data.zeta[i] - 1)),
             "z_frequency": float(z_f[i]), "z_zeta": float(z_z[i])}
            for i in range(len(data.level))]

    def rms(sel):
        r = np.concatenate([z_f[sel], z_z[sel]])
        return float(np.sqrt(np.mean(r * r))) if r.size else None

    return {"levels": rows, "rms_fitted_sd": rms(fitted), "rms_others_sd": rms(~fitted),
            "rms_all_sd": rms(np.ones_like(fitted))}
