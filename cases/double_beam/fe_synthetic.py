"""Synthetic stepped-sine series of the FE double beam hiding one FE-level effect.

:func:`draw_case` draws, from a seed, a virtual test of the double beam's measured mode:

1. **Structure**: the FE double beam of :mod:`cases.double_beam.fe_levels` with its
   Iwan glue (``chi`` uniform in (-0.7, -0.25), the glue's level-1 modal damping
   ``|kappa1| B~`` log-uniform in (3, 30) rad^2/s^2, viscous ``zeta_v`` in (0.8, 1.5) %,
   stuck frequency 252 +/- 0.5 Hz, ``K_T = 1e8 N/m``), redrawn until the glue stays in
   micro-slip (top slip below 0.9 ``phi_max``) unless the effect is macro-slip, and one
   hidden effect of :mod:`cases.double_beam.fe_causes` (:data:`KINDS`) whose size is
   drawn log-uniform in units of the noise at the top level (:data:`EFFECT_SIGMA`): the
   modal damping the air drag adds, the omega^2 the cubic spring adds, the omega^2 the
   drift moves over the series (either sign); for macro-slip the top slip over
   ``phi_max`` in (1.5, 4).
2. **Test**: 10 levels (5 mV .. 2.56 V at 1 N/V), run in a shuffled order; at every level
   the receptance at the response DOF over 41 lines (0.5 Hz, +/- 10 Hz about the stuck
   frequency), first-harmonic balance of the FE model with the effect, swept upward
   (:func:`fe.hb_resonance.frf_levels`).
3. **Identification**: LSCF of each level's FRF (:func:`ident.identify.identify_modes`,
   uniform weights, no pseudo-modes), the mode nearest 252 Hz.
4. **Noise**: Gaussian, ``omega2`` relative :data:`SIGMA_OMEGA2_REL`, ``zeta`` absolute
   :data:`SIGMA_ZETA` (the scatter of the paper's data), given to the diagnosis as the
   ``omega2_std``/``zeta_std`` columns.

The diagnosis (:func:`cases.double_beam.fe_diagnosis.fe_diagnosis`) sees only the
measured-data table; its model is the phase resonance of the same FE model, not the
identified FRF, and it never sees the drawn parameters (``SyntheticFECase.truth``).
``nonproportional-amplitude`` is not drawn: with omega^2 and zeta alone (no response
amplitude channel in the FE fit) a force compression only changes the abscissa of a
power law that chi already bends.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cases.double_beam.fe_causes import EXTENSIONS
from cases.double_beam.fe_levels import DoubleBeamLevels
from fe.hb_resonance import frf_levels
from ident.identify import identify_modes
from ident.modal_data import MeasuredData

__all__ = ["KINDS", "SIGMA_OMEGA2_REL", "SIGMA_ZETA", "EFFECT_SIGMA", "RECOVERED",
           "SyntheticFECase",
           "draw_case", "simulate_series"]

KINDS = ("quadratic-damping", "geometric-hardening", "thermal-drift", "macro-slip")
SIGMA_OMEGA2_REL = 4e-6
SIGMA_ZETA = 2e-6
EFFECT_SIGMA = (20.0, 120.0)
#: The physical reading of each effect that the diagnosis must recover.
RECOVERED = {"quadratic-damping": "C_D", "geometric-hardening": "k3",
             "thermal-drift": "drift_per_run", "macro-slip": "phi_max_m"}
EXCITATION = 0.005 * 2.0 ** np.arange(10)
LINES_HZ = np.arange(-10.0, 10.001, 0.5)


@dataclass
class SyntheticFECase:
    """A generated series (``data``) and its hidden truth (``cause``, ``truth``: the
    effect parameter and the base parameters)."""

    data: MeasuredData
    cause: str
    seed: int
    truth: dict = field(default_factory=dict)


def simulate_series(fe: DoubleBeamLevels, values: dict, extension, run_order,
                    rng: np.random.Generator) -> MeasuredData:
    """Steps 2-4 of the module docstring for parameter set ``values``."""
    j, red, scale, forces, elements = fe.setup(values, extension)
    lin = j["linear"]
    f_hz = float(values["f0_hz"]) + LINES_HZ
    q, _ = frf_levels(red, j["params"], lin.load, forces, 2 * np.pi * f_hz, scale=scale,
                      elements=elements)
    rec = (q @ lin.response_row) / forces[:, None]               # (L, n_lines), m/N
    om2 = np.full(fe.n_levels, np.nan)
    ze = np.full(fe.n_levels, np.nan)
    for lv in range(fe.n_levels):
        modes = identify_modes(f_hz, rec[lv], band=(f_hz[0], f_hz[-1]), weighting="uniform",
                               pseudo_modes=False)
        if not modes:
            raise RuntimeError(f"no mode identified at synthetic level {lv + 1}")
        m = min(modes, key=lambda m: abs(m.frequency_hz - float(values["f0_hz"])))
        om2[lv], ze[lv] = m.omega2, m.zeta
    L = fe.n_levels
    s_om2 = SIGMA_OMEGA2_REL * om2
    s_z = np.full(L, SIGMA_ZETA)
    return MeasuredData(level=np.arange(1, L + 1), excitation=fe.excitation.copy(),
                        omega2=om2 + s_om2 * rng.standard_normal(L),
                        zeta=ze + s_z * rng.standard_normal(L), mode=np.ones(L, dtype=int),
                        run_order=np.asarray(run_order), omega2_std=s_om2, zeta_std=s_z,
                        source="synthetic FE double beam")


def _effect_value(cause, fe, values, size, rng) -> float:
    """The effect parameter that moves the top level by ``size`` noise units."""
    pred = fe.predict(values)
    a = float(pred.modal_amplitude[-1])
    lin = fe.linear(10.0 ** values["log10_kt"])
    if cause == "quadratic-damping":
        c2_unit = EXTENSIONS[cause].c2({"drag_cd": 1.0}, lin)
        return size * SIGMA_ZETA / (4.0 / (3.0 * math.pi) * c2_unit * a)
    if cause == "geometric-hardening":
        return size * SIGMA_OMEGA2_REL * float(pred.omega2[-1]) / (0.75 * a * a)
    if cause == "thermal-drift":
        sign = 1.0 if rng.random() < 0.5 else -1.0
        return sign * size * SIGMA_OMEGA2_REL / float(np.ptp(fe.run_order))
    raise ValueError(cause)


def draw_case(seed: int, cause: str | None = None) -> SyntheticFECase:
    """One synthetic series (module docstring); ``cause`` drawn from :data:`KINDS`
    unless given."""
    rng = np.random.default_rng(seed)
    if cause is None:
        cause = str(KINDS[rng.integers(len(KINDS))])
    if cause not in KINDS:
        raise ValueError(f"unknown FE effect {cause!r}; choose from {', '.join(KINDS)}")
    run_order = rng.permutation(10) + 1
    fe = DoubleBeamLevels(EXCITATION, run_order, 252.0 ** 2 * 4 * math.pi ** 2, 0.0125)
    for _ in range(50):
        values = {"chi": rng.uniform(-0.7, -0.25), "ln_dc1": math.log(rng.uniform(3.0, 30.0)),
                  "zeta_v": rng.uniform(0.008, 0.015), "f0_hz": 252.0 + rng.uniform(-0.5, 0.5),
                  "log10_kt": 8.0}
        if fe.predict(values).slip_over_phi_max[-1] < 0.9:
            break
    ext = EXTENSIONS[cause]
    if cause == "macro-slip":
        ratio = math.exp(rng.uniform(math.log(1.5), math.log(4.0)))
        top_slip = float(fe.predict(values).slip_over_phi_max[-1]) * fe.joint(values)["phi_max"]
        value = math.log(top_slip / ratio / fe.linear(1e8).a_ref)
    else:
        size = math.exp(rng.uniform(*np.log(EFFECT_SIGMA)))
        value = _effect_value(cause, fe, values, size, rng)
    values[ext.parameter] = value
    data = simulate_series(fe, values, ext, run_order, rng)
    pred = fe.predict(values, ext)
    reading = ext.reading(values, fe, fe.linear(1e8), pred)
    return SyntheticFECase(data=data, cause=cause, seed=int(seed),
                           truth={"parameter": ext.parameter, "value": value, "values": values,
                                  "reading": reading, "key": RECOVERED[cause],
                                  "recovered": reading[RECOVERED[cause]]})
