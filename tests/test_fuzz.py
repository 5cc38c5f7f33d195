"""Property-based fuzzing in the suite (bounded): the file readers (tests/fuzz.py) and the
numeric options of every command.

Readers: random bytes, files cut at any byte, mutated files; allowed outcomes: a result
keeping the reader's contract (and, for a cut file, the uncut file's values) or
``InputError`` with one line naming the file (tests/fuzz.py says how). The long run of
10,000 inputs per reader is ``python tests/fuzz.py --examples 10000``.

Command-line options: extreme numbers (0, -0, +-inf, nan, 5e-324, +-1e300, ...) and
integers far out of range; allowed outcomes: exit 0 with a correct result, or exit 2 with
one line on stderr. For ``joint`` a result is checked against Segalman's closed forms
(micro-slip dissipation ``4 R A^(chi+3)/((chi+2)(chi+3))``, Coulomb bound ``D <= 4 F_S A``,
``0 <= k_in <= K_T``, ``D = pi A^2 k_q``); for ``modes`` the measured mode at 252.0 Hz within
0.5 %. For the long commands (reproduce, uncertainty, convergence, render) the work itself
is replaced by a stand-in that raises ``_WorkStarted``: validation must either refuse
with one line or let the work start.
"""
from __future__ import annotations

import contextlib
import io
import json
import math
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fuzz  # noqa: E402  (tests/fuzz.py)
from cli.main import main  # noqa: E402
from ident.frf_files import write_frf_csv  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MEASURED = str(ROOT / "cases/data/double_beam_measured.csv")

SPECIAL = [0.0, -0.0, 5e-324, 2.2e-308, 1e-300, 1e-30, 1e-5, 1e-3, 0.5, 0.999, 1.0, 2.0,
           4.0, 236.0, 252.0, 268.0, 1e5, 1e30, 1e300, 1.7e308, -1.0, -1e-3, -1e300,
           math.inf, -math.inf, math.nan]
NUMBER = st.one_of(st.sampled_from(SPECIAL), st.floats(allow_nan=True, allow_infinity=True))
INTEGER = st.one_of(st.sampled_from([0, 1, 2, 4, 6, 16, 39, 40, 100, 10_000, -1, 2**31,
                                     2**63, 10**30]), st.integers(-10**6, 10**6))
FAST = settings(deadline=None, database=None, derandomize=True,
                suppress_health_check=list(HealthCheck))


def log10_uniform(lo: float, hi: float):
    """Floats spread over decades from 10^lo to 10^hi."""
    return st.floats(lo, hi).map(lambda e: 10.0 ** e)


def mix(valid, extreme=NUMBER):
    """Mostly plausible values, one draw in eight extreme: several options are then valid
    together often enough to reach the computation."""
    return st.integers(0, 7).flatmap(lambda k: valid if k else extreme)


def _num(x) -> str:
    return repr(float(x))


class _WorkStarted(Exception):
    """Raised by the stand-ins of the long computations: validation passed."""


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(argv)
        except SystemExit as exc:      # argparse usage errors and --help
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def _refused_in_one_line(rc, err) -> bool:
    lines = err.strip().splitlines()
    return rc == 2 and len(lines) == 1 and "error" in lines[0] and "Traceback" not in err


# ------------------------------------------------------------------------ readers


@pytest.fixture(scope="module")
def fuzzer(tmp_path_factory):
    return fuzz.Fuzzer(tmp_path_factory.mktemp("fuzz"))


@pytest.mark.parametrize("reader", fuzz.READERS)
def test_readers_refuse_or_read_correctly(fuzzer, reader):
    fuzz.run(fuzzer, reader, examples=150, seed=0)
    counts = fuzzer.counts[reader]
    assert counts["result"] + counts["refused"] >= 150
    assert counts["refused"] > 0 and counts["result"] > 0   # both outcomes exercised


def test_fuzzer_catches_a_silent_truncation(tmp_path):
    """The contract check itself: a reader that silently dropped a cut UFF data set's
    lines would be caught (the check compares with the uncut file)."""
    f = fuzz.Fuzzer(tmp_path)
    full = f.full["uff"][0]
    short = fuzz.FRFSet(full.freq_hz[:-3], full.frf[:-3], full.points)
    with pytest.raises(AssertionError):
        fuzz.check_truncated_frf(short, full, b"", binary_sets=True)


