"""Model-form diagnosis: what the Iwan modal model gets wrong, why, and the gain
(``shared/spec/diagnosis.md``, v2).

Candidates: the base model (``none``), each cause of the catalogue alone and every pair
(:mod:`inverse.diagnosis_models`), fitted by weighted least squares against the noise
levels of :mod:`inverse.diagnosis_noise` (:mod:`inverse.diagnosis_fit`).

Evidence and weights. Every candidate gets its AIC (known noise levels: the
log-likelihood is ``-chi2/2``; :mod:`inverse.diagnosis_fit` says why not AICc). Its
weight is an Akaike weight with prior odds ``exp(-T/2)`` per cause it adds, ``T`` =
:data:`T_CAUSE` = 6:

    IC_i = AIC_i + T n_causes_i,    w_i = exp(-IC_i/2) / sum_j exp(-IC_j/2).

So a cause is named only when it lowers the AIC by more than 6 (evidence ratio
``e^3 = 20``), and a second cause only when it lowers it by 6 more. Argument: with
correct noise levels and no effect, a nested extension with ``q`` extra parameters
lowers ``chi2`` by a chi-square(q) amount, so it passes with probability
``P(chi2_q > 2q + 6)``: 0.5 % for q = 1, 0.7 % for q = 2 and 3; fifteen candidates,
largely nested in each other, keep the false alarms of a series without any effect
near the 1-in-10 the spec allows at most. ``ambiguous`` is true when another
explanation has at least a third of the named one's weight (:data:`W_AMBIGUOUS`): an
evidence ratio below 3 is "barely worth mentioning" (Jeffreys' scale), so both are
named.

Decision (over the candidates whose effects are not exactly zero).
1. Contradictions (:func:`inverse.contradictions.iwan_contradictions` judged against
   the same noise levels, plus the base fit collapsing to no joint while the damping
   grows) refute the base model: ``none`` is then not a possible answer.
2. The test of fit of :mod:`inverse.diagnosis_noise` (p >= 1e-3) decides which
   candidates bring the data within their noise; the named explanation is the one of
   largest weight among them. If none of them does, the cause is ``unexplained`` and
   the report says by how much the closest candidate misses.
3. ``cause`` is the pair member with the larger weight on its own, ``also`` the other.

Errors and gains (:mod:`inverse.diagnosis_cv`): leave-one-level-out and held-out-top
prediction errors in noise units, ``gain = base_error / extended_error``.
"""
from __future__ import annotations

import numpy as np

from ident.measured import MeasuredData
from inverse.contradictions import NoiseLevels, iwan_contradictions
from inverse.diagnosis_cv import held_out_top, leave_one_out, n_top
from inverse.diagnosis_fit import fit_model
from inverse.diagnosis_models import CAUSES, MODELS, Model, Observations
from inverse.diagnosis_noise import (P_UNEXPLAINED, distortion, fit_test, initial_noise,
                                     noise_from_residuals, test_chi2)
from inverse.diagnosis_params import physical_parameters
from inverse.diagnosis_report import assemble
from inverse.diagnosis_separability import separability
from inverse.diagnosis_text import chi_at_bound, own_contradictions

__all__ = ["CAUSES", "ALL_CAUSES", "T_CAUSE", "W_AMBIGUOUS", "observations_from",
           "diagnose"]

ALL_CAUSES = ("none",) + CAUSES + ("unexplained",)
#: Information-criterion cost of each cause a candidate adds (module doc).
T_CAUSE = 6.0
#: Weight ratio to the named explanation from which another one makes it ambiguous.
W_AMBIGUOUS = 1.0 / 3.0
_REFUTING = ("frequency-rises", "tie-violated", "no-joint")


