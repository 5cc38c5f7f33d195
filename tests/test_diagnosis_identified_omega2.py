"""The diagnosis models predict what identification measures: the squared modulus of the
pole of a level's equivalent linear mode, which a joint's quadrature stiffness raises by
``k_q zeta`` (models.py eq. 4). Second method: the project's LSCF
(:func:`ident.identify.identify`) on the exact FRF of a hysteretically damped SDOF."""
from __future__ import annotations

import numpy as np
import pytest

from ident.identify import identify
from inverse.diagnosis.fit import fit_model
from inverse.diagnosis.models import Model, Observations, design
from inverse.iwan_modal import kappa_ratio

W0 = (2 * np.pi * 120.0) ** 2          # rad^2/s^2
C = 2 * 0.004 * np.sqrt(W0)            # rad/s (viscous, 0.4 %)
CHI = -0.4
K1_TOP = 2 * 0.02 * W0                 # joint quadrature stiffness at the top level
S = np.geomspace(0.1, 1.0, 9)          # relative joint amplitude


def _identified():
    """omega2 and zeta identified by LSCF from the exact FRF of each level: in-phase
    stiffness ``W0 - K2 s^p``, quadrature ``K1 s^p`` (the Iwan micro-slip laws)."""
    p = CHI + 1.0
    kq = K1_TOP * S**p
    win = W0 - kappa_ratio(CHI, "exact") * kq
    om2, zeta = [], []
    for w_in, k in zip(win, kq):
        f0 = np.sqrt(w_in) / (2 * np.pi)
        bw = (C / np.sqrt(w_in) + k / w_in) / 2
        f = np.linspace(f0 * (1 - 6 * bw), f0 * (1 + 6 * bw), 81)
        w = 2 * np.pi * f
        m = identify(f, 1.0 / (w_in - w**2 + 1j * (C * w + k)), n_modes=1,
                     weighting="relative").modes[0]
        om2.append(m.omega2)
        zeta.append(m.zeta)
    return np.array(om2), np.array(zeta), win


def _obs(om2, zeta):
    sig = {"omega2": 1e-7 * om2, "zeta": 1e-4 * zeta}
    n = S.size
    return Observations(level=np.arange(1, n + 1), s=S, omega2=om2, zeta=zeta,
                        t_run=np.linspace(0, 1, n), log_r=None, response_controlled=False,
                        sigma=sig, run_monotone=True, run_span=n - 1.0)


def test_lscf_omega2_is_the_pole_modulus_raised_by_kq_zeta():
    om2, zeta, win = _identified()
    kq = K1_TOP * S ** (CHI + 1.0)
    # identification is not the in-phase stiffness: 2 zeta_h zeta ~ 1e-3 at the top
    assert np.max(np.abs(om2 / win - 1)) > 5e-4
    np.testing.assert_allclose(om2, win + kq * zeta, rtol=1e-6)   # 5e-4 of the shift


def test_base_model_predicts_identified_omega2_at_the_planted_parameters():
    om2, zeta, win = _identified()
    obs = _obs(om2, zeta)
    A, _, _ = design(Model(), obs, np.array([[CHI + 1.0]]))
    coef = np.array([W0 - om2[0], C, K1_TOP])         # W, c, K1 (relative to omega2[0])
    pred = A[0] @ coef
    n = S.size
    pred_om2 = pred[:n] * obs.sigma["omega2"] + om2[0]
    pred_zeta = pred[n:] * obs.sigma["zeta"]
    np.testing.assert_allclose(pred_om2, om2, rtol=1e-6)
    np.testing.assert_allclose(pred_zeta, zeta, rtol=2e-3)   # zeta: measured omega2 in (3)


def test_base_fit_recovers_chi_from_identified_data():
    om2, zeta, _ = _identified()
    obs = _obs(om2, zeta)
    obs.sigma = {"omega2": 2e-6 * om2, "zeta": 2e-3 * zeta}
    fit = fit_model(Model(), obs)
    assert fit.chi == pytest.approx(CHI, abs=0.01)
    assert fit.chi2 < 1.0
