"""The paper's lumped 10-DOF model (eq. 38-40) with two Iwan joints, as a case: a
nonlinear model only (no FE strip model, no measured data)."""
from __future__ import annotations

from cases.case import Case

__all__ = ["LumpedCase"]


class LumpedCase(Case):
    """The lumped model (module docstring)."""

    def __init__(self):
        super().__init__("lumped", "the paper's lumped 10-DOF model (eq. 38-40) with two "
                         "Iwan joints", "cases.lumped10")

    def offers(self) -> tuple:
        return ("nonlinear_model",)

    def _nonlinear_model(self, mode=None):
        from cases.nonlinear_case import lumped_case

        case = lumped_case() if mode is None else lumped_case(mode=int(mode))
        if mode is not None:
            if not 1 <= int(mode) <= case.model.n_reduced:
                raise ValueError(f"mode must be in 1..{case.model.n_reduced}, got {mode}")
            case.mode = int(mode)
        return case
