"""Forced response of a hardening one-sided stop (``fe/frc.py``): an oscillator
``x'' + 0.02 x' + x + max(x - 0.2, 0) = 0.01 cos(w t)`` (``tests/frc_laws.py``), harmonics
0..9 (the stop is not symmetric), 1024 AFT samples (with fewer, the contact starting
between samples wrinkles the branch near its top into spurious fold pairs: 14 folds with
harmonics 0..5 and 512 samples).

Truths: the time integration (Newmark, the law's own step, 512 steps per period) started
on an orbit stays on it if the orbit is stable and leaves it if not; the Floquet
multipliers of the Newmark period map against Hill's.
"""
from __future__ import annotations

import numpy as np
import pytest

from fe.continuation import ContinuationSettings
from fe.floquet import floquet_multipliers, period_map_monodromy
from fe.frc import FRCSettings, forced_response
from fe.hb_forced import ForcedBalance
from fe.newmark import NewmarkIntegrator, NewmarkSettings, NewmarkState
from frc_laws import OneSidedStop, sdof

HARMONICS = tuple(range(10))
LOAD = np.array([0.01])


@pytest.fixture(scope="module")
def stop_curve():
    model, law = sdof(1.0, 0.01), OneSidedStop(1.0, 0.2)
    st = FRCSettings(harmonics=HARMONICS, n_time=1024, jacobian="tangent",
                     continuation=ContinuationSettings(ds=0.05, ds_max=0.3))
    r = forced_response(model, law, LOAD, (0.9, 1.2), settings=st)
    bal = ForcedBalance(model, law, LOAD, HARMONICS, 1024, jacobian="tangent")
    return model, law, bal, r


def _newmark_peak(model, law, bal, x, w, periods, n=512):
    """Half peak-to-peak of the last of ``periods`` periods integrated from the orbit."""
    dt = 2 * np.pi / w / n
    q = bal.time_samples(x, n)
    v = bal.time_samples((bal.derivative(w) @ x.reshape(bal.nc, 1)).reshape(-1), n)
    F = np.asarray(law.step(q[0], None)[0], dtype=float)
    a = LOAD - model.C @ v[0] - model.K @ q[0] - F
    s = NewmarkState(t=0.0, q=q[0].copy(), v=v[0].copy(), a=a, anchor=None, g=F, e=1.0)
    e = np.cos(w * dt * np.arange(periods * n + 1))
    run = NewmarkIntegrator(model, law, NewmarkSettings(dt=dt)).run(LOAD, e, s, energy=False)
    last = run.q[-n - 1:, 0]
    return 0.5 * (last.max() - last.min())


def test_stop_folds_and_stability(stop_curve):
    model, law, bal, r = stop_curve
    assert r.omega[0] == pytest.approx(0.9) and r.omega[-1] == pytest.approx(1.2)
    assert len(r.folds) == 2
    w_folds = sorted(f["omega"] for f in r.folds)
    assert 1.0 < w_folds[0] < w_folds[1]                         # hardening: both above w0
    a0, a1 = sorted(f["after"] for f in r.folds)
    between = np.zeros(r.omega.size, dtype=bool)
    between[a0 + 1:a1 + 1] = True
    assert np.array_equal(~r.stable, between)                    # Hill
    upper, middle = a0 - 3, (a0 + a1) // 2
    for i in (upper, middle):
        floq = np.abs(floquet_multipliers(period_map_monodromy(bal, r.x[i], r.omega[i],
                                                               4096))).max()
        assert (floq > 1.0) == (i == middle)
        tol = 1e-6 if i == upper else 5e-3          # measured 3.2e-8 and 1.3e-3
        assert abs(floq - r.max_multiplier[i]) < tol


def test_forced_response_reports_floquet_too():
    """``FRCSettings.floquet``: the period-map multiplier beside Hill's at every point."""
    model, law = sdof(1.0, 0.01), OneSidedStop(1.0, 0.2)
    st = FRCSettings(harmonics=HARMONICS, n_time=256, jacobian="tangent",
                     continuation=ContinuationSettings(ds=0.1, ds_max=0.3),
                     floquet="period_map", floquet_steps=512)
    r = forced_response(model, law, LOAD, (0.5, 0.8), settings=st)   # below contact
    assert r.folds == [] and np.all(r.peak < law.gap)
    # linear: both are exp(-zeta w0 T) (closed form) up to the scheme's O(dt^2)
    exact = np.exp(-0.01 * 2 * np.pi / r.omega)
    assert np.max(np.abs(r.max_multiplier - exact)) < 1e-12         # measured 1.0e-15
    assert np.max(np.abs(r.floquet_multiplier - exact)) < 5e-5      # measured 1.7e-5
    pts = r.to_points()
    assert all("floquet_multiplier" in p and p["stable"] for p in pts)


def test_stop_orbits_by_time_integration(stop_curve):
    model, law, bal, r = stop_curve
    a0, a1 = sorted(f["after"] for f in r.folds)
    upper, middle = a0 - 3, (a0 + a1) // 2
    assert r.peak[upper] > 2 * law.gap                           # deep in contact
    pk = _newmark_peak(model, law, bal, r.x[upper], r.omega[upper], 60)
    assert abs(pk - r.peak[upper]) < 2e-4 * r.peak[upper]        # measured 6.9e-5
    # the middle orbit is left for the lower branch, out of contact (measured peak 0.068 m
    # after 150 periods, from 0.344 m)
    pk = _newmark_peak(model, law, bal, r.x[middle], r.omega[middle], 150)
    assert pk < law.gap < r.peak[middle]


def test_stop_folds_against_a_refined_solve(stop_curve):
    """The folds of the continuation against a second route: the extremum of ``w`` along
    the branch with one harmonic coefficient held (``test_continuation.refined_fold``,
    Brent), within 1e-6 relative (measured 2e-16). Both folds sit where the contact
    starts between two AFT samples: the tangent's frequency component jumps there
    (0.32 and 0.013 left at the located point) and the extremum is that corner."""
    from test_continuation import refined_fold

    _, _, bal, r = stop_curve
    for f in r.folds:
        assert abs(f["omega"] - refined_fold(bal, f["fold"])) < 1e-6 * f["omega"]
