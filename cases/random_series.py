"""A random-excitation test series, simulated and written as FRF files; its Iwan model.

:func:`simulate_random_series` drives a reduced jointed model with band-limited
Gaussian force at several RMS levels (:func:`runs.random_test.random_level`, one seed
per level) and writes one H1 FRF file per level (``# test = random``, ``excitation`` =
the drive RMS, a ``coherence`` column at the drive point and the drive's
autospectrum ``force_psd``, :mod:`ident.frf_files`) as
soon as the level is done; the coherence at every point, the response and slip RMS and
the seed go into ``level_XX.json`` beside it. A rerun with the same inputs keeps the
finished levels.

:func:`sdof_iwan` is the single-DOF oscillator with one Iwan joint the tests use and
:func:`sdof_rayleigh_prediction` its frequency and damping ratio under a random drive
through the expectation over the Rayleigh-distributed slip amplitude
(:func:`inverse.random_amplitude.rayleigh_describing_function`, the ``A^2``-weighted
expectation of statistical linearization): ``omega^2 = (k_lin + k_in_eq)/m`` and
``zeta = c/(2 m omega) + k_q_eq/(2 m omega^2)``. SI units: s, Hz, m, N.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fe.reduction import JointBank, ReducedModel
from runs.jsonio import to_jsonable
from runs.random_test import random_level

__all__ = ["RandomSeries", "simulate_random_series", "sdof_iwan", "sdof_rayleigh_prediction"]


@dataclass(frozen=True)
class RandomSeries:
    """What to simulate: drive RMS per level (N), the band (Hz), record ``duration``
    (s) after ``settle`` (s), line spacing ``resolution_hz``, ``steps_per_period`` of
    ``omega_ref`` (rad/s), and the ``seed`` of level 1 (level ``k`` uses ``seed + k - 1``)."""

    rms: tuple
    band_hz: tuple
    omega_ref: float
    duration: float = 150.0
    settle: float = 2.0
    resolution_hz: float = 0.1
    steps_per_period: int = 32
    seed: int = 0


def _digest(model, bank, load, outputs, series: RandomSeries) -> str:
    h = hashlib.sha256()
    for a in (model.M, model.K, model.C, model.G, model.K_T, bank.stiffness,
              bank.slip_limit, load, outputs):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(json.dumps(to_jsonable(series.__dict__), sort_keys=True).encode())
    return h.hexdigest()


def simulate_random_series(model: ReducedModel, bank: JointBank, load, outputs, points,
                           series: RandomSeries, out, progress=None) -> list[Path]:
    """Simulate every level of ``series`` and write its FRF file to ``out`` (module
    docstring); returns the FRF paths in level order.

    ``load`` (r,) reduced drive pattern per newton (the first output is the drive
    point, the ``reference``); ``outputs`` (n_out, r) rows of the recorded
    displacements, named ``points``."""
    from ident.frf_files import FRFSet, write_frf

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    digest = _digest(model, bank, load, outputs, series)
    paths = []
    for k, rms in enumerate(series.rms, start=1):
        path, meta = out / f"level_{k:02d}.csv", out / f"level_{k:02d}.json"
        paths.append(path)
        if meta.exists() and path.exists() and json.loads(meta.read_text()).get("hash") == digest:
            continue
        lvl = random_level(model, bank, load, outputs, float(rms), series.band_hz,
                           series.omega_ref, series.duration, series.resolution_hz,
                           series.seed + k - 1, series.steps_per_period, series.settle,
                           progress=progress)
        write_frf(path, FRFSet(lvl.freq_hz, lvl.h1, list(points), quantity="receptance",
                               excitation=lvl.drive_rms, reference=str(points[0]),
                               run_order=k, test="random",
                               coherence=np.clip(lvl.coherence[:, 0], 0.0, 1.0),
                               force_psd=lvl.force_psd))
        info = {"hash": digest, "level": k, "drive_rms_N": lvl.drive_rms,
                "response_rms_m": lvl.response_rms, "slip_rms_m": lvl.slip_rms,
                "seed": lvl.seed, "n_averages": lvl.n_averages, "duration_s": lvl.duration_s,
                "freq_hz": lvl.freq_hz, "coherence": lvl.coherence}
        tmp = meta.with_suffix(".tmp")
        tmp.write_text(json.dumps(to_jsonable(info)))
        os.replace(tmp, meta)
    return paths


def sdof_iwan(joint, k_lin: float, m: float, zeta: float, sliders_per_octave: int = 8,
              a_low: float = 1e-4):
    """Mass ``m`` (kg) on a spring ``k_lin`` (N/m) in parallel with the Iwan ``joint``
    (:class:`joints.iwan.IwanParameters`) and a dashpot giving the stuck-joint damping
    ratio ``zeta``: ``(ReducedModel, JointBank)``, the bank log-spaced from
    ``a_low phi_max`` to ``phi_max``."""
    k = k_lin + joint.K_T
    w = np.sqrt(k / m)
    model = ReducedModel(basis=np.eye(1), omega=np.array([w]), M=np.array([[m]]),
                         K=np.array([[k]]), C=np.array([[2 * zeta * w * m]]), G=np.eye(1),
                         K_T=np.array([joint.K_T]))
    return model, JointBank.log_spaced([joint], a_low * joint.phi_max, sliders_per_octave)


def sdof_rayleigh_prediction(joint, k_lin: float, m: float, c: float, slip_rms) -> dict:
    """``omega2`` (rad^2/s^2) and ``zeta`` of :func:`sdof_iwan` at the slip RMS values
    ``slip_rms`` (m) through the Rayleigh expectation (module docstring)."""
    from inverse.random_amplitude import rayleigh_describing_function

    k_in, k_q = rayleigh_describing_function(joint, np.asarray(slip_rms, float))
    omega2 = (k_lin + k_in) / m
    return {"omega2": omega2, "zeta": c / (2 * m * np.sqrt(omega2)) + k_q / (2 * m * omega2)}
