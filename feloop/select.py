"""The FE-level model choice shared by ``diagnose --case`` and ``update`` (any case).

:func:`fe_select` fits, on the fit levels, the base FE model
(:mod:`feloop.levels`) and the FE realization of every cause the data can
test (:mod:`feloop.causes`), then pairs of the best single cause with
each other cause that earned its cost alone (unless the best single is already so good
that no pair could outweigh it), and lets the one judge choose
(:func:`inverse.fe_selection.judge_extensions` -> :func:`inverse.judge.select`: fit
test, cost per cause, held-out gain > 1; ``unexplained`` when no candidate brings the
fit levels within their noise).

Noise (:func:`fe_noise`): :func:`inverse.judge.noise_model` of the whole series, the
abscissa of the one-mode diagnosis (``excitation / (zeta omega^2)``, or the held
response amplitude): the identification's stds plus the repeatability (the same
curve families), so the FE level and the one-mode diagnosis judge the same table
against the same noise.

Not tested (:func:`untestable`): ``thermal-drift`` when the run order is monotone in
amplitude, a repeat run next to its level counting with it
(:func:`inverse.judge.time_separable`, the one-mode diagnosis's rule: a drift with time
cannot be told from an amplitude effect);
``nonproportional-amplitude`` always (the FE fit compares omega^2 and zeta only: a force
shortfall changes the abscissa of a law that chi already bends; it needs a response
channel); a cause of the catalogue without an FE realization, always, by name.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from feloop.causes import EXTENSIONS, Combined
from feloop.engagement import KT_GRID, check_engagement, engagement
from feloop.joint_forms import MICRO_LIMIT
from feloop.levels import BASE_PARAMETERS, FELevels, Simulator
from feloop.starts import NAIVE_ZETA_SHARE, base_parameters, estimator_start, naive_ln_dc1
from inverse import judge
from inverse.diagnosis.causes import CATALOGUE
from inverse.fe_selection import FitCandidate, fit_together, judge_extensions
from inverse.update import SIMULATION_FAILURES, InternalError, NoiseModel, UpdateProblem

__all__ = ["MICRO_LIMIT", "NAIVE_ZETA_SHARE", "estimator_start", "naive_ln_dc1",
           "base_parameters", "Headline", "fe_noise", "untestable", "fit_base",
           "cold_failure", "fe_select", "chosen_model"]


@dataclass
class Headline:
    """``describe`` of :class:`inverse.update.UpdateProblem`: the headline figures of a
    parameter set: frequency (Hz) and zeta at the held-out levels, top slip over
    phi_max, R~ and phi_max (picklable)."""

    fe: FELevels
    held_out: np.ndarray
    extension: object = None

    def __call__(self, values: dict) -> dict:
        pred = self.fe.predict(values, self.extension)
        h = np.flatnonzero(self.held_out)
        return {"frequency_hz": pred.frequency_hz[h].tolist(), "zeta": pred.zeta[h].tolist(),
                "top_slip_over_phi_max": float(pred.slip_over_phi_max[-1]),
                "R": pred.joint.get("R", math.nan), "phi_max": pred.joint["slip_scale"]}


def fe_noise(data, cap: bool = True):
    """(judge noise, :class:`inverse.update.NoiseModel` of its totals) of one mode's
    levels (module docstring); ``cap`` as in :func:`inverse.judge.noise_model`."""
    jn = judge.noise_model(data.resonant_amplitude, {"omega2": data.omega2, "zeta": data.zeta},
                           {"omega2": data.omega2_std, "zeta": data.zeta_std},
                           data.level, data.run_order,
                           prior=judge.prior_for(data.rig_repeatability), cap=cap)
    dof = [jn.dof[c] for c in ("omega2", "zeta")]
    words = "; ".join(f"{c}: {jn.source[c]}" for c in ("omega2", "zeta"))
    return jn, NoiseModel(jn.total["omega2"], jn.total["zeta"], words,
                          dof=None if all(math.isinf(d) for d in dof) else int(min(dof)))


def untestable(data, catalogue=None, law: str = "iwan4") -> dict:
    """Causes the data cannot test at the FE level, with the reason (module docstring);
    every cause of the ``catalogue`` (default: :data:`inverse.diagnosis.causes.CATALOGUE`)
    without an FE realization (:data:`feloop.causes.EXTENSIONS`), or whose realization
    does not extend joints of ``law`` (``Extension.laws``), is listed as not tested at
    the FE level, never skipped without a word."""
    out = {c: "no FE realization (FE_REALIZATION = None in its cause file): not tested "
              "at the FE level"
           for c in (CATALOGUE if catalogue is None else catalogue) if c not in EXTENSIONS}
    out.update({c: f"its FE realization extends {' and '.join(e.laws)} joints, not {law}"
                for c, e in EXTENSIONS.items() if e.laws and law not in e.laws})
    out["nonproportional-amplitude"] = ("the FE fit compares omega2 and zeta only; a force "
                                        "shortfall needs a response channel")
    if not judge.time_separable(data.level, data.run_order, data.resonant_amplitude):
        out["thermal-drift"] = ("the levels were run in order of amplitude: a drift with "
                                "time cannot be told from an amplitude effect")
    return out


#: Optimizer tolerance of the selection fits (chi2 to about 1e-6 relative).
FIT_TOL = 1e-6


#: Two successful fits from different starts reached the same optimum when their chi2
#: agree within this fraction of ``1 + chi2`` (distinct optima of these models differ
#: by order one; a fit converged to ``FIT_TOL`` repeats its chi2 to ~1e-6).
SAME_OPTIMUM = 1e-3


def fit_base(problem: UpdateProblem, starts, free=BASE_PARAMETERS, only=None) -> tuple:
    """The best fit from ``starts`` (those at the indices ``only``, default all; all of
    them together, each from a cold start: :func:`inverse.fe_selection.fit_together`).
    The best: the lowest chi2 of the converged fits at the lowest optimum
    (:data:`SAME_OPTIMUM`), else the lowest. Returns the fit, every start with the
    fitted ones first, best first (the
    cross-validation folds refit from the first, the others where a fold fails:
    :func:`inverse.fe_selection.cross_validate`), and the indices of the starts that
    reached distinct optima (:data:`SAME_OPTIMUM`; every failed one kept), for a fit
    with more levels (:func:`fe_select`, ``earlier``). When the best fit from the
    starts of ``only`` failed or did not converge, every start is fitted."""
    starts = list(starts)
    idx = list(range(len(starts)) if only is None else only)
    fits, _ = fit_together(problem, [dict(free=free, start=starts[i], tol=FIT_TOL)
                                     for i in idx])
    low = min((f.chi2 for f in fits if f.success), default=math.inf)

    def rank(n):         # a converged fit at the lowest optimum before an unconverged one
        f = fits[n]
        near = f.success and f.converged and f.chi2 <= low + SAME_OPTIMUM * (1.0 + low)
        return not f.success, not near, f.chi2, n

    order = sorted(range(len(fits)), key=rank)
    if only is not None and not (fits[order[0]].success and fits[order[0]].converged):
        return fit_base(problem, starts, free)     # every start, as with no ``only``
    kept = []
    for n in order:
        if not any(fits[n].success and fits[m].success and abs(fits[n].chi2 - fits[m].chi2)
                   <= SAME_OPTIMUM * (1.0 + fits[m].chi2) for m in kept):
            kept.append(n)
    first = [idx[n] for n in order]
    rest = [i for i in range(len(starts)) if i not in first]
    return (fits[order[0]], [starts[i] for i in first + rest],
            (len(starts), tuple(idx[n] for n in kept)))


def cold_failure(fe: FELevels, f, ext=None) -> str | None:
    """Why fit ``f`` cannot be simulated at its optimum from a cold start (None: it
    can). A fit reaches its optimum through warm-started simulations, which can carry
    the balance where a cold start does not converge; every later use of the model
    (profiles, prediction intervals, ``uncertainty``) starts cold. A copy is probed,
    so ``fe`` keeps its warm starts."""
    if f is None:
        return None
    probe = copy.copy(fe)
    probe.reset()
    try:
        probe.predict(f.values, ext)
    except SIMULATION_FAILURES as exc:
        return f"its optimum cannot be simulated from a cold start: {exc}"
    return None


def _problem(base_problem, fe, ext, base_pred, top):
    spec = ext.spec(fe, base_pred, base_problem.noise, top)
    P = dict(base_problem.parameters)
    for s in (spec if isinstance(spec, list) else [spec]):
        P[s.name] = s
    return UpdateProblem(Simulator(fe, ext), base_problem.omega2, base_problem.zeta,
                         base_problem.noise, base_problem.fit_mask, P,
                         describe=Headline(fe, ~base_problem.fit_mask, ext))


def _engaged_refit(data, fe, problem, starts, bfit, base_starts) -> tuple:
    """(starts, fit, its starts best first): where the base optimum's joint has no
    effect (flat, :attr:`inverse.update.Fit.flat`: the joints slipped through or stuck
    at every level, with f0 moved to make up for it), the base model refitted from the
    form's engaged starts (:meth:`feloop.joint_forms.JointForm.engaged_starts`, at the
    first level's frequency), kept when it lowers chi2 (the FE benchmark's draw 6214:
    3182 from every default start, 218 from an engaged one); else as given."""
    engaged = fe.form.engaged_starts(problem.parameters) \
        if set(bfit.flat) & set(fe.form.names) else []
    if not engaged:
        return starts, bfit, base_starts
    f1 = math.sqrt(float(data.omega2[0])) / (2 * math.pi)
    every = list(starts) + [{**e, "f0_hz": f1} for e in engaged]
    fit2, starts2, _ = fit_base(problem, every, fe.base_parameters,
                                list(range(len(starts), len(every))))
    if fit2.success and fit2.chi2 < bfit.chi2 - SAME_OPTIMUM * (1.0 + bfit.chi2):
        return every, fit2, starts2
    return every, bfit, base_starts + every[len(starts):]


def _fit_extension(problem, ext, start_values, joint_starts, base, basins=None,
                   physical=None):
    """Multi-start fit of ``ext`` (its starts x ``joint_starts``, dicts of joint
    parameters) from ``start_values``, ``base``: the base model's parameters; with
    ``physical`` (the base fit's starts, each a full parameter dict) its starts from
    each of them too; only the
    starts of :func:`_basin_starts`; (fit or None, the starts, the distinct optima:
    :func:`fit_base`)."""
    free = tuple(base) + tuple(ext.parameter_names)
    specs = [problem.parameters[n] for n in ext.parameter_names]
    starts = [dict(start_values, **j, **s0) for s0 in ext.start_sets(specs)
              for j in joint_starts]
    starts += [dict(b, **s0) for b in physical or () for s0 in ext.start_sets(specs)]
    f, s, kept = fit_base(problem, starts, free, _basin_starts(starts, basins, ext.cause))
    return (f if f is not None and f.success else None), s, kept


def _basin_starts(starts: list, basins: dict | None, name: str) -> list | None:
    """The indices of the starts of candidate ``name`` whose fit to fewer levels reached
    a distinct optimum (``basins``: the ``basins`` of that :func:`fe_select` result,
    name -> (number of starts, indices)), where that choice had as many starts; else
    None (all of them)."""
    n, kept = (basins or {}).get(name, (None, ()))
    return list(kept) if n == len(starts) and kept else None


def _inactive(ext, f) -> bool:
    """The extension's parameter sits at its ``none`` value (the base model)."""
    bound = {"lower": ext.lower, "upper": ext.upper}
    return any(f.at_bound.get(n) and bound[f.at_bound[n]] == 0.0
               for n in ext.parameter_names) or \
        (ext.cause == "macro-slip" and f.at_bound.get("ln_phimax") == "upper")


def fe_select(data, mask, fe: FELevels, causes=None,
              progress=None, cap: bool = True, earlier: dict | None = None) -> dict:
    """Fit and judge the FE candidates on the fit levels ``mask`` (module docstring);
    ``causes``: the extensions to try (None: every one; empty: the base model alone);
    ``cap``: judge a scatter far above the assumed rig repeatability against it
    (:func:`fe_noise`); ``earlier``: the choice on fewer levels of the same data
    (for the choice with all levels, :func:`feloop.verdict.all_levels_choice`): its
    engagement check is taken, and each candidate fitted only from its starts that
    reached distinct optima there (its ``basins``, :func:`_basin_starts`).

    Returns ``fe``, ``noise`` (update form), ``judge_noise``, ``base`` (FitCandidate),
    ``extensions`` (name -> (Extension, FitCandidate)), ``judged`` (the dict of
    :func:`inverse.fe_selection.judge_extensions`), ``untested`` (cause -> reason),
    ``chosen`` (name of the selected candidate: the closest one when unexplained),
    ``estimator_start`` ("used", or why the paper's estimator gave no start:
    :func:`estimator_start`), ``basins`` (candidate -> the distinct optima of
    :func:`fit_base`) and
    ``engagement`` (:mod:`feloop.engagement`: checked first; data that move the mode
    more than its joints can are one line, exit 2, never a fit)."""
    jn, noise = fe_noise(data, cap)
    engaged = earlier["engagement"] if earlier else \
        check_engagement(engagement(data, fe, noise, 10.0 ** max(KT_GRID)))
    basins = earlier["basins"] if earlier else None
    try:
        return {**_select(data, mask, fe, causes, progress or (lambda s: None), (jn, noise),
                          basins), "engagement": engaged}
    except ValueError as exc:          # the input was checked before: ours, not the user's
        raise InternalError(f"internal failure in the FE model choice: {exc}") from exc


def _select(data, mask, fe, causes, say, noises, basins) -> dict:
    jn, noise = noises                       # fe_noise of the data, computed once
    estimated = estimator_start(data, [int(v) for v in data.level[mask]])
    P, starts = base_parameters(data, mask, fe, estimated)
    base_problem = UpdateProblem(Simulator(fe), data.omega2, data.zeta, noise, mask, P,
                                 describe=Headline(fe, ~mask))
    say("base")
    found = {}
    bfit, base_starts, found["none"] = fit_base(base_problem, starts, fe.base_parameters,
                                                _basin_starts(starts, basins, "none"))
    if not bfit.success:
        raise InternalError(f"the base FE model could not be fitted from any of its "
                            f"{len(base_starts)} starts ({bfit.message})")
    starts, bfit, base_starts = _engaged_refit(data, fe, base_problem, starts, bfit,
                                               base_starts)
    base = FitCandidate((), base_problem, bfit, base_starts)
    try:
        base_pred = fe.predict(bfit.values)
    except SIMULATION_FAILURES:      # the warm starts of the last fit evaluation
        fe.reset()
        base_pred = fe.predict(bfit.values)
    top = int(np.flatnonzero(mask).max())
    skip = untestable(data, law=fe.form.law)
    exts, singles = {}, []
    joint_starts = fe.form.restarts(bfit.values)
    # a base optimum whose joint has no effect (flat: the joints stuck, or slipped
    # through, at every level) is a degenerate start: the causes start from the base
    # fit's starts as well, where the joint works the data
    physical = [{**{n: p.start for n, p in P.items()}, **s0} for s0 in starts] \
        if set(bfit.flat) & set(fe.form.names) else None
    for cause in (EXTENSIONS if causes is None else causes):
        if cause in skip:
            continue
        say(cause)
        ext = EXTENSIONS[cause]
        try:
            prob = _problem(base_problem, fe, ext, base_pred, top)
            f, s, found[cause] = _fit_extension(prob, ext, bfit.values, joint_starts,
                                                fe.base_parameters, basins, physical)
        except (InternalError, ValueError, ArithmeticError) as exc:
            # one cause that cannot be set up is counted and reported, not fatal
            exts[cause] = (ext, FitCandidate((cause,), base_problem, None, [],
                                             f"its fit failed: {exc}"))
            continue
        why = cold_failure(fe, f, ext)
        if why:                  # counted and reported; the judge goes on with the others
            exts[cause] = (ext, FitCandidate((cause,), prob, None, s, why))
            continue
        c = FitCandidate((cause,), prob, f, s)
        if f is not None and _inactive(ext, f):
            c.excluded = "its effect fitted to zero (the base model)"
        exts[cause] = (ext, c)
        singles.append(c)
    ic = {c.name: c.fit.chi2 + 2 * c.fit.k + judge.T_CAUSE
          for c in singles if c.fit is not None and not c.excluded}
    base_ic = bfit.chi2 + 2 * bfit.k
    # a pair (one more parameter, one more cause) has IC >= 2 (k + 1) + 2 T: when the
    # best single is already below that, no pair can outweigh it, so none is fitted
    best_single = min(ic.values(), default=math.inf)
    if ic and best_single > 2 * (bfit.k + 2) + 2 * judge.T_CAUSE:
        first = min(ic, key=ic.get)
        for other in sorted(ic, key=ic.get):
            if other == first or ic[other] >= base_ic:
                continue
            say(f"{first} + {other}")
            pair = Combined(EXTENSIONS[first], EXTENSIONS[other])
            prob = _problem(base_problem, fe, pair, base_pred, top)
            f, s, found[pair.cause] = _fit_extension(prob, pair, exts[first][1].fit.values,
                                                     [{}], fe.base_parameters, basins)
            why = cold_failure(fe, f, pair)
            exts[pair.cause] = (pair, FitCandidate((first, other), prob, None if why else f,
                                                   s, why))
    judged = judge_extensions(base, [c for _, c in exts.values()], jn, progress=say)
    return {"fe": fe, "noise": noise, "judge_noise": jn, "base": base, "extensions": exts,
            "judged": judged, "untested": skip, "chosen": judged["selection"].best,
            "estimator_start": estimated[1] or "used", "basins": found}


def chosen_model(s: dict, name: str | None = None):
    """(extension or None, FitCandidate) of candidate ``name`` (default: the selected,
    or closest, one)."""
    name = s["chosen"] if name is None else name
    if name == "none":
        return None, s["base"]
    return s["extensions"][name]
