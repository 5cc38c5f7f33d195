"""Frequency and damping at every level from a damping-growth fit (paper eq. 43, 46).

``Delta omega^2(e) = (kappa2/|kappa1|) |kappa1| B r^(chi+1)``: the ratio
``kappa2/|kappa1|`` depends on chi alone, so chi and ``|kappa1| B`` predict frequency and
damping without B or R. Absolute values need the linear anchors ``omega_lin^2`` (and
``zeta_n`` or ``c_n``), estimated by least squares over the fit levels. Intervals are
the fit's delta-method t-intervals (:class:`inverse.power_law.PowerLawFit`).
"""
from __future__ import annotations

import math

import numpy as np

from inverse.iwan_modal import kappa_ratio, zeta_with_joint
from inverse.power_law import PowerLawFit


def predict_levels(fitres: PowerLawFit, d, in_fit, r, method: str, c_modal: float,
                   eq45_factor: float, confidence: float):
    """Predicted and measured omega^2, zeta and their changes at every level of ``d``.

    Parameters
    ----------
    fitres : PowerLawFit
        The fit of chi and ``|kappa1| B``.
    d : ident.measured.MeasuredData
        One mode, sorted by level.
    in_fit : ndarray of bool
        Levels of ``d`` in the fit (the others are marked ``held_out``).
    r : ndarray
        Relative amplitude of each level (the fit's abscissa).
    method : {"paper", "exact", "amplitude"}
        ``paper``: printed kappa2 and ``zeta_n omega_n / Omega ~ zeta_n``; otherwise the
        exact kappa2 and eq. 2 of :mod:`inverse.iwan_modal` with ``c_modal``.
    c_modal : float
        Viscous modal damping ``2 zeta_n omega_n``, rad/s (not used by ``paper``).
    eq45_factor : float
        Factor of Delta c in eq. 45 (2 derived, 1 printed).
    confidence : float
        Level of the t-intervals.

    Returns
    -------
    (predictions, omega2_linear, zeta_linear)
        One record per level (see :class:`inverse.estimate_result.Estimate`) and the
        linear anchors.
    """
    levels, omega2, zeta = d.level, d.omega2, d.zeta
    fi = np.flatnonzero(in_fit)
    kap = "paper" if method == "paper" else "exact"

    def q_of(p):
        return kappa_ratio(p - 1.0, kap)

    def loss(p, lk, rr):  # Delta omega^2(r) = q K r^p
        return q_of(p) * math.exp(lk) / p * np.asarray(rr) ** p

    omega2_lin = float(np.mean(omega2[fi] + loss(fitres.p, fitres.ln_kt, r[fi])))
    zeta_lin = float(np.mean(zeta[fi] - fitres.delta_c(r[fi]) / (eq45_factor * omega2[fi])))

    def absolute(p, lk):
        om2 = omega2_lin - loss(p, lk, r)
        dc = math.exp(lk) / p * r ** p
        if method == "paper":
            ze = zeta_lin + dc / (eq45_factor * om2)
        else:
            with np.errstate(invalid="ignore"):   # omega^2 <= 0: nan, named by unphysical
                ze = zeta_with_joint(dc, om2, c_modal, eq45_factor)
        return om2, ze

    om2_p, ze_p = absolute(fitres.p, fitres.ln_kt)
    lo_om2, hi_om2 = fitres.interval(lambda p, k: absolute(p, k)[0], confidence)
    lo_ze, hi_ze = fitres.interval(lambda p, k: absolute(p, k)[1], confidence)

    def d_om2(p, k):
        om2 = absolute(p, k)[0]
        return om2[:-1] - om2[1:]

    def d_ze(p, k):
        ze = absolute(p, k)[1]
        return ze[1:] - ze[:-1]

    lo_dom, hi_dom = fitres.interval(d_om2, confidence)
    lo_dze, hi_dze = fitres.interval(d_ze, confidence)
    dom_p, dze_p = d_om2(fitres.p, fitres.ln_kt), d_ze(fitres.p, fitres.ln_kt)

    def err(pred, meas):
        return 100.0 * (pred - meas) / meas if meas != 0 else None

    predictions = []
    for i in range(levels.size):
        rec = {"level": int(levels[i]), "excitation": float(d.excitation[i]),
               "held_amplitude": float(d.held_amplitude[i]),
               "held_out": bool(not in_fit[i]),
               "omega2": float(om2_p[i]), "omega2_interval": [float(lo_om2[i]), float(hi_om2[i])],
               "measured_omega2": float(omega2[i]),
               "omega2_error_percent": err(om2_p[i], omega2[i]),
               "zeta": float(ze_p[i]), "zeta_interval": [float(lo_ze[i]), float(hi_ze[i])],
               "measured_zeta": float(zeta[i]),
               "zeta_error_percent": err(ze_p[i], zeta[i])}
        if i == 0:
            rec.update(delta_omega2=None, delta_omega2_interval=None, measured_delta_omega2=None,
                       delta_omega2_error_percent=None, delta_zeta=None,
                       delta_zeta_interval=None, measured_delta_zeta=None,
                       delta_zeta_error_percent=None)
        else:
            j = i - 1
            m_dom = float(omega2[i - 1] - omega2[i])
            m_dze = float(zeta[i] - zeta[i - 1])
            rec.update(delta_omega2=float(dom_p[j]),
                       delta_omega2_interval=[float(lo_dom[j]), float(hi_dom[j])],
                       measured_delta_omega2=m_dom,
                       delta_omega2_error_percent=err(dom_p[j], m_dom),
                       delta_zeta=float(dze_p[j]),
                       delta_zeta_interval=[float(lo_dze[j]), float(hi_dze[j])],
                       measured_delta_zeta=m_dze,
                       delta_zeta_error_percent=err(dze_p[j], m_dze))
        predictions.append(rec)
    return predictions, omega2_lin, zeta_lin


def unphysical(predictions) -> str | None:
    """One sentence naming the levels where the fitted law predicts ``omega^2 <= 0`` or
    ``zeta <= 0`` (a growth law extrapolated past what it can describe), or None."""
    def levels(key):
        bad = [p["level"] for p in predictions if not p[key] > 0]   # nan counts as bad
        return ", ".join(map(str, bad))

    parts = [f"{name} <= 0 at level(s) {lv}" for name, lv in
             (("omega^2", levels("omega2")), ("zeta", levels("zeta"))) if lv]
    if not parts:
        return None
    return (f"the fitted law predicts {'; '.join(parts)}: no mode there, the fit does not "
            "describe this series (eq. 43, 46)")
