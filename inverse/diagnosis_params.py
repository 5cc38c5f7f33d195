"""Physical parameters of a fitted diagnosis model (:mod:`inverse.diagnosis_fit`).

Every value is *fitted* to the series being diagnosed (SI units: rad^2/s^2 for the
omega2 terms, fractions for damping ratios):

* ``omega2_0``, ``zeta_0``: small-amplitude natural frequency squared and damping ratio;
* ``chi``; ``kappa1_B``: the paper's ``|kappa1| B``, the hysteretic modal stiffness at
  level 1 (eq. 45), and ``kappa2_B = kappa_ratio(chi) kappa1_B`` the frequency drop at
  level 1 (eq. 43); ``kappa_ratio`` the micro-slip tie;
* per cause: ``x_top`` (top slip amplitude / phi_max) and ``beta`` (Dirac weight
  ``S (chi+1) / (R phi_max^(chi+1))``); ``gamma``, ``kappa`` and
  ``amplitude_shortfall_top`` (1 - joint amplitude ratio top/level 1 over the base
  abscissa's ratio); ``h_top`` (omega2 added at the top level), ``n_hardening`` and ``s_contact``;
  ``d_total`` (omega2 drift over the run), ``d`` per run (average) and the shape
  ``b_drift``; ``q_top`` (damping ratio
  added at the top level), ``m_damping`` and ``u_saturation``.
"""
from __future__ import annotations

import numpy as np

from inverse.diagnosis_fit import Fit
from inverse.diagnosis_models import Observations, contact_shape, hardening_power
from inverse.iwan_modal import kappa1_per_R, kappa_ratio

__all__ = ["physical_parameters"]


def physical_parameters(fit: Fit, obs: Observations, run_span: float) -> dict:
    """JSON-friendly parameters of ``fit`` (module doc); ``run_span`` = max - min run
    order (for the drift per run)."""
    m = fit.model
    lin = dict(zip(m.linear_names(obs.log_r is not None), fit.linear))
    nl = dict(zip([a[0] for a in m.nonlinear], fit.theta))
    chi = fit.chi
    p = chi + 1.0
    W = lin["W"] + obs.omega2[0]
    out = {"omega2_0": W, "zeta_0": lin["c"] / (2.0 * np.sqrt(W)), "chi": chi}
    log_s1, log_top = fit.log_s[0], float(np.max(fit.log_s))
    if m.has("macro-slip"):
        U, S = lin["U"], lin["S"]
        x_top = float(np.exp(nl["log_x_top"] + log_top))
        K1_top = U * kappa1_per_R(chi) * x_top**p   # power-law continuation at the top
        out.update(x_top=x_top, beta=S * p / U if U > 0 else float("inf"))
    else:
        K1_top = lin["K1"]
    out["kappa1_B"] = K1_top * np.exp(p * (log_s1 - log_top))
    out["kappa_ratio"] = kappa_ratio(chi, "exact")
    out["kappa2_B"] = out["kappa_ratio"] * out["kappa1_B"]
    if m.has("nonproportional-amplitude"):
        log_base = np.log(obs.s)
        shortfall = 1.0 - np.exp((log_top - log_s1) - (log_base.max() - log_base[0]))
        out.update(gamma=nl["gamma"], kappa=nl["kappa"], amplitude_shortfall_top=shortfall)
    if m.has("geometric-hardening"):
        top = np.exp(log_top)
        n_h = float(hardening_power(nl["nu_hardening"], nl["s_contact"], obs.s))
        out.update(h_top=lin["h"] * top**n_h * contact_shape(nl["s_contact"] / top),
                   n_hardening=n_h, s_contact=nl["s_contact"])
    if m.has("thermal-drift"):
        out.update(d_total=lin["d"], d=lin["d"] / run_span if run_span > 0 else 0.0,
                   b_drift=nl["b_drift"])
    if m.has("quadratic-damping"):
        sm = np.exp(nl["m_damping"] * log_top)
        out.update(q_top=lin["q"] * sm / (1.0 + nl["u_saturation"] ** nl["m_damping"] * sm),
                   m_damping=nl["m_damping"], u_saturation=nl["u_saturation"])
    return {k: float(v) for k, v in out.items()}
