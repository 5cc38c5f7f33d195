"""Settings of the double-beam reproduction (paper Section 4) and the choices behind them.

:class:`DoubleBeamStudy` holds every choice of ``iwanfe reproduce double-beam``
(:func:`cases.double_beam.study.run_study`); the defaults are the full run. The joint,
force-scale and viscous-damping decisions are stated in :mod:`cases.double_beam.joint_setup`;
the others here. The report states each with this run's numbers
(:func:`cases.double_beam.statements.assumption_statements`).

Lines. The paper stepped 2 Hz over 50-450 Hz: 3 lines in the half-power band (6.4 Hz
at 252 Hz and 1.28 %). The simulation steps 0.5 Hz over 236-268 Hz (65 lines, 13 in
the half-power band), upward with harmonic-balance continuation
(:class:`runs.stepped_sine.HBProtocol`: 7 harmonics, odd, 256 AFT samples); every level
starts from virgin joints. On the linear FRF the identifier with its default options
returns zeta to 1e-10 relative on this grid and to 4e-6 on the paper's 2 Hz grid over
50-450 Hz; the whole run takes seconds, so the finer grid costs nothing.

Jenkins discretization. The levels span a factor 512 in slip;
:meth:`fe.reduction.JointBank.log_spaced` (:func:`joints.jenkins.discretize_log` per
joint) places ``sliders_per_octave`` sliders per octave of slip limit from ``phi_max``
down to ``2^-octaves_below`` of the smallest level-1 joint amplitude (one more slider
holds the rest of the density), each with the density's stiffness on its cell and, as
slip limit, the density-weighted mean of the cell. With 16 per octave (252 sliders per
joint here) the micro-slip dissipation is within 1e-3 (6.3e-4 at chi = -0.5) and the
in-phase stiffness loss within 1.7e-4 of the exact four-parameter model
(:func:`joints.iwan.describing_function`) from 1e-3 ``phi_max`` to ``phi_max``, chi from
-0.9 to -0.1; the uniform discretization of :func:`joints.jenkins.discretize` reaches
1.1e-3 there with 1000 sliders.

Identification. LSCF + refinement (:func:`ident.levels.identify_levels`) of the
receptance at the response DOF (Acc. 1, upper strip at the exciter) over the simulated
lines, the mode nearest the FE mode, with uniform weights and without pseudo-modes. A
nonlinear FRF is no modal model (the joint damping changes along the curve with the
amplitude; relative misfit 6e-5 at level 1 to 5e-4 at level 4), and with the default
options of session 18 (noise-model weights fitted to that deterministic misfit,
F-tested free pseudo-modes, fits stopped short of their optimum) a 1e-11 relative
perturbation of the FRF moved zeta by up to 1e-6 at the low levels (1e-4 at the top
one), against a level-to-level growth of 5e-6 at low levels; since session 19 (fits to
their optimum, fixed out-of-band terms) both these options and the default ones move
it by < 1e-9 at levels 1-8 (5e-8 at level 10). The chosen options identify the linear FRF of this grid with a
relative zeta bias of 3.4e-5, the same at every level (it cancels in the differences).
The identified values are checked against an identification-free one: the modal filter
``D(w) = phi_d / (phi^T M x(w))`` of every DOF's response
(:func:`ident.modal_filter.modal_filter_levels`, exact for a linear proportionally
damped structure), at the root of ``Re D``. Joint slip amplitudes "at resonance" are
the campaign's half peak-to-peak slips interpolated (cubic spline over the lines) at
the identified frequency.

Estimates. ``paper``, ``exact`` and ``amplitude`` (:func:`inverse.estimate.estimate`),
levels 1-7 fitted and 8-10 predicted, on the measured data and on the simulated data,
LSCF and modal filter (where chi and R are known). ``amplitude`` regresses on the
simulated joint amplitude at resonance, ``A_eff = sum_m q_m A_m / sum_m q_m`` with ``q_m
= w_m (g_m . phi)^2`` (the weights of B, eq. 1 of :mod:`inverse.estimate`), instead of
assuming it grows as the drive. B~ (eq. 37) is given twice: from the linear inverse (the
estimator's own, at the FE natural frequency and the level-1 damping) and from the
nonlinear simulation (the simulated level-1 slip amplitudes at resonance), each with its
R~. Reruns with ``R`` scaled by ``weak_joint_scales`` (0.1 and 0.01,
:func:`cases.double_beam.weak_joint.weak_joint_recovery`) show how the estimator's
error depends on the joint's softening.

Determinism. Every mode comes from :func:`fe.modal.normal_modes` (ARPACK with a fixed
start vector, bitwise repeatable), the reduced basis from
:func:`fe.reduction.ritz_basis`, so R~, the basis and the campaign hash are the same on
every call of a process and a resumed campaign loads its finished levels.

SI units throughout (m, N, kg, s, rad/s); damping ratios as fractions except where a
table says %.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cases.paper_data import DATA_FILE
from fe.harmonic_balance import HBSettings
from ident.measured import MeasuredData, read_measured
from inverse.estimate import DEFAULT_FORCE_SCALE, parse_levels

__all__ = ["DEFAULT_DATA", "SOURCE_METHOD", "DoubleBeamStudy", "measured_levels"]

#: The shipped measured data (paper Tables 3-6, cases/data/README.md).
DEFAULT_DATA = DATA_FILE
#: Estimate whose chi and R~ drive the simulation.
SOURCE_METHOD = "exact"


@dataclass(frozen=True)
class DoubleBeamStudy:
    """Settings of the double-beam reproduction (defaults: the full run).

    Parameters
    ----------
    data_path : str or None
        Measured-data CSV (default: the shipped paper data :data:`DEFAULT_DATA`).
    mode_label : int
        Mode label in the file (2: the paper's "second mode", 252 Hz).
    n_levels : int
        The first ``n_levels`` measured levels are simulated (10: all).
    fit_levels : str
        Levels of the chi fit, e.g. ``"1-7"``; the others are predicted.
    force_scale : float
        N per V of drive voltage (an assumption, see :mod:`cases.double_beam.joint_setup`).
    beta : float
        Dirac-to-continuous stiffness ratio of the Iwan joints (>= 0).
    chi, R : float, optional
        Override the joint's chi and total R (N m^-(chi+2)); default: the
        :data:`SOURCE_METHOD` estimate of the measured fit levels.
    band_hz, df_hz : (lo, hi) Hz and Hz
        Stepped-sine lines ``lo, lo + df, ..., hi`` (also the identification band).
    sliders_per_octave, octaves_below : int
        :meth:`fe.reduction.JointBank.log_spaced` resolution.
    n_modes : int
        Normal modes in the reduced basis (plus one static mode per joint).
    hb : fe.harmonic_balance.HBSettings
    identify_weighting, identify_pseudo_modes
        Options of :func:`ident.identify.identify_modes` (module docstring).
    weak_joint_scales : tuple of float
        Extra simulations with ``R`` times each factor (same chi): the estimator's
        recovery of chi when the joint softens less
        (:func:`cases.double_beam.weak_joint.weak_joint_recovery`).
    """

    data_path: str | None = None
    mode_label: int = 2
    n_levels: int = 10
    fit_levels: str = "1-7"
    force_scale: float = DEFAULT_FORCE_SCALE
    beta: float = 0.0
    chi: float | None = None
    R: float | None = None
    band_hz: tuple = (236.0, 268.0)
    df_hz: float = 0.5
    sliders_per_octave: int = 16
    octaves_below: int = 6
    n_modes: int = 40
    hb: HBSettings = field(default_factory=HBSettings)
    identify_weighting: str = "uniform"
    identify_pseudo_modes: bool = False
    weak_joint_scales: tuple = (0.1, 0.01)

    def __post_init__(self):
        def positive(name, v):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive number, got {v!r}")

        positive("force_scale", self.force_scale)
        positive("df_hz", self.df_hz)
        if not (math.isfinite(self.beta) and self.beta >= 0):
            raise ValueError(f"beta must be >= 0, got {self.beta!r}")
        lo, hi = self.band_hz
        if not (0 < lo < hi):
            raise ValueError(f"band must satisfy 0 < LO < HI, got {lo!r} {hi!r}")
        if (hi - lo) / self.df_hz < 8:
            raise ValueError(f"band {lo:g}-{hi:g} Hz with df {self.df_hz:g} Hz gives fewer "
                             f"than 9 lines: too few to identify a mode")
        if int(self.n_levels) != self.n_levels or self.n_levels < 4:
            raise ValueError(f"n_levels must be an integer >= 4, got {self.n_levels!r}")
        if int(self.sliders_per_octave) != self.sliders_per_octave or self.sliders_per_octave < 1:
            raise ValueError(f"sliders_per_octave must be an integer >= 1, got "
                             f"{self.sliders_per_octave!r}")
        if int(self.octaves_below) != self.octaves_below or self.octaves_below < 0:
            raise ValueError(f"octaves_below must be an integer >= 0, got {self.octaves_below!r}")
        if int(self.n_modes) != self.n_modes or self.n_modes < 4:
            raise ValueError(f"n_modes must be an integer >= 4, got {self.n_modes!r}")
        if self.chi is not None and not -1.0 < self.chi < 0.0:
            raise ValueError(f"chi must lie in (-1, 0), got {self.chi!r}")
        if self.R is not None:
            positive("R", self.R)
        for k in self.weak_joint_scales:
            positive("weak_joint_scales", k)
        levels = parse_levels(self.fit_levels)
        if max(levels) > self.n_levels:
            raise ValueError(f"fit levels {self.fit_levels} exceed the {self.n_levels} "
                             f"simulated levels")

    @property
    def lines(self) -> np.ndarray:
        """Line frequencies (Hz), ascending."""
        lo, hi = self.band_hz
        return np.round(np.arange(lo, hi + 0.5 * self.df_hz, self.df_hz), 9)

    @property
    def fit(self) -> list[int]:
        return parse_levels(self.fit_levels)

    @property
    def identify_options(self) -> dict:
        """Options of :func:`ident.identify.identify_modes` (module docstring)."""
        return {"weighting": self.identify_weighting, "pseudo_modes": self.identify_pseudo_modes}


def measured_levels(study: DoubleBeamStudy) -> MeasuredData:
    """The first ``study.n_levels`` levels of the studied mode of the measured data."""
    path = DEFAULT_DATA if study.data_path is None else Path(study.data_path)
    data = read_measured(path).for_mode(study.mode_label)
    if len(data) < study.n_levels:
        raise ValueError(f"{path}: mode {study.mode_label} has {len(data)} levels, "
                         f"{study.n_levels} requested")
    return data.take(np.arange(study.n_levels))
