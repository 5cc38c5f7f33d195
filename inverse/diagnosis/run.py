"""Model-form diagnosis: what the Iwan modal model gets wrong, why, and the gain
(``docs/formats/diagnosis.md``, v2).

Candidates: the base model (``none``), each testable cause of the catalogue
(:mod:`inverse.diagnosis.causes`) alone and every pair, fitted by weighted least
squares (:mod:`inverse.diagnosis.fit`) against the noise of :mod:`inverse.judge`:
the identification's stds plus the test's repeatability (from repeats, else the
scatter about a model-free smooth curve), never the residuals of a model being judged.
A cause the data cannot test (``testable``: a drift on a monotone run order, a force
shortfall without a response channel) is not fitted and is listed with the reason.

Decision: the one rule of :func:`inverse.judge.select`. Every candidate gets
``IC = chi2 + 2k + T n_causes`` (``T`` = :data:`T_CAUSE` = 6: a cause is worth naming
when it lowers the AIC by more than 6, evidence ratio ``e^3 = 20``; with correct noise
and no effect a nested extension with ``q`` extra parameters passes with probability
``P(chi2_q > 2q + 6)``, 0.5-0.7 % for q = 1-3; with a noise estimated on few degrees
of freedom the drop of chi2 enters at its known-noise equivalent, which keeps that
rate) and its Akaike weight. Eligible are the
candidates within the noise (fit test, p >= 1e-3) whose held-out (leave-one-level-out)
gain exceeds 1 (on a series too short to leave a level out, where no gain can be
measured, by the fit test and IC alone); the named explanation is the eligible one of
largest weight,
``ambiguous`` when another has a third of its weight (:data:`W_AMBIGUOUS`; an evidence
ratio below 3 is "barely worth mentioning", Jeffreys). Contradictions
(:func:`inverse.contradictions.iwan_contradictions`, the base fit collapsing to no
joint while the damping grows) refute the base model: ``none`` is then excluded. An
extension whose non-negative effect came out exactly 0 is the base model in disguise
and is excluded. No eligible candidate: ``unexplained``, with the closest miss.

The verdict is also taken with the identification's noise alone
(``verdict_identification_only``, refitting every candidate), so the report says
whether it follows from the repeatability; and, where a channel's scatter far above the
assumed rig repeatability was judged against it (:mod:`inverse.judge.prior`), with
that scatter as the noise (``verdict_own_scatter``).
"""
from __future__ import annotations

import numpy as np
from scipy import stats

from ident.measured import MeasuredData
from ident.modal_data import mean_per_level
from inverse.contradictions import NoiseLevels, iwan_contradictions
from inverse.diagnosis.causes import CATALOGUE, CAUSES
from inverse.diagnosis.cv import held_out_top, leave_one_out, n_top, untestable_gain
from inverse.diagnosis.fit import fit_model, profile_interval
from inverse.diagnosis.intervals import (averaging_weights, model_averaged,
                                         prediction_intervals)
from inverse.diagnosis.models import MODELS, Observations
from inverse.diagnosis.noise import one_mode_noise, test_chi2
from inverse.diagnosis.params import physical_parameters
from inverse.diagnosis.report import assemble
from inverse.diagnosis.separability import separability
from inverse.diagnosis.text import chi_at_bound, own_contradictions
from inverse.judge import (P_UNEXPLAINED, T_CAUSE, W_AMBIGUOUS, Candidate, at_bound, prior_for,
                           effective_dof, select, time_separable)

__all__ = ["CAUSES", "ALL_CAUSES", "T_CAUSE", "W_AMBIGUOUS", "observations_from",
           "diagnose"]

ALL_CAUSES = ("none",) + CAUSES + ("unexplained",)
_REFUTING = ("frequency-rises", "tie-violated", "no-joint")


