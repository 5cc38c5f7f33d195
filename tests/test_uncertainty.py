"""Monte Carlo over the identified joint parameters (inverse.uncertainty,
inverse.sample_store, cases.double_beam.uncertainty and uncertainty_report) and
``iwanfe uncertainty``.

Truths used: the estimator's own delta-method t-intervals (inverse.estimate, checked here
to come from the closed form written out below), the chi-square law of sums of squared
normal draws and the F law of the Mahalanobis distance of Student-t draws, the
Student-t mass of the Iwan range, run_study (cases.double_beam.study) at the
same settings, and the default settings of ``reproduce double-beam``. FE samples use a
coarse 7-level study (1 Hz lines over 240-264 Hz) to stay fast.
"""
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import cases.double_beam.uncertainty as unc
from cases.double_beam.joint_setup import source_estimate
from cases.double_beam.model import build_double_beam
from cases.double_beam.settings import DoubleBeamStudy, measured_levels
from cases.double_beam.study import run_study
from cases.double_beam.uncertainty_report import run_uncertainty
from cli.main import main
from inverse.iwan_modal import kappa_ratio, zeta_with_joint
from inverse.sample_store import SampleStore
from inverse.uncertainty import ParameterDistribution, SweepInputs, run_samples, sweep_hash
from runs.executor import ExecutorSpec, task_seeds

GOLDEN_HASH = Path(__file__).resolve().parent / "golden" / "uncertainty_sweep_hash.json"
COARSE = dataclasses.replace(unc.SAMPLE_STUDY, n_levels=7, df_hz=1.0, band_hz=(240.0, 264.0),
                             sliders_per_octave=6, n_modes=20)
N_FE = 3   # FE samples of the executor / resume tests


@pytest.fixture(scope="module")
def model():
    return build_double_beam()


@pytest.fixture(scope="module")
def source(model):
    """The exact estimate of measured levels 1-7 at the 90 % level (3 dof), with
    predictions of all 10 levels."""
    st = unc.SAMPLE_STUDY
    return source_estimate(model, measured_levels(st), st, confidence=0.9)


@pytest.fixture(scope="module")
def reference(model, tmp_path_factory):
    """Uninterrupted serial run of N_FE samples, stored."""
    out = tmp_path_factory.mktemp("ref")
    settings = unc.UncertaintySettings(study=COARSE, n_samples=N_FE, seed=11)
    rep = run_uncertainty(settings, out=out, progress=False, model=model)
    return settings, rep, out


def same(a, b):
    return a.same_bits(b)


# --------------------------------------------------------------------------- closed form


def closed_form(est, p, ln_kt):
    """The ``exact`` method's predictions (inverse.estimate eq. 2, 43 and eq. 3 with the
    fit's anchors): omega^2 = omega2_lin - (kappa2/|kappa1|) Delta c, zeta from eq. 2,
    Delta c = (Kt/p) r^p."""
    r = np.array([p_["excitation"] for p_ in est.predictions])
    r = r / r[0]
    dc = math.exp(ln_kt) / p * r ** p
    om2 = est.omega2_linear - kappa_ratio(p - 1.0, "exact") * dc
    return om2, zeta_with_joint(dc, om2, est.c_modal)


def closed_form_sample(inputs, p, ln_kt):
    """Per-sample model of the sweep replaced by the closed form (``inputs.model``
    carries the estimate)."""
    est = inputs.model
    om2, ze = closed_form(est, est.fit.p if p is None else p,
                          est.fit.ln_kt if ln_kt is None else ln_kt)
    return {"omega2": om2, "zeta": ze, "chi": (est.fit.p if p is None else p) - 1.0}


