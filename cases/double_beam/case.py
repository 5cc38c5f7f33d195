"""The double beam as a case: its case file (``double-beam.toml``: FE model, summary,
measured data) with the Python model of the paper's study beside it, which gives its
nonlinear model (chi, R~ from the measured levels 1-7), its ``update`` and FE-levels
model (:class:`cases.double_beam.fe_levels.DoubleBeamLevels`, the grip re-calibrated per
K_T), its FE check of the uncalibrated frequency gap and its Monte Carlo (a stepped sine
per sample). With an ``updated_model.json`` (``--model``) it is its case file alone.
"""
from __future__ import annotations

from pathlib import Path

from cases.case_file import CaseFileCase

__all__ = ["CASE_FILE", "DoubleBeamCase"]

CASE_FILE = Path(__file__).resolve().parent / "double-beam.toml"


class DoubleBeamCase(CaseFileCase):
    """The double beam (module docstring); ``cf`` its checked case file."""

    def offers(self) -> tuple:
        # its nonlinear model comes from its study (chi, R~ of its levels), not the file
        return tuple(dict.fromkeys((*super().offers(), "nonlinear_model", "fe_check",
                                    "uncertainty")))

    def _nonlinear_model(self, mode=None):
        from cases.nonlinear_case import build_nonlinear_case

        return build_nonlinear_case("double-beam", mode=mode)

    def _update(self, executor="serial", progress=False, store=None, **settings):
        """``run_update`` of the Python model on the shipped data, mode label 2, fit
        levels 1-7 (``settings``: fields of :class:`feloop.update.UpdateSettings`)."""
        from cases.double_beam.fe_levels import DoubleBeamLevels, assumption_variants
        from cases.double_beam.model import DoubleBeamConfig
        from cases.double_beam.settings import DEFAULT_DATA
        from feloop.case_file import fitted_plausibility
        from feloop.update import UpdateSettings, run_update

        settings = {"data_path": str(DEFAULT_DATA), "mode_label": 2, "fit_levels": "1-7",
                    **{k: v for k, v in settings.items() if v is not None}}
        variants = assumption_variants() if settings.get("assumptions") else None
        r = run_update(UpdateSettings(**settings), DoubleBeamLevels.from_data,
                       executor=executor, progress=progress, store=store,
                       case_name="double-beam", model_key=repr(DoubleBeamConfig()),
                       assumptions=variants)
        # the same glue interface as its case file describes
        r["plausibility"] = fitted_plausibility(self.file, r)
        return r

    def _fe_levels(self, data, force_scale: float = 1.0):
        from cases.double_beam.fe_levels import DoubleBeamLevels

        return DoubleBeamLevels.from_data(data, force_scale=force_scale)

    def _fe_check(self, measured_omega2: float) -> dict:
        from cases.double_beam.fe_check import double_beam_fe_check

        return double_beam_fe_check(measured_omega2=measured_omega2)

    def _uncertainty(self, settings, **options):
        from cases.double_beam.uncertainty_report import run_uncertainty

        return run_uncertainty(settings, **options)
