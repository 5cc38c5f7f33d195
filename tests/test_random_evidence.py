"""A series given without its test type whose files look random gets one warning line
with its numbers (ident.random_evidence); a stepped-sine series gets none.

The random levels are simulated in time (cases.random_series: band-limited Gaussian
drive, Newmark, Welch H1 and G_ff), with a number of Welch averages drawn from a seed the
detector never sees, and written without ``# test`` (and, for the drive-spectrum
evidence alone, without the coherence column). The stepped sines are the project's
synthetic series (tests/frf_series_synth.py: force column measured line by line).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from cases.random_series import RandomSeries, sdof_iwan, simulate_random_series
from cli.main import main
from frf_series_synth import planted_series
from ident.frf_files import read_frf, write_frf
from ident.random_evidence import AVERAGED_SCATTER, GIVEN_AS, random_evidence
from ident.series import load_series
from joints.iwan import IwanParameters


@pytest.fixture(scope="module")
def untyped_random(tmp_path_factory):
    """Four simulated random levels, written as plain FRF files: (with coherence, without)."""
    rng = np.random.default_rng(5151)
    joint = IwanParameters(chi=-0.4, K_T=8e4, F_S=150.0, beta=2.0)
    model, bank = sdof_iwan(joint, 6e5, 1.3, 0.006)
    w0 = float(model.omega[0])
    f0 = w0 / (2 * np.pi)
    averages = int(rng.integers(10, 40))              # unseen by the detector
    resolution = 0.2
    series = RandomSeries(rms=(0.5, 1.5, 4.5, 13.5), band_hz=(f0 - 30.0, f0 + 30.0),
                          omega_ref=w0, duration=(averages + 1) / (2 * resolution),
                          resolution_hz=resolution, seed=77)
    root = tmp_path_factory.mktemp("untyped")
    paths = simulate_random_series(model, bank, np.ones(1), np.eye(1), ["1"], series,
                                   root / "sim")
    with_coh, bare = [], []
    for p in paths:
        s = read_frf(p)
        s.test = None
        write_frf(root / f"coh_{p.name}", s)
        with_coh.append(str(root / f"coh_{p.name}"))
        s.coherence = None
        write_frf(root / f"bare_{p.name}", s)
        bare.append(str(root / f"bare_{p.name}"))
    return dict(with_coh=with_coh, bare=bare, averages=averages)


def _hits(warnings):
    return [w for w in warnings if GIVEN_AS in w]


def test_untyped_random_series_gets_one_line_from_its_drive_spectrum(untyped_random):
    data = load_series(untyped_random["bare"], n_modes=1)
    assert set(data.test) == {"stepped-sine"}          # identified as given
    hits = _hits(data.warnings)
    assert len(hits) == 1 and "\n" not in hits[0]
    assert "4 of 4 levels" in hits[0] and "force_psd flat over the band" in hits[0]
    assert all(GIVEN_AS in w for w in data.extra["x_warning"])     # kept per level
    for p in untyped_random["bare"]:
        ev = random_evidence(read_frf(p))
        assert ev.scatter > 4 * AVERAGED_SCATTER and ev.trend_db < 3.0     # margins
        # the averages the scatter implies, against the simulation's (seeded) count
        assert 0.5 < ev.averages / untyped_random["averages"] < 2.0


def test_untyped_random_series_with_coherence_names_its_numbers(untyped_random):
    data = load_series(untyped_random["with_coh"], n_modes=1)
    hits = _hits(data.warnings)
    assert len(hits) == 1 and "coherence column (median 0." in hits[0] and "min 0." in hits[0]


def test_warning_line_in_text_and_json_output(untyped_random, capsys):
    assert main(["estimate", *untyped_random["bare"], "--modes", "1"]) == 0
    text = capsys.readouterr().out
    assert sum(1 for line in text.splitlines()
               if line.startswith("warning: FRF series: " + GIVEN_AS)) == 1
    # identify reads the series through the same ident.series.load_series (25 s a run
    # here: the noisy levels' pole refinement), so estimate's JSON stands for both
    assert main(["estimate", *untyped_random["bare"], "--modes", "1", "--json"]) == 0
    assert len(_hits(json.loads(capsys.readouterr().out)["data_warnings"])) == 1


@pytest.mark.parametrize("control", ["force", "response"])
def test_stepped_sine_series_gets_no_random_warning(tmp_path, control):
    paths = planted_series(tmp_path, [20.0, 19.98, 19.95, 19.9, 19.84],
                           [0.01, 0.011, 0.012, 0.0135, 0.015], [1.0, 2, 4, 8, 16],
                           control=control, seed=8)
    data = load_series(paths, n_modes=1)
    assert not _hits(data.warnings)
    for p in paths:
        ev = random_evidence(read_frf(p))
        assert ev.spectrum == "force" and ev.scatter < AVERAGED_SCATTER / 4
        assert not ev.looks_random
