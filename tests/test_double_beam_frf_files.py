"""FRF files of the simulated double-beam campaign (cases.double_beam.files.
write_frf_files) through ``iwanfe identify``.

Truths: the campaign's own receptance (exact CSV round trip), the study's identification
of the same FRFs (simulated_measured.csv), and the drive voltages of the measured data.
"""
import numpy as np
import pytest

from cases.double_beam.files import write_report
from cases.double_beam.settings import DoubleBeamStudy
from cases.double_beam.study import run_study
from cli.main import main
from ident.frf_files import read_frf
from ident.identify import identify
from ident.measured import read_measured
from ident.tracking import agree_on_modes

COARSE = dict(df_hz=1.0, band_hz=(236.0, 268.0), sliders_per_octave=8, weak_joint_scales=())


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("double-beam")
    rep = run_study(DoubleBeamStudy(**COARSE), progress=False)
    write_report(rep, out)
    return rep, out


def test_frf_files_hold_the_campaign_receptance(written):
    rep, out = written
    files = sorted((out / "frf").glob("level_*.csv"))
    assert [f.name for f in files] == [f"level_{k:02d}.csv" for k in range(1, 11)]
    sets = [read_frf(f) for f in files]
    for i, s in enumerate(sets):
        assert s.quantity == "receptance" and s.points == ["acc1"]
        assert s.excitation == rep.measured.excitation[i]            # drive V
        assert np.array_equal(s.freq_hz, rep.campaign.frequency_hz)
        assert np.array_equal(s.frf[:, 0], rep.campaign.receptance[i, :, rep.response_dof])
    # the study's identification of the files (each level, then the levels agree on the
    # number of modes: level 10, in macro-slip, is otherwise fitted with two poles):
    # simulated_measured.csv, bit for bit
    band = rep.study.band_hz

    def fit(i, n_modes=None):
        return identify(sets[i].freq_hz, sets[i].frf[:, 0], band=band, n_modes=n_modes,
                        **rep.study.identify_options)

    results, notes = agree_on_modes([fit(i) for i in range(len(sets))], fit)
    assert [bool(n) for n in notes] == [False] * 9 + [True]
    for i, res in enumerate(results):
        m = min(res.modes, key=lambda m: abs(m.frequency_hz - 252.0))
        assert m.zeta == rep.simulated.zeta[i] and m.omega2 == rep.simulated.omega2[i]


def test_identify_command_on_the_frf_files_agrees_with_the_study(written, capsys):
    """``iwanfe identify frf/level_*.csv --band 236 268 --out modal.csv``: levels and drive
    voltages from the files; with identify's default options (noise weights, F-tested
    out-of-band terms) against the study's (uniform weights, none), omega2 within 2e-4
    and zeta within 3e-3 relative and 3 of the command's own zeta_std of
    simulated_measured.csv at the micro-slip levels 1-8 (measured 6.5e-6..1.4e-4 and
    7e-5..2.5e-3, 0.9-1.5 zeta_std: the options weigh the joint's distortion of these
    noise-free FRFs differently; level 10 is in macro-slip and its FRF is no modal
    model: 2 % in zeta)."""
    rep, out = written
    files = [str(f) for f in sorted((out / "frf").glob("level_*.csv"))]
    assert main(["identify", *files, "--band", "236", "268", "--out",
                 str(out / "modal.csv")]) == 0
    assert "wrote" in capsys.readouterr().out
    cli = read_measured(out / "modal.csv")
    sim = read_measured(out / "simulated_measured.csv")
    np.testing.assert_array_equal(cli.level, sim.level)
    np.testing.assert_array_equal(cli.excitation, sim.excitation)
    np.testing.assert_allclose(cli.omega2[:8], sim.omega2[:8], rtol=2e-4)
    np.testing.assert_allclose(cli.zeta[:8], sim.zeta[:8], rtol=3e-3)
    assert np.all(np.abs(cli.zeta[:8] - sim.zeta[:8]) < 3 * cli.zeta_std[:8])
    # the damping growth between levels survives: zeta increases level by level
    assert np.all(np.diff(cli.zeta) > 0)


def test_a_level_that_cannot_be_identified_again_keeps_its_modes():
    """Levels of 1, 1 and 2 well-separated modes: the third is identified again with
    one; when that identification fails (as a gen_dev case's level did: "2 mode(s)
    requested, 1 left after the refinement") the level keeps its own modes and its note
    says so, instead of the whole series failing."""
    from types import SimpleNamespace

    def mode(f):
        return SimpleNamespace(frequency_hz=f, zeta=0.001, shape=np.array([1.0]))

    levels = [SimpleNamespace(modes=[mode(100.0)]), SimpleNamespace(modes=[mode(100.1)]),
              SimpleNamespace(modes=[mode(100.2), mode(140.0)])]

    def refit(k, n):
        raise ValueError(f"{n} mode(s) requested, 0 left after the refinement")

    results, notes = agree_on_modes(levels, refit)
    assert results[2] is levels[2] and len(results[2].modes) == 2
    assert notes[:2] == [[], []] and "failed" in notes[2][0] and "kept" in notes[2][0]
    ok = SimpleNamespace(modes=[mode(100.2)])
    results, notes = agree_on_modes(levels, lambda k, n: ok)
    assert results[2] is ok and "identified with 1" in notes[2][0]
