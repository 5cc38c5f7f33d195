"""Monte Carlo over the identified joint parameters: how uncertain are the predictions?

``iwanfe estimate`` fits chi and ``|kappa1| B`` to the damping growth between levels
(paper eq. 33-35, :mod:`inverse.estimate`) and gives linearized (delta-method) Student-t
intervals. The sweep propagates the same fit uncertainty through the *nonlinear FE
model* instead of the closed form (eq. 43, 46): every sample is a joint of the double
beam (:mod:`cases.double_beam.study`) driven through the stepped-sine levels, and the
spread of the simulated natural frequency and damping ratio per level is reported beside
the estimator's closed-form interval and the measurement
(:func:`cases.double_beam.uncertainty_report.run_uncertainty`). The draws (eq. (1), a
Student t truncated to the Iwan range), the tasks and the resumable store are
:mod:`inverse.uncertainty`; this module holds the double beam's settings and per-sample
model. With the shipped data (levels 1-7, 3 dof) about a fifth of the t mass lies
outside the Iwan range.

Joint of a sample (paper eq. 36, 37): ``chi = p - 1``, ``|kappa1| B = Kt / p`` at level 1
and ``R~ = |kappa1| B / ((|kappa1|/R) B~(chi))`` with the estimator's ``B~`` (FE mode,
linear-inverse slips at level 1); then exactly
:func:`~cases.double_beam.joint_setup.joint_setup` with these ``chi, R`` overrides (the
viscous damping is re-chosen so that level 1 has the measured damping ratio, eq. 2 of
:mod:`inverse.estimate`). The *nominal* sample is the study without overrides, i.e.
:func:`~cases.double_beam.study.run_study` at the same settings.

Per sample (:func:`simulate_fe`): :func:`~cases.double_beam.joint_setup.nonlinear_model`,
the HB stepped-sine campaign (:func:`runs.stepped_sine.run_campaign`, serial inside the
task) and the per-level modal data
(:func:`~cases.double_beam.pipeline.identify_campaign`). The reported frequency
``Omega/(2 pi)`` (Hz) and damping ratio are the **modal filter**'s (``D = phi_d / (phi^T
M x)`` at the root of ``Re D``; identification-free and exact for the linear structure):
on smooth simulated FRFs of some samples the LSCF identification with the study's
options picks a wrong pole (zeta 2.6-4 times the modal filter's, e.g. chi = -0.845,
level 8). The LSCF values are stored per sample and the samples where they disagree with
the modal filter by more than
:data:`~cases.double_beam.uncertainty_report.LSCF_DISAGREEMENT` are counted.

Per-sample settings (:data:`SAMPLE_STUDY`): 8 Jenkins sliders per octave and 128 AFT
samples per period instead of 16 and 256, everything else as ``reproduce double-beam``
(0.5 Hz lines over 236-268 Hz, 10 levels, 40 modes, 7 odd harmonics). Measured on the
nominal joint and on chi = -0.845, -0.59, -0.068 (from no glue slip to macro-slip at
level 8): modal-filter frequency within 5e-6 and damping ratio within 3e-4 relative of
the default settings, at about 40 % of the cost (tests/test_uncertainty.py checks the
nominal). The 0.5 Hz lines are kept on purpose: with 1 Hz lines the harmonic-balance
continuation failed at the top level of strongly softening samples. A sample whose
simulation fails (no harmonic-balance convergence, even after the retries of
:func:`simulate_fe` with lower first lines) is kept with its reason and excluded from
the quantiles (the report gives the count).

Store: ``samples-<hash12>/`` under the output directory
(:class:`inverse.sample_store.SampleStore`, :func:`inverse.uncertainty.sweep_hash`).

SI units: Hz, rad^2/s^2, N, m; damping ratios as fractions.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from cases.double_beam.joint_setup import (
    joint_setup,
    level_campaign,
    mode_weights,
    nonlinear_model,
    source_estimate,
)
from cases.double_beam.pipeline import identify_campaign
from cases.double_beam.settings import DoubleBeamStudy
from fe.harmonic_balance import HBSettings
from inverse.iwan_modal import r_tilde
from inverse.uncertainty import DISTRIBUTIONS, SweepInputs

__all__ = [
    "SAMPLE_STUDY",
    "DEFAULT_SAMPLES",
    "DEFAULT_SEED",
    "DEFAULT_CONFIDENCE",
    "RETRY_EXTENSIONS_HZ",
    "UncertaintySettings",
    "simulate_fe",
]

#: Per-sample simulation: coarser Jenkins banks and AFT grid than ``reproduce`` (module
#: docstring), no weak-joint reruns.
SAMPLE_STUDY = DoubleBeamStudy(sliders_per_octave=8, hb=HBSettings(n_time=128),
                               weak_joint_scales=())
DEFAULT_SAMPLES = 80
DEFAULT_SEED = 1
#: Central interval of the Monte Carlo and level of the delta-method t-interval (5-95 %).
DEFAULT_CONFIDENCE = 0.90
#: Downward extensions (Hz) of the first line for the retries of a failed campaign.
RETRY_EXTENSIONS_HZ = (10.0, 20.0)


@dataclass(frozen=True)
class UncertaintySettings:
    """Settings of the Monte Carlo sweep.

    Parameters
    ----------
    study : DoubleBeamStudy
        Data, fit levels, force scale and the per-sample simulation (default
        :data:`SAMPLE_STUDY`); its ``chi``/``R`` overrides must be unset.
    n_samples : int
        Samples (each one nonlinear simulation) besides the nominal one.
    seed : int
        Root seed of :func:`runs.executor.task_seeds`.
    confidence : float
        Central interval of the samples (quantiles ``(1 -+ confidence)/2``) and level
        of the estimator's delta-method t-interval.
    distribution : {"t", "normal"}
        Eq. (1) of :mod:`inverse.uncertainty` with the fit's degrees of freedom, or
        normal with the same covariance.
    """

    study: DoubleBeamStudy = field(default_factory=lambda: SAMPLE_STUDY)
    n_samples: int = DEFAULT_SAMPLES
    seed: int = DEFAULT_SEED
    confidence: float = DEFAULT_CONFIDENCE
    distribution: str = "t"

    def __post_init__(self):
        if isinstance(self.n_samples, bool) or int(self.n_samples) != self.n_samples \
                or self.n_samples < 1:
            raise ValueError(f"samples must be an integer >= 1, got {self.n_samples!r}")
        if isinstance(self.seed, bool) or int(self.seed) != self.seed or self.seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")
        if not 0 < self.confidence < 1:
            raise ValueError(f"confidence must lie in (0, 1), got {self.confidence!r}")
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got "
                             f"{self.distribution!r}")
        if self.study.chi is not None or self.study.R is not None:
            raise ValueError("the sampled study must not override chi or R")

    @property
    def quantiles(self) -> tuple[float, float]:
        a = 0.5 * (1.0 - self.confidence)
        return a, 1.0 - a


def simulate_fe(inputs: SweepInputs, p=None, ln_kt=None) -> dict:
    """The nonlinear FE prediction of one joint sample (module docstring).

    Parameters
    ----------
    inputs : SweepInputs
    p, ln_kt : float or None
        ``chi + 1`` and ``ln((chi+1) |kappa1| B)``; None: the study's own estimate.

    Returns
    -------
    dict
        ``frequency_hz``, ``zeta`` (modal filter), ``lscf_frequency_hz``, ``lscf_zeta``,
        ``slip_over_phi_max`` (largest joint slip at resonance / phi_max), all
        (n_levels,); ``chi``, ``R`` (N m^-(chi+2)), ``phi_max`` (m), ``zeta_viscous``,
        ``first_line_hz`` (Hz), ``fallback_levels`` (levels with a steady state reached
        by a fallback, :meth:`runs.campaign.CampaignResult.fallback_lines`).

    Notes
    -----
    When the harmonic-balance campaign fails (Newton from the linear guess at the first
    line of a level deep in macro-slip), it is rerun with the lines started
    :data:`RETRY_EXTENSIONS_HZ` lower (same spacing and top line; the identification
    band follows), where the linear guess is closer; ``first_line_hz`` records the
    start. On the failing sample of the shipped data (chi = -0.75, level 10 failing at
    236 Hz) the retry converged and levels 1-9 moved by < 2e-13 relative (frequency
    and damping ratio).
    """
    from runs.stepped_sine import run_campaign

    model, data, study = inputs.model, inputs.data, inputs.study
    src = source_estimate(model, data, study)
    if p is not None:
        chi = p - 1.0
        R = r_tilde(math.exp(ln_kt) / p, chi, src.case.B_of_chi(chi))   # eq. 36, 37
        study = dataclasses.replace(study, chi=chi, R=R)
    setup = joint_setup(model, data, study, source=src)
    red, bank = nonlinear_model(model, setup, study)
    lo, hi = study.band_hz
    starts = [0.0] + [e for e in RETRY_EXTENSIONS_HZ if lo - e > 0]
    for k, extension in enumerate(starts):
        if extension:
            study = dataclasses.replace(study, band_hz=(lo - extension, hi))
        try:
            res = run_campaign(red, bank, level_campaign(model, setup, study), progress=False,
                               executor="serial")
            break
        except RuntimeError:
            if k == len(starts) - 1:
                raise
    phi, weights = mode_weights(model, setup)
    ident, mf = identify_campaign(model, setup, study, res, phi, weights)
    return {"frequency_hz": mf.frequency_hz, "zeta": mf.zeta,
            "lscf_frequency_hz": ident.frequency_hz, "lscf_zeta": ident.zeta,
            "slip_over_phi_max": np.nanmax(mf.slip, axis=1) / setup.phi_max,
            "chi": setup.chi, "R": setup.R, "phi_max": setup.phi_max,
            "zeta_viscous": setup.zeta_viscous, "first_line_hz": study.band_hz[0],
            "fallback_levels": float(len(res.fallback_lines()))}
