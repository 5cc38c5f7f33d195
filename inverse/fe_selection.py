"""Judging fitted simulator extensions by the one judge (:mod:`inverse.judge`).

Works on :class:`inverse.update.UpdateProblem` / :class:`inverse.update.Fit` pairs (any
simulator, e.g. the FE double beam and its cause extensions,
:mod:`feloop.select`). Errors are root-mean-square residuals in noise
units over both channels (omega2 and zeta), ``sqrt(mean r^2)``:

* :func:`cross_validate`: leave-one-level-out over the interior fit levels (the lowest
  and highest fit level always stay in: they anchor the amplitude range). Each fold
  repeats the candidate's whole fit from its *original* start that reached the full
  optimum (never from the full optimum, which has seen the left-out level), and from
  its other starts where that fold's fit fails, the best kept; all these fits from a
  cold start, run together (:func:`fit_together`: the simulations they need at
  one point of their progress in one batch of the simulator); a fold whose fit or
  prediction fails, or whose fit did not converge (:attr:`inverse.update.Fit.converged`:
  its prediction would depend on where the optimizer stopped), is counted as failed, and
  an error over failed folds is ``None`` (``n/a``);
* :func:`held_out_errors`: the levels outside the fit, predicted by the fit itself.

:func:`judge_extensions` applies :func:`inverse.judge.select` (fit test, cost per
cause, held-out gain > 1) to the base model and the extensions. The held-out gain
``base_error / extended_error`` is computed lazily, heaviest Akaike weight first, only
where it can change the answer. :func:`prediction_sd` gives linearized prediction
standard deviations (delta method) with parameters at a bound held there.
"""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field, replace

import numpy as np

from inverse.judge import W_AMBIGUOUS, Candidate, fit_test, select
from inverse.update import Fit, UpdateProblem, fit

__all__ = ["FitCandidate", "held_out_errors", "cross_validate", "fit_together",
           "judge_extensions", "prediction_sd", "fit_test_of"]


@dataclass
class FitCandidate:
    """A fitted explanation: ``causes`` (() for the base model), its ``problem``, its
    ``fit`` (None: every start failed), the original ``starts`` its fit began from, and
    ``excluded`` (why it may not be named, or None)."""

    causes: tuple
    problem: UpdateProblem
    fit: Fit | None
    starts: list = field(default_factory=list)
    excluded: str | None = None
    cv_error: float | None = None
    cv_failed: int = 0
    cv_unconverged: int = 0
    cv_done: bool = False
    chi2_by_channel: dict | None = field(default=None, repr=False)

    @property
    def name(self) -> str:
        return "+".join(self.causes) if self.causes else "none"


def held_out_errors(problem: UpdateProblem, values: dict) -> float | None:
    """rms residual (noise units) at the levels outside ``problem.fit_mask``; nan when
    there are none, None when the simulation fails."""
    held = ~np.asarray(problem.fit_mask, dtype=bool)
    if not held.any():
        return math.nan
    before = problem.failures
    r = problem.residuals(values, held)
    if problem.failures > before:
        return None
    return float(np.sqrt(np.mean(r * r)))


#: A fold fit whose chi2 lies above the full fit's point on its levels by more than
#: this fraction of ``1 + chi2`` has ended in another basin (the margin of
#: :data:`feloop.select.SAME_OPTIMUM`: a fit converged to 1e-6 repeats its chi2 far
#: closer).
ABOVE_FULL = 1e-3


