"""Calibration of a case file's unknown lengths or masses to measured linear frequencies.

Each frequency of ``[calibrate] frequencies_hz`` belongs to one bending mode of the model:
the one ``[measured] mode`` names when the frequency is ``[measured] frequency_hz`` (or
the only one), otherwise the bending mode nearest to it in the model at the file's values.
The parameters solve ``f_order(p) / f_target - 1 = 0`` in the least-squares sense
(:func:`scipy.optimize.least_squares`, trust-region reflective within
:func:`casefile.parameters.bounds`), starting from the file's values; the result
says how close each frequency came. SI units, Hz.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.optimize import brentq, least_squares

from casefile.build import build_model
from casefile.parameters import bounds, get_parameter, set_parameter
from casefile.tables import CaseFileError
from fe.modal import normal_modes

#: relative frequency error a calibration must reach (else it fails), or
#: ROUNDOFF_MARGIN times the round-off of the model's frequencies where that is larger (a
#: 14.8 Hz mode of a 0.3 m clamped lap: ~4e-6 at 1.25 mm elements, ~6e-5 at 0.625 mm)
CALIBRATION_TOLERANCE = 1e-6
ROUNDOFF_MARGIN = 3.0
MAX_DOUBLINGS = 36
#: finite-difference step of a parameter, relative to its scale (:func:`_difference_steps`)
DIFFERENCE_STEP = 1e-3


def _bending_frequencies(cf, n: int, sigma: float | None = None) -> np.ndarray:
    """The first ``n`` bending frequencies (Hz; NaN where missing), the eigen-solution at
    shift ``sigma`` (default :func:`fe.modal.normal_modes`' own)."""
    model = build_model(cf).model
    omega, shapes = normal_modes(model.K, model.M, min(n + 8, model.n_free - 2), sigma=sigma)
    order = model.bending_order(omega, shapes)
    f = np.full(n, np.nan)
    for k in range(1, n + 1):
        i = np.flatnonzero(order == k)
        if i.size:
            f[k - 1] = omega[i[0]] / (2 * np.pi)
    return f


def mode_orders(cf) -> list[int]:
    """The bending-mode order of each calibration frequency (module docstring)."""
    cal, meas = cf.calibrate, cf.measured
    targets = cal.frequencies_hz
    orders = []
    f_model = None
    for f in targets:
        if meas is not None and meas.mode is not None and (
                len(targets) == 1 or meas.frequency_hz == f):
            orders.append(int(meas.mode))
            continue
        if f_model is None:
            f_model = _bending_frequencies(cf, 12)
        orders.append(int(np.nanargmin(np.abs(f_model / f - 1))) + 1)
    return orders


def calibrate(cf):
    """``(calibrated case file, report)``; without ``[calibrate]``: ``(cf, None)``.

    ``report``: parameters with initial and calibrated values and bounds, targets with the
    bending-mode order, the initial and the calibrated frequency, ``converged``,
    ``max_relative_error``, ``roundoff_estimate``. A calibration that does not reach its
    targets raises :class:`CaseFileError` naming ``[calibrate]`` (one line: the error left
    and the best values): nothing downstream may use its parameters as calibrated.
    """
    if cf.calibrate is None:
        return cf, None
    out, report = _calibrate_cached(cf)
    if not report["converged"]:
        best = ", ".join(f"{p['parameter']} = {p['calibrated']:.6g}"
                         + (" (at a bound)" if p["at_bound"] else "")
                         for p in report["parameters"])
        raise CaseFileError(
            f"{cf.path}: [calibrate]: failed at element size {cf.element_size:g} m: relative "
            f"frequency error {report['max_relative_error']:.2e} remains (tolerance "
            f"{report['tolerance']:.1e}) at {best}; the targets are out of the parameters' "
            f"reach, or the mode orders are wrong")
    return out, report


@lru_cache(maxsize=32)
def _calibrate_cached(cf):
    cal = cf.calibrate
    names = list(cal.parameters)
    targets = np.asarray(cal.frequencies_hz, dtype=float)
    orders = mode_orders(cf)
    n = max(orders)
    x0 = np.array([get_parameter(cf, p) for p in names])
    lo, hi = (np.array(v) for v in zip(*(bounds(cf, p) for p in names)))

    def with_values(x):
        out = cf
        for p, v in zip(names, x):
            out = set_parameter(out, p, v)
        return out

    def residual(x):
        try:
            f = _bending_frequencies(with_values(x), n)[np.array(orders) - 1]
        except ValueError:            # e.g. the drive point moved into a clamp
            return np.full(targets.size, 1e3)
        if not np.all(np.isfinite(f)):
            return np.full(targets.size, 1e3)
        return f / targets - 1.0

    f_initial = targets * (1.0 + residual(x0))
    start = np.clip(x0, lo + 1e-12 * np.maximum(1, abs(lo)), hi)
    scale = np.where(np.abs(x0) > 0, np.abs(x0), 0.01 * _length_scale(cf))
    if x0.size == 1 and targets.size == 1:
        x_fit, r_fit = _root_1d(lambda v: residual(np.array([v]))[0], x0[0], lo[0], hi[0], scale[0])
    else:
        steps = _difference_steps(cf, names, scale)
        fit = least_squares(residual, start, jac=_central_jacobian(residual, steps, lo, hi),
                            bounds=(lo, hi), x_scale=scale, xtol=1e-10, ftol=1e-12, gtol=1e-12,
                            max_nfev=100)
        x_fit, r_fit = fit.x, fit.fun
    x_fit, r_fit = np.atleast_1d(x_fit), np.atleast_1d(r_fit)
    f_final = targets * (1.0 + r_fit)
    # round-off of the fitted frequencies: the eigen-solution again at another shift
    with np.errstate(invalid="ignore"):
        f_other = _bending_frequencies(with_values(x_fit), n,
                                       sigma=-4.0 * (2 * np.pi * np.min(f_final)) ** 2)
    roundoff = float(np.nanmax(np.abs(f_other[np.array(orders) - 1] / f_final - 1.0)))
    tolerance = max(CALIBRATION_TOLERANCE, ROUNDOFF_MARGIN * roundoff)
    report = {
        "parameters": [{"parameter": p, "initial": float(a), "calibrated": float(b),
                        "bounds": [float(l_), float(h_)],
                        "at_bound": bool(np.isclose(b, l_) or np.isclose(b, h_))}
                       for p, a, b, l_, h_ in zip(names, x0, x_fit, lo, hi)],
        "targets": [{"frequency_hz": float(t), "bending_mode": int(o),
                     "initial_hz": float(a), "calibrated_hz": float(b)}
                    for t, o, a, b in zip(targets, orders, f_initial, f_final)],
        "converged": bool(np.max(np.abs(r_fit)) <= tolerance),
        "max_relative_error": float(np.max(np.abs(r_fit))),
        "roundoff_estimate": roundoff, "tolerance": tolerance,
    }
    return with_values(x_fit), report


def _difference_steps(cf, names, scale) -> np.ndarray:
    """Finite-difference step of each parameter: :data:`DIFFERENCE_STEP` times its scale,
    and for a position (key ``x``) at least half the element size: a named point within
    the snap distance of another x shares its node, so the model is piecewise constant in
    it over up to ``0.2 h`` (:mod:`casefile.build`). Relative steps of 1e-6 were
    below the eigen-solution's round-off (~4e-8 relative at 1.25 mm elements against a
    change of 1e-8 per step): the Jacobian was noise, and a calibration that reaches its
    targets at 5 mm failed at 1.25 mm."""
    steps = DIFFERENCE_STEP * np.asarray(scale, dtype=float)
    is_position = np.array([p.rsplit(".", 1)[-1] == "x" for p in names])
    return np.where(is_position, np.maximum(steps, 0.5 * cf.element_size), steps)


def _central_jacobian(residual, steps, lo, hi):
    """``jac`` of :func:`scipy.optimize.least_squares`: central differences of
    ``residual`` with absolute ``steps``, one-sided where a bound is nearer."""
    def jac(x):
        columns = []
        for i, d in enumerate(steps):
            up, down = x.copy(), x.copy()
            up[i], down[i] = min(x[i] + d, hi[i]), max(x[i] - d, lo[i])
            columns.append((residual(up) - residual(down)) / (up[i] - down[i]))
        return np.column_stack(columns)
    return jac


def _root_1d(r, x0: float, lo: float, hi: float, scale: float):
    """Root of ``r`` in [lo, hi]: steps doubling from ``x0`` in both directions (at most
    :data:`MAX_DOUBLINGS`, i.e. 2^30 times the scale) until the sign changes, then Brent's
    method; the best point seen if there is no sign change (the report says not converged)."""
    r0 = r(x0)
    best = (abs(r0), x0, r0)
    for direction in (1.0, -1.0):
        a, ra, step = x0, r0, scale / 64
        for _ in range(MAX_DOUBLINGS):
            b = min(max(a + direction * step, lo), hi)
            if b == a:
                break
            rb = r(b)
            best = min(best, (abs(rb), b, rb))
            if np.sign(rb) != np.sign(ra) and abs(rb) < 1e2 and abs(ra) < 1e2:
                x = brentq(r, min(a, b), max(a, b), xtol=1e-14, rtol=1e-12)
                return x, r(x)
            a, ra, step = b, rb, 2 * step
    return best[1], best[2]


def _length_scale(cf) -> float:
    return max(b.x[1] - b.x[0] for b in cf.beams)
