"""The paper's lumped study through one joint (cases/lumped10/modes_study.py): chi and R
fitted on mode 2 of the 10-DOF model's reproduction (Jenkins banks of 100 sliders,
multi-harmonic stepped sine, LSCF; lines in the modes' bands) predict modes 4 and 6.
Truth: the model's own joints (chi = -0.5)."""
from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def study():
    from cases.lumped10.modes_study import run_modes_study
    from cases.lumped10.study import LumpedStudy, run_study

    return run_modes_study(run_study(LumpedStudy(bands_only=True, df=1.0), progress=False))


def test_mode_2_recovers_chi(study):
    """chi from mode 2 within 0.05 of the model's (measured -0.526); each mode alone
    too (-0.526, -0.498, -0.467)."""
    assert abs(study["fit"].fit.values["chi"] - study["truth"]["chi"]) < 0.05
    for fit in study["all"].alone.values():
        assert abs(fit.values["chi"] - study["truth"]["chi"]) < 0.05


def test_modes_4_and_6_predicted_from_mode_2(study):
    """The frequency drop over the micro-slip levels predicted within 10 % (mode 4:
    0.201 % against 0.215 % measured) and 25 % (mode 6: 0.302 % against 0.368 %) of the
    measured, and the damping growth within a factor 2 (mode 6: x1.0135 against x1.026);
    the gain over no amplitude dependence > 5. The noise-free series make the intervals
    narrow, so levels are missed: the misses are said, with numbers."""
    tol = {4: 0.10, 6: 0.25}
    for lb, p in study["predicted"].items():
        c = p.change
        assert abs(c["predicted_frequency_drop_pct"] / c["measured_frequency_drop_pct"] - 1) \
            < tol[lb], (lb, c)
        g = (c["predicted_zeta_growth"] - 1) / (c["measured_zeta_growth"] - 1)
        assert 0.5 < g < 2.0, (lb, c)
        assert p.gain > 5
        assert all({"level", "z_frequency", "z_zeta"} <= set(m) for m in p.misses)