def cross_validate(problem: UpdateProblem, result: Fit, starts, tol: float = 1e-8) -> tuple:
    """Leave-one-level-out rms error over the interior fit levels (module docstring),
    each fold refitted from the first of ``starts`` (the one the full fit's optimum came
    from, :func:`feloop.select.fit_base`), a fold whose fit fails or does not converge
    from it refitted from the others, the best kept; and a fold whose optimum lies above
    the full fit's point on its own levels (which is feasible for it, so no fold optimum
    of the same basin can: :data:`ABOVE_FULL`) refitted from that point, the better
    kept (the FE benchmark's draw 6110: a fold from the start ended where the joint
    slips through, fold error 37.8 against 2.0). Every fit's simulations from a cold
    start, each pass together (:func:`fit_together`). Optimizer tolerance ``tol``.
    Returns ``(error or None, failed folds, of them those whose fit did not
    converge)``."""
    idx = np.flatnonzero(problem.fit_mask)
    starts = list(starts or [{}])
    masks = []
    for i in idx[1:-1]:
        m = problem.fit_mask.copy()
        m[i] = False
        masks.append(m)

    def together(jobs):
        fits, warm = fit_together(problem, [dict(free=result.free, start=s, mask=masks[j],
                                                 tol=tol) for j, s in jobs])
        return list(zip(fits, warm))

    def worse(fw):
        return (not (fw[0].success and fw[0].converged), fw[0].chi2)

    best = together([(j, starts[0]) for j in range(len(masks))])
    retry = [j for j, fw in enumerate(best) if not (fw[0].success and fw[0].converged)]
    again = together([(j, s) for j in retry for s in starts[1:]])
    for n, j in enumerate(retry):
        best[j] = min([best[j]] + again[n * (len(starts) - 1):(n + 1) * (len(starts) - 1)],
                      key=worse)
    full = _residuals(problem, [result.values] * len(masks), [None] * len(masks), masks)
    above = [j for j, ((f, _), r) in enumerate(zip(best, full)) if r is not None
             and f.chi2 > float(r @ r) + ABOVE_FULL * (1.0 + float(r @ r))]
    optimum = {**starts[0], **{n: result.values[n] for n in result.free}}
    for j, fw in zip(above, together([(j, optimum) for j in above])):
        best[j] = min([best[j], fw], key=worse)
    one = [np.arange(problem.fit_mask.size) == i for i in idx[1:-1]]
    r2, failed, unconverged = [], 0, 0
    for (f, _), r in zip(best, _residuals(problem, [f.values for f, _ in best],
                                          [w for _, w in best], one)):
        if not f.converged or r is None:
            failed += 1
            unconverged += f.feasible and not f.converged
            continue
        r2.extend((r * r).tolist())
    if failed or not r2:
        return None, failed, unconverged
    return float(np.sqrt(np.mean(r2))), failed, unconverged


def _residuals(problem: UpdateProblem, values, warm, masks) -> list:
    """The residuals of every parameter set on its mask, each simulated from its warm
    starts (together, by the simulator's batch, where it has one); None where the
    simulation failed (counted in ``problem.failures``)."""
    batch = getattr(problem.simulate, "batch", None)
    outs = batch(values, warm)[0] if batch is not None and None not in warm else None
    out = []
    for k, (v, m) in enumerate(zip(values, masks)):
        before = problem.failures
        r = problem.residuals(v, m) if outs is None else problem.residuals_of(outs[k], m)
        out.append(None if problem.failures > before else r)
    return out


class _Job(threading.Thread):
    """One fit of :func:`fit_together` in a thread of its own, whose simulations are
    requests to the coordinator (the caller's thread); only one of the two runs at a
    time, so the fits run one after another between batches."""

    def __init__(self, problem: UpdateProblem, kwargs: dict):
        super().__init__(daemon=True)
        self.kwargs, self.request, self.reply = kwargs, None, None
        self.result = self.error = None
        self.done = False
        self._go, self._back = threading.Semaphore(0), threading.Semaphore(0)
        self.problem = replace(problem, simulate=_Requests(self), failures=0)

    def run(self) -> None:
        self._go.acquire()
        try:
            self.result = fit(self.problem, **self.kwargs)
        except BaseException as exc:       # handed to the coordinator, raised there
            self.error = exc
        self.done = True
        self._back.release()

    def ask(self, request):
        """In the job's thread: hand ``request`` over and wait for the reply."""
        self.request = request
        self._back.release()
        self._go.acquire()
        return self.reply

    def resume(self, reply=None) -> None:
        """In the coordinator's thread: reply and wait for the next request."""
        self.reply = reply
        self._go.release()
        self._back.acquire()


@dataclass
class _Requests:
    """The simulator of a job's problem: a call (one set, from the job's warm starts,
    which it then advances) or a batch (sets from them, leaving them) is a request."""

    job: _Job

    def __call__(self, values: dict):
        out = self.job.ask((False, [values]))[0]
        if isinstance(out, BaseException):
            raise out
        return out

    def batch(self, values: list, warm=None) -> tuple:
        return self.job.ask((True, list(values))), None


