"""Modal identification from FRFs (ident.identify) and ``iwanfe identify``.

Truth: FRFs of linear modal systems with proportional viscous damping,
``H_p(w) = sum_r phi_pr phi_0r / (w_r^2 - w^2 + 2 i zeta_r w_r w)`` (receptance, drive
point 0), whose parameters are drawn from seeds the identifier never sees. Noise:
circular complex Gaussian, standard deviation 1 % of |H| at each line. The statistical
limit is the Cramer-Rao bound of the same model, computed here independently (Fisher
information of poles, residues and residual terms, analytic Jacobian).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli.main import main
from ident.frf_files import FRFSet, write_frf
from ident.identify import identify, identify_modes
from ident.measured import read_measured
from ident.poles import mac
from ident.tracking import match_modes, modal_data_from_levels

FREQ = np.arange(20.0, 500.0 + 1e-9, 0.5)        # 0.5 Hz lines


def draw_system(seed, n_points):
    """3 modes in 50-450 Hz (>= 15 % apart), zeta 0.5-5 %, shapes of a drive point
    exciting every mode (|phi_0r| >= 0.6) and responses |phi_pr| in [0.3, 1]."""
    rng = np.random.default_rng(seed)
    while True:
        fn = np.sort(rng.uniform(50.0, 450.0, 3))
        if np.all(fn[1:] / fn[:-1] > 1.15):
            break
    zeta = rng.uniform(0.005, 0.05, 3)
    phi = rng.uniform(0.3, 1.0, (n_points, 3)) * rng.choice([-1.0, 1.0], (n_points, 3))
    phi[0] = rng.uniform(0.6, 1.0, 3)
    return fn, zeta, phi


def receptance(fn, zeta, phi, f):
    w = 2 * np.pi * np.asarray(f)[:, None]
    wn = 2 * np.pi * fn
    return np.einsum("pr,r,kr->kp", phi, phi[0], 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w))


def add_noise(H, level, seed):
    rng = np.random.default_rng(seed)
    n = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    return H * (1.0 + level * n)


def cramer_rao(fn, zeta, phi, f, noise):
    """Standard deviations (relative) of natural frequency and damping ratio.

    Model per point p: sum_r A_pr/(iw - l_r) + conj(A_pr)/(iw - conj l_r) + U_p + L_p/w^2
    (U, L complex); parameters sigma_r, wd_r (l = -sigma + i wd), Re/Im A_pr, U_p, L_p;
    noise variance (noise |H|)^2 / 2 per real component."""
    w = 2 * np.pi * f
    wn = 2 * np.pi * fn
    sig, wd = zeta * wn, wn * np.sqrt(1 - zeta**2)
    lam = -sig + 1j * wd
    A = phi * phi[0] / (2j * wd)                              # receptance residues
    P, m = A.shape
    H = receptance(fn, zeta, phi, f)
    iw = 1j * w[:, None, None]
    d1, d2 = 1 / (iw - lam) ** 2, 1 / (iw - lam.conj()) ** 2   # (K, 1, m)
    cols = [-(A * d1 + A.conj() * d2), 1j * (A * d1 - A.conj() * d2)]   # d/dsigma, d/dwd
    J = [c for c in cols]                                      # each (K, P, m)
    blocks = []
    for p in range(P):
        b = np.zeros((w.size, P, 2 * m + 4), complex)
        b[:, p, :m] = 1 / (1j * w[:, None] - lam) + 1 / (1j * w[:, None] - lam.conj())
        b[:, p, m:2 * m] = 1j * (1 / (1j * w[:, None] - lam) - 1 / (1j * w[:, None] - lam.conj()))
        b[:, p, 2 * m:] = np.stack([np.ones_like(w), 1j * np.ones_like(w), 1 / w**2,
                                    1j / w**2], axis=1)
        blocks.append(b)
    Jc = np.concatenate(J + blocks, axis=2)                    # (K, P, n_par)
    s = noise * np.abs(H)[:, :, None] / np.sqrt(2)
    Jr = np.concatenate([(Jc.real / s).reshape(-1, Jc.shape[2]),
                         (Jc.imag / s).reshape(-1, Jc.shape[2])])
    c = np.linalg.norm(Jr, axis=0)
    C = np.linalg.inv((Jr / c).T @ (Jr / c)) / np.outer(c, c)
    g = np.zeros((m, C.shape[0]))
    h = np.zeros((m, C.shape[0]))
    r = np.arange(m)
    g[r, r], g[r, m + r] = sig / wn, wd / wn                     # d wn
    h[r, r], h[r, m + r] = 1 / wn - sig**2 / wn**3, -sig * wd / wn**3   # d zeta
    sd_f = np.sqrt(np.einsum("ri,ij,rj->r", g, C, g)) / wn
    sd_z = np.sqrt(np.einsum("ri,ij,rj->r", h, C, h)) / zeta
    return sd_f, sd_z


def errors(modes, fn, zeta):
    assert len(modes) == fn.size, [m.frequency_hz for m in modes]
    f = np.array([m.frequency_hz for m in modes])
    z = np.array([m.zeta for m in modes])
    return f / fn - 1.0, z / zeta - 1.0


# ------------------------------------------------------------------ acceptance

@pytest.mark.parametrize("seed", [11, 12, 13])
def test_three_modes_several_points(seed):
    fn, zeta, phi = draw_system(seed, n_points=6)
    H = add_noise(receptance(fn, zeta, phi, FREQ), 0.01, seed + 1000)
    modes = identify_modes(FREQ, H)                      # no manual choice at all
    ef, ez = errors(modes, fn, zeta)
    sd_f, sd_z = cramer_rao(fn, zeta, phi, FREQ, 0.01)
    assert np.all(np.abs(ef) < 1e-4), ef                 # 0.01 %
    assert np.all(np.abs(ez) < 0.02), ez                 # 2 %
    assert np.all(np.abs(ef) < 4.5 * sd_f) and np.all(np.abs(ez) < 4.5 * sd_z)
    # shapes: residues of receptance, phi_p phi_0 / (2 i w_d)
    true = phi * phi[0] / (2j * 2 * np.pi * fn * np.sqrt(1 - zeta**2))
    got = np.stack([m.shape for m in modes], axis=1)
    np.testing.assert_allclose(np.diag(mac(got, true)), 1.0, atol=2e-3)
    np.testing.assert_allclose(np.abs(got), np.abs(true), rtol=0.03)
    np.testing.assert_allclose([m.omega2 for m in modes],
                               (2 * np.pi * np.array([m.frequency_hz for m in modes])) ** 2)


@pytest.mark.parametrize("seed", [21, 22])
def test_three_modes_single_point(seed):
    """Drive-point FRF only. The Cramer-Rao bound of the frequency is 2e-5 to 2e-4 for
    these modes, so 0.01 % cannot be promised; the estimate must be efficient."""
    fn, zeta, phi = draw_system(seed, n_points=1)
    H = add_noise(receptance(fn, zeta, phi, FREQ), 0.01, seed + 1000)
    ef, ez = errors(identify_modes(FREQ, H[:, 0]), fn, zeta)
    sd_f, sd_z = cramer_rao(fn, zeta, phi, FREQ, 0.01)
    assert np.all(np.abs(ef) < np.maximum(1e-4, 4.5 * sd_f)), (ef, sd_f)
    assert np.all(np.abs(ez) < 0.02), ez
    assert np.all(np.abs(ez) < 4.5 * sd_z)


def test_noise_free_is_exact_on_any_grid_and_quantity():
    fn, zeta, phi = draw_system(31, n_points=2)
    rng = np.random.default_rng(5)
    f = np.sort(rng.uniform(30.0, 480.0, 700))                         # stepped-sine-like
    H = receptance(fn, zeta, phi, f)
    w = 2 * np.pi * f[:, None]
    for quantity, data in [("receptance", H), ("mobility", 1j * w * H),
                           ("accelerance", -(w**2) * H)]:
        ef, ez = errors(identify_modes(f, data, quantity=quantity), fn, zeta)
        assert np.abs(ef).max() < 1e-9 and np.abs(ez).max() < 1e-7, quantity


def test_narrow_band_single_point_with_neighbours_outside():
    """One mode in a band of a few half-power widths; a mode 20 % below the band edge
    (whose tail U - L/w^2 cannot follow: the fixed out-of-band poles take it) and one
    above."""
    fn = np.array([82.9, 164.9, 422.2])
    zeta = np.array([0.034, 0.043, 0.049])
    phi = np.array([[0.8, 0.7, 0.9]])
    f = np.arange(100.0, 300.0, 0.5)
    H = add_noise(receptance(fn, zeta, phi, f), 0.01, 77)
    res = identify(f, H[:, 0])
    assert len(res.modes) == 1
    ef, ez = errors(res.modes, fn[1:2], zeta[1:2])
    assert abs(ef[0]) < 1e-4 and abs(ez[0]) < 0.02
    assert res.fit_error < 0.012                 # at the noise level (1 %)
    off = identify(f, H[:, 0], pseudo_modes=False)
    assert off.fit_error > 0.05                  # what the plain residual terms leave
    # a band of +-1 half-power width around the mode, noise-free: no room for
    # out-of-band terms (ident.refine.OUT_OF_BAND_ROOM), so U - L/w^2 stand for the
    # neighbours' tails. Their second-order term (band / distance)^2 of the tail is the
    # error: ~1e-4 in frequency, below a rig's 5e-4 repeatability; alone, the mode is exact
    wdth = 2 * zeta[1] * fn[1]
    g = np.linspace(fn[1] - wdth, fn[1] + wdth, 60)
    ef, ez = errors(identify_modes(g, receptance(fn, zeta, phi, g)[:, 0]), fn[1:2], zeta[1:2])
    assert 1e-6 < abs(ef[0]) < 1.5e-4 and abs(ez[0]) < 5e-4
    alone = receptance(fn[1:2], zeta[1:2], phi[:, 1:2], g)[:, 0]
    ef, ez = errors(identify_modes(g, alone), fn[1:2], zeta[1:2])
    assert abs(ef[0]) < 1e-10 and abs(ez[0]) < 1e-8


def test_n_modes_and_errors():
    fn, zeta, phi = draw_system(41, n_points=3)
    H = add_noise(receptance(fn, zeta, phi, FREQ), 0.01, 4)
    two = identify_modes(FREQ, H, band=(fn[0] * 0.8, fn[1] * 1.2), n_modes=2)
    ef, _ = errors(two, fn[:2], zeta[:2])
    assert np.all(np.abs(ef) < 1e-4)
    with pytest.raises(ValueError, match="at least 8"):
        identify_modes(FREQ, H, band=(100.0, 102.0))
    with pytest.raises(ValueError, match="lo < hi"):
        identify_modes(FREQ, H, band=(300.0, 100.0))
    with pytest.raises(ValueError, match="shape"):
        identify_modes(FREQ[:-1], H)
    with pytest.raises(ValueError, match="requested"):
        identify_modes(FREQ, H, band=(fn[0] * 0.9, fn[0] * 1.1), n_modes=40, max_order=6)


def test_diagram_marks_the_modes():
    fn, zeta, phi = draw_system(51, n_points=4)
    res = identify(FREQ, add_noise(receptance(fn, zeta, phi, FREQ), 0.01, 9))
    d = res.diagram
    np.testing.assert_allclose(d.selected_hz, fn, rtol=1e-4)
    for f0 in fn:   # fully stable poles near every mode at most orders above the 4th
        near = (np.abs(d.frequency_hz / f0 - 1) < 1e-3) & (d.status == 3)
        assert np.unique(d.order[near]).size >= 0.5 * d.order.max()


# ------------------------------------------------------------- several levels

def test_levels_matched_and_tabulated():
    fn, zeta, phi = draw_system(61, n_points=4)
    exc = np.array([4.0, 0.5, 2.0, 1.0, 8.0])            # run order != level order
    results = []
    for k, e in enumerate(exc):
        f2, z2 = fn.copy(), zeta.copy()
        f2[1] *= 1 - 2e-3 * e**0.5                       # softening mode 2
        z2[1] *= 1 + 0.1 * e**0.5
        H = add_noise(receptance(f2, z2, phi, FREQ), 0.005, 100 + k)
        results.append(identify_modes(FREQ, H))
    table = modal_data_from_levels(exc, results)
    np.testing.assert_array_equal(table.modes, [1, 2, 3])
    m2 = table.for_mode(2)
    np.testing.assert_array_equal(m2.excitation, np.sort(exc))
    np.testing.assert_array_equal(m2.run_order, np.argsort(exc) + 1)
    truth = fn[1] * (1 - 2e-3 * np.sort(exc) ** 0.5)
    np.testing.assert_allclose(np.sqrt(m2.omega2) / (2 * np.pi), truth, rtol=1e-4)
    assert np.all(np.diff(m2.zeta) > 0)
    assert np.nanmin(table.extra["x_mac"]) > 0.99
    # a mode missing at one level is matched by frequency, not by position
    assert match_modes(results[0], results[1][1:]) == [1, 2]


# ---------------------------------------------------------------------- CLI

def _write_set(path, f, H, excitation=None, quantity="receptance"):
    write_frf(path, FRFSet(f, H, [str(p + 1) for p in range(H.shape[1])], quantity,
                           excitation, "1"))


def test_cli_csv_and_uff_give_the_same_result(tmp_path, capsys):
    fn, zeta, phi = draw_system(71, n_points=3)
    H = add_noise(receptance(fn, zeta, phi, FREQ), 0.01, 3)
    _write_set(tmp_path / "s.csv", FREQ, H, 2.0)
    _write_set(tmp_path / "s.uff", FREQ, H, 2.0)
    out = {}
    for name in ("s.csv", "s.uff"):
        assert main(["identify", str(tmp_path / name), "--json"]) == 0
        out[name] = json.loads(capsys.readouterr().out)["sets"][0]
    a, b = out["s.csv"], out["s.uff"]
    assert a["excitation"] == b["excitation"] == 2.0
    assert len(a["modes"]) == len(b["modes"]) == 3
    for ma, mb in zip(a["modes"], b["modes"]):
        assert ma["frequency_hz"] == pytest.approx(mb["frequency_hz"], rel=1e-9)
        assert ma["zeta"] == pytest.approx(mb["zeta"], rel=1e-7)
    np.testing.assert_allclose([m["frequency_hz"] for m in a["modes"]], fn, rtol=1e-4)


def test_cli_levels_to_measured_data(tmp_path, capsys):
    fn, zeta, phi = draw_system(81, n_points=2)
    band = (fn[1] * 0.9, fn[1] * 1.1)
    files, exc = [], [1.0, 2.0, 4.0, 8.0]
    for k, e in enumerate(exc):
        f2, z2 = fn.copy(), zeta.copy()
        f2[1] *= 1 - 1e-3 * e
        z2[1] *= 1 + 0.05 * e
        p = tmp_path / f"level{k}.csv"
        _write_set(p, FREQ, add_noise(receptance(f2, z2, phi, FREQ), 0.003, k),
                   excitation=None if k == 2 else e)
        files.append(str(p))
    out = tmp_path / "modal.csv"
    png = tmp_path / "stab.png"
    # level 3 has no excitation in its file: refused, one line, exit 2
    assert main(["identify", *files, "--band", *map(str, band)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "level2.csv" in err and "--excitation" in err
    assert main(["identify", *files, "--excitation", "1", "2"]) == 2
    assert "one value per FILE" in capsys.readouterr().err
    rc = main(["identify", *files, "--band", *map(str, band), "--excitation", *map(str, exc),
               "--out", str(out), "--plot", str(png)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "modes across levels" in text
    data = read_measured(out)
    np.testing.assert_array_equal(data.level, [1, 2, 3, 4])
    np.testing.assert_array_equal(data.excitation, exc)
    np.testing.assert_allclose(np.sqrt(data.omega2) / (2 * np.pi),
                               fn[1] * (1 - 1e-3 * np.array(exc)), rtol=1e-4)
    np.testing.assert_allclose(data.zeta, zeta[1] * (1 + 0.05 * np.array(exc)), rtol=0.01)
    assert all((tmp_path / f"stab-{k}.png").stat().st_size > 10_000 for k in range(1, 5))


def test_cli_single_file_table(tmp_path, capsys):
    fn, zeta, phi = draw_system(91, n_points=1)
    H = add_noise(receptance(fn, zeta, phi, FREQ), 0.01, 1)
    _write_set(tmp_path / "one.csv", FREQ, H)
    assert main(["identify", str(tmp_path / "one.csv"), "--modes", "3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    rows = [ln.split() for ln in lines[2:5]]
    np.testing.assert_allclose([float(r[1]) for r in rows], fn, rtol=3e-4)
    np.testing.assert_allclose([float(r[3]) for r in rows], zeta, rtol=0.02)
    assert main(["identify", str(tmp_path / "missing.csv")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_the_identification_gives_the_same_numbers_whatever_the_callers_blas_threads(
        monkeypatch):
    """A force-controlled FRF deep in macro-slip (level 9 of the benchmark's series
    80092010, ``tests/data``): its refinement has two nearly equal optima, and without the
    one-thread guard two BLAS threads settle in the other one (72.6816 Hz against
    72.6797 Hz here). With the guard the caller's setting does not matter; inside the
    identification BLAS runs one thread."""
    from pathlib import Path

    from threadpoolctl import threadpool_info, threadpool_limits

    import ident.identify as ident_identify

    d = np.load(Path(__file__).parent / "data" / "distorted_force_controlled_frf.npz")
    seen = []
    inner = ident_identify.refine_selected

    def spy(*args, **kwargs):
        seen.append({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})
        return inner(*args, **kwargs)

    monkeypatch.setattr(ident_identify, "refine_selected", spy)
    out = {}
    for n in (1, 2):
        with threadpool_limits(limits=n, user_api="blas"):
            m = identify(d["freq_hz"], d["frf"], n_modes=1).modes[0]
        out[n] = (m.frequency_hz, m.zeta)
    assert out[1] == out[2]
    assert seen and all(s == {1} for s in seen)