def test_closed_form_here_is_the_estimators(source):
    """The closed form above reproduces the estimator's predictions and, through the
    fit's delta method, its t-intervals (so the comparison below is against them)."""
    f = source.fit
    om2, ze = closed_form(source, f.p, f.ln_kt)
    pr = source.predictions
    np.testing.assert_allclose(om2, [p["omega2"] for p in pr], rtol=1e-13)
    np.testing.assert_allclose(ze, [p["zeta"] for p in pr], rtol=1e-13)
    lo, hi = f.interval(lambda p, k: closed_form(source, p, k)[0], 0.9)
    np.testing.assert_allclose(lo, [p["omega2_interval"][0] for p in pr], rtol=1e-13)
    np.testing.assert_allclose(hi, [p["omega2_interval"][1] for p in pr], rtol=1e-13)
    # the covariance exposed in (chi + 1, ln |kappa1| B): delta method of ln K = ln Kt - ln p
    c = f.cov_kappa1_B
    g = f.gradient(lambda p, k: k - math.log(p))
    np.testing.assert_allclose(c[1, 1], g @ f.cov @ g, rtol=1e-6)
    np.testing.assert_allclose(c[0, 0], f.cov[0, 0], rtol=0)


def test_monte_carlo_interval_agrees_with_delta_method_in_the_linear_regime(source):
    """Closed-form sweep with the fit's Student-t distribution scaled to 0.5 % of its
    spread (prediction linear in the parameters, no truncation): the 5 % and 95 %
    sample quantiles of omega^2 and zeta at the held-out levels 8-10 and of chi agree
    with the delta-method t-interval within 4.5 standard errors of a sample quantile,
    sqrt(q (1-q) / N) / f_t(t_q) times the delta-method standard error (measured
    |z| <= 1.9; at 2 % of the spread the curvature already shifts omega^2 by 2-3
    standard errors, at the full spread by 40-90)."""
    s, N, conf = 0.005, 20000, 0.9
    f = source.fit
    dist = ParameterDistribution.from_fit(f, "t", scale=s)
    inputs = SweepInputs(model=source, data=None, study=None, distribution=dist,
                             simulate=closed_form_sample)
    nominal, samples = run_samples(inputs, N, seed=5, progress=False)
    assert all(x.n_draws == 1 for x in samples)
    scaled = dataclasses.replace(f, cov=s ** 2 * f.cov)
    t_q = scaled.tquantile(conf)
    q_se = math.sqrt(0.05 * 0.95 / N) / stats.t.pdf(t_q, f.dof)      # in units of the s.e.
    held = [i for i, p in enumerate(source.predictions) if p["held_out"]]
    assert [source.predictions[i]["level"] for i in held] == [8, 9, 10]
    checks = [("chi", lambda p, k: p - 1.0, None)]
    checks += [("omega2", (lambda i: lambda p, k: closed_form(source, p, k)[0][i])(i), i)
               for i in held]
    checks += [("zeta", (lambda i: lambda p, k: closed_form(source, p, k)[1][i])(i), i)
               for i in held]
    for name, fun, i in checks:
        v = np.array([x.values[name] if i is None else x.values[name][i] for x in samples])
        lo, hi = scaled.interval(fun, conf)
        se = (hi - lo) / (2 * t_q)
        mc_lo, mc_hi = np.quantile(v, [0.05, 0.95])
        for got, want in ((mc_lo, lo), (mc_hi, hi)):
            assert abs(got - want) < 4.5 * q_se * se, (name, i, got, want,
                                                       (got - want) / (q_se * se))


# --------------------------------------------------------------------------- sampling


def test_normal_draws_reproduce_the_covariance():
    """(N sum of (a.(x - m))^2 / a^T C a) ~ chi^2_N for every direction a (mean known):
    four directions fix the 2x2 covariance; two-sided bounds at 1e-4 in total."""
    C = np.array([[0.004, -0.003], [-0.003, 0.01]])
    dist = ParameterDistribution(mean=[0.6, 3.0], cov=C, dof=math.inf)
    N = 4000
    draws = [dist.draw(sd) for sd in task_seeds(7, N)]
    assert all(n == 1 for _, n in draws)
    d = np.array([x for x, _ in draws]) - dist.mean
    for a in (np.array([1.0, 0.0]), np.array([0.0, 1.0]), np.array([1.0, 1.0]),
              np.array([1.0, -1.0])):
        Q = float(np.sum((d @ a) ** 2) / (a @ C @ a))
        cdf = stats.chi2.cdf(Q, N)
        assert 1.25e-5 < cdf < 1 - 1.25e-5, (a, Q / N, cdf)
    S = d.T @ d / N                    # sample covariance about the known mean
    assert np.all(np.abs(S - C) <= 0.1 * np.sqrt(np.outer(np.diag(C), np.diag(C)))), S


