"""The ``iwanfe modes`` report of any case with an FE strip model: its modes in a band
(frequency, kind, bending order, joint-slip participation, the mode matching the measured
frequency) and the calibration statement (each calibrated parameter, the frequency before
and after). SI units, Hz."""
from __future__ import annotations

import numpy as np

#: Round-off of the Hermite beam element grows as (L/h)^4 eps: the relative error of a
#: low eigenvalue is about eps times the ratio of the mesh's highest eigenvalue (~ EI/(rho
#: A h^4), the shortest element) to the mode's (~ EI/(rho A L^4)). Measured on the double
#: beam (its 252 Hz mode against the converged 251.999907 Hz): 2.3e-6 at h = 0.1 mm,
#: 7.0e-5 at 0.05 mm, 5.6e-4 at 0.025 mm, 5.8e-2 at 0.01 mm, i.e. ROUNDOFF_COEFFICIENT
#: (L/h)^4 eps with the coefficient at most 2.2e-4. Elements smaller than
#: :func:`min_element_size` would make that error exceed ROUNDOFF_TOLERANCE: refused.
ROUNDOFF_COEFFICIENT = 2.2e-4
ROUNDOFF_TOLERANCE = 1e-5
MATCH_TOLERANCE = 0.005   # relative: "matches_measured"


def min_element_size(length: float) -> float:
    """Smallest useful element size (m) for a beam of ``length`` (m): ``L (c eps /
    tol)^(1/4)`` (comment above)."""
    eps = np.finfo(float).eps
    return float(length * (ROUNDOFF_COEFFICIENT * eps / ROUNDOFF_TOLERANCE) ** 0.25)


def max_band_hz(E: float, rho: float, thickness: float, element_size: float) -> float:
    """Highest frequency (Hz) an Euler-Bernoulli strip of this material and thickness and
    this mesh answers for: the bending wave of length ``max(10 t, 4 h)``, ``f = (2 pi /
    lambda)^2 sqrt(E t^2 / (12 rho)) / (2 pi)`` (shear and rotary inertia grow as
    (t/lambda)^2; a cubic element resolves about 4 elements per wave)."""
    wavelength = max(10.0 * thickness, 4.0 * element_size)
    return float((2 * np.pi / wavelength) ** 2 * np.sqrt(E * thickness**2 / (12 * rho))
                 / (2 * np.pi))


def band_modes(model, band_hz, measured_hz=None, tolerance: float = MATCH_TOLERANCE) -> list[dict]:
    """Modes with lo <= f <= hi as records (index = 1-based order in the whole model);
    a mode below 1e-3 of the highest frequency computed is a rigid-body mode (as in
    ``bending_order``), whatever its shape's larger energy share."""
    lo, hi = band_hz
    omega, shapes = model.modes_below(hi)
    order = model.bending_order(omega, shapes)
    rigid = omega <= 1e-3 * max(float(np.max(omega, initial=0.0)), 1e-300)
    f = omega / (2 * np.pi)
    return [{"index": int(i + 1), "frequency_hz": float(f[i]), "omega2": float(omega[i] ** 2),
             "kind": "rigid-body" if rigid[i] else model.classify_mode(shapes[:, i]),
             "bending_order": int(order[i]),
             "glue_slip": model.glue_slip_participation(shapes[:, i]),
             "matches_measured": bool(measured_hz is not None
                                      and abs(f[i] / measured_hz - 1) <= tolerance)}
            for i in np.flatnonzero((f >= lo) & (f <= hi))]


#: Default top of the band (Hz), or this many times the measured frequency if higher.
DEFAULT_TOP_HZ, DEFAULT_TOP_OVER_MEASURED = 1000.0, 1.8


def mode_report(case, band=None, element_size=None, uncalibrated=False) -> dict:
    """Modes of ``case`` (:class:`cases.case.Case` with an FE model) in ``band`` (Hz;
    None: from 0 to :data:`DEFAULT_TOP_HZ` or :data:`DEFAULT_TOP_OVER_MEASURED` times the
    measured frequency, whichever is higher, within what the mesh represents) plus the
    calibration statement."""
    case.require("fe_model")
    cf = case.file
    measured = cf.measured.frequency_hz if cf.measured is not None else None
    given = band is not None
    lo, hi = (float(v) for v in band) if given else \
        (0.0, max(DEFAULT_TOP_HZ, DEFAULT_TOP_OVER_MEASURED * (measured or 0.0)))
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ValueError(f"--band {lo:g} {hi:g}: needs finite 0 <= LO < HI (Hz)")
    length = max(b.x[1] - b.x[0] for b in cf.beams)
    h = cf.element_size if element_size is None else float(element_size)
    if element_size is not None:
        h_min = min_element_size(length)
        if not (np.isfinite(h) and h <= length / 7):
            raise ValueError(f"--element-size {h:g}: must be a finite size <= {length / 7:.3g} m "
                             "(at least 7 elements over the longest beam)")
        if not h >= h_min:
            raise ValueError(f"--element-size {h:g}: must be >= {h_min:.2g} m; below it the "
                             f"beam element's round-off, ~2e-4 (L/h)^4 eps, exceeds "
                             f"{ROUNDOFF_TOLERANCE:g} of the frequency")
    top = min(max_band_hz(cf.material(b.material).E, cf.material(b.material).rho,
                          min([b.thickness] + [s.thickness for s in b.sections]), h)
              for b in cf.beams)
    if not given:
        hi = min(hi, top)
    if hi > top:
        raise ValueError(f"--band {lo:g} {hi:g}: HI must be <= {top:.4g} Hz, the shortest "
                         f"bending wave this beam model and mesh represent")
    # --uncalibrated runs no calibration (a failed one raises one line naming [calibrate])
    file_at = case.require("calibrated_file")
    calibration = None if uncalibrated else file_at(element_size=element_size)[1]
    model = case.fe_model(element_size=element_size, calibrated=not uncalibrated)
    return {"case": case.name, "band_hz": [lo, hi], "measured_frequency_hz": measured,
            "model": "uncalibrated" if uncalibrated and cf.calibrate else
                     ("calibrated" if calibration else "as given"),
            "n_free_dofs": model.n_free, "calibration": calibration,
            "modes": band_modes(model, (lo, hi), measured)}