def observations_from(data: MeasuredData, mode: int | None = None):
    """One mode as :class:`Observations` (noise not yet set), the one-mode table, the
    stds by channel, the raw abscissa and the warnings."""
    warnings = list(data.warnings)
    if mode is None:
        if data.modes.size > 1:
            warnings.append(f"the table holds modes {', '.join(map(str, data.modes))}; "
                            f"diagnosing mode {data.modes[0]} (choose with --mode)")
        mode = int(data.modes[0])
    d = data.for_mode(int(mode))
    if len(set(d.control)) > 1:
        raise ValueError(f"mode {mode} mixes force- and response-controlled levels")
    rc = d.response_abscissa
    if rc:
        raw = np.asarray(d.response_amplitude, float)
        what = {"random": "random test: the response RMS (micro-slip laws hold on it "
                          "up to a constant factor, inverse.random_amplitude)",
                "free-decay": "free decay: the envelope along the decay"}.get(
            str(d.test[0]), "response-controlled: the held response amplitude")
        warnings.append(f"{what} is the abscissa; nonproportional-amplitude does not apply")
    else:
        raw = d.excitation / (d.zeta * d.omega2)
    s = raw / raw.max()
    log_r = None
    if d.response_amplitude is not None and not rc:
        log_r = np.log(d.response_amplitude) - np.log(s)
    elif not rc:
        warnings.append("no response_amplitude column: nonproportional-amplitude cannot "
                        "be tested")
    run = d.run_order.astype(float)
    span = float(run.max() - run.min())
    monotone = bool(np.all(np.diff(d.run_order) > 0) or np.all(np.diff(d.run_order) < 0))
    if monotone:
        warnings.append("the levels were run in order of amplitude: a drift with time "
                        "cannot be told from an amplitude effect, so thermal-drift is not "
                        "tested (shuffle the run order or repeat the lowest level at the "
                        "end)")
    if d.level.size < 7:
        warnings.append(f"only {d.level.size} levels: several causes cannot be told "
                        "apart (see separability)")
    obs = Observations(level=d.level, s=s, omega2=d.omega2, zeta=d.zeta,
                       t_run=(run - run.min()) / span if span > 0 else 0 * run,
                       log_r=log_r, response_controlled=rc, sigma={}, run_monotone=monotone)
    stds = {"omega2": d.omega2_std, "zeta": d.zeta_std, "response": None}
    return obs, d, stds, raw, warnings


def _unavailable(model: Model, obs: Observations):
    if model.has("nonproportional-amplitude"):
        if obs.response_controlled:
            return "under response control the response amplitude is the abscissa"
        if obs.log_r is None:
            return "needs the response_amplitude column"
    if model.has("thermal-drift") and obs.run_monotone:
        return ("the levels were run in order of amplitude: a drift with time cannot be "
                "told from an amplitude effect")
    return None


def _channel_residuals(fit, obs):
    """Residuals of a fit in the channels' own units (for the scatter estimate)."""
    n = obs.n
    return {ch: fit.residual[i * n:(i + 1) * n] * obs.sigma[ch]
            for i, ch in enumerate(obs.channels)}


def _values(obs):
    out = {"omega2": obs.omega2, "zeta": obs.zeta}
    if obs.log_r is not None:
        out["response"] = obs.log_r
    return out


def _test_chi2(fit, obs):
    """chi2 of ``fit`` for the test of fit (identification model error under force
    control, :func:`inverse.diagnosis_noise.test_chi2`)."""
    nc, n = len(obs.channels), obs.n
    res = fit.residual.reshape(nc, n)
    sig = np.stack([obs.sigma[ch] for ch in obs.channels])
    fitted = np.stack([obs.omega2, obs.zeta])[:2] - res[:2] * sig[:2]
    rows = np.broadcast_to(fit.train, (nc, n))
    return test_chi2(res, sig, fitted, np.log(obs.s), rows, not obs.response_controlled)


def _pair_starts(model, fits):
    """Starting points of a pair from the fits of its causes alone: the chi of either,
    each cause's own shape parameters."""
    a, b = (fits[c] for c in model.causes)
    return [np.concatenate([[f.theta[0]], a.theta[1:], b.theta[1:]]) for f in (a, b)]


def _inactive(fit, obs) -> bool:
    """A cause whose non-negative effect came out exactly zero (hardening ``h`` or added
    damping ``q`` on its bound): the candidate is a smaller one in disguise, not an
    explanation of its own."""
    lin = dict(zip(fit.model.linear_names(obs.log_r is not None), fit.linear))
    return any(lin.get(k, 1.0) <= 0.0 for k in ("h", "q"))


def _fit_all(models, obs):
    fits = {m.name: fit_model(m, obs) for m in models if len(m.causes) < 2}
    for m in models:
        if len(m.causes) == 2:
            fits[m.name] = fit_model(m, obs, n_starts=5, extra_starts=_pair_starts(m, fits))
    return fits


