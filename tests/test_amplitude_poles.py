"""The amplitude-dependent refit of a force-controlled level (ident.amplitude_poles)
against the backbone it was simulated from.

Truth: one mode of unit modal mass whose backbone is a closed form the code never sees,
``omega_n^2(a) = w0^2 (1 - kappa (a/a0)^p)``, ``zeta(a) = z0 + eta (a/a0)^q`` (p, q,
kappa, eta drawn from a seeded generator), driven at constant force: at every line the
steady amplitude solves ``a |omega_n^2(a) - w^2 + 2 i zeta(a) omega_n(a) w| = F``
(first harmonic), the receptance is ``1 / (that bracket)``. The reference is the backbone
at the peak of the amplitude curve, found on a line grid 50 times finer.
"""
import numpy as np
import pytest
from scipy.optimize import brentq

from frf_series_synth import rattle_series

from ident.frf_files import FRFSet
from ident.identify import identify
from ident.series import identify_level, identify_series
from ident.series_table import series_table


def _backbone(rng, strength):
    w0 = 2 * np.pi * rng.uniform(40.0, 400.0)
    law = dict(w0=w0, z0=rng.uniform(0.002, 0.006), p=rng.uniform(0.3, 1.2),
               q=rng.uniform(0.3, 1.2), a0=1e-5)
    law["kappa"] = strength * rng.uniform(0.5, 1.0) * 4 * law["z0"]    # drop ~ bandwidths
    law["eta"] = strength * rng.uniform(0.5, 1.5) * law["z0"]
    return law


def _at(law, a):
    s = a / law["a0"]
    return (law["w0"] ** 2 * (1 - law["kappa"] * s ** law["p"]),
            law["z0"] + law["eta"] * s ** law["q"])


def _amplitude(law, w, force):
    def g(la):
        w2, z = _at(law, np.exp(la))
        return np.exp(la) * abs(w2 - w**2 + 2j * z * np.sqrt(w2) * w) - force
    top = law["a0"] * min(100.0, (0.5 / max(law["kappa"], 1e-12)) ** (1 / law["p"]))
    return np.exp(brentq(g, np.log(1e-30), np.log(top)))


def _level(law, force, n_lines, noise, rng):
    """(freq_hz, receptance with noise, true peak amplitude)."""
    wr, zr = np.sqrt(_at(law, force / (2 * law["z0"] * law["w0"] ** 2))[0]), law["z0"]
    w = np.linspace(wr * (1 - 8 * zr), wr * (1 + 8 * zr), n_lines)
    a = np.array([_amplitude(law, x, force) for x in w])
    w2, z = _at(law, a)
    H = 1.0 / (w2 - w**2 + 2j * z * np.sqrt(w2) * w)
    H = H * (1 + noise * (rng.standard_normal(H.size) + 1j * rng.standard_normal(H.size))
             / np.sqrt(2))
    fine = np.linspace(w[0], w[-1], 50 * n_lines)
    peak = max(_amplitude(law, x, force) for x in fine[np.abs(fine - w[np.argmax(a)])
                                                      < 2 * (w[1] - w[0])])
    return w / (2 * np.pi), H, peak


def _set(f, H, force):
    return FRFSet(f, H[:, None], ["1"], quantity="receptance", excitation=force,
                  reference="1", source="level", control="force")


def _both_fits(seed, strength):
    """(law, true peak amplitude, refitted mode, linear mode) of one drawn level."""
    rng = np.random.default_rng(seed)
    law = _backbone(rng, strength)
    force = law["w0"] ** 2 * 2 * law["z0"] * law["a0"]
    f, H, peak = _level(law, force, 60, 2e-3, rng)
    new = identify_level(_set(f, H, force), "receptance", n_modes=1, amplitude=True).modes[0]
    return law, peak, new, identify(f, H, n_modes=1).modes[0]


@pytest.mark.parametrize("seed", [3, 11, 29])
def test_refit_recovers_the_backbone_at_the_peak(seed):
    law, peak, new, lin = _both_fits(seed, 3.0)
    w2, z = _at(law, peak)
    # the linear fit is biased by the amplitudes it averages over (the planted effect:
    # -0.9e-3 .. -2.3e-3 in omega2, +0.9 .. +3.6 % in zeta on these seeds; twice that
    # before the fixed out-of-band terms of session 19, whose free pseudo-modes took
    # part of the distortion)
    lin_w2, lin_z = lin.omega2 / w2 - 1, lin.zeta / z - 1
    assert abs(lin_w2) > 5e-4 and abs(lin_z) > 0.005
    # the refit: omega2 within 4 of its uncertainties and 0.4 of the linear bias; zeta
    # within 3 of its uncertainties and 1 % (the first-order damping law leaves ~1 %)
    assert abs(new.omega2 - w2) < 4 * new.omega2_std
    assert abs(new.omega2 / w2 - 1) < 0.4 * abs(lin_w2)
    assert abs(new.zeta / z - 1) < 0.6 * abs(lin_z)
    assert abs(new.zeta - z) < 3 * new.zeta_std + 0.01 * z
    assert new.response_at_peak == pytest.approx(peak, rel=0.005)
    # the slopes are the backbone's at the peak: d ln(omega^2)/d ln a, d ln zeta/d ln a
    s = peak / law["a0"]
    alpha = -law["p"] * law["kappa"] * s ** law["p"] / (1 - law["kappa"] * s ** law["p"])
    beta = law["q"] * law["eta"] * s ** law["q"] / z
    assert new.omega2_slope == pytest.approx(alpha, rel=0.5)     # a by-product: rough
    assert new.zeta_slope == pytest.approx(beta, rel=0.5)


