"""Stepped-sine campaigns: what to run (protocols, force levels x frequency lines) and
the result types.

At each line the structure is driven by ``f(t) = F cos(theta(t)) * load`` and the
first harmonic of the periodic response is recorded (receptance ``X_1 / F`` at the
output DOFs, joint-slip harmonics and half peak-to-peak slip amplitudes). Three
protocols:

* :class:`HBProtocol` (default, fast): harmonic balance (:mod:`fe.harmonic_balance`)
  with natural-parameter continuation from line to line (the previous lines'
  solutions predict the next one, as the structure's state does in a sweep).
* :class:`NewmarkProtocol`: time integration (:mod:`fe.newmark`) with the state and
  the excitation phase carried from line to line like a real stepped-sine test; a
  line is finished when the response is periodic: the change ``d_p`` of the
  first-harmonic vector between successive periods, extrapolated geometrically
  (``d_p rho/(1 - rho)`` with ``rho`` the largest of the last three ratios
  ``d_p/d_{p-1}``: a bound on the remaining drift of a decaying transient), falls
  below ``tol`` relative to the response. Optional frequency pre-warping removes the
  trapezoidal rule's frequency error: with ``n`` steps per period the discrete
  system driven at ``w'`` responds like the continuous one at
  ``(2/dt) tan(w' dt/2)``, so driving at ``w' = w pi/(n tan(pi/n))`` yields the
  response at ``w`` exactly (the Jenkins banks are rate independent).
* :class:`PaperProtocol`: the paper's fixed duration per line, every line from rest:
  9 s of settling then a 1-s window in which the first harmonic is obtained by least
  squares (paper section 3, Table 1: half peak-to-peak in the last second).

The campaign is run by :func:`runs.stepped_sine.run_campaign`. SI units: Hz for line
frequencies, N for force amplitudes, m for displacements.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fe.harmonic_balance import HBSettings

__all__ = [
    "HBProtocol",
    "NewmarkProtocol",
    "PaperProtocol",
    "Campaign",
    "LevelResult",
    "CampaignResult",
]


@dataclass(frozen=True)
class HBProtocol:
    """Harmonic balance with continuation over the lines."""

    settings: HBSettings = field(default_factory=HBSettings)
    name: str = "hb"


@dataclass(frozen=True)
class NewmarkProtocol:
    """Time integration until periodic (see module docstring).

    ``steps_per_period`` time steps per excitation period; ``tol`` relative bound on
    the remaining drift of the first harmonic; ``min_periods``/``max_periods`` per line
    (``max_periods`` reached raises); HHT ``alpha``; ``prewarp`` the frequency
    correction of the trapezoidal rule. ``hb_start``: None carries the state from line
    to line (from rest at the first line), like a test; harmonic-balance settings start
    every line on the harmonic-balance orbit of that line instead
    (:meth:`fe.newmark.NewmarkState.periodic`, phase 0), so that only the difference
    between the two steady states has to decay (not the transients of the slow low
    modes a line change excites), then integrate until periodic as above;
    ``macro_steps_per_period`` (with ``hb_start``) is used instead of
    ``steps_per_period`` on a level whose harmonic-balance orbits leave micro-slip (a
    slip amplitude at or above the bank's largest slip limit at some line), where the
    joint force is far from smooth (:meth:`steps_for`). ``period_newton`` (with
    ``hb_start``, ``alpha = 0``): after each period the start of the next is moved by a
    Newton step on the period map with the monodromy of the model linearized on the
    line's harmonic-balance orbit (:mod:`fe.newmark_period`), as long as the change over
    a period keeps falling; the steady state is still the integration's own.
    """

    steps_per_period: int = 256
    tol: float = 1e-6
    min_periods: int = 4
    max_periods: int = 5000
    alpha: float = 0.0
    prewarp: bool = True
    hb_start: HBSettings | None = None
    macro_steps_per_period: int | None = None
    period_newton: bool = False
    name: str = "newmark"

    def steps_for(self, slip_amplitude_max: float, slip_limit_max: float) -> int:
        """Steps per period of a level whose largest slip amplitude (m) is
        ``slip_amplitude_max``, for a bank whose largest slip limit is ``slip_limit_max``."""
        if self.macro_steps_per_period and slip_amplitude_max >= slip_limit_max:
            return int(self.macro_steps_per_period)
        return int(self.steps_per_period)


@dataclass(frozen=True)
class PaperProtocol:
    """The paper's fixed ``settle`` + ``window`` seconds per line, from rest."""

    settle: float = 9.0
    window: float = 1.0
    steps_per_period: int = 256
    alpha: float = 0.0
    name: str = "paper"


@dataclass(frozen=True)
class Campaign:
    """Force levels x frequency lines.

    Parameters
    ----------
    frequency_hz : (n_lines,) line frequencies (Hz), swept in the given order.
    force : (n_levels,) force amplitudes (N).
    load : (n,) physical load pattern (multiplied by ``force``).
    outputs : (n_out,) DOFs whose receptance is recorded.
    protocol : HBProtocol | NewmarkProtocol | PaperProtocol
    """

    frequency_hz: np.ndarray
    force: np.ndarray
    load: np.ndarray
    outputs: np.ndarray
    protocol: object = field(default_factory=HBProtocol)

    def __post_init__(self):
        f = np.atleast_1d(np.asarray(self.frequency_hz, dtype=float))
        F = np.atleast_1d(np.asarray(self.force, dtype=float))
        if f.size < 1 or np.any(~(f > 0)):
            raise ValueError("frequency lines must be > 0 Hz")
        if F.size < 1 or np.any(~(F > 0)):
            raise ValueError("force levels must be > 0 N")
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "force", F)
        object.__setattr__(self, "load", np.asarray(self.load, dtype=float))
        object.__setattr__(self, "outputs", np.atleast_1d(np.asarray(self.outputs, dtype=int)))