def test_student_t_draws_have_the_f_law_and_truncation_keeps_the_iwan_range(source):
    """Mahalanobis^2 / 2 of bivariate t draws ~ F(2, nu) (KS); with the fit's own
    distribution every draw has -1 < chi < 0 and the acceptance matches the t mass of
    the Iwan range within 4.5 binomial standard deviations."""
    C = np.array([[0.004, -0.003], [-0.003, 0.01]])
    dist = ParameterDistribution(mean=[0.5, 3.0], cov=C, dof=3.0)
    N = 3000
    x = np.array([dist.draw(sd)[0] for sd in task_seeds(8, N)]) - dist.mean
    m2 = np.einsum("ni,ij,nj->n", x, np.linalg.inv(C), x)
    assert stats.kstest(m2 / 2.0, stats.f(2, 3).cdf).pvalue > 1e-3
    fit = ParameterDistribution.from_fit(source.fit, "t")
    draws = [fit.draw(sd) for sd in task_seeds(9, N)]
    p = np.array([x[0] for x, _ in draws])
    assert np.all((p > 0) & (p < 1))
    total = sum(n for _, n in draws)
    a = fit.admissible_fraction()
    assert 0.6 < a < 0.95
    assert abs(N / total - a) < 4.5 * math.sqrt(a * (1 - a) / total), (N / total, a)
    # same seed, same draw; no covariance, the nominal point
    assert np.array_equal(fit.draw(task_seeds(9, 1)[0])[0], draws[0][0])
    zero = ParameterDistribution.from_fit(source.fit, "t", scale=0.0)
    assert np.array_equal(zero.draw(task_seeds(1, 1)[0])[0], [source.fit.p, source.fit.ln_kt])


# --------------------------------------------------------------------------- FE sweep


def _fixed_sweep_inputs(kind: str) -> SweepInputs:
    """The default sweep's study and per-sample model with a small model, data and
    distribution written out in numbers: their bytes do not depend on the CPU (a fit's
    last bits do: the default sweep's own hash differs between AVX2 and AVX-512)."""
    import types

    import scipy.sparse as sparse

    k = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]) * 1e4
    model = types.SimpleNamespace(M=sparse.identity(3) * 0.1, K=sparse.csr_matrix(k),
                                  slip_matrix=sparse.csr_matrix([[1.0, -1.0, 0.0]]),
                                  joint_stiffness=[1e4], drive_dof=2, response_dof=2)
    data = types.SimpleNamespace(level=[1, 2, 3], excitation=[0.1, 0.2, 0.4],
                                 omega2=[2.5e6, 2.49e6, 2.47e6], zeta=[1e-3, 1.2e-3, 1.5e-3])
    dist = ParameterDistribution(mean=np.array([0.6, 12.5]),
                                 cov=np.array([[1e-3, 2e-4], [2e-4, 4e-3]]),
                                 dof=5.0 if kind == "t" else math.inf)
    return SweepInputs(model, data, unc.SAMPLE_STUDY, dist, unc.simulate_fe)


def test_store_hash_of_the_default_sweep_is_unchanged(model):
    """Golden values (tests/golden/uncertainty_sweep_hash.json, its note says why): what
    the store's name hashes, and how, changes only on purpose (a finished store stays
    readable). The default sweep's own hash is reproducible within one machine."""
    golden = json.loads(GOLDEN_HASH.read_text())
    for kind in ("t", "normal"):
        assert sweep_hash(_fixed_sweep_inputs(kind), golden["seed"]) == golden[kind], kind
    st = unc.SAMPLE_STUDY
    data = measured_levels(st)
    src = source_estimate(model, data, st, confidence=unc.DEFAULT_CONFIDENCE)
    hashes = {sweep_hash(SweepInputs(model, data, st, ParameterDistribution.from_fit(
        src.fit, "t"), unc.simulate_fe), seed) for seed in (1, 1, 2)}
    assert len(hashes) == 2                  # the same inputs: the same store; seeds differ


