"""The series :func:`inverse.estimate.estimate` fits: the mode, its level means, the fit
levels (``--fit-levels``: :func:`parse_levels`, :func:`format_levels`) and the abscissa
each level is regressed on (module doc of :mod:`inverse.estimate`)."""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ident.errors import InputError
from ident.modal_data import mean_per_level

#: A resonant amplitude that falls this far behind the excitation over the fit levels is
#: worth a warning (the paper's abscissa then misplaces the top levels by as much).
RESONANT_LAG = 1.2
#: The reference level: the lowest level of the mode = the paper's f_e0.
REF = 0


def parse_levels(text: str) -> list[int]:
    """``"1-7"`` -> [1..7]; ``"1,3-5,8"`` -> [1, 3, 4, 5, 8]. ValueError on bad input."""
    out: list[int] = []
    for item in str(text).replace(" ", "").split(","):
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", item)
        if not m:
            raise InputError(f"--fit-levels: cannot read {item!r} (use e.g. 1-7 or 1,3-7)")
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) else a
        if b < a:
            raise InputError(f"--fit-levels: range {item!r} runs backwards")
        if b > 10_000:   # a stepped-sine test has tens of levels; this bounds the list
            raise InputError(f"--fit-levels: level {b} in {item!r} exceeds 10000")
        out.extend(range(a, b + 1))
    if len(set(out)) != len(out):
        raise InputError(f"--fit-levels: {text!r} repeats a level")
    return sorted(out)


def format_levels(levels) -> str:
    """[1, 2, 3, 5] -> ``"1-3,5"`` (the inverse of :func:`parse_levels`)."""
    levels = list(levels)
    parts, start = [], levels[0]
    for a, b in zip(levels, levels[1:] + [None]):
        if b != a + 1:
            parts.append(f"{start}" if start == a else f"{start}-{a}")
            start = b
    return ",".join(parts)


def _select_mode(data, mode):
    """The mode label (default the only one in ``data``) and its rows."""
    modes = np.unique(data.mode)
    if mode is None:
        if modes.size != 1:
            raise InputError(f"{data.source or 'data'} holds modes "
                             f"{', '.join(map(str, modes))}: choose one with --mode")
        mode = int(modes[0])
    return int(mode), data.for_mode(int(mode))


def _resonant_lag(zeta_omega2) -> list:
    """A warning when the excitation is the abscissa (force control: the paper takes the
    joint amplitude proportional to it) but the resonant amplitude ``E / (2 zeta
    omega^2)`` falls behind it, because ``zeta omega^2`` grew over the fit levels."""
    lag = float(np.max(zeta_omega2) / zeta_omega2[0])
    if lag <= RESONANT_LAG:
        return []
    return [f"zeta omega^2 grows {lag:.3g}x over the fit levels: under force control the "
            f"resonant amplitude E / (2 zeta omega^2) then grows {lag:.3g}x less than the "
            f"excitation, which the paper's abscissa (joint amplitude proportional to the "
            f"excitation) ignores, and chi comes out biased; `iwanfe diagnose` takes the "
            f"resonant amplitude; with a response_amplitude column use --method amplitude"]


def _fit_level_list(fit_levels, levels: np.ndarray, mode: int) -> list[int]:
    """The fit levels asked for (default all ``levels``), checked against ``levels``."""
    if fit_levels is None:
        fit = list(map(int, levels))
    elif isinstance(fit_levels, str):
        fit = parse_levels(fit_levels)
    else:
        fit = sorted(int(v) for v in fit_levels)
    missing = sorted(set(fit) - set(map(int, levels)))
    if missing:
        raise InputError(f"--fit-levels: level(s) {format_levels(missing)} not in mode {mode} "
                         f"(levels {format_levels(list(map(int, levels)))})")
    if len(fit) < 3:
        raise InputError(f"--fit-levels: need at least 3 levels (2 differences), got {len(fit)}")
    return fit


def _abscissa(d, method: str, amplitude, test: str) -> tuple[np.ndarray, str]:
    """The amplitude of each level the fit regresses on, and its name."""
    # abscissa: what each level held (excitation; the response amplitude under response
    # control, where it is the level's abscissa), or a supplied/measured amplitude
    held_label = {"random": "response_amplitude (RMS of a random test)",
                  "free-decay": "response_amplitude (envelope of a free decay)"}.get(
        test, "response_amplitude (held: control = response)")
    abscissa = "excitation"
    amp = d.excitation
    if d.response_abscissa:
        amp = d.held_amplitude
        abscissa = held_label
    if method == "amplitude":
        if amplitude is not None:
            amp = np.asarray(amplitude, dtype=float).ravel()
            if amp.shape != d.level.shape or np.any(~(amp > 0)):
                raise InputError(f"amplitude must hold {d.level.size} positive values, "
                                 "one per level")
            abscissa = "amplitude (supplied)"
        elif d.response_amplitude is not None:
            amp = d.response_amplitude
            abscissa = held_label if d.response_abscissa else "response_amplitude"
        else:
            raise InputError(f"method 'amplitude' needs a response_amplitude column in "
                             f"{d.source or 'the data'} (or amplitudes from a simulation)")
    return amp, abscissa


@dataclass
class Series:
    """One mode's level means as the estimator fits them: ``d`` (sorted by level), the
    ``fit`` levels and the mask ``in_fit`` over ``d``, the abscissa ``amp`` (named
    ``abscissa``) and ``r = amp / amp[REF]``, the ``test`` type and the ``warnings`` so
    far."""

    mode: int
    d: object
    fit: list
    in_fit: np.ndarray
    amp: np.ndarray
    abscissa: str
    r: np.ndarray
    test: str
    warnings: list

    @property
    def fi(self) -> np.ndarray:
        """Indices into ``d`` of the fit levels."""
        return np.flatnonzero(self.in_fit)


def prepare_series(data, mode, fit_levels, method: str, amplitude) -> Series:
    """The mode of ``data`` (default its only one) averaged per level, its fit levels
    and abscissa, checked (:class:`Series`; one-line ``InputError`` otherwise).

    Parameters
    ----------
    data : ident.measured.MeasuredData
    mode, fit_levels, method, amplitude
        As in :func:`inverse.estimate.estimate`.

    Returns
    -------
    Series
    """
    mode, d = _select_mode(data, mode)
    warnings = list(data.warnings)
    d, averaged = mean_per_level(d)
    if averaged:
        warnings.append(averaged)
    fit = _fit_level_list(fit_levels, d.level, mode)
    test = str(d.test[0])
    amp, abscissa = _abscissa(d, method, amplitude, test)
    in_fit = np.isin(d.level, fit)
    fi = np.flatnonzero(in_fit)
    if abscissa == "excitation":
        warnings += _resonant_lag(d.zeta[fi] * d.omega2[fi])
    if np.any(np.diff(amp[fi]) <= 0):
        raise InputError(f"{abscissa} must increase over the fit levels")
    return Series(mode, d, fit, in_fit, amp, abscissa, amp / amp[REF], test, warnings)
