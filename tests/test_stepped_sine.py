"""Stepped-sine campaigns (runs.campaign, runs.stepped_sine): protocols and resumable
storage."""
import json

import numpy as np
import pytest

from cases.lumped10.model import LumpedParameters, force_vector, lumped10_bank, lumped10_system
from fe.reduction import JointBank, reduced_basis
from runs.campaign import Campaign, NewmarkProtocol, PaperProtocol
from runs.stepped_sine import run_campaign


@pytest.fixture(scope="module")
def lumped():
    p = LumpedParameters()
    s = lumped10_system(p)
    return p, s, reduced_basis(s), lumped10_bank(p, 30)


class Stop(Exception):
    pass


def test_interrupted_campaign_resumes_without_recomputing(lumped, tmp_path):
    p, s, m, bank = lumped
    camp = Campaign(np.arange(59.0, 64.01, 0.5), [2.0, 16.0, 128.0, 1024.0], force_vector(p),
                    [4, 5])
    full = run_campaign(m, bank, camp, store=tmp_path / "a", progress=False)
    assert full.computed.all()

    def stop_after_1(level, res):
        if level == 1:
            raise Stop

    with pytest.raises(Stop):
        run_campaign(m, bank, camp, store=tmp_path / "b", progress=False, on_level=stop_after_1)
    manifest = json.loads((tmp_path / "b" / "manifest.json").read_text())
    assert sorted(manifest["levels"]) == ["0", "1"]
    seen = []
    again = run_campaign(m, bank, camp, store=tmp_path / "b", progress=False,
                         on_level=lambda lv, r: seen.append(lv))
    assert seen == [2, 3]                                   # finished levels not recomputed
    assert list(again.computed) == [False, False, True, True]
    np.testing.assert_array_equal(again.receptance, full.receptance)
    np.testing.assert_array_equal(again.slip_amplitude, full.slip_amplitude)
    # another campaign in the same store is refused
    other = Campaign(camp.frequency_hz, [3.0], camp.load, camp.outputs)
    with pytest.raises(ValueError, match="other parameters"):
        run_campaign(m, bank, other, store=tmp_path / "b", progress=False)


def test_newmark_protocol_matches_hb(lumped):
    """State carried from line to line, periodicity criterion: within 0.5 % of HB."""
    p, s, m, bank = lumped
    lines = np.array([60.5, 61.5, 62.5])
    hb = run_campaign(m, bank, Campaign(lines, [64.0], force_vector(p), np.arange(10)),
                      progress=False)
    nm = run_campaign(m, bank, Campaign(lines, [64.0], force_vector(p), np.arange(10),
                                        NewmarkProtocol(tol=1e-5)), progress=False)
    rel = np.abs(np.abs(nm.receptance) / np.abs(hb.receptance) - 1)
    assert rel.max() < 5e-3
    np.testing.assert_allclose(nm.slip_amplitude, hb.slip_amplitude, rtol=5e-3)
    # the periodicity test stopped well before a fixed 9 s would (per line)
    assert np.all(nm.work[0] < 9.0 * lines)


def test_paper_protocol_linear_response():
    """Fixed settle + window from rest, stuck joints: the least-squares first harmonic
    equals the linear FRF at the warped frequency (closed form)."""
    p = LumpedParameters()
    s = lumped10_system(p)
    m = reduced_basis(s)
    stuck = JointBank(np.full((2, 1), 1.1e5), np.full((2, 1), 1e3))
    proto = PaperProtocol(settle=3.0, window=0.5, steps_per_period=64)
    res = run_campaign(m, stuck, Campaign([61.5], [2.0], force_vector(p), np.arange(10), proto),
                       progress=False)
    w = 2 * np.pi * 61.5
    dt = 2 * np.pi / (w * 64)
    W = 2 / dt * np.tan(w * dt / 2)
    exact = np.linalg.solve(s.K_J - W ** 2 * s.M + 1j * W * s.C, force_vector(p))
    np.testing.assert_allclose(res.receptance[0, 0], exact, rtol=2e-4,
                               atol=1e-4 * np.abs(exact).max())


def test_campaign_input_checks(lumped):
    p, s, m, bank = lumped
    with pytest.raises(ValueError):
        Campaign([0.0, 10.0], [1.0], force_vector(p), [0])
    with pytest.raises(ValueError):
        Campaign([10.0], [-1.0], force_vector(p), [0])


def test_a_fallback_is_recorded_per_line_and_kept_by_the_store(lumped, tmp_path,
                                                                monkeypatch):
    """Newton from the secant prediction refused at one drawn line (a stand-in for a
    failed corrector): that line, and no other, records how it was reached
    (fe.newton_path._recover); the store keeps it and the report line names it."""
    import fe.harmonic_balance as hb
    from fe.newton_path import SteadyStateError

    p, s, m, bank = lumped
    camp = Campaign(np.arange(59.0, 64.01, 0.5), [2.0, 16.0], force_vector(p), [4, 5])
    line = int(np.random.default_rng(11).integers(1, camp.frequency_hz.size))
    newton, calls = hb.damped_newton, [0]

    def refuse_once(*args, **kwargs):
        calls[0] += 1
        if calls[0] == line + 1:             # serial: level 1, one call per line
            raise SteadyStateError("", "refused by the test")
        return newton(*args, **kwargs)

    monkeypatch.setattr(hb, "damped_newton", refuse_once)
    res = run_campaign(m, bank, camp, store=tmp_path / "s", progress=False)
    hit = np.argwhere(res.fallbacks != "")
    assert hit.tolist() == [[0, line]]
    assert res.fallbacks[0, line] == "previous line as the guess (refused by the test)"
    assert res.fallback_lines() == [
        f"level 1 (F = 2 N): 1 of 11 lines, first at {camp.frequency_hz[line]:g} Hz: "
        "previous line as the guess (refused by the test)"]
    monkeypatch.setattr(hb, "damped_newton", newton)
    again = run_campaign(m, bank, camp, store=tmp_path / "s", progress=False)
    assert not again.computed.any()
    np.testing.assert_array_equal(again.fallbacks, res.fallbacks)