def test_nominal_sample_is_run_study_and_zero_covariance_sample_matches_it(reference, model):
    settings, rep, _ = reference
    ref = run_study(COARSE, progress=False, model=model)
    nom = rep.nominal.values
    for mine, theirs in (("frequency_hz", ref.modal_filter.frequency_hz),
                         ("zeta", ref.modal_filter.zeta), ("lscf_zeta", ref.simulated.zeta),
                         ("lscf_frequency_hz", ref.identification.frequency_hz)):
        assert np.array_equal(nom[mine], theirs), mine
    assert float(nom["R"]) == ref.setup.R and float(nom["chi"]) == ref.setup.chi
    # the sampled path (chi, R overrides) at zero covariance: round-off only
    data = measured_levels(COARSE)
    dist = ParameterDistribution.from_fit(rep.source.fit, "t", scale=0.0)
    inputs = SweepInputs(model, data, COARSE, dist, unc.simulate_fe)
    _, (zero,) = run_samples(inputs, 1, seed=3, progress=False)
    for k in ("frequency_hz", "zeta"):
        np.testing.assert_allclose(zero.values[k], nom[k], rtol=1e-11, atol=0)


def test_per_sample_settings_agree_with_the_default_ones(model):
    """SAMPLE_STUDY (8 sliders per octave, 128 AFT samples) against the defaults of
    ``reproduce double-beam`` on the nominal joint, all 10 levels: frequency within
    5e-6 and damping ratio within 3e-4 relative (measured 1.4e-6, 1.0e-4)."""
    got = []
    for st in (unc.SAMPLE_STUDY, DoubleBeamStudy(weak_joint_scales=())):
        data = measured_levels(st)
        src = source_estimate(model, data, st)
        inputs = SweepInputs(model, data, st,
                                 ParameterDistribution.from_fit(src.fit), unc.simulate_fe)
        got.append(unc.simulate_fe(inputs))
    a, b = got
    np.testing.assert_allclose(a["frequency_hz"], b["frequency_hz"], rtol=5e-6)
    np.testing.assert_allclose(a["zeta"], b["zeta"], rtol=3e-4)


def test_process_pool_gives_bitwise_the_serial_samples(reference, model):
    settings, rep, _ = reference
    pool = run_uncertainty(settings, executor=ExecutorSpec("processes", 2),
                               progress=False, model=model)
    assert same(pool.nominal, rep.nominal)
    assert len(pool.samples) == N_FE
    assert all(same(a, b) for a, b in zip(pool.samples, rep.samples))
    assert rep.n_failed < N_FE and all(np.isfinite(s.values["zeta"]).all()
                                       for s in rep.samples if s.ok)


class Stop(Exception):
    pass


