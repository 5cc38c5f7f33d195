"""A mode the fit never saw, predicted from the joint fitted on others
(:mod:`feloop.modes`, module docstring): its ``zeta_v`` and ``f0_hz`` calibrated to its
lowest level, every level predicted with a prediction sd (delta method), judged level by
level against its 95 % interval, and the gain over "no amplitude dependence". SI units
(frequencies in Hz)."""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from feloop.digits import Z95
from feloop.modes import ModeSeries, ModesFit, calibrate

__all__ = ["ModePrediction", "prediction_sd", "predict_mode"]


@dataclass
class ModePrediction:
    """A mode the fit never saw, predicted from the fitted joint (:func:`predict_mode`):
    ``label``; ``values`` (its parameter set: the joint fitted, ``zeta_v`` and ``f0_hz``
    calibrated to its lowest level); per level ``rows`` (measured, predicted, sd, z,
    inside the 95 % interval); ``misses``; ``gain`` (module docstring); the measured and
    predicted largest frequency drop and damping growth over the levels, from the lowest."""

    label: int
    values: dict
    rows: list
    misses: list
    gain: float
    change: dict
    stiffness_scale: float

    @property
    def inside(self) -> bool:
        return not self.misses


def prediction_sd(s: ModeSeries, mf: ModesFit, rel_step: float = 1e-3) -> tuple:
    """(values, frequency_hz (L,), zeta (L,), sd_hz (L,), sd_zeta (L,)) of mode ``s``
    predicted from fit ``mf``: the joint covariance of the fit (misfit scaled; parameters
    at a bound held) and the calibration level's noise, both through the recalibrated
    prediction by forward differences (module docstring), and each level's own noise
    (the calibration level: its sd is the calibration's)."""
    names, f = mf.names, mf.fit
    joint = mf.joint_values

    def out(jv, shift=(0.0, 0.0)):
        d = copy.copy(s.data)
        d.omega2 = d.omega2.copy()
        d.zeta = d.zeta.copy()
        d.omega2[0] += shift[0]
        d.zeta[0] += shift[1]
        v = calibrate(ModeSeries(s.label, d, s.mask, s.fe, s.noise), jv, names)
        p = s.fe.predict(v)
        return v, np.concatenate([p.frequency_hz, p.zeta])

    values, y0 = out(joint)
    n = s.data.omega2.size
    free = [x for x in f.free if x in joint and not f.at_bound.get(x)]
    J = np.zeros((y0.size, len(free)))
    for j, name in enumerate(free):
        p = mf.problem.parameters[name]
        h = rel_step * p.step if joint[name] + rel_step * p.step <= p.upper \
            else -rel_step * p.step
        J[:, j] = (out({**joint, name: joint[name] + h})[1] - y0) / h
    var = np.zeros(y0.size)
    if f.cov is not None and free:
        idx = [f.free.index(x) for x in free]
        C = f.cov[np.ix_(idx, idx)] * f.misfit_scale
        var += np.maximum(np.einsum("ij,jk,ik->i", J, C, J), 0.0)
    s1 = (float(s.noise.sigma_omega2[0]), float(s.noise.sigma_zeta[0]))
    for k, sig in enumerate(s1):
        shift = [0.0, 0.0]
        shift[k] = sig
        var += (out(joint, tuple(shift))[1] - y0) ** 2
    f_meas = np.sqrt(s.data.omega2) / (2 * math.pi)
    own_f = np.asarray(s.noise.sigma_omega2) / (8 * math.pi ** 2 * f_meas)
    own = np.concatenate([own_f, np.asarray(s.noise.sigma_zeta)])
    own[[0, n]] = 0.0                       # the calibration level: its noise is in var
    sd = np.sqrt(var + own ** 2)
    return values, y0[:n], y0[n:], sd[:n], sd[n:]


def predict_mode(s: ModeSeries, mf: ModesFit) -> ModePrediction:
    """Mode ``s`` (not fitted) predicted at every level from the joint of ``mf`` (module
    docstring)."""
    values, fp, zp, sf, sz = prediction_sd(s, mf)
    f_meas = np.sqrt(s.data.omega2) / (2 * math.pi)
    z_meas = np.asarray(s.data.zeta, float)
    rows, misses = [], []
    for i, lv in enumerate(s.data.level):
        zf, zz = (f_meas[i] - fp[i]) / sf[i], (z_meas[i] - zp[i]) / sz[i]
        row = {"level": int(lv), "measured_hz": float(f_meas[i]), "predicted_hz": float(fp[i]),
               "sd_hz": float(sf[i]), "z_frequency": float(zf),
               "measured_zeta": float(z_meas[i]), "predicted_zeta": float(zp[i]),
               "sd_zeta": float(sz[i]), "z_zeta": float(zz),
               "calibration": bool(i == 0)}
        row["inside_pi95"] = bool(abs(zf) <= Z95 and abs(zz) <= Z95)
        rows.append(row)
        if not row["inside_pi95"]:
            misses.append({"level": int(lv), "z_frequency": float(zf), "z_zeta": float(zz)})
    pred = np.concatenate([(f_meas[1:] - fp[1:]) / sf[1:], (z_meas[1:] - zp[1:]) / sz[1:]])
    flat = np.concatenate([(f_meas[1:] - fp[0]) / sf[1:], (z_meas[1:] - zp[0]) / sz[1:]])
    gain = float(flat @ flat) / float(pred @ pred) if pred @ pred > 0 else math.inf
    change = {"measured_frequency_drop_pct": float(100 * (1 - f_meas.min() / f_meas[0])),
              "predicted_frequency_drop_pct": float(100 * (1 - fp.min() / fp[0])),
              "measured_zeta_growth": float(z_meas.max() / z_meas[0]),
              "predicted_zeta_growth": float(zp.max() / zp[0])}
    pr = s.fe.predict(values)
    return ModePrediction(s.label, values, rows, misses, gain, change,
                          float(pr.joint["stiffness_scale"]))