# ------------------------------------------------------------------------ joint


def _joint_truth_holds(out: dict) -> None:
    chi, K_T, F_S = out["chi"], out["K_T"], out["F_S"]
    R, pm = out["R"], out["phi_max"]
    for row in out["amplitudes"]:
        A, ki, kq, D = (row[k] for k in ("amplitude", "stiffness_in_phase",
                                           "stiffness_quadrature", "dissipation_per_cycle"))
        assert all(math.isfinite(v) for v in (ki, kq, D))
        assert D > 0 and kq > 0
        assert -1e-9 * K_T <= ki <= K_T * (1 + 1e-12)
        assert D <= 4 * F_S * A * (1 + 1e-9)                       # Coulomb bound
        assert D == pytest.approx(math.pi * A * A * kq, rel=1e-9)
        assert row["regime"] == ("micro" if A < pm else "macro")
        if A < pm:
            closed = 4 * R * A ** (chi + 3) / ((chi + 2) * (chi + 3))   # Segalman 2005
            assert D == pytest.approx(closed, rel=1e-9)


@settings(FAST, max_examples=150)
@given(chi=mix(st.one_of(st.floats(-0.999, -0.001), st.sampled_from([-0.999999, -1e-9]))),
       kt=mix(log10_uniform(-30, 30)), fs=mix(log10_uniform(-30, 30)),
       beta=mix(st.one_of(st.floats(0, 100), log10_uniform(-10, 10))),
       amplitudes=st.lists(mix(log10_uniform(-150, 150)), min_size=0, max_size=3))
def test_joint_options(chi, kt, fs, beta, amplitudes):
    argv = ["joint", "--chi", _num(chi), "--kt", _num(kt), "--fs", _num(fs), "--beta",
            _num(beta), "--json"]
    if amplitudes:
        argv += ["--amplitude", *map(_num, amplitudes)]
    rc, out, err = _run(argv)
    if rc == 0:
        _joint_truth_holds(json.loads(out))
    else:
        assert _refused_in_one_line(rc, err), (argv, rc, err)


def test_joint_table_rows_refused_or_right():
    """The rows of issue 15's table for ``joint``."""
    base = ["joint", "--chi", "-0.5", "--kt", "1.1e5", "--fs", "400", "--beta", "4"]
    for extra in (["--kt", "1e300"], ["--fs", "1e-300"], ["--amplitude", "1e300"]):
        rc, _, err = _run(base[:1] + [a for a in base[1:]] + extra)
        assert _refused_in_one_line(rc, err), (extra, err)
        assert extra[0] in err
    rc, out, err = _run(base + ["--amplitude", "-1e-3"])
    assert _refused_in_one_line(rc, err) and "--amplitude -0.001: must be" in err


# ------------------------------------------------------------------------ modes


@settings(FAST, max_examples=12)
@given(lo=mix(st.floats(0, 250)), hi=mix(st.floats(253, 5000)),
       h=st.one_of(st.none(), mix(log10_uniform(-3, math.log10(0.05)))))
def test_modes_options(lo, hi, h):
    argv = ["modes", "--band", _num(lo), _num(hi), "--json"]
    if h is not None:
        argv += ["--element-size", _num(h)]
    rc, out, err = _run(argv)
    if rc != 0:
        assert _refused_in_one_line(rc, err), (argv, err)
        return
    rows = json.loads(out)
    assert all(lo <= r["frequency_hz"] <= hi for r in rows)
    if lo <= 251.0 and hi >= 253.0:
        (m,) = [r for r in rows if r["matches_measured"]]
        assert m["frequency_hz"] == pytest.approx(252.0, rel=0.005)


def test_modes_fine_element_limit():
    """``--element-size 1e-5`` gave 237.71 Hz for the 252 Hz mode: now refused; the
    finest size allowed still gives 252.0 Hz."""
    rc, _, err = _run(["modes", "--element-size", "1e-5"])
    assert _refused_in_one_line(rc, err) and "round-off" in err
    from cases.mode_report import min_element_size

    h = min_element_size(0.35)    # the double beam's case file: strips 0.35 m long
    rc, out, err = _run(["modes", "--element-size", repr(h * 1.001), "--json"])
    assert rc == 0, err
    (m,) = [r for r in json.loads(out) if r["matches_measured"]]
    assert m["frequency_hz"] == pytest.approx(252.0, rel=1e-4)


