"""The response-amplitude routes of the FE double beam (``DoubleBeamLevels`` with
``abscissa = response | random``, :mod:`fe.hb_response`) and ``update`` on free-decay,
response-controlled and random series.

Truth: the FE double beam with a planted joint (chi, strength, viscous damping; seeded
noise) simulated by other routes (``tests/fe_response_synth.py``): the EPMC backbone
(Krack 2015, its own Newton solver and normalization) for free-decay and
response-controlled rows; its energy-weighted Rayleigh expectation by adaptive quadrature
for random rows; and the force route (:func:`fe.hb_resonance.resonance_levels`) for the
closed loop at the forces it gives.
"""
from __future__ import annotations

import numpy as np
import pytest

import fe_response_synth as synth
from cases.double_beam.fe_levels import DoubleBeamLevels
from feloop.levels import abscissa_of
from fe.hb_resonance import resonance_levels
from fe.hb_response import BRACKETED, response_levels
from ident.measured import write_measured


def _planted_on(amplitudes, abscissa):
    """A levels model whose first level is the planted joint's reference amplitude, so
    that the planted parameters mean the planted joint."""
    ref, p, _ = synth.planted()
    amps = np.r_[synth.REFERENCE, amplitudes]
    fe = DoubleBeamLevels(np.full(amps.size, np.nan), np.arange(1, amps.size + 1),
                          ref.omega_1 ** 2, ref.zeta_1, abscissa=abscissa,
                          response_amplitude=amps)
    return fe, p


def test_held_response_gives_back_the_force_route_levels():
    """Closed loop: the response amplitudes the force route gives at 10 forces over 3
    decades (micro slip to macro slip), held, give back its omega^2, zeta and force.
    With two Newton steps on (ln w, ln F) instead of 8, more levels are left unsettled
    and go to the bracketed secant: each names it in ``fallbacks`` (as the 8-step path
    names its own), and the answer is the force route's all the same."""
    ref, p, j = synth.planted()
    lin = j["linear"]
    _, red, scale, _, _ = ref.setup(p)
    forces = np.geomspace(1e-4, 0.3, 10)
    f = resonance_levels(red, j["params"], lin.load, forces, lin.k, scale=scale[0])
    held = np.abs(f.q @ lin.response_row)
    r = response_levels(red, j["params"], lin.load, held, lin.response_row, lin.k,
                        scale=scale[0])
    assert f.slip_amplitude.max() / j["phi_max"] > 3.0          # reaches macro slip
    np.testing.assert_allclose(r.omega2, f.omega2, rtol=1e-12)
    np.testing.assert_allclose(r.zeta, f.zeta, rtol=1e-8)
    np.testing.assert_allclose(r.force, forces, rtol=1e-8)
    np.testing.assert_allclose(np.abs(r.response), held, rtol=1e-9)
    short = response_levels(red, j["params"], lin.load, held, lin.response_row, lin.k,
                            scale=scale[0], max_steps=2)
    np.testing.assert_allclose(short.omega2, f.omega2, rtol=1e-10)
    np.testing.assert_allclose(short.force, forces, rtol=1e-7)
    took = {n: np.array([BRACKETED in w for w in x.fallbacks]) for n, x in ((8, r), (2, short))}
    assert took[2].sum() > took[8].sum() and not took[2].all()
    assert np.all(took[2] | ~took[8])      # what 8 steps could not settle, 2 could not


def test_response_route_is_the_epmc_backbone():
    """At the held amplitudes of the planted series (glue slip 1 % to 45 % of phi_max)
    the response route is the EPMC backbone: frequency within 1e-6, zeta within 0.1 %
    (measured 1.5e-7 and 0.02 %; single-nonlinear-mode theory, not an identity)."""
    fe, p = _planted_on(synth.AMPLITUDES, "response")
    pred = fe.predict(p)
    bb = synth.backbone(synth.AMPLITUDES)
    assert np.abs(np.sqrt(pred.omega2[1:] / bb.omega2) - 1).max() < 1e-6
    assert np.abs(pred.zeta[1:] / bb.zeta - 1).max() < 1e-3
    assert bb.zeta[-1] > 2.5 * bb.zeta[0]                      # the joint is seen


def test_random_route_is_the_rayleigh_expectation_of_the_backbone():
    """Random levels (response RMS a third of the held amplitudes): the Gauss-Laguerre
    expectation of the route against adaptive quadrature over the EPMC backbone:
    omega^2 within 2e-6, zeta within 0.1 % (measured 7e-7 and 0.036 %)."""
    rms = synth.AMPLITUDES / 3
    fe, p = _planted_on(rms, "random")
    pred = fe.predict(p)
    o2, z = synth.rayleigh_truth(rms)
    assert np.abs(pred.omega2[1:] / o2 - 1).max() < 2e-6
    assert np.abs(pred.zeta[1:] / z - 1).max() < 1e-3


def test_route_of_a_series_and_one_line_for_what_has_none():
    from feloop.case_levels import CaseLevels

    fd = synth.series("free-decay", amplitudes=synth.AMPLITUDES[:5] + 0)
    assert abscissa_of(fd) == "response"
    with pytest.raises(ValueError, match="response rows are not supported"):
        CaseLevels.from_data(fd)             # the case-file loop: force control only
    fd.control[:] = "response"
    fd.test[:] = "stepped-sine"
    assert abscissa_of(fd) == "response"
    fd.control[0] = "force"
    with pytest.raises(ValueError, match="mixed control"):
        abscissa_of(fd)
    fd.test[0] = "random"
    with pytest.raises(ValueError, match="one test type"):
        abscissa_of(fd)


@pytest.mark.slow
def test_update_recovers_chi_from_a_free_decay_series(tmp_path, capsys):
    """``iwanfe update --case double-beam --data decay.csv``: the planted chi -0.45 is
    recovered within 0.05 (measured -0.474, 95 % interval -0.529 .. -0.419 holding it),
    no cause named, no failed simulation."""
    import json

    from cli.main import main

    path = tmp_path / "decay.csv"
    write_measured(path, synth.series("free-decay"))
    assert main(["update", "--case", "double-beam", "--data", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    chi = out["parameters"]["chi"]
    assert abs(chi["value"] - synth.CHI) < 0.05
    assert chi["interval"][0] < synth.CHI < chi["interval"][1]
    assert out["cause"] == "none" and out["failed_simulations"] == 0


@pytest.mark.slow
def test_update_recovers_chi_from_a_random_series(tmp_path):
    """A random series (response RMS a third of every other free-decay amplitude, 5
    levels over the same range): the base fit of ``update`` recovers chi within 0.05 of
    the planted -0.45 through the Rayleigh route (measured -0.454; the base fit alone,
    18 s of CPU; on 7 levels 46 s; the whole command, extensions and their
    cross-validation included, which the free-decay test above runs, took 80 s)."""
    from feloop.select import fe_select
    from feloop.update import UpdateSettings, load_levels

    path = tmp_path / "random.csv"
    write_measured(path, synth.series("random", amplitudes=synth.AMPLITUDES[::2] / 3))
    data, mask = load_levels(UpdateSettings(data_path=str(path), fit_levels="1-5"))
    base = fe_select(data, mask, DoubleBeamLevels.from_data(data), causes=())["base"]
    assert abs(base.fit.values["chi"] - synth.CHI) < 0.05
    assert base.fit.failed_simulations == 0
