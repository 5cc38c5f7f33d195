"""Random excitation, simulated (runs.random_test, cases.random_series), identified as a
measured random series and fed to the estimator: chi of a seeded joint recovered, the
Rayleigh-expectation model against the simulation, chi against a stepped sine."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cases.random_series import (RandomSeries, sdof_iwan, sdof_rayleigh_prediction,
                                 simulate_random_series)
from joints.iwan import IwanParameters
from runs.random_test import band_limited_noise, h1_estimate

K_LIN, MASS, ZETA = 9e5, 1.0, 0.005


def test_band_limited_noise_and_h1_of_a_linear_filter():
    dt = 1e-3
    e = band_limited_noise(200_000, dt, (50.0, 150.0), 2.5, seed=3)
    assert np.sqrt(np.mean(e ** 2)) == pytest.approx(2.5, rel=1e-12)
    spec = np.abs(np.fft.rfft(e)) ** 2
    f = np.fft.rfftfreq(e.size, dt)
    assert spec[(f < 45) | (f > 155)].sum() < 1e-6 * spec.sum()
    # H1 of a known FIR filter: y = e - 0.5 e(-1) -> H = 1 - 0.5 exp(-i w dt) (Welch's
    # bias for a delay of one sample in a segment of 4096: ~1/4096)
    y = e - 0.5 * np.concatenate([[0.0], e[:-1]])
    fr, H, coh, n_avg = h1_estimate(e, y[:, None], 1 / dt, 4096)
    band = (fr > 60) & (fr < 140)
    np.testing.assert_allclose(H[band, 0], 1 - 0.5 * np.exp(-2j * np.pi * fr[band] * dt),
                               rtol=1e-3)
    assert coh[band].min() > 0.999999 and n_avg > 90


@pytest.fixture(scope="module")
def seeded_joint():
    """A joint whose chi the estimator never sees (seeded draw)."""
    chi = float(np.random.default_rng(2121).uniform(-0.75, -0.25))
    return IwanParameters(chi=chi, K_T=1e5, F_S=100.0, beta=0.5)


def _drive_rms(joint, slip_rms, band_width):
    """Drive RMS (N) whose linear response has the slip RMS ``slip_rms`` (m): white
    drive of PSD RMS^2/B, sigma^2 = pi S(w) / (2 zeta w^3 m^2) per rad/s."""
    k = K_LIN + joint.K_T
    w = np.sqrt(k / MASS)
    per_newton = np.sqrt(np.pi / (2 * np.pi * band_width) / (2 * ZETA * w ** 3 * MASS ** 2))
    return np.asarray(slip_rms) / per_newton


@pytest.fixture(scope="module")
def random_series(seeded_joint, tmp_path_factory):
    """Five random levels of the seeded joint (slip RMS 0.4 % to 5.5 % of phi_max),
    simulated and identified from their FRF files as a measured series."""
    from ident.series import load_series

    joint = seeded_joint
    model, bank = sdof_iwan(joint, K_LIN, MASS, ZETA)
    w0 = model.omega[0]
    f0 = w0 / (2 * np.pi)
    B = 80.0
    rms = _drive_rms(joint, joint.phi_max * np.geomspace(0.006, 0.09, 5), B)
    series = RandomSeries(rms=tuple(rms), band_hz=(f0 - B / 2, f0 + B / 2), omega_ref=w0,
                          seed=11)
    out = tmp_path_factory.mktemp("random")
    paths = simulate_random_series(model, bank, np.ones(1), np.eye(1), ["1"], series, out)
    return model, bank, out, load_series(paths)


@pytest.mark.slow
def test_random_series_recovers_chi_and_agrees_with_the_rayleigh_model(seeded_joint,
                                                                       random_series):
    from inverse.estimate import estimate

    joint = seeded_joint
    model, bank, tmp_path, data = random_series
    assert set(data.test) == {"random"}
    est = estimate(data, method="amplitude")
    assert abs(est.chi - joint.chi) < 0.05
    # the Iwan model through the Rayleigh expectation at three RMS levels
    slip = np.array([json.loads((tmp_path / f"level_{k:02d}.json").read_text())["slip_rms_m"][0]
                     for k in (1, 3, 5)])
    pred = sdof_rayleigh_prediction(joint, K_LIN, MASS, float(model.C[0, 0]), slip)
    idx = np.array([0, 2, 4])
    assert np.abs(np.sqrt(data.omega2[idx] / pred["omega2"]) - 1).max() < 2e-4
    assert np.abs(data.zeta[idx] / pred["zeta"] - 1).max() < 0.01
    # the joint's share of the damping is seen, not only the dashpot's
    assert data.zeta[-1] - data.zeta[0] > 0.5 * (pred["zeta"][-1] - pred["zeta"][0])


@pytest.mark.slow
def test_chi_of_a_random_series_agrees_with_a_stepped_sine_of_the_same_joint(
        seeded_joint, random_series, tmp_path):
    """The same joint tested both ways, both identified from FRF files by the same
    route (ident.series.load_series -> inverse.estimate, amplitude method)."""
    from ident.frf_files import FRFSet, write_frf
    from ident.series import load_series
    from inverse.estimate import estimate
    from runs.campaign import Campaign, HBProtocol
    from runs.response_control import ResponseControlProtocol
    from runs.stepped_sine import run_campaign

    joint = seeded_joint
    model, bank = random_series[0], random_series[1]
    f0 = model.omega[0] / (2 * np.pi)
    # response-controlled stepped sine (each level holds one amplitude: the clean
    # stepped-sine route; force control adds the bias of cases.backbones) at slip
    # amplitudes spanning the random series' envelopes
    held = joint.phi_max * np.geomspace(0.012, 0.18, 5)
    lines = np.round(np.arange(f0 - 6.0, f0 + 4.0, 0.1), 6)
    proto = ResponseControlProtocol(0, "bank", HBProtocol().settings)
    res = run_campaign(model, bank, Campaign(lines, held, np.ones(1), [0], proto),
                       progress=False)
    paths = []
    for k, A in enumerate(held):
        p = tmp_path / "sine" / f"level_{k + 1:02d}.csv"
        p.parent.mkdir(exist_ok=True)
        write_frf(p, FRFSet(lines, res.receptance[k], ["1"], quantity="receptance",
                            excitation=float(A), reference="1", control="response"))
        paths.append(p)
    chi_sine = estimate(load_series(paths), method="amplitude").chi
    chi_random = estimate(random_series[3], method="amplitude").chi
    print(f"chi: true {joint.chi:.4f}, stepped sine {chi_sine:.4f}, random {chi_random:.4f}")
    assert abs(chi_sine - joint.chi) < 0.02
    assert abs(chi_random - chi_sine) < 0.05
