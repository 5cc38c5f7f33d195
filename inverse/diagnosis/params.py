"""Physical parameters of a fitted diagnosis model (:mod:`inverse.diagnosis.fit`).

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
  added at the top level), ``m_damping`` and ``u_saturation`` (each cause's file in
  :mod:`inverse.diagnosis.causes` defines its own).
"""
from __future__ import annotations

import numpy as np

from inverse.diagnosis.causes import CATALOGUE
from inverse.diagnosis.fit import Fit
from inverse.diagnosis.models import Observations
from inverse.iwan_modal import kappa_ratio

__all__ = ["physical_parameters"]


def physical_parameters(fit: Fit, obs: Observations) -> dict:
    """JSON-friendly parameters of ``fit`` (module doc; each cause's own from its
    ``parameters``)."""
    m = fit.model
    lin = dict(zip(m.linear_names(obs.log_r is not None), fit.linear))
    nl = dict(zip([a[0] for a in m.nonlinear], fit.theta))
    chi = fit.chi
    p = chi + 1.0
    W = lin["W"] + obs.omega2[0]
    # a failed or runaway fit can put the stuck omega2 at or below 0: no zeta_0 then
    zeta_0 = lin["c"] / (2.0 * np.sqrt(W)) if W > 0 else float("nan")
    out = {"omega2_0": W, "zeta_0": zeta_0, "chi": chi}
    log_s1, log_top = fit.log_s[0], float(np.max(fit.log_s))
    own = {}
    for c in m.causes:
        own.update(CATALOGUE[c].parameters(lin, nl, obs, fit.log_s, chi))
    K1_top = own.pop("K1_top", lin.get("K1"))
    out["kappa1_B"] = K1_top * np.exp(p * (log_s1 - log_top))
    out["kappa_ratio"] = kappa_ratio(chi, "exact")
    out["kappa2_B"] = out["kappa_ratio"] * out["kappa1_B"]
    out.update(own)
    return {k: float(v) for k, v in out.items()}
