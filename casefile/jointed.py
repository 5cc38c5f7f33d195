"""A jointed model ready for backbones and virtual tests: reduced model, joints on both
paths (Jenkins bank and exact describing function), drive point (SI units). The shipped
cases build theirs in :mod:`cases.nonlinear_case`, a case file in :mod:`casefile.nonlinear`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from fe.joint_harmonics import joint_path
from fe.reduction import JointBank, ReducedModel

__all__ = ["NonlinearCase"]


@dataclass
class NonlinearCase:
    """A jointed model ready for backbones and virtual tests (SI units).

    Attributes
    ----------
    name : str
    model : ReducedModel
    bank : JointBank
    joints : list of IwanParameters (one per joint)
    fe_model : object with ``M, K, slip_matrix, joint_stiffness, drive_dof, modes`` (the
        estimator's FE model, :mod:`inverse.fe_reference`)
    drive_dof, response_dof : int, physical DOFs of the drive and the measured response
    mode : int, 1-based mode studied by default
    chi, R : the joint's true exponent and total R (module docstring)
    phi_max : float (m)
    force : (n_levels,) force levels of the case's test (N)
    lines_hz : (n_lines,) stepped-sine lines (Hz); band_hz : (lo, hi)
    fit_levels : str, the levels of the estimator's fit (micro-slip, as the case study)
    joint_source : str, where the joint parameters come from (calibrated or assumed)
    identify_options : keyword options of :func:`ident.identify.identify_modes` (the
        case study's)
    harmonics, n_time : the bank path's harmonics and AFT samples
    """

    name: str
    model: ReducedModel
    bank: JointBank
    joints: list
    fe_model: object
    drive_dof: int
    response_dof: int
    mode: int
    chi: float
    R: float
    phi_max: float
    force: np.ndarray
    lines_hz: np.ndarray
    band_hz: tuple
    fit_levels: str = "1-7"
    joint_source: str = ""
    identify_options: dict = dataclasses.field(default_factory=dict)
    harmonics: tuple = (1, 3, 5, 7)
    n_time: int = 256

    def joint_harmonics(self, path: str):
        """The joints on ``path`` (``bank`` or ``exact``, :func:`fe.joint_harmonics.joint_path`)."""
        return joint_path(path, bank=self.bank, joints=self.joints,
                          n_joints=self.model.n_joints, harmonics=self.harmonics,
                          n_time=self.n_time)

    @property
    def phi_max_per_joint(self) -> np.ndarray:
        """``phi_max`` of each joint (m)."""
        return np.array([p.phi_max for p in self.joints])

    def load(self) -> np.ndarray:
        """Reduced unit load at the drive DOF (``Phi^T e_d``)."""
        return np.asarray(self.model.basis[self.drive_dof], dtype=float).copy()
