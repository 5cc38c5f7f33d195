"""The independent series generator: it imports nothing of the diagnosis, its physics
against independent truth (the project's closed-form Iwan describing function,
textbook first harmonics, a planted repeatability), and the drawn series against
their design."""
from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from synthetic import (CATALOGUE, OUT_OF_CATALOGUE, generate_series, truth_of,
                                    without_stds)
from synthetic import mechanisms as mx
from synthetic.first_harmonic import SliderBank, first_harmonic, jenkins_loss
from synthetic.rig import Structure, solve_level
from ident.identify import identify
from joints.describing import describing_function
from joints.iwan import IwanParameters

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {p.name for p in ROOT.iterdir() if (p / "__init__.py").exists()}


def _project_imports(path: Path):
    """Project modules imported anywhere in ``path`` (function-level imports too)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                 [node.module] if isinstance(node, ast.ImportFrom) and node.module and
                 node.level == 0 else [])
        out |= {n for n in names if n.split(".")[0] in PACKAGES}
    return out


def _module_file(name: str):
    p = ROOT.joinpath(*name.split("."))
    for f in (p.with_suffix(".py"), p / "__init__.py"):
        if f.exists():
            return f
    return None          # a name imported from a package: its __init__ is listed


def test_generator_imports_nothing_from_inverse_transitively():
    todo = [f"synthetic.{p.stem}" if p.stem != "__init__" else
            "synthetic" for p in (ROOT / "synthetic").glob("*.py")]
    seen, chains = set(), {}
    while todo:
        mod = todo.pop()
        if mod in seen:
            continue
        seen.add(mod)
        f = _module_file(mod)
        if f is None:
            continue
        for imp in _project_imports(f):
            parts = imp.split(".")
            for k in range(1, len(parts) + 1):   # a package's __init__ runs too
                sub = ".".join(parts[:k])
                chains.setdefault(sub, mod)
                todo.append(sub)
    bad = sorted(m for m in seen if m.split(".")[0] == "inverse")
    assert not bad, [(m, chains[m]) for m in bad]
    assert "ident.series" in seen and "synthetic.rig" in seen   # the walk ran


# --------------------------------------------------------------------------- physics


@pytest.mark.parametrize("chi", [-0.85, -0.5, -0.15])
@pytest.mark.parametrize("x", [0.05, 0.6, 0.99, 1.7])
def test_slider_bank_equals_the_closed_form_iwan(chi, x):
    # micro- and macro-slip, no Dirac share: the project's incomplete-Beta closed form
    R, phi = 2e7, 1e-4
    joint = IwanParameters.from_density(R, chi, phi, 0.0)
    k_in, k_q = describing_function(joint, x * phi)
    dk, kq = SliderBank(R, chi, phi).loss(np.array([x * phi]))
    assert dk[0] == pytest.approx(joint.K_T - k_in, rel=2e-6)
    assert kq[0] == pytest.approx(k_q, rel=2e-6)
    assert SliderBank(R, chi, phi).stuck_stiffness == pytest.approx(joint.K_T, rel=1e-12)


def test_first_harmonics_against_textbook_values():
    X, W = np.array([0.3, 1.7]), 5.0
    k_in, k_q = first_harmonic(lambda x, v: 2.0 * x**3 + 0.4 * v, X, W)
    np.testing.assert_allclose(k_in, 0.75 * 2.0 * X**2, rtol=1e-12)     # Duffing 3/4
    np.testing.assert_allclose(k_q, 0.4 * W, rtol=1e-12)                 # viscous
    # Coulomb friction mu N sgn(v): dissipation 4 mu N X per cycle = pi X^2 k_q
    _, k_q = first_harmonic(lambda x, v: 0.2 * np.sign(v), X, W)
    np.testing.assert_allclose(k_q, 4 * 0.2 / (np.pi * X), rtol=1e-4)
    # Jenkins element: dissipation = loop area 4 phi (X - phi) (unit spring)
    u = np.array([0.1, 0.5, 0.9])
    _, q = jenkins_loss(u)
    np.testing.assert_allclose(np.pi * q, 4 * u * (1 - u), rtol=1e-14)
    assert jenkins_loss(1.0)[0] == pytest.approx(0.0, abs=1e-14)


def _structure(**kw):
    joint = SliderBank(8e6, -0.4, 1e-4)     # K_T 21 % of omega0^2
    return Structure(2 * np.pi * 80, 0.004, joint, **kw)


def test_force_control_balances_the_force_and_the_shaker_circuit():
    st = _structure(exciter=mx.ShakerImpedance(Bl=2.0, R_c=1.0, L=2e-4, m_a=0.05, k_a=100.0,
                                               c_a=0.3))
    run = mx.Run(1)
    W = st.omega0 * np.linspace(0.98, 1.01, 21)
    H, F, X, fold = solve_level(st, W, "force", 1e-3, run)
    assert not fold
    D = st.stiffness(X, W, run)
    # structure: D q = F; shaker: F = G V - i W Z q (q real by choice of phase)
    np.testing.assert_allclose(np.abs(D) * X, F, rtol=1e-12)
    np.testing.assert_allclose(np.abs(D + st.exciter.load(W)) * X,
                               np.abs(st.exciter.gain(1e-3, W)), rtol=1e-6)
    assert F.min() < 0.8 * np.abs(st.exciter.gain(1e-3, W)).max()   # drop-out at resonance


def test_noise_free_none_level_identifies_the_closed_form_backbone():
    # response control holds X, so the level is the linear oscillator
    # D = w2 - W^2 + i (c W + k_q) with w2 = omega0^2 - (K_T - k_in(X)) from the closed
    # form: its pole W* (root of D) is what the identification must return
    st = _structure()
    R, chi, phi = st.joint.R, st.joint.chi, st.joint.lo
    joint = IwanParameters.from_density(R, chi, phi, 0.0)
    c = 2 * st.zeta0 * st.omega0
    for x in (0.1, 0.5, 0.9):
        k_in, k_q = describing_function(joint, x * phi)
        w2 = st.omega0**2 - (joint.K_T - k_in)
        pole = (1j * c + np.sqrt(4 * (w2 + 1j * k_q) - c**2)) / 2
        W = np.sqrt(w2) * np.linspace(0.97, 1.03, 60)
        H, *_ = solve_level(st, W, "response", x * phi, mx.Run(1))
        m = identify(W / (2 * np.pi), H, n_modes=1).modes[0]
        assert m.omega2 == pytest.approx(abs(pole) ** 2, rel=5e-5)
        assert m.zeta == pytest.approx(pole.imag / abs(pole), rel=2e-3)


def test_planted_repeatability_is_recovered_from_repeated_runs():
    rng = np.random.default_rng(7)
    st = _structure()
    s_f, s_z = 6e-4, 0.03
    w_r = math.sqrt(st.omega0**2 - st.joint.loss(np.array([0.5e-4]))[0][0])
    W = w_r * np.linspace(0.98, 1.02, 50)
    f, z = [], []
    for k in range(60):
        run = mx.Run(k + 1, eps_f=s_f * rng.standard_normal(), eps_z=s_z * rng.standard_normal())
        H, *_ = solve_level(st, W, "response", 0.5e-4, run)
        m = identify(W / (2 * np.pi), H, n_modes=1).modes[0]
        f.append(m.frequency_hz)
        z.append(m.zeta)
    # the joint's loss is not scaled by the frequency offset: sd slightly under s_f
    assert np.std(f) / np.mean(f) == pytest.approx(s_f, rel=0.25)
    assert np.std(z) / np.mean(z) == pytest.approx(s_z, rel=0.25)


# --------------------------------------------------------------------------- series


def test_labels():
    assert truth_of("none") == ()
    assert truth_of("macro-slip+thermal-drift") == ("macro-slip", "thermal-drift")
    assert truth_of("capped-dashpot") == truth_of("out-of-catalogue") == ("unexplained",)
    for bad in ("gremlins", "macro-slip+macro-slip", "a+b+c"):
        with pytest.raises(ValueError, match="label"):
            truth_of(bad)
    assert set(CATALOGUE).isdisjoint(OUT_OF_CATALOGUE)
    with pytest.raises(ValueError, match="force control"):
        generate_series("nonproportional-amplitude", 1, control="response")


@pytest.mark.parametrize("label, kw", [
    ("thermal-drift", dict(repeats=2, repeatability=True, n_levels=6)),
    ("nonproportional-amplitude+quadratic-damping", dict(repeats=0, n_levels=5)),
])
def test_series_respect_their_design(label, kw):
    s = generate_series(label, 11, **kw)
    d, t = s.data, s.truth
    n = t["n_levels"]
    assert n == kw["n_levels"] and len(d) == n + kw["repeats"] == len(s.frfs)
    assert sorted(d.run_order) == list(range(1, len(d) + 1))
    assert np.all(d.omega2_std > 0) and np.all(d.zeta_std > 0)
    assert without_stds(d).omega2_std is None and d.omega2_std is not None
    assert t["causes"] == truth_of(label)
    for m in t["mechanisms"]:                       # honest visibility, >= 3 noise units
        assert m["visibility"] >= 3.0
        assert len(m["with_omega2"]) == len(d)
    if kw["repeats"]:
        lv, counts = np.unique(d.level, return_counts=True)
        assert counts.max() == 2 and lv[counts == 2][0] in d.level[n:]
        rep = t["repeatability"]
        assert rep["on"] and 2e-4 <= rep["s_f"] <= 1e-3 and 0.01 <= rep["s_z"] <= 0.05
        assert t["run_kind"] in ("shuffled", "interleaved")
    if "nonproportional-amplitude" in label:
        assert t["control"] == "force"
        # the held level is a drive voltage: the force reaching the structure falls short
        held = np.array([f["held"] for f in sorted(s.frfs, key=lambda f: f["level"])])
        assert np.all(np.diff(held) > 0)
        np.testing.assert_allclose(np.sort(d.excitation), held)
        ex = next(m for m in t["mechanisms"] if m["cause"] == "nonproportional-amplitude")
        short = np.array(ex["x_peak_without"]) / np.array(ex["x_peak_with"])
        assert short.max() > 1.02 and short.min() > 0.999     # the drive falls short


def test_same_seed_same_series():
    a = generate_series("none", 3, n_levels=4, repeats=0)
    b = generate_series("none", 3, n_levels=4, repeats=0)
    np.testing.assert_array_equal(a.data.omega2, b.data.omega2)
