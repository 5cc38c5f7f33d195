"""The ``iwanfe modes`` report of the double beam: its modes in a band (frequency, kind,
glue-slip participation, the mode matching the measured one) and the calibration
statement (clamp grip, calibrated and uncalibrated frequency of the measured mode)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from cases.double_beam import model as db

from cases.mode_report import (ROUNDOFF_COEFFICIENT, ROUNDOFF_TOLERANCE,  # noqa: F401
                                min_element_size)


def max_band_hz(config) -> float:
    """Highest frequency (Hz) the model answers for: the bending wave of length
    ``max(10 t, 4 h)``, ``f = (2 pi/lambda)^2 sqrt(E t^2/(12 rho))/(2 pi)``. Shorter waves
    leave the Euler-Bernoulli beam's range (shear and rotary inertia, neglected, grow as
    (t/lambda)^2: about 10 % at lambda = 10 t) or the mesh's (a cubic element resolves
    wavelengths down to about 4 elements). 23 kHz for the shipped model."""
    t = config.thickness
    wavelength = max(10.0 * t, 4.0 * config.element_size)
    return float((2 * np.pi / wavelength) ** 2 * np.sqrt(config.E * t * t / (12 * config.rho))
                 / (2 * np.pi))


def double_beam_report(band=(50.0, 450.0), contact=None, element_size=None, joints=None,
                       uncalibrated=False) -> dict:
    """Modes of the double beam in ``band`` plus the calibration statement (a dict)."""
    lo, hi = (float(v) for v in band)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ValueError(f"--band {lo:g} {hi:g}: needs finite 0 <= LO < HI (Hz)")
    overrides = {}
    if contact is not None:
        overrides["contact"] = contact
    if element_size is not None:
        h_min = min_element_size(db.DoubleBeamConfig().free_length)
        if not (np.isfinite(element_size) and element_size <= 0.05):
            raise ValueError(f"--element-size {element_size:g}: must be a finite size <= 0.05 m "
                             "(at least 7 elements over the free length)")
        if not element_size >= h_min:
            raise ValueError(f"--element-size {element_size:g}: must be >= {h_min:.2g} m; below "
                             f"it the beam element's round-off, ~2e-4 (L/h)^4 eps, exceeds "
                             f"{ROUNDOFF_TOLERANCE:g} of the frequency")
        overrides["element_size"] = element_size
    if joints is not None:
        if not 2 <= joints <= 200:
            raise ValueError(f"--joints must be in 2..200, got {joints}")
        overrides["n_joints"] = joints
    config = replace(db.DoubleBeamConfig(), **overrides)
    if hi > max_band_hz(config):
        raise ValueError(f"--band {lo:g} {hi:g}: HI must be <= {max_band_hz(config):.4g} Hz, the "
                         f"shortest bending wave this beam model and mesh represent")
    uncal_config = replace(config, clamp_length=db.UNCALIBRATED_CLAMP_LENGTH)
    if uncalibrated:
        config = uncal_config
    model = db.build_double_beam(config)
    rows = model.band_modes((lo, hi))
    f_cal = db.bending_mode_frequency(db.build_double_beam(replace(config, clamp_length=None)),
                                      db.MEASURED_BENDING_ORDER)
    f_uncal = db.bending_mode_frequency(db.build_double_beam(uncal_config), db.MEASURED_BENDING_ORDER)
    return {
        "case": "double-beam",
        "band_hz": [lo, hi],
        "measured_frequency_hz": db.MEASURED_FREQUENCY_HZ,
        "model": "uncalibrated" if uncalibrated else "calibrated",
        "contact": config.contact,
        "n_free_dofs": model.n_free,
        "calibration": {
            "parameter": "clamp_length",
            "description": "length of strip held in the clamp (free length = 0.35 m - grip)",
            "value_m": db.CALIBRATED_CLAMP_LENGTH,
            "target_hz": db.MEASURED_FREQUENCY_HZ,
            "measured_mode": f"in-phase bending mode {db.MEASURED_BENDING_ORDER}",
            "calibrated_frequency_hz": f_cal,
            "uncalibrated_frequency_hz": f_uncal,
            "uncalibrated_error": f_uncal / db.MEASURED_FREQUENCY_HZ - 1.0,
        },
        "modes": rows,
    }