def _once(simulate, values: list, warm: list) -> tuple:
    """``simulate.batch(values, warm)``, a set asked for again from the same warm starts
    (the folds' fits from one start begin at one point) simulated once."""
    key = [(tuple(sorted(v.items())),
            None if w is None else tuple(sorted((k, id(g)) for k, g in w.items())))
           for v, w in zip(values, warm)]
    first: dict = {}
    index = [first.setdefault(k, len(first)) for k in key]
    pick = {}                              # unique set -> where it is first asked for
    for at, i in enumerate(index):
        pick.setdefault(i, at)
    outs, after = simulate.batch([values[at] for at in pick.values()],
                                 [warm[at] for at in pick.values()])
    return [outs[i] for i in index], [after[i] for i in index]


def fit_together(problem: UpdateProblem, jobs: list, cold: bool = True) -> tuple:
    """``fit(problem, **job)`` of every job (its keyword arguments), each from a cold start
    (empty warm starts; ``cold=False``: from the simulator's own), with the simulations
    all the fits need at one point of their progress solved in one call of the
    simulator's ``batch(values, warm)`` (:mod:`inverse.update`): each fit's results are
    the ones it has run alone from that start. Returns the fits and each fit's warm
    starts at its end (None for all when the simulator has no batch: then one fit after
    another)."""
    if getattr(problem.simulate, "batch", None) is None:
        return [fit(problem, **job) for job in jobs], [None] * len(jobs)
    threads = [_Job(problem, job) for job in jobs]
    warm = [{} if cold else None for _ in jobs]
    for t in threads:
        t.start()
        t.resume()
    live = [n for n, t in enumerate(threads) if not t.done]
    while live:
        values, owner = [], []
        for n in live:
            values += threads[n].request[1]
            owner += [n] * len(threads[n].request[1])
        outs, after = _once(problem.simulate, values, [warm[n] for n in owner])
        at = 0
        for n in live:
            many, vs = threads[n].request
            if not many:
                warm[n] = after[at]
            reply, at = outs[at:at + len(vs)], at + len(vs)
            threads[n].resume(reply)
        live = [n for n in live if not threads[n].done]
    for t in threads:
        if t.error is not None:
            raise t.error
        problem.failures += t.problem.failures
    return [t.result for t in threads], warm


def _cv(c: FitCandidate, say) -> None:
    if not c.cv_done and c.fit is not None:
        say(f"cross-validation: {c.name}")
        c.cv_error, c.cv_failed, c.cv_unconverged = cross_validate(c.problem, c.fit,
                                                                   c.starts)
        c.cv_done = True


def _untestable(c: FitCandidate, base: FitCandidate) -> str | None:
    """Why no held-out gain can be measured (cross-validated without a failure and
    still no error: no interior fit level), or None."""
    if (c.causes and c.cv_done and base.cv_done and not (c.cv_failed or base.cv_failed)
            and (c.cv_error is None or base.cv_error is None)):
        return "fewer than 3 fit levels: none to leave out"
    return None


def _candidates(cands, base: FitCandidate) -> list:
    base_cv = base.cv_error
    out = []
    for c in cands:
        if c.fit is None:
            out.append(Candidate(c.causes, 0, math.inf, 0, None, 1,
                                 c.excluded or "every start of its fit failed"))
            continue
        gain = None
        if c.causes and c.cv_done and c.cv_error is not None and base_cv is not None:
            gain = base_cv / c.cv_error if c.cv_error > 0 else math.inf
        if c.chi2_by_channel is None:
            c.chi2_by_channel = c.problem.chi2_by_channel(c.fit.values)
        out.append(Candidate(c.causes, c.fit.k, c.fit.chi2, c.fit.n, gain, c.cv_failed,
                             c.excluded, c.chi2_by_channel or None, _untestable(c, base)))
    return out


def _reason(c: FitCandidate, sel) -> str | None:
    why = sel.why_not.get(c.name)
    if why and c.causes and not c.cv_done and why.startswith("no held-out gain"):
        return ("held-out gain not computed: its weight is below a third of the named "
                "one's, so it could not be named")
    return why


