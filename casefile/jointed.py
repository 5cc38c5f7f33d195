"""A jointed model ready for backbones and virtual tests: reduced model, joints on both
paths (Jenkins bank and exact describing function), drive point (SI units). The shipped
cases build theirs in :mod:`cases.nonlinear_case`, a case file in :mod:`casefile.nonlinear`.

The joints are of one law (:attr:`NonlinearCase.law_name`, :mod:`casefile.laws`):
``iwan4`` carries Iwan parameters (``joints``), their Jenkins banks (``bank``) and the
Iwan figures ``chi``, ``R``; another law carries itself as ``joints`` (a
:class:`joints.law.JointLaw`), ``bank`` only when it is one (``jenkins``: one slider per
joint) and ``chi = R = None`` (n/a: no Iwan density). ``phi_max`` is then the law's slip
scale (:data:`casefile.laws.SLIP_SCALE`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from fe.joint_harmonics import joint_path
from fe.reduction import JointBank, ReducedModel
from joints.describing import as_joint_law
from joints.law import JointLaw

__all__ = ["NonlinearCase"]


@dataclass
class NonlinearCase:
    """A jointed model ready for backbones and virtual tests (SI units).

    Attributes
    ----------
    name : str
    model : ReducedModel
    bank : JointBank, or None (a law with no bank: ``bouc-wen``)
    joints : list of IwanParameters (one per joint; law ``iwan4``) or the joint law
    fe_model : object with ``M, K, slip_matrix, joint_stiffness, drive_dof, modes`` (the
        estimator's FE model, :mod:`inverse.fe_reference`)
    drive_dof, response_dof : int, physical DOFs of the drive and the measured response
    mode : int, 1-based mode studied by default
    chi, R : the joint's true exponent and total R (module docstring); None for a law
        other than ``iwan4``
    phi_max : float (m), the largest joint's ``phi_max`` (other laws: slip scale)
    force : (n_levels,) force levels of the case's test (N)
    lines_hz : (n_lines,) stepped-sine lines (Hz); band_hz : (lo, hi)
    fit_levels : str, the levels of the estimator's fit (micro-slip, as the case study)
    joint_source : str, where the joint parameters come from (calibrated or assumed)
    identify_options : keyword options of :func:`ident.identify.identify_modes` (the
        case study's)
    harmonics, n_time : the bank path's harmonics and AFT samples
    law_name : ``iwan4``, ``jenkins`` or ``bouc-wen`` (module docstring)
    drive_kind : ``point`` (a force at ``drive_dof``) or ``base`` (``[drive] kind =
        "base"``: the supports move as one base; ``drive_dof`` is then the response DOF
        and means nothing, :meth:`load` refuses)
    base_acceleration : the file's base acceleration amplitude (m/s^2; base drive)
    base_load : (r,) reduced load per m/s^2 of base acceleration, ``Phi^T (-(M_all
        r)_free)`` (:func:`fe.base_excitation.base_load`; base drive); responses are
        relative to the base
    """

    name: str
    model: ReducedModel
    bank: JointBank | None
    joints: object
    fe_model: object
    drive_dof: int
    response_dof: int
    mode: int
    chi: float | None
    R: float | None
    phi_max: float
    force: np.ndarray
    lines_hz: np.ndarray
    band_hz: tuple
    fit_levels: str = "1-7"
    joint_source: str = ""
    identify_options: dict = dataclasses.field(default_factory=dict)
    harmonics: tuple = (1, 3, 5, 7)
    n_time: int = 256
    law_name: str = "iwan4"
    drive_kind: str = "point"
    base_acceleration: float | None = None
    base_load: np.ndarray | None = None

    def joint_harmonics(self, path: str):
        """The joints on ``path`` (``bank`` or ``exact``, :func:`fe.joint_harmonics.joint_path`);
        ValueError (one line) for ``bank`` when the law has no bank."""
        if path == "bank" and self.bank is None:
            raise ValueError(f"{self.name}: law {self.law_name} has no Jenkins-bank path (the "
                             f"AFT march is the banks'): use the exact path")
        return joint_path(path, bank=self.bank, joints=self.joints,
                          n_joints=self.model.n_joints, harmonics=self.harmonics,
                          n_time=self.n_time)

    @property
    def law(self) -> JointLaw:
        """The joints as a :class:`joints.law.JointLaw` (``iwan4``: the exact Iwan joints)."""
        return as_joint_law(self.joints, self.model.n_joints)

    @property
    def time_path(self) -> str:
        """The path the time domain integrates: ``bank`` (Jenkins banks) when the case has
        them, else ``exact`` (the law's own step and describing function)."""
        return "exact" if self.bank is None else "bank"

    @property
    def time_law(self) -> JointLaw:
        """The joints the time domain integrates (the bank, or the law)."""
        return self.law if self.bank is None else self.bank

    @property
    def phi_max_per_joint(self) -> np.ndarray:
        """``phi_max`` of each joint (m); another law's slip scale."""
        if isinstance(self.joints, JointLaw):
            return np.asarray(self.joints.slip_scale, dtype=float)
        return np.array([p.phi_max for p in self.joints])

    def require_iwan(self, what: str) -> None:
        """ValueError (one line) when ``what`` needs Iwan joints and the law is another."""
        if self.law_name != "iwan4":
            raise ValueError(f"{self.name}: {what} needs Iwan joints (law iwan4); the law "
                             f"here is {self.law_name}")

    def require_point_drive(self, what: str) -> None:
        """ValueError (one line) when the case is base-driven and ``what`` (a command)
        knows only a point force."""
        if self.drive_kind != "point":
            raise ValueError(f"{self.name}: base drive not supported by {what} yet "
                             f"([drive] kind = \"{self.drive_kind}\"; iwanfe frc takes it)")

    def load(self) -> np.ndarray:
        """Reduced unit load at the drive DOF (``Phi^T e_d``); ValueError for a base
        drive (no drive point: :attr:`base_load`)."""
        self.require_point_drive("this command (it drives a point)")
        return np.asarray(self.model.basis[self.drive_dof], dtype=float).copy()