@dataclass
class LevelResult:
    """One force level: receptance (n_lines, n_out) complex (m/N), first-harmonic slips
    (n_lines, n_joints) complex (m), half peak-to-peak slips (n_lines, n_joints) (m),
    work per line (Newton iterations or periods), wall time (s), and per line how the
    steady state was reached when not by an ordinary Newton convergence (``fallbacks``,
    :attr:`fe.harmonic_balance.HBSolution.fallback`; empty strings otherwise)."""

    force: float
    receptance: np.ndarray
    slip: np.ndarray
    slip_amplitude: np.ndarray
    work: np.ndarray
    elapsed: float
    fallbacks: np.ndarray

    def to_npz(self, path: Path) -> None:
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, force=self.force, receptance=self.receptance, slip=self.slip,
                 slip_amplitude=self.slip_amplitude, work=self.work, elapsed=self.elapsed,
                 fallbacks=self.fallbacks)
        os.replace(tmp, path)

    @classmethod
    def from_npz(cls, path: Path) -> "LevelResult":
        with np.load(path) as d:
            return cls(float(d["force"]), d["receptance"], d["slip"], d["slip_amplitude"],
                       d["work"], float(d["elapsed"]), d["fallbacks"])


@dataclass
class CampaignResult:
    """All levels: ``receptance`` (n_levels, n_lines, n_out), ``slip`` and
    ``slip_amplitude`` (n_levels, n_lines, n_joints), ``work`` (n_levels, n_lines),
    ``elapsed`` (n_levels,) seconds, ``computed`` (n_levels,) False for levels loaded
    from the store, the campaign ``hash`` and ``fallbacks`` (n_levels, n_lines) str
    (:class:`LevelResult`)."""

    frequency_hz: np.ndarray
    force: np.ndarray
    receptance: np.ndarray
    slip: np.ndarray
    slip_amplitude: np.ndarray
    work: np.ndarray
    elapsed: np.ndarray
    computed: np.ndarray
    hash: str
    protocol: str
    fallbacks: np.ndarray

    def fallback_lines(self, labels=None) -> list[str]:
        """One line per level whose steady states needed a fallback: the level (its label
        in ``labels``, default 1, 2, ...), how many lines, the first line's frequency and
        how it was reached."""
        out = []
        labels = range(1, len(self.fallbacks) + 1) if labels is None else labels
        for i, (label, row) in enumerate(zip(labels, self.fallbacks)):
            hit = np.flatnonzero(row != "")
            if hit.size:
                out.append(f"level {label} (F = {self.force[i]:.4g} N): {hit.size} of "
                           f"{row.size} lines, first at {self.frequency_hz[hit[0]]:.6g} Hz: "
                           f"{row[hit[0]]}")
        return out

    def fallback_summary(self) -> str:
        """:meth:`fallback_lines` on one line, ``"none"`` without any."""
        return "; ".join(self.fallback_lines()) or "none"
