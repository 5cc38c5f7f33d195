"""EPMC backbone vs response-controlled vs force-controlled virtual tests, each fed to the
estimator against the joint's true parameters.

:func:`compare_routes` runs the three routes of :mod:`cases.backbone_routes` on one case
(the same drive-point amplitudes at resonance for all three: those the force-controlled
levels reach), estimates chi and R~ from each (:func:`inverse.estimate.estimate`, B~ from
the case's FE model at 1 N per excitation unit, the levels ``fit_levels``), and states
each route's bias against the true chi and R (:mod:`cases.nonlinear_case`).

The paper's protocol is estimated twice: as the paper does it (``exact`` method,
abscissa the force, i.e. the joint amplitude assumed proportional to the force) and on
the identified response amplitude (``amplitude`` method). The response-controlled and
EPMC data are estimated on their held amplitude (``amplitude`` method).

Explanation of a bias. The estimator's modal relation (paper eq. 30-32, eq. 1 of
:mod:`inverse.iwan_modal`) ties the damping growth to ``B = sum_m w_m (g_m . phi)^2
A_m^(chi+1)``, with the stuck-joint mode ``phi`` and the slips ``A_m``, and eq. 33 takes
``A_m`` proportional to the abscissa. The EPMC's energy balance (exact: the artificial
damping's work equals the viscous and joint dissipation, a test checks it to 1e-14)
gives instead ``Delta c = sum_m k_q,m(A_m) A_m^2 / a^2 = |kappa1| R sum_m w_m (A_m/a)^2
A_m^(chi+1)`` with ``a`` the modal amplitude: the slip per modal amplitude ``A_m/a``
replaces ``g_m . phi``. The same estimator is run on data built from the true joint
(``Delta c`` as above, ``Delta omega^2 = (kappa2/|kappa1|) Delta c``, eq. 2 of
:mod:`inverse.iwan_modal`) with each route's own slips:

* ``chi_slip_law``: with ``(g_m . phi)^2`` (eq. 30-32 as the estimator assumes): its
  bias is what the slips' growth against the abscissa does (eq. 33 fails);
* ``chi_energy``: with ``(A_m/a)^2`` (``a`` from the EPMC at the same drive-point
  amplitude): the difference ``chi_energy - chi_slip_law`` is what the growth of the
  slip per modal amplitude does (the glue's in-phase softening concentrates the slip);
* ``chi - chi_energy``: the rest (the mode's frequency change, the viscous damping of the
  changed shape, higher harmonics, the identification).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cases.backbone_routes import epmc_route, force_route, response_route
from casefile.jointed import NonlinearCase
from fe.epmc import epmc_backbone, linear_mode
from ident.modal_data import MeasuredData
from inverse.estimate import estimate
from inverse.iwan_modal import zeta_with_joint
from joints.describing import kappa1, kappa2_exact

__all__ = ["RouteEstimate", "BackboneComparison", "compare_routes", "decoupled_data"]

#: (route, estimator method, abscissa) of the comparison.
ROUTES = (("force", "exact", "force"), ("force", "amplitude", "response amplitude"),
          ("response", "amplitude", "held amplitude"), ("epmc", "amplitude", "held amplitude"))


@dataclass
class RouteEstimate:
    """One route's estimate: ``chi``, ``R`` (R~), B~, and the ``chi_slip_law`` and
    ``chi_energy`` of its bias's explanation (module docstring); ``error`` when the
    estimator refused."""

    route: str
    method: str
    abscissa: str
    chi: float = float("nan")
    R: float = float("nan")
    B: float = float("nan")
    chi_slip_law: float = float("nan")
    chi_energy: float = float("nan")
    error: str | None = None

    def to_dict(self, chi_true: float, R_true: float) -> dict:
        return {"route": self.route, "method": self.method, "abscissa": self.abscissa,
                "chi": self.chi, "chi_bias": self.chi - chi_true, "R": self.R,
                "R_relative_error": self.R / R_true - 1.0, "B_tilde": self.B,
                "chi_slip_law": self.chi_slip_law,
                "chi_bias_slip_law": self.chi_slip_law - chi_true,
                "chi_energy": self.chi_energy,
                "chi_bias_slip_per_modal_amplitude": self.chi_energy - self.chi_slip_law,
                "chi_bias_rest": self.chi - self.chi_energy, "error": self.error}


@dataclass
class BackboneComparison:
    """The three routes on one case (module docstring); SI units."""

    case: str
    path: str
    chi_true: float
    R_true: float
    phi_max: float
    fit_levels: str
    data: dict                      # route -> MeasuredData
    slip: dict                      # route -> (n_levels, n_joints) slips at resonance (m)
    estimates: list                 # RouteEstimate
    backbone: object                # fe.backbone.Backbone, dense (for the figure)
    drive_dof: int
    notes: list = field(default_factory=list)

    def deviation(self, route: str) -> dict:
        """Relative deviation of ``route``'s frequency and damping from the EPMC backbone
        at the same drive-point amplitude, per level."""
        d, e = self.data[route], self.data["epmc"]
        return {"frequency": np.sqrt(d.omega2 / e.omega2) - 1.0, "zeta": d.zeta / e.zeta - 1.0}

    def to_dict(self) -> dict:
        routes = {}
        for name, d in self.data.items():
            routes[name] = {"source": d.source, "excitation_N": d.excitation,
                            "frequency_hz": d.omega_hz, "zeta": d.zeta,
                            "drive_amplitude_m": d.response_amplitude,
                            "slip_over_phi_max": self.slip[name].max(axis=1) / self.phi_max}
            if name != "epmc":
                routes[name]["deviation_from_epmc"] = self.deviation(name)
        return {"case": self.case, "path": self.path, "chi_true": self.chi_true,
                "R_true": self.R_true, "phi_max": self.phi_max, "fit_levels": self.fit_levels,
                "routes": routes,
                "estimates": [e.to_dict(self.chi_true, self.R_true) for e in self.estimates],
                "notes": self.notes}


def decoupled_data(case: NonlinearCase, data: MeasuredData, slip,
                   modal_amplitude=None) -> MeasuredData:
    """``data`` with omega2 and zeta from the true joint at the slips ``slip`` (n_levels,
    n_joints): ``B = sum_m w_m (g_m . phi)^2 A_m^(chi+1)`` (eq. 30-32), or with
    ``modal_amplitude`` (n_levels,) ``(A_m/a)^2`` in place of ``(g_m . phi)^2`` (the energy
    balance; module docstring)."""
    w0, phi = linear_mode(case.model, case.mode)
    K_T = case.model.K_T
    A = np.asarray(slip, dtype=float)
    shape2 = ((case.model.G @ phi) ** 2)[None, :] if modal_amplitude is None else \
        (A / np.asarray(modal_amplitude, dtype=float)[:, None]) ** 2
    B = ((K_T / K_T.sum()) * shape2 * A ** (case.chi + 1.0)).sum(axis=1)
    dc = abs(kappa1(case.R, case.chi)) * B
    om2 = w0 ** 2 - kappa2_exact(case.R, case.chi) * B
    zeta = zeta_with_joint(dc, om2, float(phi @ case.model.C @ phi))
    return MeasuredData(level=data.level, excitation=data.excitation, omega2=om2, zeta=zeta,
                        mode=None, run_order=None, response_amplitude=data.response_amplitude,
                        control=data.control, source=data.source + " (modal relation)")


def _estimate(case, data, method, fit_levels):
    amp = data.response_amplitude if method == "amplitude" else None
    return estimate(data, fit_levels=fit_levels, method=method, model=case.fe_model,
                    fe_mode=case.mode, amplitude=amp, case_name=case.name)


def compare_routes(case: NonlinearCase, path: str = "exact", fit_levels: str = "1-7",
                   n_backbone: int = 60, progress: bool = False) -> BackboneComparison:
    """Run the three routes on ``case`` and estimate from each (module docstring).

    Parameters
    ----------
    case : NonlinearCase
    path : {"exact", "bank"}
        Joint path of every route.
    fit_levels : str
        Levels of the estimator's fit (the others are outside its micro-slip theory or
        held out).
    n_backbone : int
        Points of the dense EPMC backbone kept for the figure (slip 1e-3 phi_max up to
        the top level's).
    """
    data, slip = {}, {}
    data["force"], slip["force"] = force_route(case, path, progress=progress)
    held = data["force"].response_amplitude
    data["response"], slip["response"] = response_route(case, held, path, progress=progress)
    data["epmc"], slip["epmc"], at_held = epmc_route(case, held, path)
    top = max(float(slip["force"].max()) / case.phi_max, 2e-3)
    dense = epmc_backbone(case.model, case.joint_harmonics(path), case.mode,
                          np.geomspace(1e-3, top, n_backbone) * case.phi_max, at="slip")
    estimates = []
    for route, method, absc in ROUTES:
        rec = RouteEstimate(route, method, absc)
        try:
            e = _estimate(case, data[route], method, fit_levels)
            rec.chi, rec.R, rec.B = e.chi, e.R, e.B
            for name, a_m in (("chi_slip_law", None),
                                ("chi_energy", at_held.modal_amplitude)):
                d = decoupled_data(case, data[route], slip[route], a_m)
                setattr(rec, name, _estimate(case, d, method, fit_levels).chi)
        except ValueError as exc:
            rec.error = str(exc)
        estimates.append(rec)
    return BackboneComparison(case=case.name, path=path, chi_true=case.chi, R_true=case.R,
                              phi_max=case.phi_max, fit_levels=fit_levels, data=data,
                              slip=slip, estimates=estimates, backbone=dense,
                              drive_dof=case.drive_dof)
