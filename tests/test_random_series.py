"""Random-excitation series from their FRF files (``# test = random``): the response RMS
of a level, chi against a stepped-sine series of the same joint, the warning on a random
series given as stepped sine.

The random levels are built here from an SDOF with a seeded Iwan joint: at drive RMS
``e`` (flat over the file's lines) the response RMS ``sigma`` solves
``sigma^2 = e^2/df int |H_sigma|^2 df`` with ``H_sigma`` the linear FRF whose joint
stiffnesses are the Rayleigh expectations at ``sigma`` (inverse.random_amplitude, closed
form, checked against quadrature in test_random_amplitude.py); the integral is taken by
quadrature of that FRF, not through the identified modes.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import integrate

from cli.main import main
from frf_series_synth import planted_series
from ident.frf_files import FRFSet, write_frf
from ident.random_frf import mode_response_rms, random_signature
from ident.series import load_series
from inverse.estimate import estimate
from inverse.random_amplitude import rayleigh_micro_slip
from joints.describing import describing_function
from joints.iwan import IwanParameters


def test_mode_response_rms_against_the_closed_form():
    """Viscous SDOF: ``sigma = (e/m) sqrt(1 / (8 zeta w_n^3 df))`` for a flat drive over
    df Hz (int_0^inf |H|^2 dw = pi / (4 zeta w_n^3 m^2)); mobility: times w_n, to
    O(zeta)."""
    m, wn, zeta, e = 2.5, 2 * np.pi * 31.0, 0.004, 0.7
    wd = wn * np.sqrt(1 - zeta ** 2)
    mode = SimpleNamespace(pole=complex(-zeta * wn, wd), shape=np.array([1 / (2j * m * wd)]))
    freq = np.linspace(20.0, 45.0, 501)
    sigma = mode_response_rms(mode, 0, "receptance", freq, e)
    assert sigma == pytest.approx(e / m * np.sqrt(1 / (8 * zeta * wn ** 3 * 25.0)), rel=1e-8)
    assert mode_response_rms(mode, 0, "mobility", freq, e) == pytest.approx(sigma * wn,
                                                                             rel=2 * zeta)


def _joint_sdof(seed):
    rng = np.random.default_rng(seed)
    p = IwanParameters(chi=-rng.uniform(0.2, 0.8), K_T=rng.uniform(5e4, 2e5),
                       F_S=rng.uniform(50, 200), beta=rng.uniform(0.5, 3))
    f0 = rng.uniform(15, 40)
    k0 = p.K_T * rng.uniform(2, 5)
    m = (k0 + p.K_T) / (2 * np.pi * f0) ** 2
    c = 2 * 0.002 * np.sqrt((k0 + p.K_T) * m)
    return p, f0, k0, m, c


def _frf(k0, m, c, law, f):
    k_in, k_q = law
    w = 2 * np.pi * f
    return 1.0 / (k0 + k_in - m * w ** 2 + 1j * (c * w + k_q))


def random_levels(p, f0, k0, m, c, drive_rms, freq, rng, noise=2e-3):
    """(sigma, noisy H1) per level (module doc); noise uniform across lines."""
    df = freq[-1] - freq[0]
    out = []
    for e in drive_rms:
        sigma = 1e-3 * p.phi_max
        for _ in range(200):
            law = rayleigh_micro_slip(p, sigma)
            f_res = np.sqrt((k0 + law[0]) / m) / (2 * np.pi)
            hw = (c * 2 * np.pi * f_res + law[1]) / (8 * np.pi ** 2 * m * f_res)  # half width
            h2 = integrate.quad(     # f = f_res + hw tan(th): the peak spread over th
                lambda th: abs(_frf(k0, m, c, law, f_res + hw * np.tan(th))) ** 2
                * hw / np.cos(th) ** 2, np.arctan(-0.5 * f_res / hw), np.pi / 2,
                limit=400, epsrel=1e-11)[0] + integrate.quad(
                lambda f: abs(_frf(k0, m, c, law, f)) ** 2, 0, 0.5 * f_res, epsrel=1e-11)[0]
            new = e * np.sqrt(h2 / df)
            if abs(new / sigma - 1) < 1e-12:
                break
            sigma = new
        H = _frf(k0, m, c, rayleigh_micro_slip(p, sigma), freq)
        n = (rng.standard_normal(H.size) + 1j * rng.standard_normal(H.size)) / np.sqrt(2)
        out.append((sigma, H + noise * np.abs(H).max() * n))
    return out


@pytest.fixture(scope="module")
def random_series(tmp_path_factory):
    p, f0, k0, m, c = _joint_sdof(13)
    rng = np.random.default_rng(14)
    freq = np.linspace(0.75 * f0, 1.25 * f0, 161)
    drive = np.geomspace(1.0, 1.0e3, 7) * 1e-3 * p.phi_max * (k0 + p.K_T) * 0.01
    levels = random_levels(p, f0, k0, m, c, drive, freq, rng)
    root = tmp_path_factory.mktemp("random")
    paths, bare = [], []
    for k, (e, (_, H)) in enumerate(zip(drive, levels)):
        for test, target in (("random", paths), (None, bare)):
            path = root / f"{test or 'bare'}_{k + 1}.csv"
            write_frf(path, FRFSet(freq, H, ["1"], "receptance", e, "1", control="force",
                                   run_order=k + 1, test=test))
            target.append(str(path))
    return dict(p=p, f0=f0, k0=k0, m=m, c=c, sigma=np.array([s for s, _ in levels]),
                paths=paths, bare=bare)


def test_random_series_identified_with_its_response_rms(random_series):
    data = load_series(random_series["paths"], band=None, n_modes=1)
    assert set(data.test) == {"random"} and data.response_abscissa
    np.testing.assert_allclose(data.response_amplitude, random_series["sigma"], rtol=0.02)
    assert not any("given as stepped sine" in w for w in data.warnings)


def test_chi_from_random_and_from_stepped_sine_series_of_one_joint_agree(random_series):
    """Random series of the joint (RMS abscissa, Rayleigh law) and a response-controlled
    stepped sine of the same joint (describing function at A_v = sigma_v): chi within
    0.05 of each other and of the planted chi."""
    s = random_series
    rand = estimate(load_series(s["paths"], n_modes=1), method="exact")
    amps = s["sigma"]
    k_in, k_q = describing_function(s["p"], amps)
    om2 = (s["k0"] + k_in) / s["m"]
    zeta = (s["c"] * np.sqrt(om2) + k_q) / (2 * s["m"] * om2)
    from ident.modal_data import MeasuredData
    n = amps.size
    sine = estimate(MeasuredData(level=np.arange(1, n + 1), excitation=np.ones(n),
                                 omega2=om2, zeta=zeta, mode=None, run_order=None,
                                 response_amplitude=amps, control=np.full(n, "response")),
                    method="exact")
    assert rand.test == "random" and rand.rayleigh_factor is not None
    assert rand.chi == pytest.approx(sine.chi, abs=0.05)
    assert rand.chi == pytest.approx(s["p"].chi, abs=0.05)


def test_random_series_given_as_stepped_sine_gets_one_warning_line(random_series):
    bare = load_series(random_series["bare"], n_modes=1)
    assert set(bare.test) == {"stepped-sine"}
    hits = [w for w in bare.warnings if "given as stepped sine" in w]
    assert len(hits) == 1 and "\n" not in hits[0]           # one line for the series
    assert f"{len(random_series['bare'])} of {len(random_series['bare'])} levels" in hits[0]
    assert "line-to-line noise uniform" in hits[0]
    assert all("given as stepped sine" in w for w in bare.extra["x_warning"])  # per level


def test_stepped_sine_series_with_relative_noise_gets_no_random_warning(tmp_path):
    paths = planted_series(tmp_path, [20.0, 19.98, 19.95, 19.9, 19.84],
                           [0.01, 0.011, 0.012, 0.0135, 0.015], [1.0, 2, 4, 8, 16],
                           control="force", seed=3)
    data = load_series(paths, n_modes=1)
    assert not any("given as stepped sine" in w for w in data.warnings)
    assert random_signature(np.linspace(1, 2, 40), np.ones((40, 1))) is None


def test_cli_test_option_overrides_the_files(random_series, capsys):
    assert main(["estimate", *random_series["bare"], "--modes", "1", "--test", "random",
                 "--json"]) == 0
    import json
    out = json.loads(capsys.readouterr().out)
    assert out["test"] == "random" and out["rayleigh_factor"] > 1
    with pytest.raises(SystemExit) as exc:
        main(["estimate", *random_series["bare"], "--test", "white"])
    assert exc.value.code == 2


def test_coherence_column_round_trips_and_names_a_random_test(random_series, tmp_path):
    """A level file with a coherence column (an averaged estimate) given as stepped sine:
    the warning says so; CSV keeps the column exactly; out-of-range values are refused."""
    from ident.frf_files import read_frf
    paths = []
    for k, p in enumerate(random_series["bare"]):
        s = read_frf(p)
        s.coherence = np.linspace(0.5, 0.99, s.freq_hz.size)
        paths.append(tmp_path / f"coh_{k}.csv")
        write_frf(paths[-1], s)
    back = read_frf(paths[0])
    np.testing.assert_array_equal(back.coherence, np.linspace(0.5, 0.99, back.freq_hz.size))
    data = load_series(paths, n_modes=1)
    assert sum("coherence column" in w for w in data.warnings) == 1      # the series' line
    assert all("coherence column" in w for w in data.extra["x_warning"])  # every level
    text = paths[0].read_text().splitlines()
    head = text.index(next(t for t in text if t.startswith("freq_hz")))
    row = text[head + 1].split(",")
    row[-1] = "1.5"
    text[head + 1] = ",".join(row)
    paths[0].write_text("\n".join(text) + "\n")
    with pytest.raises(ValueError, match="coherence must be in"):
        read_frf(paths[0])


def test_mode_response_rms_from_the_drive_spectrum_against_the_time_domain_rms():
    """A shaker's force drop at resonance (a notch of seeded depth and width in the drive
    spectrum, which the code never sees) under a linear SDOF: the response RMS from the
    file's ``force_psd`` (Welch G_ff at the lines) and the mode's FRF matches the RMS of
    the response in time (circular convolution of the drawn drive: exact), while the flat
    drive assumption (eq. 1) misses it by the notch."""
    from scipy import signal
    rng = np.random.default_rng(4141)
    m, f0, zeta = 1.7, rng.uniform(40.0, 80.0), rng.uniform(0.004, 0.008)
    depth, width = rng.uniform(0.4, 0.7), rng.uniform(1.0, 3.0)       # notch, Hz
    wn = 2 * np.pi * f0
    fs, T = 8 * (f0 + 30.0), 200.0
    n = int(fs * T)
    freq = np.fft.rfftfreq(n, 1 / fs)
    band = (freq > f0 - 25.0) & (freq < f0 + 25.0)
    F = (rng.standard_normal(freq.size) + 1j * rng.standard_normal(freq.size)) * band
    F *= 1.0 - depth / (1.0 + ((freq - f0) / width) ** 2)
    H = 1.0 / (m * (wn ** 2 - (2 * np.pi * freq) ** 2) + 2j * zeta * wn * m * 2 * np.pi * freq)
    force, x = np.fft.irfft(F, n), np.fft.irfft(H * F, n)
    truth = np.sqrt(np.mean(x ** 2))
    lines, gff = signal.welch(force, fs=fs, window="hann", nperseg=int(fs / 0.1))
    keep = (lines > f0 - 24.0) & (lines < f0 + 24.0)
    wd = wn * np.sqrt(1 - zeta ** 2)
    mode = SimpleNamespace(pole=complex(-zeta * wn, wd), shape=np.array([1 / (2j * m * wd)]))
    rms = np.sqrt(np.mean(force ** 2))
    by_psd = mode_response_rms(mode, 0, "receptance", lines[keep], rms, gff[keep])
    flat = mode_response_rms(mode, 0, "receptance", lines[keep], rms)
    assert by_psd == pytest.approx(truth, rel=0.03)        # measured 1.011
    assert flat / truth > 1.3                                # measured 1.73
    with pytest.raises(ValueError, match="drive_psd"):
        mode_response_rms(mode, 0, "receptance", lines[keep], rms, -gff[keep])


def test_force_psd_column_round_trips_and_sets_the_response_rms(random_series, tmp_path):
    """``force_psd`` in an FRF CSV: kept exactly, refused when <= 0, and a random level's
    ``response_amplitude`` follows it (a drive spectrum 4x the flat one: RMS 2x)."""
    from ident.frf_files import read_frf
    paths = []
    for k, p in enumerate(random_series["paths"]):
        s = read_frf(p)
        s.force_psd = np.full(s.freq_hz.size, 4.0 * s.excitation ** 2
                              / (s.freq_hz[-1] - s.freq_hz[0]))
        paths.append(tmp_path / f"psd_{k}.csv")
        write_frf(paths[-1], s)
    back = read_frf(paths[0])
    np.testing.assert_array_equal(back.force_psd, read_frf(paths[0]).force_psd)
    assert back.force_psd[0] == 4.0 * back.excitation ** 2 / (back.freq_hz[-1] - back.freq_hz[0])
    data = load_series(paths, n_modes=1)
    np.testing.assert_allclose(data.response_amplitude, 2 * random_series["sigma"], rtol=0.02)
    text = paths[0].read_text().splitlines()
    head = text.index(next(t for t in text if t.startswith("freq_hz")))
    row = text[head + 1].split(",")
    row[-1] = "0"
    text[head + 1] = ",".join(row)
    paths[0].write_text("\n".join(text) + "\n")
    with pytest.raises(ValueError, match="force_psd must be > 0"):
        read_frf(paths[0])
