"""The paper's lumped study through one joint (issue 41): chi and R fitted on mode 2
predict modes 4 and 6, beside each mode's own fit.

The 10-DOF model (paper eq. 38-40) as a :class:`feloop.levels.FELevels`
(:class:`LumpedLevels`: the two identical Iwan joints, each ``w = 1/2`` of ``K_T`` and of
the Iwan density; first-harmonic balance with the exact describing function at phase
resonance), the levels those of the paper's reproduction (:func:`cases.lumped10.study.
run_study`: Jenkins banks of 100 sliders, multi-harmonic stepped sine, LSCF), each mode's
micro-slip levels (Table 1's, where both joints stay below phi_max). Then
:func:`feloop.modes.fit_modes` on mode 2 alone and on 2, 4, 6 (the one-joint test, each
mode alone) and :func:`feloop.mode_prediction.predict_mode` of modes 4 and 6 from mode 2.

``python -m cases.lumped10.modes_study`` prints the comparison. SI units.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from cases.lumped10.model import LumpedParameters, lumped10_system
from feloop.case_levels import linear_part
from feloop.levels import FELevels

__all__ = ["LumpedLevels", "lumped_mode_data", "run_modes_study"]


@dataclasses.dataclass
class _LumpedModel:
    """The face :func:`feloop.case_levels.linear_part` reads of an FE model."""

    system: object
    drive_dof: int
    response_dof: int

    @property
    def M(self):
        return self.system.M

    @property
    def K(self):
        return self.system.K_J

    @property
    def K_without_joints(self):
        return self.system.K

    @property
    def slip_matrix(self):
        return self.system.G

    @property
    def joint_stiffness(self):
        return self.system.K_T

    def modes(self, n: int):
        from fe.modal import normal_modes

        return normal_modes(self.system.K_J, self.system.M, min(int(n), self.system.n_dof))


class LumpedLevels(FELevels):
    """The measured levels of one mode simulated by the lumped model (module docstring);
    ``params``: the model (its joints' K_T the default, assumed as given)."""

    label = "lumped 10-DOF model"

    def __init__(self, excitation, run_order, omega2_1, zeta_1,
                 params: LumpedParameters = LumpedParameters(), force_scale: float = 1.0):
        super().__init__(excitation, run_order, omega2_1, zeta_1, force_scale=force_scale,
                         n_modes=8)
        self.params = params
        self.default_kt = 2.0 * params.joint.K_T

    @classmethod
    def from_data(cls, data, **kw) -> "LumpedLevels":
        return cls(data.excitation, data.run_order, data.omega2[0], data.zeta[0], **kw)

    def _build(self, K_T: float):
        p = self.params
        p = dataclasses.replace(p, joint=dataclasses.replace(p.joint, K_T=K_T / 2.0))
        model = _LumpedModel(lumped10_system(p), p.force_dof, p.force_dof)
        return linear_part(self, model, K_T, lambda phi: 0.0, width=1.0, grip=None)

    def structure(self, lin) -> str:
        return "the paper's lumped model (eq. 38-40), joints at the given K_T"


def lumped_mode_data(report) -> dict:
    """Mode label -> its micro-slip levels as measured data (the reproduction's
    identification, :class:`cases.lumped10.report.LumpedReport`)."""
    from ident.modal_data import MeasuredData

    out = {}
    F = report.campaign.force if hasattr(report.campaign, "force") else None
    for m, r in report.modes.items():
        lv = np.asarray(r.fit_levels, int)
        exc = (F if F is not None else LumpedParameters().base_force
               * LumpedParameters().level_ratio ** np.arange(r.frequency_hz.size))[lv - 1]
        out[m] = MeasuredData(level=lv, excitation=exc,
                              omega2=(2 * math.pi * r.frequency_hz[lv - 1]) ** 2,
                              zeta=r.zeta[lv - 1], mode=np.full(lv.size, m), run_order=lv)
    return out


def run_modes_study(report=None) -> dict:
    """The comparison of the module docstring: ``fit`` (mode 2), ``predicted`` (4, 6:
    :class:`feloop.mode_prediction.ModePrediction`), ``all`` (the fit of 2, 4, 6 with each
    mode alone and the one-joint test), the truth (chi, R of the model's joints)."""
    from cases.lumped10.study import LumpedStudy, run_study
    from feloop.mode_prediction import predict_mode
    from feloop.modes import fit_modes, mode_series

    report = run_study(LumpedStudy(), progress=False) if report is None else report
    data = lumped_mode_data(report)
    masks = {m: np.ones(len(d), bool) for m, d in data.items()}
    series = mode_series(data, masks, LumpedLevels.from_data)
    fit2 = fit_modes(series[:1])
    predicted = {s.label: predict_mode(s, fit2) for s in series[1:]}
    every = fit_modes(mode_series(data, masks, LumpedLevels.from_data))
    j = LumpedParameters().joint
    return {"fit": fit2, "predicted": predicted, "all": every,
            "truth": {"chi": j.chi, "R": j.R, "phi_max": j.phi_max}}


def main() -> int:
    r = run_modes_study()
    t, f = r["truth"], r["fit"]
    print(f"the model's joints: chi {t['chi']:g}, R {t['R']:.4g} each, R~ {2 * t['R']:.3g} "
          "both (R~ moves with chi: N/m^(chi+2))")
    print(f"mode 2 fitted: chi {f.fit.values['chi']:.3f} +- {f.fit.std_error('chi'):.1g}, "
          f"R~ {f.joint()['R']:.3g} (both joints)")
    for lb, a in r["all"].alone.items():
        print(f"mode {lb} alone: chi {a.values['chi']:.3f}, R~ "
              f"{r['all'].alone_joint[lb]['R']:.3g}, chi2 {a.chi2:.3g}")
    o = r["all"].one_joint
    print(f"one joint over modes 2, 4, 6: D = {o['D']:.3g}, {o['test']}, p = "
          f"{o['p_value']:.1g} ({'passes' if o['passes'] else 'fails'})")
    for lb, p in r["predicted"].items():
        c = p.change
        print(f"mode {lb} from mode 2: frequency drop {c['measured_frequency_drop_pct']:.3f} % "
              f"measured, {c['predicted_frequency_drop_pct']:.3f} % predicted; damping growth "
              f"x{c['measured_zeta_growth']:.4f} / x{c['predicted_zeta_growth']:.4f}; "
              f"{len(p.misses)} of {len(p.rows) - 1} levels outside the 95 % interval; "
              f"gain {p.gain:.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