def observations_from(data: MeasuredData, mode: int | None = None):
    """One mode as :class:`Observations` (noise not yet set), the one-mode table (rows
    sorted by level and run order; repeats kept), the stds by channel, the raw abscissa
    and the warnings."""
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
    raw = d.resonant_amplitude
    if rc:
        what = {"random": "random test: the response RMS (micro-slip laws hold on it "
                          "up to a constant factor, inverse.random_amplitude)",
                "free-decay": "free decay: the envelope along the decay"}.get(
            str(d.test[0]), "response-controlled: the held response amplitude")
        warnings.append(f"{what} is the abscissa; nonproportional-amplitude does not apply")
    s = raw / raw.max()
    log_r = None
    if d.response_amplitude is not None and not rc:
        log_r = np.log(d.response_amplitude) - np.log(s)
    run = d.run_order.astype(float)
    span = float(run.max() - run.min())
    n_levels = np.unique(d.level).size
    if n_levels < d.level.size:
        warnings.append(f"{d.level.size - n_levels} repeated run(s) of "
                        f"{np.sum(np.bincount(d.level) > 1)} level(s): the repeatability "
                        "comes from them")
    if n_levels < 7:
        warnings.append(f"only {n_levels} levels: several causes cannot be told "
                        "apart (see separability)")
    obs = Observations(level=d.level, s=s, omega2=d.omega2, zeta=d.zeta,
                       t_run=(run - run.min()) / span if span > 0 else 0 * run,
                       log_r=log_r, response_controlled=rc, sigma={},
                       run_monotone=not time_separable(d.level, d.run_order, raw), run_span=span,
                       level_ids=d.level)
    stds = {"omega2": d.omega2_std, "zeta": d.zeta_std, "response": None}
    return obs, d, stds, raw, warnings


def _pair_starts(model, fits):
    """Starting points of a pair from the fits of its causes alone: the chi of either,
    each cause's own shape parameters."""
    a, b = (fits[c] for c in model.causes)
    return [np.concatenate([[f.theta[0]], a.theta[1:], b.theta[1:]]) for f in (a, b)]


def _inactive(fit, obs) -> str | None:
    """Why a candidate is the base model in disguise: a cause whose non-negative effect
    came out exactly zero (its ``EFFECT`` on its bound)."""
    lin = dict(zip(fit.model.linear_names(obs.log_r is not None), fit.linear))
    for c in fit.model.causes:
        e = CATALOGUE[c].EFFECT
        if e is not None and lin.get(e, 1.0) <= 0.0:
            return f"{c}: its effect {e} came out 0 (on its bound)"
    return None


def _fit_all(models, obs, also_from=None):
    """Every model fitted (grid search, then refinement); ``also_from``: fits of the
    same models against another noise, whose optima are refined too (the best of all
    starts is kept, so the fit is never worse than either search alone)."""
    def more(m):
        return [also_from[m.name].theta] if also_from and m.name in also_from else []
    fits = {m.name: fit_model(m, obs, extra_starts=more(m) or None)
            for m in models if len(m.causes) < 2}
    for m in models:
        if len(m.causes) == 2:
            fits[m.name] = fit_model(m, obs, n_starts=5,
                                     extra_starts=_pair_starts(m, fits) + more(m))
    return fits


def _candidates(fits, cv, obs, refuted):
    base_err, base_failed = cv["none"][0], cv["none"][3]
    out = []
    for k, f in fits.items():
        err, failed = cv[k].error, cv[k].failed
        gain = None if base_err is None or err is None or err <= 0 else base_err / err
        if gain is None and k != "none":
            failed += base_failed        # a gain over the base model's failed folds
        excluded = ("refuted by the contradictions" if refuted and k == "none"
                    else _inactive(f, obs) if k != "none" else None)
        if f.failed:
            excluded, failed = "the fit failed", failed + 1
        r = f.residual.reshape(len(obs.channels), obs.n)[:, np.asarray(f.train, bool)]
        out.append(Candidate(f.model.causes, f.n_params, f.chi2, f.n_data,
                             gain=1.0 if k == "none" else gain, failures=failed,
                             excluded=excluded,
                             gain_untestable=untestable_gain(cv[k], cv["none"]),
                             chi2_by_channel=dict(zip(obs.channels, np.sum(r**2, axis=1)))))
    return out