def test_interrupted_run_resumes_bitwise_computing_only_missing_samples(reference, model,
                                                                         tmp_path):
    settings, rep, ref_out = reference
    seen = []

    def stop_after_two(res):
        seen.append(res.index)
        if len(seen) == 2:
            raise Stop

    with pytest.raises(Stop):
        run_uncertainty(settings, out=tmp_path, progress=False, model=model,
                            on_sample=stop_after_two)
    computed = []
    again = run_uncertainty(settings, out=tmp_path, progress=False, model=model,
                                on_sample=lambda r: computed.append(r.index))
    assert seen == [-1, 0] and computed == list(range(1, N_FE))
    assert again.timings["computed"] == N_FE - 1 and again.timings["loaded"] == 2
    assert same(again.nominal, rep.nominal)
    assert all(same(a, b) for a, b in zip(again.samples, rep.samples))
    # a deleted sample is recomputed, nothing else; a loaded store equals fresh results
    (next(tmp_path.glob("samples-*")) / "sample_00001.npz").unlink()
    computed.clear()
    third = run_uncertainty(settings, out=tmp_path, progress=False, model=model,
                                on_sample=lambda r: computed.append(r.index))
    assert computed == [1]
    assert all(same(a, b) for a, b in zip(third.samples, rep.samples))
    # more samples extend the finished run (seeds do not depend on n)
    more = dataclasses.replace(settings, n_samples=N_FE + 1)
    computed.clear()
    ext = run_uncertainty(more, out=ref_out, progress=False, model=model,
                              on_sample=lambda r: computed.append(r.index))
    assert computed == [N_FE]
    assert all(same(a, b) for a, b in zip(ext.samples, rep.samples))
    # another seed is another sweep: its own directory; a foreign manifest is refused
    assert sweep_hash(SweepInputs(model, measured_levels(COARSE), COARSE,
                                          rep.distribution, unc.simulate_fe), 12) != rep.digest
    store = next(tmp_path.glob("samples-*"))
    with pytest.raises(ValueError, match="another Monte Carlo sweep"):
        SampleStore(store, "0" * 64)


def test_report_bands_and_closed_form(reference):
    _, rep, _ = reference
    rows = rep.per_level()
    assert [r["level"] for r in rows] == list(range(1, 8))
    for r in rows:
        for key in ("mc_frequency_hz", "mc_zeta"):
            b = r[key]
            assert b["lo"] <= b["median"] <= b["hi"]
        lo, hi = r["closed_form_zeta_interval"]
        assert lo < r["closed_form_zeta"] < hi
    v = rep.values("zeta")
    ok = np.array([s.ok for s in rep.samples])
    np.testing.assert_array_equal(np.median(v[ok], axis=0),
                                  [r["mc_zeta"]["median"] for r in rows])


# --------------------------------------------------------------------------- CLI


def cli(argv):
    try:
        return main(argv)
    except SystemExit as exc:          # argparse: --help, usage errors
        return exc.code


def test_cli_help(capsys):
    assert cli(["uncertainty", "--help"]) == 0
    out = capsys.readouterr().out
    assert "--samples" in out and "--workers" in out and "delta-method" in out


