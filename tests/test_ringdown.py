"""Simulated free decay (runs.ringdown): time axis, energy balance, orbit start."""
from __future__ import annotations

import numpy as np
import pytest

from fe.epmc import solve_epmc
from fe.joint_harmonics import BankHarmonics
from fe.reduction import JointBank, ReducedModel
from joints.iwan import IwanParameters
from runs.ringdown import impulse_start, orbit_start, ring_down, warped_step


def sdof(K_T, k_lin, m, zeta):
    """Mass on a linear spring in parallel with a joint of stuck stiffness ``K_T``."""
    k = k_lin + K_T
    w = np.sqrt(k / m)
    return ReducedModel(basis=np.eye(1), omega=np.array([w]), M=np.array([[m]]),
                        K=np.array([[k]]), C=np.array([[2 * zeta * w * m]]), G=np.eye(1),
                        K_T=np.array([K_T]))


def crossings(t, x):
    """Upward zero crossings, linearly interpolated (s)."""
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    return t[i] + (t[i + 1] - t[i]) * x[i] / (x[i] - x[i + 1])


def test_linear_decay_rings_at_the_exact_frequency_on_the_warped_axis():
    zeta, m = 0.01, 2.0
    model = sdof(1e4, 3e5, m, zeta)
    bank = JointBank(np.array([[1e4]]), np.array([[1.0]]))     # never slips: linear
    w0 = model.omega[0]
    rec = ring_down(model, bank, impulse_start(model, bank, np.ones(1), 0.1), w0, 60,
                    np.eye(1), steps_per_period=32)
    x = rec.response[:, 0]
    tc = crossings(rec.time_s, x)
    wd = w0 * np.sqrt(1 - zeta ** 2)
    period = np.polyfit(np.arange(tc.size), tc, 1)[0]
    # 32 steps per period without the warp would be (2 pi/32)^2/12 = 3.2e-3 off
    assert abs(period * wd / (2 * np.pi) - 1) < 5e-5
    peaks = np.array([np.abs(x[(rec.time_s >= a) & (rec.time_s < b)]).max()
                      for a, b in zip(tc[:-1], tc[1:])])
    slope = np.polyfit(np.arange(peaks.size) * period, np.log(peaks), 1)[0]
    # damping ratio: multiplied by sin(2 pi/n)/(2 pi/n) (module docstring): 6.4e-3 at n=32
    assert -slope / w0 == pytest.approx(zeta * np.sin(2 * np.pi / 32) / (2 * np.pi / 32),
                                         rel=2e-3)


def iwan_sdof():
    p = IwanParameters(chi=-0.5, K_T=2e4, F_S=20.0, beta=1.0)
    model = sdof(p.K_T, 2e5, 1.0, 0.002)
    bank = JointBank.log_spaced([p], p.phi_max * 1e-4, 16)
    return p, model, bank


def test_energy_balance_of_a_decay_with_a_slipping_joint():
    """Energy-consistent with the joint hysteresis: what the decay loses is what the
    dashpot and the sliders dissipate, up to the scheme's O(dt^2) joint work in the
    steps where a slider starts to slip (halving dt quarters it)."""
    p, model, bank = iwan_sdof()
    w0 = model.omega[0]
    pt = solve_epmc(model, BankHarmonics(bank, (1, 3, 5, 7), 256), 1, 0.8 * p.phi_max)
    residual = {}
    for n in (64, 128):
        dt, _ = warped_step(w0, n)
        st = orbit_start(model, bank, pt.harmonics, pt.q[0], pt.omega[0], dt)
        rec = ring_down(model, bank, st, w0, 400, np.eye(1), steps_per_period=n,
                        chunk_cycles=37)
        e = rec.energy
        assert e.joint_dissipation > 0.2 * e.viscous > 0
        # the decay ends (nearly) at rest: the energy lost is the energy dissipated
        assert -(e.kinetic + e.strain + e.joint_stored) == pytest.approx(
            e.viscous + e.joint_dissipation, rel=2e-3)
        residual[n] = e.relative_residual
        assert rec.response.shape == (400 * n + 1, 1)
        np.testing.assert_allclose(rec.time_s[1], 2 * np.pi / (n * w0))
    assert residual[64] < 2e-3
    assert residual[128] < residual[64] / 3


def test_orbit_start_decays_like_the_backbone_sdof():
    """Envelope decay and zero-crossing frequency along the decay of an SDOF Iwan
    oscillator against its EPMC backbone (one mode: no band-pass needed)."""
    p, model, bank = iwan_sdof()
    w0 = model.omega[0]
    n = 128
    dt, _ = warped_step(w0, n)
    joints = BankHarmonics(bank, (1, 3, 5, 7, 9, 11), 512)
    a0 = 0.8 * p.phi_max
    pt = solve_epmc(model, joints, 1, a0)
    st = orbit_start(model, bank, pt.harmonics, pt.q[0], pt.omega[0], dt, 512)
    rec = ring_down(model, bank, st, w0, 150, np.eye(1), steps_per_period=n)
    t, x = rec.time_s, rec.response[:, 0]
    tc = crossings(t, x)
    # per cycle: mean amplitude (half peak to peak), frequency, log decrement
    pk = np.array([0.5 * np.ptp(x[(t >= a) & (t < b)]) for a, b in zip(tc[:-1], tc[1:])])
    per = np.diff(tc)
    mid = 0.5 * (tc[:-1] + tc[1:])
    k = np.arange(2, pk.size - 2)
    amp = pk[k]
    f = 1.0 / per[k]
    lnA = np.log(pk)
    decay = -(lnA[k + 1] - lnA[k - 1]) / (mid[k + 1] - mid[k - 1])
    zeta = decay / (2 * np.pi * f)
    win = (amp > 0.05 * a0) & (amp < 0.8 * a0)
    assert win.sum() > 20
    from fe.epmc import epmc_backbone

    bb = epmc_backbone(model, joints, 1, np.geomspace(0.04 * a0, 0.85 * a0, 30))
    ref = bb.at(amp[win])
    df = f[win] / (np.sqrt(ref["omega2"]) / (2 * np.pi)) - 1
    dz = zeta[win] / ref["zeta"] - 1
    assert np.abs(df).max() < 1e-4
    assert np.abs(dz).max() < 0.02


