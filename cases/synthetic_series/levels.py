"""Every level of a drawn series: FRF, measurement noise, identification, the table.

FRF noise: complex Gaussian, relative ``eps`` of ``|H|`` per line plus a floor of
2 % of ``eps`` times the peak; the force transducer reads the force with relative
noise ``eps``. Each level is identified on its own (:func:`identify_level`); a level
whose response folds over (several steady states) or whose identification fails
rejects the draw (the caller draws again).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cases.synthetic_series.identification import identify_level
from cases.synthetic_series.mode import level_frf
from ident.modal_data import MeasuredData

__all__ = ["SyntheticSeries", "noisy", "force_for", "simulate_levels"]


@dataclass
class SyntheticSeries:
    """A generated series: the table the diagnosis sees, the FRFs it came from
    (``frfs``: per level ``freq_hz``, ``frf``, ``force``, ``held``, ``run_order``,
    ``control``) and the hidden truth (never shown to the diagnosis)."""

    data: MeasuredData
    frfs: list
    truth: dict = field(default_factory=dict)


def noisy(rng, H, eps):
    """``H`` with relative complex noise ``eps`` and a floor (module doc)."""
    n = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / math.sqrt(2)
    m = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / math.sqrt(2)
    return H * (1 + eps * n) + 0.02 * eps * np.abs(H).max() * m


def force_for(mode, X, run=1.0, c_e=0.0) -> float:
    """Drive amplitude that holds amplitude ``X`` at resonance (``Re D = 0``), N;
    with back-EMF damping ``c_e`` the exciter's output before the back-EMF."""
    w_res = math.sqrt(max(mode.stiffness(X, 0.0, run).real, 1e-12))
    return X * float(abs(mode.stiffness(X, w_res, run) + 1j * w_res * c_e))


def simulate_levels(rng, drawn: dict, control: str) -> SyntheticSeries | None:
    """Simulate, add noise and identify every level of ``drawn`` (from
    :mod:`cases.synthetic_series.draw`); None when a level folds or fails."""
    mode, W, rel, eps = drawn["mode"], drawn["W"], drawn["rel"], drawn["eps"]
    X_top, run, exciter = drawn["X_top"], drawn["run"], drawn["exciter"]
    n = rel.size
    if control == "response":
        held = X_top * rel
    else:
        F_top = force_for(mode, X_top, float(run[-1]), 0.0 if exciter is None else exciter.c_e)
        held = F_top * rel
        if exciter is not None:                             # volts; top reaches X_top
            exciter.g = 1.0
            exciter.g = F_top / float(exciter.force(1.0))
            held = rel.copy()
    scale = drawn["scale"] if drawn["scale"] is not None else np.ones(n)
    rows, frfs, x_peak = [], [], []
    for v in range(n):
        H, F, X, fold = level_frf(mode, W, control, held[v], float(run[v]),
                                  exciter, float(scale[v]))
        if fold:
            return None
        Hn = noisy(rng, H, eps)
        Fm = F * (1 + eps * rng.standard_normal(F.shape))
        f_hz = W / (2 * math.pi)
        try:
            with np.errstate(all="ignore"):
                row = identify_level(f_hz, Hn, Fm, control, float(held[v]))
        except (ValueError, IndexError, np.linalg.LinAlgError):
            return None
        if not (np.isfinite(row["omega2"]) and 0 < row["zeta"] < 1):
            return None
        rows.append(row)
        x_peak.append(float(X.max()))
        frfs.append({"freq_hz": f_hz, "frf": Hn, "force": Fm, "held": float(held[v]),
                     "run_order": int(run[v]), "control": control})
    col = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    data = MeasuredData(level=np.arange(1, n + 1), excitation=col["excitation"],
                        omega2=col["omega2"], zeta=col["zeta"], mode=np.ones(n, int),
                        run_order=run, response_amplitude=col["response_amplitude"],
                        omega2_std=col["omega2_std"], zeta_std=col["zeta_std"],
                        control=np.full(n, control), source="synthetic")
    truth = dict(drawn["truth"], x_peak=np.array(x_peak) / mode.joint.phi_max,
                 fit_error=col["fit_error"])
    return SyntheticSeries(data=data, frfs=frfs, truth=truth)
