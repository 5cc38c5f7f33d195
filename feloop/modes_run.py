"""``update --modes`` and ``loop --fit-modes/--predict-modes``: the measured modes read,
tied to FE modes, one joint fitted to some and the others predicted (:mod:`feloop.modes`).

:func:`run_modes` takes the measured table, the fit modes (the first the reference) and
the predicted modes; the fit levels of a fit mode are ``fit_levels`` (level labels, the
same for every mode; None: all of them), a predicted mode is predicted at every level.
Returns a dict rendered by :mod:`feloop.modes_report`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from feloop.levels import abscissa_of
from feloop.mode_prediction import predict_mode
from feloop.modes import fit_modes, mode_series
from ident.measured import read_measured
from inverse.estimate import parse_levels

__all__ = ["ModesSettings", "parse_modes", "run_modes"]

#: levels a fitted mode needs (the base model has up to 4 parameters of its own)
MIN_LEVELS = 5


def parse_modes(text: str, flag: str = "--modes") -> tuple[int, ...]:
    """``"1,2"`` -> (1, 2): mode labels, distinct, in order; ValueError (one line)."""
    try:
        labels = tuple(int(t) for t in str(text).split(",") if t.strip())
    except ValueError:
        raise ValueError(f"{flag}: expected mode labels like 1,2, got {text!r}") from None
    if not labels or len(set(labels)) != len(labels) or min(labels) < 1:
        raise ValueError(f"{flag}: expected distinct positive mode labels, got {text!r}")
    return labels


@dataclass(frozen=True)
class ModesSettings:
    """The table (``data_path``), the fit modes (the first the reference), the predicted
    modes, the fit levels (level labels; None: all), the force scale (N per excitation
    unit, assumed) and the rig's repeatability as the user states it
    (:attr:`ident.modal_data.MeasuredData.rig_repeatability`)."""

    data_path: str
    fit_modes: tuple
    predict_modes: tuple = ()
    fit_levels: str | None = None
    force_scale: float = 1.0
    rig_repeatability: tuple | None = None

    def __post_init__(self):
        both = set(self.fit_modes) & set(self.predict_modes)
        if both:
            raise ValueError(f"mode(s) {sorted(both)} both fitted and predicted")
        if self.fit_levels is not None:
            parse_levels(self.fit_levels)


def _mode_data(table, label: int, settings: ModesSettings):
    try:
        data = table.for_mode(label)
    except ValueError as exc:
        raise ValueError(f"{settings.data_path}: {exc}") from None
    data.rig_repeatability = settings.rig_repeatability
    route = abscissa_of(data)
    if route != "force":
        raise ValueError(f"{settings.data_path}: mode {label}: several modes are fitted on "
                         f"force-controlled stepped sine; its rows are {route}")
    return data


def _mask(data, label: int, settings: ModesSettings, fitted: bool) -> np.ndarray:
    if not fitted or settings.fit_levels is None:
        mask = np.ones(len(data), bool)
    else:
        mask = np.isin(data.level, parse_levels(settings.fit_levels))
    if fitted and mask.sum() < MIN_LEVELS:
        raise ValueError(f"mode {label}: {int(mask.sum())} fit levels, need at least "
                         f"{MIN_LEVELS}")
    if not fitted and len(data) < 2:
        raise ValueError(f"mode {label}: one level; a prediction needs a calibration level "
                         "and another")
    return mask


def run_modes(settings: ModesSettings, levels, case_name: str = "") -> dict:
    """One joint fitted to ``settings.fit_modes``, the ``predict_modes`` predicted
    (module docstring); ``levels(data, force_scale=)``: the case's FE-levels model."""
    t0 = time.perf_counter()
    table = read_measured(settings.data_path)
    labels = tuple(settings.fit_modes) + tuple(settings.predict_modes)
    data = {m: _mode_data(table, m, settings) for m in labels}
    masks = {m: _mask(data[m], m, settings, m in settings.fit_modes) for m in labels}
    series = mode_series(data, masks, lambda d: levels(d, force_scale=settings.force_scale))
    fitted = [s for s in series if s.label in settings.fit_modes]
    mf = fit_modes(fitted)
    t_fit = time.perf_counter() - t0
    predicted = {s.label: predict_mode(s, mf) for s in series
                 if s.label in settings.predict_modes}
    return {"case": case_name, "settings": settings, "series": series, "fit": mf,
            "predicted": predicted,
            "timing_s": {"fit": t_fit, "total": time.perf_counter() - t0}}
