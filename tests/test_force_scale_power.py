"""What a fitted cause parameter owes to the assumed force scale s (N per excitation
unit): omega^2 and zeta of every level are invariant to s when the parameter scales as
s^force_scale_power (feloop.causes), so the power the reports print ("rests on
the force scale ...: it scales as s^-1") is checked by the simulation itself: the lap
cantilever's FE-levels model at s = 1 and s = 3."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from feloop.causes import EXTENSIONS, force_scale_power
from cases.registry import resolve_case
from ident.measured import read_measured

LAP = Path(__file__).resolve().parents[1] / "docs" / "case-files" / "bolted-lap-cantilever.toml"
BASE = {"chi": -0.6, "ln_dc1": 1.3, "zeta_v": 1e-3, "f0_hz": 85.2375}


def _levels(scale):
    case = resolve_case(str(LAP))
    data = read_measured(case.measured_data()).for_mode(2)
    return case.builders["fe_levels"](data, force_scale=scale)


@pytest.mark.parametrize("cause, power", [("quadratic-damping", -1),
                                          ("geometric-hardening", -2),
                                          ("macro-slip", 0)])
def test_parameter_scaled_by_its_power_leaves_every_level_unchanged(cause, power):
    ext = EXTENSIONS[cause]
    assert force_scale_power(ext.parameter) == power
    one, three = _levels(1.0), _levels(3.0)
    base = one.predict(BASE)
    a = float(base.modal_amplitude[-1])
    value = {"quadratic-damping": 10.0,                         # C_D
             "geometric-hardening": 1e-3 * base.omega2[-1] / (0.75 * a * a),   # k3
             "macro-slip": 1.0}[cause]                          # ln(phi_max / a_ref)
    p1 = one.predict({**BASE, ext.parameter: value}, ext)
    p3 = three.predict({**BASE, ext.parameter: value * 3.0 ** power}, ext)
    effect = max(np.max(np.abs(p1.omega2 / base.omega2 - 1)), np.max(np.abs(p1.zeta / base.zeta - 1)))
    assert effect > 1e-4, effect                  # the cause shows: the test can fail
    assert np.allclose(p3.omega2, p1.omega2, rtol=1e-9)
    assert np.allclose(p3.zeta, p1.zeta, rtol=1e-7)


def test_base_parameters_do_not_scale():
    assert all(force_scale_power(n) == 0 for n in BASE)
    assert math.isclose(_levels(1.0).predict(BASE).zeta[-1], _levels(3.0).predict(BASE).zeta[-1],
                        rel_tol=1e-7)