def diagnose(data: MeasuredData, mode: int | None = None) -> dict:
    """Diagnose one mode of amplitude-dependent modal data (module doc).

    Returns the spec's JSON object (see :func:`inverse.diagnosis_report.assemble`).
    """
    obs, d, stds, raw, warnings = observations_from(data, mode)
    log_s = np.log(obs.s)
    error = None if obs.log_r is None else {"response": distortion(log_s, obs.zeta)}
    noise = initial_noise(log_s, _values(obs), stds, error)
    obs.sigma = noise.sigma
    models = [m for m in MODELS if _unavailable(m, obs) is None]
    unavailable = {m.name: _unavailable(m, obs) for m in MODELS if _unavailable(m, obs)}
    if "scatter" in noise.source.values():
        known = noise.source["omega2"] == noise.source["zeta"] == "identification"
        first = _fit_all([m for m in models if not m.causes or (len(m.causes) == 1
                                                                and not known)], obs)
        ok = [f for f in first.values() if f.aic is not None]
        ref = min(ok, key=lambda f: f.aic) if ok else first["none"]
        noise = noise_from_residuals(noise, log_s, _channel_residuals(ref, obs), _values(obs))
        obs.sigma = noise.sigma
    fits = _fit_all(models, obs)
    base = fits["none"]
    run_span = float(np.ptp(d.run_order))
    params = {k: physical_parameters(f, obs, run_span) for k, f in fits.items()}

    ic = {k: f.aic + T_CAUSE * len(f.model.causes) for k, f in fits.items()
          if f.aic is not None}
    lo = min(ic.values())
    w = {k: float(np.exp(-(v - lo) / 2)) for k, v in ic.items()}
    total = sum(w.values())
    weight = {k: w.get(k, 0.0) / total for k in fits}
    tests = {k: fit_test(f.chi2, f.n_data, f.n_params, noise) for k, f in fits.items()}

    levels_noise = NoiseLevels(noise.sigma["omega2"], noise.sigma["zeta"],
                               noise.source["omega2"])
    found = iwan_contradictions(d, None, levels_noise)
    base_zeta = obs.zeta - base.residual[obs.n:2 * obs.n] * obs.sigma["zeta"]
    found += own_contradictions(d, params["none"], base_zeta, levels_noise)
    refuted = [c for c in found if c.kind in _REFUTING]
    pool = [k for k in ic if not (refuted and k == "none") and not _inactive(fits[k], obs)]
    testable = [k for k in pool if tests[k]["p_value"] is not None]
    inside = [k for k in testable if tests[k]["p_value"] >= P_UNEXPLAINED]
    if not testable and pool:
        warnings.append("too few levels to test any candidate's fit against the noise "
                        "(as many parameters as data): the choice rests on the weights")
        inside = pool
    if inside:
        best = max(inside, key=weight.get)
        causes = fits[best].model.causes
        if len(causes) == 2:
            causes = tuple(sorted(causes, key=lambda c: -weight.get(c, 0.0)))
        cause, also = (causes[0], list(causes[1:])) if causes else ("none", [])
        rivals = [k for k in pool if k != best and weight[k] >= W_AMBIGUOUS * weight[best]]
    else:
        best = max(pool, key=weight.get) if pool else "none"
        cause, also, rivals = "unexplained", [], []
        f = fits[best]
        lenient = fit_test(_test_chi2(f, obs), f.n_data, f.n_params, noise)["p_value"]
        if not obs.response_controlled and lenient is not None and lenient >= P_UNEXPLAINED:
            warnings.append(
                f"force control: with the model error a distorted FRF gives the identified "
                f"omega2 and zeta (0.17 x their log-amplitude slope) the closest candidate "
                f"({best}) would fit (p = {lenient:.2g}): the misfit may come from the "
                f"identification of nonlinear FRFs; a response-controlled test would tell")
    if best != "none" and chi_at_bound(params[best], best) is not None:
        found.append(chi_at_bound(params[best], best))
    base_err, base_res, base_why = leave_one_out(base, obs)
    cv = {"none": (base_err, base_res, base_why)}
    for k in pool:
        if k != "none":
            cv[k] = leave_one_out(fits[k], obs)
    held = {k: held_out_top(fits[k], obs) for k in {"none", best}}
    if cause == "none" or rivals or obs.n < 8:
        sep = separability(obs, fits, models, unavailable, T_CAUSE, W_AMBIGUOUS)
    else:
        sep = {"inseparable": [], "untestable": {k: v for k, v in unavailable.items()
                                                 if "+" not in k},
               "note": f"not analysed: {cause} is named without a rival on {obs.n} levels"}
    report = assemble(
        obs=obs, d=d, raw=raw, fits=fits, params=params, weight=weight, ic=ic,
        tests=tests, cv=cv, held=held, n_top=n_top(obs.n), noise=noise,
        unavailable=unavailable, contradictions=found, refuted=bool(refuted),
        cause=cause, also=also, best=best, rivals=rivals, separability=sep,
        warnings=warnings, t_cause=T_CAUSE, w_ambiguous=W_AMBIGUOUS)
    report["test"] = str(d.test[0])
    return report
