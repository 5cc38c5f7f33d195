"""Every level of a drawn series: FRF, measurement noise, identification, the table.

FRF noise: complex Gaussian, relative ``eps`` of ``|H|`` per line plus a floor of
2 % of ``eps`` times the peak; the force transducer reads the force with relative
noise ``eps``. Each level becomes an FRF set (receptance at the drive point, the
``force`` column, the held level, ``control``, ``run_order``) and the series goes
through the project's own identification, as ``iwanfe diagnose FILE...`` would take
it (:func:`ident.series.identify_series` with one mode per level, as ``--modes 1``;
the band-sensitivity check is skipped for speed: it only adds warnings), and
:func:`ident.series_table.series_table` writes the table (stds, response amplitude,
excitation, warnings). A level whose response folds over (several steady states) or
a series the identification refuses rejects the draw (the caller draws again).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cases.synthetic_series.mode import level_frf
from ident.errors import InputError
from ident.frf_files import FRFSet
from ident.series import identify_series
from ident.series_table import series_table

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
    sets, frfs, x_peak = [], [], []
    for v in range(n):
        H, F, X, fold = level_frf(mode, W, control, held[v], float(run[v]),
                                  exciter, float(scale[v]))
        if fold:
            return None
        Hn = noisy(rng, H, eps)
        Fm = F * (1 + eps * rng.standard_normal(F.shape))
        f_hz = W / (2 * math.pi)
        sets.append(FRFSet(f_hz, Hn, ["1"], quantity="receptance", excitation=float(held[v]),
                           reference="1", source=f"level_{v + 1:02d}", control=control,
                           run_order=int(run[v]), force=Fm))
        x_peak.append(float(X.max()))
        frfs.append({"freq_hz": f_hz, "frf": Hn, "force": Fm, "held": float(held[v]),
                     "run_order": int(run[v]), "control": control})
    try:
        with np.errstate(all="ignore"):
            data = series_table(identify_series(sets, n_modes=1, check_band=False))
    except (InputError, ValueError, IndexError, np.linalg.LinAlgError):
        return None
    if len(data) != n or data.omega2_std is None:
        return None
    data.source = "synthetic"
    truth = dict(drawn["truth"], x_peak=np.array(x_peak) / mode.joint.phi_max,
                 fit_error=np.asarray(data.extra["x_fit_error"], float))
    return SyntheticSeries(data=data, frfs=frfs, truth=truth)
