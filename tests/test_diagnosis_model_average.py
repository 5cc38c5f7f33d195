"""Model-averaged held-out prediction intervals (``inverse.diagnosis.intervals``;
Burnham & Anderson 2002, sec. 4.3), against hand calculations."""
from __future__ import annotations

import math

import pytest
from scipy import stats

from inverse.diagnosis.intervals import averaging_weights, model_averaged
from inverse.judge import Selection


def _row(pred, sd, y=2.5, dof=None):
    return {"level": 9, "omega2": {"measured": y, "predicted": pred, "sd": sd, "dof": dof},
            "zeta": {"measured": 0.01, "predicted": 0.01, "sd": 1e-4}}


def test_one_model_keeps_its_interval_and_two_add_their_spread():
    one = model_averaged({"a": [_row(1.0, 1.0)]}, {"a": 1.0})[0]["omega2"]
    q = stats.norm.ppf(0.975)
    assert one["predicted"] == 1.0 and one["interval"] == pytest.approx([1 - q, 1 + q])
    # one model with 4 dof keeps its t interval: (t_4 / z) sd on the normal scale
    t4 = stats.t.ppf(0.975, 4)
    alone = model_averaged({"a": [_row(1.0, 1.0, dof=4.0)]}, {"a": 1.0})[0]["omega2"]
    assert alone["interval"][1] - 1.0 == pytest.approx(t4)
    # predictions 1 and 3 (sd 1, 4 dof each), weights 1/4 and 3/4: mean 2.5, variance
    # (t_4/z)^2 + (1/4)(1.5^2) + (3/4)(0.5^2) = (t_4/z)^2 + 0.75, interval z sqrt(...)
    two = model_averaged({"a": [_row(1.0, 1.0, dof=4.0)], "b": [_row(3.0, 1.0, dof=4.0)]},
                         {"a": 0.25, "b": 0.75})[0]["omega2"]
    assert two["predicted"] == pytest.approx(2.5)
    assert two["sd"] == pytest.approx(math.sqrt((t4 / q) ** 2 + 0.75))
    assert two["interval"][1] - 2.5 == pytest.approx(q * math.sqrt((t4 / q) ** 2 + 0.75))
    # a candidate whose held-out fit failed is left out, the others renormalized
    left = model_averaged({"a": [_row(1.0, 1.0)], "b": []},
                          {"a": 0.25, "b": 0.75})[0]["omega2"]
    assert left["predicted"] == 1.0


def test_weights_are_the_eligible_candidates_renormalized():
    sel = Selection("macro-slip", [], "macro-slip",
                    {"none": 0.5, "macro-slip": 0.3, "thermal-drift": 0.196,
                     "quadratic-damping": 0.004}, {}, ["macro-slip", "thermal-drift",
                                                       "quadratic-damping"], [], False)
    w = averaging_weights(sel)
    assert set(w) == {"macro-slip", "thermal-drift"}          # 0.004/0.5 < W_MIN
    assert w["macro-slip"] == pytest.approx(0.3 / 0.496)
    miss = Selection("unexplained", [], "none", {"none": 1.0}, {}, [], [], True)
    assert averaging_weights(miss) == {"none": 1.0}
