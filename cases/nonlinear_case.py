"""The shipped cases as nonlinear models: reduced model, joints on both paths, drive point.

What the backbone (:mod:`fe.epmc`), the response-controlled virtual test
(:mod:`runs.response_control`) and their comparison (:mod:`cases.backbones`) need of a
case, built from the case's own study settings (no choice is made here):

* ``double-beam``: the FE double beam with one Iwan element per glue node, chi and
  R~ from the ``exact`` estimate of the measured levels 1-7, ``beta = 0``, viscous
  modal damping matched to level 1 (:mod:`cases.double_beam.joint_setup`); Jenkins banks
  log-spaced, 16 per octave; the paper's 10 force levels at 1 N/V. ``R_scale`` scales
  R at the same chi (the weak glue of :mod:`cases.double_beam.weak_joint`).
* ``lumped``: the paper's 10-DOF model (eq. 38-40) with its two Iwan joints (chi =
  -0.5), 100 uniform sliders per joint, 12 force levels.

``R`` is the total density coefficient in the estimator's convention (sum over the
joint elements, each carrying its share ``w_m = k_m / sum k``; :mod:`inverse.fe_reference`):
for the lumped model's two identical joints of R each it is 2 R.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from casefile.jointed import NonlinearCase
from fe.modal import normal_modes

__all__ = ["NonlinearCase", "double_beam_case", "lumped_case", "build_nonlinear_case"]


def double_beam_case(R_scale: float = 1.0, study=None) -> NonlinearCase:
    """The FE double beam with its simulated glue (module docstring)."""
    from cases.double_beam.joint_setup import joint_setup, nonlinear_model
    from cases.double_beam.model import build_double_beam
    from cases.double_beam.settings import DoubleBeamStudy, measured_levels

    study = DoubleBeamStudy() if study is None else study
    fe = build_double_beam()
    data = measured_levels(study)
    setup = joint_setup(fe, data, study)
    if R_scale != 1.0:
        study = dataclasses.replace(study, chi=setup.chi, R=setup.R * float(R_scale),
                                    weak_joint_scales=())
        setup = joint_setup(fe, data, study, source=setup.source)
    red, bank = nonlinear_model(fe, setup, study)
    return NonlinearCase(name="double-beam", model=red, bank=bank, joints=setup.params,
                         fe_model=fe, drive_dof=int(fe.drive_dof),
                         response_dof=int(fe.response_dof), mode=setup.fe_mode,
                         chi=setup.chi, R=setup.R, phi_max=setup.phi_max,
                         force=setup.force, lines_hz=study.lines, band_hz=study.band_hz,
                         identify_options=study.identify_options, fit_levels=study.fit_levels,
                         joint_source=(f"calibrated: chi, R~ from the exact estimate of the "
                                       f"measured levels {study.fit_levels} (beta = 0)"
                                       + (f", R x {R_scale:g}" if R_scale != 1.0 else "")),
                         harmonics=tuple(int(h) for h in study.hb.harmonics),
                         n_time=study.hb.n_time)


@dataclass
class LumpedFE:
    """The 10-DOF model as the estimator's FE model (:mod:`inverse.fe_reference`)."""

    M: np.ndarray
    K: np.ndarray
    slip_matrix: np.ndarray
    joint_stiffness: np.ndarray
    drive_dof: int

    def modes(self, n_modes: int):
        return normal_modes(self.K, self.M, min(int(n_modes), self.M.shape[0]))


def lumped_case(mode: int = 2, df_hz: float = 0.5) -> NonlinearCase:
    """The paper's 10-DOF model (module docstring); lines over the identification band
    of ``mode`` (:data:`cases.lumped10.study.MODE_BANDS`, mode 2 if ``mode`` has none),
    identified with the default options (as :func:`cases.lumped10.study.run_study`)."""
    from cases.lumped10.study import MODE_BANDS, LumpedStudy, lumped10_setup

    study = LumpedStudy()
    s = lumped10_setup(study)
    p = study.params
    band = MODE_BANDS.get(int(mode), MODE_BANDS[2])
    lines = np.round(np.arange(band[0], band[1] + 0.5 * df_hz, df_hz), 9)
    fe = LumpedFE(M=np.asarray(s.system.M), K=np.asarray(s.system.K_J),
                  slip_matrix=np.asarray(s.system.G), joint_stiffness=s.system.K_T.copy(),
                  drive_dof=int(p.force_dof))
    return NonlinearCase(name="lumped", model=s.model, bank=s.bank,
                         joints=[p.joint] * s.system.n_joints, fe_model=fe,
                         drive_dof=int(p.force_dof), response_dof=int(p.force_dof),
                         mode=int(mode), chi=p.joint.chi, R=p.joint.R * s.system.n_joints,
                         phi_max=p.joint.phi_max, force=s.levels, lines_hz=lines,
                         band_hz=band, joint_source="assumed: paper eq. 38-40 (chi = -0.5, "
                         "K_T = 1.1e5 N/m, F_S = 400 N, beta = 4 per joint)")


def build_nonlinear_case(name: str, mode: int | None = None, **options) -> NonlinearCase:
    """``double-beam`` (options of :func:`double_beam_case`) or ``lumped`` (of
    :func:`lumped_case`), studying ``mode`` (1-based; default the case's)."""
    builders = {"double-beam": double_beam_case, "lumped": lumped_case}
    if name not in builders:
        raise ValueError(f"unknown case {name!r}; known: {', '.join(builders)}")
    if mode is not None and name == "lumped":
        options["mode"] = int(mode)
    case = builders[name](**options)
    if mode is not None:
        if not 1 <= int(mode) <= case.model.n_reduced:
            raise ValueError(f"mode must be in 1..{case.model.n_reduced}, got {mode}")
        case.mode = int(mode)
    return case