def judge_extensions(base: FitCandidate, extensions: list, noise, progress=None) -> dict:
    """The one rule (:func:`inverse.judge.select`) over ``base`` and ``extensions``
    (:class:`FitCandidate`); ``noise`` an :class:`inverse.judge.NoiseModel`.

    Returns ``selection`` (the judge's answer), ``candidates`` (name -> FitCandidate)
    and ``evidence`` (per candidate: ``chi2``, ``n_params``, ``weight``, ``fit_test``,
    ``converged``, ``cv_error``, ``gain``, ``gain_computed``, ``failed_folds`` with
    ``unconverged_folds`` of them, ``gain_untestable``, ``why_not``)."""
    say = progress or (lambda s: None)
    cands = [base] + list(extensions)
    _cv(base, say)
    base_cv = base.cv_error
    # weights and fit tests do not need the gain: compute the gain lazily, heaviest
    # first, until the named candidate and its possible rivals are settled
    while True:
        sel = select(_candidates(cands, base), noise)
        pending = [c for c in cands if c.causes and not c.cv_done and c.fit is not None
                   and not c.excluded and sel.tests[c.name].passes()]
        if not pending:
            break
        top = max((sel.weights[k] for k in sel.eligible), default=0.0)
        need = [c for c in pending if sel.weights[c.name] >= W_AMBIGUOUS * top]
        named = next((c for c in cands if c.name == sel.best), None)
        if not need and named is not None and len(named.causes) > 1:
            # a pair is named only when it predicts unseen levels better than its
            # causes alone: their gains are needed too
            need = [c for c in cands if len(c.causes) == 1 and c.causes[0] in named.causes
                    and not c.cv_done and c.fit is not None]
        if not need:
            break
        _cv(max(need, key=lambda c: sel.weights[c.name]), say)
    ev = {}
    for c in cands:
        gain = None
        if c.causes and c.cv_error is not None and base_cv is not None:
            gain = base_cv / c.cv_error if c.cv_error > 0 else math.inf
        t = sel.tests[c.name]
        ev[c.name] = {"causes": list(c.causes),
                      "chi2": None if c.fit is None else c.fit.chi2,
                      "n_params": None if c.fit is None else c.fit.k,
                      "converged": None if c.fit is None else c.fit.converged,
                      "weight": sel.weights[c.name], "fit_test": t.to_json(),
                      "cv_error": c.cv_error, "gain": gain,
                      "gain_computed": c.cv_done, "failed_folds": c.cv_failed,
                      "unconverged_folds": c.cv_unconverged,
                      "gain_untestable": _untestable(c, base),
                      "failed_simulations": 0 if c.fit is None else c.fit.failed_simulations,
                      "why_not": _reason(c, sel)}
    return {"selection": sel, "candidates": {c.name: c for c in cands}, "evidence": ev,
            "base_cv_error": base_cv}


def prediction_sd(problem: UpdateProblem, result: Fit, mask, rel_step: float = 1e-3) -> dict:
    """Standard deviations of the predicted frequency (Hz) and zeta at the levels
    ``mask``: ``J C J^T`` with ``C`` the fit's covariance (parameters at a bound held
    there: zero rows, :func:`inverse.update.fit`) times its misfit scale and ``J`` by
    forward differences (``rel_step`` of each parameter's ``step``, taken into the
    parameter's range)."""
    m = np.asarray(mask, dtype=bool)
    n = int(m.sum())
    if result.cov is None or not result.free or n == 0:
        return {"frequency_hz": [math.nan] * n, "zeta": [math.nan] * n}

    def out(v):
        om2, ze = problem.simulate(v)
        return np.concatenate([np.sqrt(om2[m]) / (2 * math.pi), ze[m]])

    y0 = out(result.values)
    J = np.zeros((y0.size, result.k))
    for j, name in enumerate(result.free):
        if result.at_bound.get(name):
            continue                                    # held at the bound
        p = problem.parameters[name]
        h = rel_step * p.step
        if result.values[name] + h > p.upper:
            h = -h
        v = dict(result.values)
        v[name] = v[name] + h
        J[:, j] = (out(v) - y0) / h
    var = np.einsum("ij,jk,ik->i", J, result.cov * result.misfit_scale, J)
    sd = np.sqrt(np.maximum(var, 0.0))
    return {"frequency_hz": sd[:n].tolist(), "zeta": sd[n:].tolist()}


def fit_test_of(result: Fit, noise):
    """The judge's fit test of one fit."""
    return fit_test(result.chi2, result.n, result.k, noise)
