"""Frequency and damping at every level from a damping-growth fit (paper eq. 43, 46).

``Delta omega^2(e) = (kappa2/|kappa1|) |kappa1| B r^(chi+1)``: the ratio
``kappa2/|kappa1|`` depends on chi alone, so chi and ``|kappa1| B`` predict frequency and
damping without B or R. Absolute values need the linear anchors ``omega_lin^2`` (and
``zeta_n`` or ``c_n``), estimated by least squares over the fit levels. Intervals are
the fit's delta-method t-intervals (:class:`inverse.power_law.PowerLawFit`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

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
    omega2, zeta = d.omega2, d.zeta
    fi = np.flatnonzero(in_fit)
    kap = "paper" if method == "paper" else "exact"
    omega2_lin = float(np.mean(omega2[fi] + _loss(fitres.p, fitres.ln_kt, r[fi], kap)))
    zeta_lin = float(np.mean(zeta[fi] - fitres.delta_c(r[fi]) / (eq45_factor * omega2[fi])))
    law = _Law(method, kap, r, c_modal, eq45_factor, omega2_lin, zeta_lin)
    bands = _bands(fitres, law, confidence)
    predictions = [_record(d, i, bool(not in_fit[i]), bands) for i in range(d.level.size)]
    return predictions, omega2_lin, zeta_lin


def _loss(p, lk, rr, kap: str):
    """The loss of omega^2 at ``rr``: ``Delta omega^2(r) = q K r^p``."""
    return kappa_ratio(p - 1.0, kap) * math.exp(lk) / p * np.asarray(rr) ** p


@dataclass(frozen=True)
class _Law:
    """Omega^2 and zeta of the fitted law at the levels' amplitudes ``r``, as functions of
    the fit's ``(p, ln Kt)``, from the linear anchors."""

    method: str
    kap: str
    r: np.ndarray
    c_modal: float
    eq45_factor: float
    omega2_lin: float
    zeta_lin: float

    def absolute(self, p, lk) -> tuple[np.ndarray, np.ndarray]:
        """(omega^2, zeta) at every level."""
        om2 = self.omega2_lin - _loss(p, lk, self.r, self.kap)
        dc = math.exp(lk) / p * self.r ** p
        if self.method == "paper":
            ze = self.zeta_lin + dc / (self.eq45_factor * om2)
        else:
            with np.errstate(invalid="ignore"):   # omega^2 <= 0: nan, named by unphysical
                ze = zeta_with_joint(dc, om2, self.c_modal, self.eq45_factor)
        return om2, ze

    def d_om2(self, p, k) -> np.ndarray:
        """The loss of omega^2 from each level to the next."""
        om2 = self.absolute(p, k)[0]
        return om2[:-1] - om2[1:]

    def d_ze(self, p, k) -> np.ndarray:
        """The growth of zeta from each level to the next."""
        ze = self.absolute(p, k)[1]
        return ze[1:] - ze[:-1]


def _bands(fitres: PowerLawFit, law: _Law, confidence: float) -> dict:
    """``{name: (prediction, lower, upper)}`` for omega2, zeta and their changes."""
    om2_p, ze_p = law.absolute(fitres.p, fitres.ln_kt)
    lo_om2, hi_om2 = fitres.interval(lambda p, k: law.absolute(p, k)[0], confidence)
    lo_ze, hi_ze = fitres.interval(lambda p, k: law.absolute(p, k)[1], confidence)
    lo_dom, hi_dom = fitres.interval(law.d_om2, confidence)
    lo_dze, hi_dze = fitres.interval(law.d_ze, confidence)
    dom_p, dze_p = law.d_om2(fitres.p, fitres.ln_kt), law.d_ze(fitres.p, fitres.ln_kt)
    return {"omega2": (om2_p, lo_om2, hi_om2), "zeta": (ze_p, lo_ze, hi_ze),
            "delta_omega2": (dom_p, lo_dom, hi_dom), "delta_zeta": (dze_p, lo_dze, hi_dze)}


def _err(pred, meas):
    """Percent error of ``pred`` against ``meas`` (None for ``meas == 0``)."""
    return 100.0 * (pred - meas) / meas if meas != 0 else None


def _entries(name: str, band: tuple, j: int, measured) -> dict:
    """``name`` at index ``j`` of its band, its interval, the measured value, the error."""
    pred, lo, hi = band
    return {name: float(pred[j]), f"{name}_interval": [float(lo[j]), float(hi[j])],
            f"measured_{name}": float(measured), f"{name}_error_percent": _err(pred[j], measured)}


def _record(d, i: int, held_out: bool, bands: dict) -> dict:
    """The prediction record of level ``i`` of ``d`` (with the change from level i - 1)."""
    omega2, zeta = d.omega2, d.zeta
    rec = {"level": int(d.level[i]), "excitation": float(d.excitation[i]),
           "held_amplitude": float(d.held_amplitude[i]), "held_out": held_out,
           **_entries("omega2", bands["omega2"], i, omega2[i]),
           **_entries("zeta", bands["zeta"], i, zeta[i])}
    if i == 0:
        rec.update(delta_omega2=None, delta_omega2_interval=None, measured_delta_omega2=None,
                   delta_omega2_error_percent=None, delta_zeta=None,
                   delta_zeta_interval=None, measured_delta_zeta=None,
                   delta_zeta_error_percent=None)
    else:
        m_dom = float(omega2[i - 1] - omega2[i])
        m_dze = float(zeta[i] - zeta[i - 1])
        rec.update(_entries("delta_omega2", bands["delta_omega2"], i - 1, m_dom))
        rec.update(_entries("delta_zeta", bands["delta_zeta"], i - 1, m_dze))
    return rec


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