def level_means_and_noise(obs, d, stds, raw, cap: bool = True):
    """The judge's noise model of one mode (identification plus repeatability,
    :func:`inverse.diagnosis.noise.one_mode_noise`; sets ``obs.sigma``), the level means
    and the noise of each mean (over the square root of the level's runs): what every
    command states contradictions against. Arguments: :func:`observations_from`'s;
    ``cap`` as in :func:`inverse.judge.noise_model`.

    Returns (noise model, level means, :class:`inverse.contradictions.NoiseLevels`)."""
    noise = one_mode_noise(obs, stds, raw, d.run_order, d.identified_at_peak,
                           prior_for(d.rig_repeatability), cap=cap)
    obs.sigma = noise.total
    dm, _ = mean_per_level(d)
    first = np.r_[0, np.flatnonzero(np.diff(obs.levels)) + 1]
    cnt = np.diff(np.r_[first, obs.n])
    levels = NoiseLevels(noise.total["omega2"][first] / np.sqrt(cnt),
                         noise.total["zeta"][first] / np.sqrt(cnt), noise.source["omega2"],
                         noise.dof["omega2"], noise.dof["zeta"])
    return noise, dm, levels


def _contradictions(dm, levels, obs, base_zeta, base_params):
    """Contradictions on the level means, against the total noise of a mean."""
    first = np.r_[0, np.flatnonzero(np.diff(obs.levels)) + 1]
    cnt = np.diff(np.r_[first, obs.n])
    zm = np.add.reduceat(base_zeta, first) / cnt
    return (iwan_contradictions(dm, None, levels)
            + own_contradictions(dm, base_params, zm, levels))


def _judged(models, obs, noise, dm, mean_noise):
    """Every candidate fitted against ``obs.sigma`` and cross-validated, the
    contradictions on the base fit, and the rule's selection against ``noise``:
    (fits, physical parameters, contradictions, refuted, cv, selection)."""
    fits = _fit_all(models, obs)
    params = {k: physical_parameters(f, obs) for k, f in fits.items()}
    base_zeta = obs.zeta - fits["none"].residual[obs.n:2 * obs.n] * obs.sigma["zeta"]
    found = _contradictions(dm, mean_noise, obs, base_zeta, params["none"])
    refuted = any(c.kind in _REFUTING for c in found)
    cv = {k: leave_one_out(f, obs) for k, f in fits.items()}
    return fits, params, found, refuted, cv, select(_candidates(fits, cv, obs, refuted), noise)


def _identification_only(models, obs, noise, cv, refuted, fits):
    """The verdict with the identification's noise alone (every candidate refitted, also
    from its optimum in ``fits``, the fits with the total noise; the held-out gains are
    those of the folds with the total noise) and its failed fits, or (None, why, None)."""
    if not noise.has_identification():
        return None, "the table has no identification uncertainty (no std columns)", None
    if all(np.all(r == 0) for r in noise.repeatability.values()):
        return None, "the repeatability adds nothing to the identification's noise", None
    only = noise.identification_only()
    sig = obs.sigma
    obs.sigma = only.total
    try:
        fits = _fit_all(models, obs, also_from=fits)
        sel = select(_candidates(fits, cv, obs, refuted), only)
    finally:
        obs.sigma = sig
    return sel, None, {"fits": sum(f.failed for f in fits.values()),
                       "unconverged_fits": _unconverged(fits)}


def _own_scatter(models, obs, d, stds, raw, noise):
    """The verdict with the data's own scatter as the noise where a channel's was judged
    against the assumed rig repeatability (:meth:`inverse.judge.NoiseModel.capped`;
    every candidate, fold and contradiction again) and its failed fits and folds, or
    (None, None) when none was."""
    if not noise.capped():
        return None, None
    sig = obs.sigma
    try:
        fits, _, _, _, cv, sel = _judged(models, obs,
                                         *level_means_and_noise(obs, d, stds, raw, cap=False))
    finally:
        obs.sigma = sig
    return sel, {"fits": sum(f.failed for f in fits.values()),
                 "folds": sum(v.failed for v in cv.values()),
                 "unconverged_fits": _unconverged(fits)}


def _unconverged(fits) -> int:
    """How many of ``fits`` (name -> Fit) gave a chi2 but did not converge."""
    return sum(not f.failed and not f.converged for f in fits.values())


def _profiles(fit, obs, dof):
    """Profile intervals of the nonlinear parameters of ``fit`` on a bound, the failed
    profile points and the unconverged ones."""
    out, failed, unconverged = {}, 0, 0
    threshold = float(stats.f.ppf(0.95, 1, dof)) if np.isfinite(dof) else 3.841
    for j, (v, (_, lo, hi, _)) in enumerate(zip(fit.theta, fit.model.nonlinear)):
        if at_bound(v, lo, hi)[0]:
            out[j], k, u = profile_interval(fit, obs, j, threshold)
            failed, unconverged = failed + k, unconverged + u
    return out, failed, unconverged