def test_a_linear_level_keeps_its_linear_fit():
    """No amplitude dependence: the slopes do not pass the F-test, the linear fit stands
    (and it recovers the planted pole)."""
    for seed in (7, 8, 9):
        law, _, new, lin = _both_fits(seed, 0.0)
        assert new.omega2 == lin.omega2 and new.zeta == lin.zeta
        assert np.isnan(new.omega2_slope) and np.isnan(new.response_at_peak)
        assert abs(new.omega2 - law["w0"] ** 2) < 4 * new.omega2_std
        assert abs(new.zeta - law["z0"]) < 4 * new.zeta_std
    rng = np.random.default_rng(7)                   # and the level says so
    law = _backbone(rng, 0.0)
    force = law["w0"] ** 2 * 2 * law["z0"] * law["a0"]
    f, H, _ = _level(law, force, 60, 2e-3, rng)
    notes = identify_level(_set(f, H, force), "receptance", n_modes=1, amplitude=True).notes
    assert any("did not lower the misfit significantly" in n for n in notes), notes


def test_response_control_is_not_refitted_and_the_table_takes_the_peak_amplitude():
    rng = np.random.default_rng(5)
    law = _backbone(rng, strength=1.0)
    force = law["w0"] ** 2 * 2 * law["z0"] * law["a0"]
    f, H, peak = _level(law, force, 60, 2e-3, rng)
    held = FRFSet(f, H[:, None], ["1"], quantity="receptance", excitation=peak,
                  reference="1", source="level", control="response")
    same = identify_level(held, "receptance", n_modes=1, amplitude=True).modes[0]
    lin = identify(f, H, n_modes=1).modes[0]
    assert same.omega2 == lin.omega2 and np.isnan(same.response_at_peak)
    sets = []
    for k, scale in enumerate((0.5, 0.7, 1.0, 1.4)):
        fk, Hk, _ = _level(law, scale * force, 60, 2e-3, rng)
        s = _set(fk, Hk, scale * force)
        s.run_order = k + 1
        sets.append(s)
    fits = identify_series(sets, n_modes=1, check_band=False, amplitude_refit=True)
    table = series_table(fits)
    assert np.allclose(table.response_amplitude,
                       [fit.result.modes[0].response_at_peak for fit in fits])


def test_a_level_whose_band_holds_a_resonance_the_series_leaves_out_keeps_its_linear_fit(
        tmp_path):
    """The rattle of tests/test_series_identify.py (a second resonance 0.9 Hz away at one
    level, which the series identifies with one mode): with the refit that level keeps
    its linear fit and says why (the slopes took the rattle for an amplitude dependence,
    the pole 14 of its standard uncertainties off); the planted values come back."""
    from ident.series import read_series_sets

    paths, fn, _ = rattle_series(tmp_path)
    fits = identify_series(read_series_sets(paths), check_band=False, amplitude_refit=True)
    assert any("left out of this level's band: linear fit kept" in w
               for w in fits[2].warnings[0])
    d = series_table(fits)
    assert np.all(np.abs(d.omega2 - (2 * np.pi * fn) ** 2) < 4 * d.omega2_std)


def test_identify_says_which_levels_are_at_their_peak(tmp_path, capsys):
    """``iwanfe identify --amplitude-refit`` names the refitted levels; without the
    option the line is absent and the table's slopes are empty."""
    from cli.main import main
    from ident.frf_files import write_frf
    from ident.measured import read_measured

    rng = np.random.default_rng(3)
    law = _backbone(rng, 3.0)
    force = law["w0"] ** 2 * 2 * law["z0"] * law["a0"]
    paths = []
    for k, scale in enumerate((0.3, 0.5, 0.8, 1.2)):
        f, H, _ = _level(law, scale * force, 60, 2e-3, rng)
        paths.append(str(tmp_path / f"level_{k + 1}.csv"))
        write_frf(paths[-1], FRFSet(f, H[:, None], ["1"], quantity="receptance",
                                    excitation=scale * force, reference="1",
                                    control="force", run_order=k + 1))
    assert main(["identify", *paths, "--amplitude-refit", "--no-band-check",
                 "--out", str(tmp_path / "t.csv")]) == 0
    assert "peak amplitude (fitted with their slopes" in capsys.readouterr().out
    t = read_measured(str(tmp_path / "t.csv"))
    slopes = [float(v) if str(v).strip() else np.nan for v in t.extra["x_omega2_slope"]]
    assert np.sum(np.isfinite(slopes)) >= 3
    assert main(["identify", *paths, "--no-band-check"]) == 0
    assert "peak amplitude" not in capsys.readouterr().out
