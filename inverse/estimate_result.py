"""The estimator's result record (:class:`Estimate`) and its plain-JSON form."""
from __future__ import annotations

from dataclasses import dataclass, field

from inverse.fe_reference import FEReference
from inverse.power_law import PowerLawFit


@dataclass
class Estimate:
    """Everything the estimator returns (SI units; zeta as fractions).

    ``predictions`` holds one record per level of the mode (its ``excitation`` and
    ``held_amplitude``, the abscissa of a response-controlled series): predicted and measured
    ``omega2``, ``zeta`` and, from the previous level, ``delta_omega2`` (loss of
    omega^2, positive = softening, the sign of the paper's Table 3) and
    ``delta_zeta`` (growth), with percent errors ``100 (pred - meas)/meas`` and
    t-intervals; ``held_out`` marks levels outside the fit. ``points_used`` /
    ``points_excluded`` are the fit's level pairs (``x = log_z(e_from/e_ref)``, ``y =
    log_z Delta d``, the model's ``model_delta_d``); ``differences`` lists every pair
    of successive levels of the mode (held-out ones too) in the same form.
    ``abscissa`` names the amplitude the fit regressed on (``reference_amplitude`` its
    value at the reference level); ``contradictions`` are plain statements of what the
    data show that no Iwan joint can do (:mod:`inverse.contradictions`).
    ``kappa2_over_kappa1`` is the Iwan value only where ``chi_in_range``.
    ``test`` is the series' test type; for ``random`` ``rayleigh_factor`` is ``c(chi)``
    of :mod:`inverse.random_amplitude` and ``kappa1_B_sine`` the stepped-sine
    ``|kappa1| B`` at the reference RMS amplitude (``kappa1_B / c``); None otherwise.
    """

    method: str
    mode: int
    fit_levels: list
    reference_level: int
    reference_excitation: float
    chi: float
    chi_interval: tuple
    kappa1_B: float
    kappa1_B_interval: tuple
    kappa2_over_kappa1: float
    B: float | None
    R: float | None
    R_interval: tuple | None
    confidence: float
    ratio_z: float | None
    intercept_a0: float | None
    residual_std: float
    dof: int
    omega2_linear: float
    zeta_linear: float
    c_modal: float
    points_used: list
    points_excluded: list
    differences: list
    log_base: float
    predictions: list
    data_warnings: list
    case: FEReference | None
    fit: PowerLawFit = field(repr=False)
    abscissa: str = "excitation"
    control: str = "force"
    reference_amplitude: float = float("nan")
    contradictions: list = field(default_factory=list)
    contradiction_details: list = field(default_factory=list)
    test: str = "stepped-sine"
    rayleigh_factor: float | None = None
    kappa1_B_sine: float | None = None

    @property
    def chi_in_range(self) -> bool:
        """True when the fitted chi lies in the Iwan range -1 < chi < 0."""
        return bool(-1.0 < self.chi < 0.0)

    def to_dict(self) -> dict:
        """Plain-JSON form (``iwanfe estimate --json``)."""
        case = None
        if self.case is not None:
            c = self.case
            case = {"name": c.name, "fe_mode": c.fe_mode, "fe_frequency_hz": c.fe_frequency_hz,
                    "force_scale": c.force_scale, "reference_force": c.reference_force,
                    "slip_amplitudes": c.slip_amplitudes, "shares": c.shares}
        return {
            "method": self.method, "mode": self.mode, "fit_levels": self.fit_levels,
            "abscissa": self.abscissa, "control": self.control,
            "reference_level": self.reference_level,
            "reference_excitation": self.reference_excitation,
            "reference_amplitude": self.reference_amplitude,
            "chi_in_iwan_range": self.chi_in_range,
            "chi": self.chi, "chi_interval": list(self.chi_interval),
            "kappa1_B": self.kappa1_B, "kappa1_B_interval": list(self.kappa1_B_interval),
            "B": self.B, "R": self.R,
            "R_interval": None if self.R_interval is None else list(self.R_interval),
            "confidence": self.confidence,
            "kappa2_over_kappa1": self.kappa2_over_kappa1,
            "ratio_z": self.ratio_z, "intercept_a0": self.intercept_a0,
            "residual_std": self.residual_std, "dof": self.dof,
            "omega2_linear": self.omega2_linear, "zeta_linear": self.zeta_linear,
            "c_modal": self.c_modal,
            "points_used": self.points_used, "points_excluded": self.points_excluded,
            "differences": self.differences, "log_base": self.log_base,
            "predictions": self.predictions, "data_warnings": self.data_warnings,
            "contradictions": self.contradictions,
            "contradiction_details": self.contradiction_details,
            "case": case, "test": self.test, "rayleigh_factor": self.rayleigh_factor,
            "kappa1_B_sine": self.kappa1_B_sine,
        }