def diagnose(data: MeasuredData, mode: int | None = None) -> dict:
    """Diagnose one mode of amplitude-dependent modal data (module doc).

    Returns the spec's JSON object (see :func:`inverse.diagnosis.report.assemble`).
    """
    obs, d, stds, raw, warnings = observations_from(data, mode)
    noise, dm, mean_noise = level_means_and_noise(obs, d, stds, raw)
    peak = d.identified_at_peak
    if peak is not None and peak.any():
        warnings.append(f"levels {', '.join(map(str, np.unique(d.level[peak])))} were "
                        "identified at their peak amplitude (--amplitude-refit): their "
                        "response carries no identification-distortion error")
    untestable = {c: CATALOGUE[c].testable(obs)[1] for c in CAUSES
                  if not CATALOGUE[c].testable(obs)[0]}
    models = [m for m in MODELS if not set(m.causes) & set(untestable)]
    unavailable = {m.name: "; ".join(untestable[c] for c in m.causes if c in untestable)
                   for m in MODELS if set(m.causes) & set(untestable)}
    fits, params, found, refuted, cv, sel = _judged(models, obs, noise, dm, mean_noise)
    best = sel.best
    if sel.unexplained:
        f = fits[best]
        nc, n = len(obs.channels), obs.n
        res = f.residual.reshape(nc, n)
        sig = np.stack([obs.sigma[ch] for ch in obs.channels])
        fitted = np.stack([obs.omega2, obs.zeta]) - res[:2] * sig[:2]
        lenient = select([Candidate(f.model.causes, f.n_params, test_chi2(
            res, sig, fitted, np.log(obs.s), np.broadcast_to(f.train, (nc, n)),
            not obs.response_controlled, obs.levels, peak), f.n_data, gain=2.0)], noise)
        p = lenient.tests[best].p_value
        if not obs.response_controlled and p is not None and p >= P_UNEXPLAINED:
            warnings.append(
                f"force control: with the model error a distorted FRF gives the identified "
                f"omega2 and zeta (0.17 x their log-amplitude slope) the closest candidate "
                f"({best}) would fit (p = {p:.2g}): the misfit may come from the "
                f"identification of nonlinear FRFs; a response-controlled test would tell")
    if best != "none" and chi_at_bound(params[best], best) is not None:
        found.append(chi_at_bound(params[best], best))
    sel_id, why_id, id_failed = _identification_only(models, obs, noise, cv, refuted, fits)
    sel_own, own_failed = _own_scatter(models, obs, d, stds, raw, noise)
    averaged = averaging_weights(sel)
    held = {k: held_out_top(fits[k], obs) for k in {"none", best} | set(averaged)}
    predictions = model_averaged(       # unexplained: widened by the closest's misfit
        {k: prediction_intervals(held[k][2], obs, noise.dof,
                                 misfit_of=fits[k] if sel.unexplained else None)
         for k in averaged if held[k][0] is not None}, averaged)
    profiles, profile_failures, profile_unconverged = _profiles(fits[best], obs,
                                                                effective_dof(noise))
    if sel.cause == "none" or sel.rivals or np.unique(obs.levels).size < 8:
        sep = separability(obs, fits, models, unavailable, T_CAUSE, W_AMBIGUOUS,
                           effective_dof(noise))
    else:
        sep = {"inseparable": [], "untestable": dict(untestable),
               "note": f"not analysed: {sel.cause} is named without a rival on "
                       f"{np.unique(obs.levels).size} levels"}
    report = assemble(
        obs=obs, d=d, raw=raw, fits=fits, params=params, selection=sel, cv=cv,
        held=held, n_top=n_top(np.unique(obs.levels).size), noise=noise, averaged=averaged,
        unavailable=unavailable, untestable=untestable, contradictions=found,
        refuted=refuted, separability=sep, warnings=warnings, predictions=predictions,
        selection_id_only=sel_id, why_id_only=why_id, id_only_failures=id_failed,
        profiles=profiles, profile_unconverged=profile_unconverged,
        profile_failures=profile_failures, selection_own_scatter=sel_own,
        own_scatter_failures=own_failed)
    report["test"] = str(d.test[0])
    return report