@pytest.mark.parametrize("argv, message", [
    (["--samples", "0"], "must be >= 1"),
    (["--seed", "x"], "whole number"),
    (["--confidence", "1.5"], "--confidence 1.5: must lie in (0, 1)"),
    (["--fit-levels", "1-12"], "exceed"),
    (["no_such_file.csv"], "no such file"),
    (["--executor", "serial", "--workers", "2"], "takes neither"),
    (["--band", "260", "250"], "band"),
])
def test_cli_bad_input_is_one_line_exit_2(argv, message, tmp_path, capsys):
    rc = cli(["uncertainty", *argv, "--out", str(tmp_path / "x"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and err.count("\n") == 1, err


def test_cli_json_run_writes_report_and_plot(tmp_path, capsys):
    out = tmp_path / "u"
    rc = cli(["uncertainty", "--samples", "1", "--seed", "4", "--out", str(out), "--json",
              "--no-progress", "--df", "1", "--band", "240", "264",
              "--sliders-per-octave", "6"])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    assert d["n_samples"] == 1 and d["fit_levels"] == list(range(1, 8))
    assert len(d["levels"]) == 10 and [r["held_out"] for r in d["levels"]].count(True) == 3
    for key in ("mc_frequency_hz", "mc_zeta", "closed_form_zeta_interval",
                "nominal_frequency_hz", "measured_zeta"):
        assert key in d["levels"][-1]
    assert d["distribution"]["kind"] == "t" and d["distribution"]["dof"] == 3
    assert (out / "uncertainty.png").stat().st_size > 0
    assert json.loads((out / "uncertainty.json").read_text())["hash"] == d["hash"]
    assert len(list(out.glob("samples-*/sample_*.npz"))) == 1


def _update_fit(chi2_over_dof=2.0):
    """A model-updating fit with a planted covariance (chi, ln_dc1, f0_hz free; zeta_v
    free but on its lower bound), misfit scale ``chi2_over_dof``."""
    from inverse.update import Fit, Parameter

    sd = np.array([0.1 / math.sqrt(chi2_over_dof), 0.5, 0.2])   # chi: sd 0.1 when scaled
    corr = np.array([[1.0, 0.6, -0.3], [0.6, 1.0, 0.2], [-0.3, 0.2, 1.0]])
    cov = np.zeros((4, 4))
    cov[np.ix_([0, 1, 3], [0, 1, 3])] = corr * np.outer(sd, sd)
    values = {"chi": -0.5, "ln_dc1": 5.0, "zeta_v": 1e-5, "f0_hz": 80.0, "log10_kt": 7.0}
    fit = Fit(values, ("chi", "ln_dc1", "zeta_v", "f0_hz"), chi2=chi2_over_dof * 16, n=20,
              cov=cov, nfev=1, seconds=0.0, success=True, at_bound={"zeta_v": "lower"})
    params = {"chi": Parameter("chi", -0.5, -0.6, -0.4, 0.05),
              "ln_dc1": Parameter("ln_dc1", 5.0, -15.0, 15.0, 0.2),
              "zeta_v": Parameter("zeta_v", 1e-5, 1e-5, 0.2, 1e-5),
              "f0_hz": Parameter("f0_hz", 80.0, 70.0, 90.0, 1e-3)}
    return fit, params, chi2_over_dof * cov[np.ix_([0, 1, 3], [0, 1, 3])]


def test_fit_distribution_draws_the_fit_inside_its_bounds():
    """``FitDistribution`` of an update fit (normal): the parameter on a bound and the
    assumed one held; chi truncated to its bounds [-0.6, -0.4] = mean +- 1 sd, so the
    kept fraction is the normal mass within 1 sd (0.6827) and every draw lies inside;
    the untruncated parameter's mean is unbiased by a symmetric truncation (its
    covariance with chi only scales its variance, closed form:
    ``var(y) = s_y^2 (1 - rho^2 (1 - v1))``, ``v1 = 1 - 2 phi(1)/(2 Phi(1) - 1)`` the
    variance of a standard normal truncated to +-1), and the sample carries the
    fit's (p, ln_kt) coordinates."""
    from inverse.uncertainty import FitDistribution

    fit, params, cov = _update_fit()
    dist = FitDistribution.from_fit(fit, params, "normal")
    assert dist.names == ("chi", "ln_dc1", "f0_hz")
    assert dist.fixed == {"zeta_v": 1e-5, "log10_kt": 7.0}
    assert np.allclose(dist.cov, cov)
    n, draws, xs = 4000, 0, []
    for seed in task_seeds(3, n):
        x, k = dist.draw(seed)
        xs.append(x)
        draws += k
    xs = np.array(xs)
    assert np.all((xs[:, 0] >= -0.6) & (xs[:, 0] <= -0.4))
    mass = stats.norm.cdf(1) - stats.norm.cdf(-1)
    assert abs(n / draws - mass) < 4 * math.sqrt(mass * (1 - mass) / draws)
    v1 = 1 - 2 * stats.norm.pdf(1) / mass
    for j in (1, 2):
        s2, rho = cov[j, j], cov[0, j] / math.sqrt(cov[0, 0] * cov[j, j])
        var = s2 * (1 - rho ** 2 * (1 - v1))
        assert abs(xs[:, j].mean() - dist.mean[j]) < 4 * math.sqrt(var / n)
        assert xs[:, j].var() == pytest.approx(var, rel=0.1)
    v = dist.values(xs[0])
    assert v["zeta_v"] == 1e-5 and v["chi"] == xs[0, 0]
    p, ln_kt = dist.joint(xs[0])
    assert p == pytest.approx(v["chi"] + 1) and ln_kt == pytest.approx(math.log(p) + v["ln_dc1"])