# ------------------------------------------------------------------------ identify


@pytest.fixture(scope="module")
def frf_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("frf") / "set.csv"
    write_frf_csv(path, fuzz.frf_set(n_lines=80))
    return str(path)


@settings(FAST, max_examples=25)
@given(band=st.one_of(st.none(), st.tuples(mix(st.floats(30, 47)), mix(st.floats(53, 90)))),
       modes=st.one_of(st.none(), mix(st.integers(1, 20), INTEGER)),
       order=st.one_of(st.none(), mix(st.integers(1, 20), INTEGER)),
       excitation=st.one_of(st.none(), mix(log10_uniform(-10, 10))))
def test_identify_options(frf_file, band, modes, order, excitation):
    argv = ["identify", frf_file, "--json"]
    if band is not None:
        argv += ["--band", *map(_num, band)]
    if modes is not None:
        argv += ["--modes", str(modes)]
    if order is not None:
        argv += ["--max-order", str(order)]
    if excitation is not None:
        argv += ["--excitation", _num(excitation)]
    rc, out, err = _run(argv)
    if rc != 0:
        assert _refused_in_one_line(rc, err), (argv, err)
        return
    (s,) = json.loads(out)["sets"]
    for m in s["modes"]:   # identified modes lie in the band and are physical
        assert 0 < m["zeta"] < 1 and m["frequency_hz"] > 0


# ------------------------------------------------------------------------ estimate, diagnose


_BASELINE = {}


def _baseline_chi():
    if "chi" not in _BASELINE:
        rc, out, err = _run(["estimate", MEASURED, "--fit-levels", "1-7", "--json"])
        assert rc == 0, err
        _BASELINE["chi"] = json.loads(out)["chi"]
    return _BASELINE["chi"]


@settings(FAST, max_examples=20)
@given(force_scale=mix(log10_uniform(-10, 10)), confidence=mix(st.floats(0.01, 0.99)),
       fe_mode=st.one_of(st.none(), mix(st.integers(1, 10), INTEGER)),
       mode=st.one_of(st.none(), mix(st.just(2), INTEGER)))
def test_estimate_options(force_scale, confidence, fe_mode, mode):
    argv = ["estimate", MEASURED, "--force-scale", _num(force_scale), "--confidence",
            _num(confidence), "--fit-levels", "1-7", "--json"]
    if fe_mode is not None:
        argv += ["--case", "double-beam", "--fe-mode", str(fe_mode)]
    if mode is not None:
        argv += ["--mode", str(mode)]
    rc, out, err = _run(argv)
    if rc != 0:
        assert _refused_in_one_line(rc, err), (argv, err)
        return
    # chi comes from the damping growth alone: the force scale, the interval level and
    # the FE mode must not move it (truth: the run without those options)
    assert json.loads(out)["chi"] == _baseline_chi()


# ------------------------------------------------------------------------ long commands


@pytest.fixture
def stand_ins(monkeypatch):
    """The long computations raise _WorkStarted instead of running."""
    def started(*args, **kwargs):
        raise _WorkStarted

    import cases.convergence
    import cases.double_beam.study
    import cases.double_beam.uncertainty_report
    import cases.lumped10.study
    import viz.render

    monkeypatch.setattr(cases.double_beam.study, "run_study", started)
    monkeypatch.setattr(cases.lumped10.study, "run_study", started)
    monkeypatch.setattr(cases.double_beam.uncertainty_report, "run_uncertainty", started)
    monkeypatch.setattr(cases.convergence, "convergence_report", started)
    monkeypatch.setattr(viz.render, "render_mode_shape", started)
    monkeypatch.setenv("IWANFE_TRACEBACK", "1")   # a stand-in's exception propagates


def _validated_or_refused(argv):
    try:
        rc, out, err = _run(argv)
    except _WorkStarted:
        return "started"
    assert _refused_in_one_line(rc, err), (argv, rc, err)
    return "refused"


#: Root of the output folders the commands are given; removed when the session ends.
_OUT_ROOT = tempfile.TemporaryDirectory(prefix="iwanfe-fuzz-out-")


