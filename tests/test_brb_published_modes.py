"""The Brake-Reuss beam case file (cases/brb/brb.toml) against the published free-free
bending modes (x-z) of the same beam, issue 20.

Published (read, see the case file's header): the 3-D model of Porter and Brake, MSSP 192
(2023) 110210, after bolt prestress, as printed by tmd-lab/tmdsimpy
examples/structures/brb_epmc.py, "Expected bending mode frequencies": flat interface
168.5026, 580.4082, 1177.6498 Hz; measured mesoscale topology 180.6293, 595.2815,
1199.9013 Hz. The measured backbones lie in 175.5-180 Hz (mode 1) and 591.8-595 Hz (mode
2) (the plot windows of tmd-lab/microslip-rough-contact PLOTS/elastic_bb.m).

"Within the scatter the literature reports": the model is no farther from the centre of
the two published predictions than they are from each other (their spread: 7.2, 2.6,
1.9 %), a range that holds the measured windows of modes 1 and 2 (the mesoscale values lie
0.35 and 0.05 % above their upper ends). The model's geometry and bolt masses are read,
its contact patch and stuck stiffness per area reasoned (assumed), nothing calibrated to
these frequencies.
"""
from __future__ import annotations

import numpy as np

from cases.registry import resolve_case

FLAT_HZ = np.array([168.5026, 580.4082, 1177.6498])
MESOSCALE_HZ = np.array([180.6293, 595.2815, 1199.9013])


def _bending_hz() -> np.ndarray:
    model = resolve_case("brb").fe_model()
    return np.array([model.bending_mode_frequency(k) for k in (1, 2, 3)])


def test_first_bending_modes_within_the_published_scatter():
    f = _bending_hz()
    centre, spread = 0.5 * (FLAT_HZ + MESOSCALE_HZ), MESOSCALE_HZ - FLAT_HZ
    assert np.all(np.abs(f - centre) <= spread), (f, centre, spread)
    # and within 1.1 % of the nearer published value (the file's RESULT: 1.0, 0.5, 0.6 %)
    nearest = np.minimum(np.abs(f / FLAT_HZ - 1), np.abs(f / MESOSCALE_HZ - 1))
    assert np.all(nearest < 0.011), nearest



def test_a_free_free_beam_lists_three_rigid_body_modes_then_its_bending_modes():
    """Free-free in x-z: axial translation, heave and pitch have zero frequency (the model
    gives < 0.1 Hz against 166 Hz) and are listed as rigid-body modes, not as 'bending'
    or 'axial'; bending orders 1, 2, 3 follow."""
    from cases.mode_report import band_modes

    rows = band_modes(resolve_case("brb").fe_model(), (0.0, 1300.0))
    assert [r["kind"] for r in rows[:3]] == ["rigid-body"] * 3
    assert all(r["frequency_hz"] < 0.1 for r in rows[:3])
    assert [r["bending_order"] for r in rows[3:6]] == [1, 2, 3]
    assert all(r["kind"] == "bending" for r in rows[3:6])