def test_sdof_decay_identified_like_a_measured_record():
    """The same SDOF decay (64 steps per period) through ident.free_decay (Hilbert,
    end effects trimmed): every row between 5 % and 80 % of the start against EPMC."""
    from ident.free_decay_table import identify_free_decay
    from ident.time_records import TimeRecord
    from fe.epmc import epmc_backbone

    p, model, bank = iwan_sdof()
    w0, n = model.omega[0], 64
    dt, _ = warped_step(w0, n)
    joints = BankHarmonics(bank, (1, 3, 5, 7), 256)
    a0 = 0.8 * p.phi_max
    pt = solve_epmc(model, joints, 1, a0)
    rec = ring_down(model, bank, orbit_start(model, bank, pt.harmonics, pt.q[0],
                                             pt.omega[0], dt), w0, 150, np.eye(1),
                    steps_per_period=n)
    x = rec.response[:, 0]
    end = np.flatnonzero(np.abs(x) >= 0.01 * np.abs(x).max())[-1] + 10 * n
    f0 = w0 / (2 * np.pi)
    res = identify_free_decay(TimeRecord(rec.time_s[:end], x[:end, None], ["1"]),
                              (0.7 * f0, 1.3 * f0), 16)
    h, start = res.hilbert, pt.dof_amplitude(0)[0]
    win = (h.amplitude > 0.05 * start) & (h.amplitude < 0.8 * start)
    assert win.sum() >= 10 and h.amplitude[win].min() < 0.07 * start
    ref = epmc_backbone(model, joints, 1, np.geomspace(0.04 * a0, 0.85 * a0, 30)).at(
        h.amplitude[win])
    assert np.abs(h.frequency_hz[win] / (np.sqrt(ref["omega2"]) / (2 * np.pi)) - 1).max() < 1e-4
    assert np.abs(h.zeta[win] / ref["zeta"] - 1).max() < 0.02
    # the joint carries most of the damping here: the test is not the dashpot's
    assert ref["zeta"].max() > 2 * 0.002


@pytest.fixture(scope="module")
def double_beam_mode4():
    from cases.ringdown_study import ringdown_case

    return ringdown_case("double-beam", 4)


def test_double_beam_decay_identified_back_against_the_backbone(double_beam_mode4, tmp_path):
    """Issue 21 acceptance: the FE double beam's mode 4 from its EPMC orbit at half
    phi_max, 150 cycles, identified by ident.free_decay; every row between 5 % and 80 %
    of the start amplitude (the compared rows bracket that window: one trimmed period
    at the start) within 1e-4 in frequency and 2 % in damping of the EPMC backbone
    (bank path)."""
    from cases.ringdown_routes import compare_ringdown, identify_record
    from cases.ringdown_study import RECORD_FILE, RingdownSettings, simulate_ringdown

    case = double_beam_mode4
    settings = RingdownSettings(mode=4, amplitude=0.5, cycles=150)
    rec, info = simulate_ringdown(case, settings, tmp_path)
    assert info["energy_J"]["relative_residual"] < 1e-4
    assert info["energy_J"]["joint_dissipation"] > 0
    ident = identify_record(tmp_path / RECORD_FILE, info["omega0_rad_s"] / (2 * np.pi))
    assert any("end effects trimmed" in n for n in ident["notes"])
    start = info["start"]["drive_amplitude_m"]
    cmp = compare_ringdown(case, ident, start, 0.05, 0.8, n_response=0, n_backbone=12)
    assert cmp["window"]["rows_in_window"] >= 6
    over = [r["over_start"] for r in cmp["rows"]]
    assert min(over) <= 0.05 and max(over) >= 0.8
    assert cmp["max_deviation"]["ringdown"]["frequency"] < 1e-4
    assert cmp["max_deviation"]["ringdown"]["zeta"] < 0.02
    assert cmp["met"]
    # the identified frequency falls with amplitude (softening joints) like the backbone
    f = np.array([r["frequency_hz"] for r in cmp["rows"]])
    assert np.all(np.diff(f) > 0)
    # a rerun with the same inputs reuses the stored record
    rec2, info2 = simulate_ringdown(case, settings, tmp_path)
    assert info2.get("loaded") and np.array_equal(rec2.response, rec.response)


def test_ringdown_command_rejects_bad_input_in_one_line(capsys):
    from cli.main import main

    assert main(["ringdown", "--case", "double-beam", "--mode", "4", "--amplitude",
                 "-1", "--out", "/tmp/unused-ringdown"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--amplitude" in err[0]
    assert main(["ringdown", "--case", "double-beam", "--mode", "4", "--window", "0.5",
                 "0.2"]) == 2