def _tmp_out():
    return tempfile.mkdtemp(dir=_OUT_ROOT.name)


@settings(FAST, max_examples=25)
@given(band=st.tuples(mix(st.floats(200, 250)), mix(st.floats(254, 300))),
       df=mix(st.floats(0.005, 5)), spo=mix(st.integers(1, 300), INTEGER),
       chi=mix(st.floats(-0.99, -0.01)), R=mix(log10_uniform(-20, 20)),
       beta=mix(st.floats(0, 10)), force_scale=mix(log10_uniform(-10, 10)))
def test_reproduce_double_beam_options(stand_ins, band, df, spo, chi, R, beta, force_scale):
    argv = ["reproduce", "double-beam", "--out", _tmp_out(), "--no-progress",
            "--band", *map(_num, band), "--df", _num(df), "--sliders-per-octave", str(spo),
            "--chi", _num(chi), "--R", _num(R), "--beta", _num(beta),
            "--force-scale", _num(force_scale)]
    if _validated_or_refused(argv) == "started":
        # what validation let through: lines bounded, band holding the 252 Hz mode
        lo, hi = band
        assert lo <= 248.7 and hi >= 255.2 and (hi - lo) / df <= 10_000
        assert -1 < chi < 0 and 1 <= spo <= 256


@settings(FAST, max_examples=25)
@given(samples=mix(st.integers(1, 1000), INTEGER), seed=mix(st.integers(0, 2**32), INTEGER),
       confidence=mix(st.floats(0.01, 0.99)),
       band=st.tuples(mix(st.floats(200, 250)), mix(st.floats(254, 300))),
       df=mix(st.floats(0.005, 5)), spo=mix(st.integers(1, 300), INTEGER),
       force_scale=mix(log10_uniform(-10, 10)))
def test_uncertainty_options(stand_ins, samples, seed, confidence, band, df, spo, force_scale):
    argv = ["uncertainty", "--out", _tmp_out(), "--no-progress", "--samples", str(samples),
            "--seed", str(seed), "--confidence", _num(confidence), "--band", *map(_num, band),
            "--df", _num(df), "--sliders-per-octave", str(spo), "--force-scale",
            _num(force_scale)]
    if _validated_or_refused(argv) == "started":
        assert 0 < confidence < 1 and samples >= 1 and band[0] <= 248.7


@settings(FAST, max_examples=15)
@given(n=mix(st.integers(2, 20_000), INTEGER),
       workers=st.one_of(st.none(), mix(st.integers(1, 4), INTEGER)))
def test_lumped_and_convergence_options(stand_ins, n, workers):
    argv = ["reproduce", "lumped", "--out", _tmp_out(), "--n-sliders", str(n), "--no-progress"]
    if _validated_or_refused(argv) == "started":
        assert 2 <= n <= 10_000
    argv = ["convergence", "--out", _tmp_out()]
    if workers is not None:
        argv += ["--executor", "processes", "--workers", str(workers)]
    if _validated_or_refused(argv) == "started":
        assert workers is None or workers >= 1


@settings(FAST, max_examples=20)
@given(mode=mix(st.integers(1, 45), INTEGER),
       scale=st.one_of(st.none(), mix(log10_uniform(-5, 13))),
       thick=st.one_of(st.none(), mix(log10_uniform(-3, 5))),
       size=st.tuples(mix(st.integers(10, 9000), INTEGER), mix(st.integers(10, 9000), INTEGER)),
       modes=mix(st.integers(1, 45), INTEGER))
def test_render_and_export_options(stand_ins, mode, scale, thick, size, modes):
    folder = Path(_tmp_out())
    argv = ["render", "--mode", str(mode), "--out", str(folder / "m.png"),
            "--size", *map(str, size)]
    if scale is not None:
        argv += ["--scale", _num(scale)]
    if thick is not None:
        argv += ["--thickness-scale", _num(thick)]
    _validated_or_refused(argv)
    rc, out, err = _run(["export", "--out", str(folder / "m.vtu"), "--modes", str(modes),
                         "--json"])
    if rc == 0:
        assert len(json.loads(out)["modes"]) == modes
    else:
        assert _refused_in_one_line(rc, err), err
