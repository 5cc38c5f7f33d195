"""Noise of a series: identification uncertainty plus the test's repeatability (the
module doc of :mod:`inverse.judge`, "Noise model")."""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.stats import chi2 as chi2_dist

from inverse.judge.prior import RIG_REPEATABILITY, RepeatabilityPrior, pool

__all__ = ["time_separable", "MIN_REPEAT_DOF", "SCATTER_P", "FLOORS", "NoiseModel",
           "noise_model", "smooth_scatter", "pooled_repeats"]

#: Repeats with fewer degrees of freedom are pooled with the smooth-curve scatter.
MIN_REPEAT_DOF = 6
#: The scatter counts as repeatability when a chi-square test says it exceeds the
#: identification's noise at this level (module doc of :mod:`inverse.judge`).
SCATTER_P = 0.05
#: Noise floors: relative for omega2 and zeta, absolute for other channels.
FLOORS = {"omega2": 1e-9, "zeta": 1e-7}
_DEFAULT_FLOOR = 1e-2
_RELATIVE = ("omega2", "zeta")


@dataclass
class NoiseModel:
    """Noise per channel and row: ``identification``, ``repeatability``, ``total`` (each
    ``{channel: (n,)}`` in the channel's units), ``source`` (words per channel), ``dof``
    (per channel, ``math.inf`` when known), ``kind`` (``repeats``, ``smooth``,
    ``repeats+smooth`` or ``identification``; ``+assumed`` / ``+stated`` when the rig's
    repeatability was pooled in, ``+assumed+capped`` when a scatter far above it was
    judged against it, ``assumed`` / ``stated`` alone without a scatter) and
    ``assumed`` (per channel with a prior: its ``rel_sd``, ``dof``, whether it was
    ``used``, the conflict check's ``conflict_p``, ``capped`` and ``kind``;
    :mod:`inverse.judge.prior`)."""

    identification: dict
    repeatability: dict
    total: dict
    source: dict
    dof: dict
    kind: dict = field(default_factory=dict)
    floor: dict = field(default_factory=dict)
    assumed: dict = field(default_factory=dict)

    @property
    def channels(self) -> list:
        return list(self.total)

    def identification_only(self) -> "NoiseModel":
        """The same noise with the repeatability part set to 0 (known noise)."""
        zero = {c: np.zeros_like(v) for c, v in self.repeatability.items()}
        total = {c: np.maximum(self.identification[c], self.floor.get(c, 0.0))
                 for c in self.total}
        return replace(self, repeatability=zero, total=total,
                       source={c: "identification only" for c in self.total},
                       dof={c: math.inf for c in self.total},
                       kind={c: "identification" for c in self.total})

    def capped(self) -> list:
        """The channels whose scatter was judged against the assumed repeatability
        (:func:`inverse.judge.prior.pool`)."""
        return [c for c, a in self.assumed.items() if a and a.get("capped")]

    def has_identification(self) -> bool:
        """Whether any channel has an identification part."""
        return any(np.any(v > 0) for v in self.identification.values())

    def to_json(self, values: dict) -> dict:
        """``{channel: {source, identification_rel, repeatability_rel, total_rel, dof}}``
        (median relative sd; absolute for channels that are not relative)."""
        out = {}
        for c in self.total:
            scale = np.abs(values[c]) if c in _RELATIVE else 1.0

            def rel(a):
                return float(np.median(a / scale))

            out[c] = {"source": self.source[c], "kind": self.kind.get(c),
                      "identification_rel": rel(self.identification[c]),
                      "repeatability_rel": rel(self.repeatability[c]),
                      "total_rel": rel(self.total[c]),
                      "relative": c in _RELATIVE,
                      "dof": None if math.isinf(self.dof[c]) else float(self.dof[c]),
                      "assumed_repeatability": self.assumed.get(c)}
        return out


#: Exponents of the power laws of amplitude the model-free curves may take (a fixed
#: grid; each exponent a curve uses counts as one fitted parameter).
EXPONENTS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0, 1.15, 1.3, 1.5, 1.75, 2.0, 2.5, 3.0,
             4.5)
#: Time constants (runs) of the warm-up drifts ``exp(-run / tau)`` a curve may add.
WARM_UP_RUNS = (0.7, 1.5, 3.0)
#: A run-order term is taken out when it lowers the leave-one-out error by this factor.
RUN_ORDER_GAIN = 0.3
#: Curves in amplitude that the run-order terms are tried with (the best by PRESS).
_N_TRIED = 5
#: Relative round-off of a fitted value: leave-one-out errors below it are ties.
ROUNDOFF = 1e-12


def _curves(x):
    """Model-free curve families over the log amplitude ``x`` (n,): (parameters,
    columns). Lines and parabolas in ``x``; ``1, s^p``; ``1, x, s^p``; ``1, s^p, s^q``
    (``s = exp(x - max x)``, ``p, q`` from :data:`EXPONENTS`: power laws of amplitude,
    their sums, a bend at the top); the Muntz polynomial ``1, x, s^(1/3), s^(2/3), s``."""
    n = x.size
    s, one, xc = np.exp(x - x.max()), np.ones(n), x - x.mean()
    sp = {p: s**p for p in EXPONENTS}
    yield 2, [one, xc]
    yield 3, [one, xc, xc**2]
    for p in EXPONENTS:
        yield 3, [one, sp[p]]
        yield 4, [one, xc, sp[p]]
    for p, q in itertools.combinations(EXPONENTS, 2):
        yield 5, [one, sp[p], sp[q]]
    yield 5, [one, xc, s ** (1 / 3), s ** (2 / 3), s]


def _run_order_terms(t):
    """Run-order terms a curve may add over the run order ``t`` (n,): (parameters,
    columns, words). A step between two successive runs (a bolt loosening; its place
    counts as a parameter); a linear and a quadratic drift with time; a warm-up
    ``exp(-run / tau)`` (tau from :data:`WARM_UP_RUNS`, counted as a parameter)."""
    tt = (t - t.mean()) / (np.ptp(t) or 1.0)
    for cut in np.unique(t)[1:]:
        yield 2, [(t >= cut).astype(float)], "a step"
    yield 1, [tt], "a drift"
    yield 2, [tt, tt**2], "a drift"
    for tau in WARM_UP_RUNS:
        yield 2, [np.exp(-(t - t.min()) / tau)], "a drift"


def _press(col_sets, y):
    """(leave-one-out error, RSS) of ``y`` about its least-squares fit on each set of
    columns in ``col_sets`` (None where the columns are rank-deficient), in order: the
    sets with as many columns are factored together (one batched QR)."""
    out = [None] * len(col_sets)
    by_k = {}
    for i, cols in enumerate(col_sets):
        by_k.setdefault(len(cols), []).append(i)
    for idx in by_k.values():
        q, r = np.linalg.qr(np.stack([np.column_stack(col_sets[i]) for i in idx]))
        d = np.abs(np.diagonal(r, axis1=1, axis2=2))
        e = y - (q @ (np.swapaxes(q, 1, 2) @ y[:, None]))[..., 0]
        h = np.sum(q**2, axis=2)
        for j, i in enumerate(idx):     # the sums row by row: the same bits as one fit
            if d[j].min() >= 1e-10 * d[j].max():
                out[i] = (float(np.sum((e[j] / np.maximum(1.0 - h[j], 1e-9)) ** 2)),
                          float(e[j] @ e[j]))
    return out


def _scatter(x, y, t=None, reserved: int = 0):
    """The best curve's scatter with the run-order term it took out: (sd, dof, words or
    None, the term's fitted values (n,), its parameter count). ``reserved``: dof already
    spent on ``y`` (a run-order term taken out before)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    n = x.size - reserved
    none = np.zeros(x.size)
    if n < 3:
        return 0.0, 0, None, none, 0
    t = None if t is None else np.asarray(t, float)
    # leave-one-out errors at round-off are ties (which exact fit comes first would
    # depend on the CPU): floored there, the fewest parameters win
    tiny = x.size * (ROUNDOFF * float(np.max(np.abs(y)))) ** 2
    curves = [(k, cols) for k, cols in _curves(x) if n - k >= 1]
    fits = [(max(f[0], tiny), f[1], k, cols)
            for (k, cols), f in zip(curves, _press([c for _, c in curves], y)) if f is not None]
    fits.sort(key=lambda f: (f[0], f[2]))
    best = (*fits[0][:3], None, none, 0)
    tried = [(k, cols, kt, extra, words)
             for _, _, k, cols in (fits[:_N_TRIED] if t is not None else [])
             for kt, extra, words in _run_order_terms(t) if n - k - kt >= 1]
    for (k, cols, kt, extra, words), f in zip(
            tried, _press([cols + extra for k, cols, kt, extra, words in tried], y)):
        if f is None:
            continue
        f = (max(f[0], tiny), f[1])
        if f[0] < min(RUN_ORDER_GAIN * fits[0][0], best[0]):
            a = np.column_stack(cols + extra)
            coef = np.linalg.lstsq(a, y, rcond=None)[0]
            best = (f[0], f[1], k + kt, words, a[:, len(cols):] @ coef[len(cols):], kt)
    _, rss, k, term, part, kt = best
    return math.sqrt(rss / (n - k)), n - k, term, part, kt


def _without_run_order(x, y, relative, t):
    """``y`` (n,) rows with the run-order term of :func:`_scatter` over the rows taken
    out (in log for a ``relative`` channel), its words and parameter count."""
    if t is None:
        return y, None, 0
    yl = np.log(y) if relative else y
    _, _, words, part, kt = _scatter(x, yl, t)
    if words is None:
        return y, None, 0
    return (np.exp(yl - part) if relative else yl - part), words, kt


def smooth_scatter(x, y, t=None):
    """Scatter of ``y`` (n,) about a model-free smooth curve over ``x`` (n,), the log
    amplitude, distinct ``x`` (module doc): (sd, degrees of freedom).

    The curve is the member of :func:`_curves` with the least leave-one-out error
    (PRESS), ``sigma^2 = RSS / (n - k)`` with its ``k`` parameters (a grid exponent
    counts as one). With a run order ``t`` (n,), a step between two runs or a drift
    with time (:func:`_run_order_terms`) is taken out when it lowers the leave-one-out
    error of one of the best curves: a change with run order is not repeatability.
    The curve is then chosen again on ``y`` without that term, and its ``k_t``
    parameters count: ``sigma^2 = RSS / (n - k - k_t)``. (0, 0) for n < 3."""
    y, _, kt = _without_run_order(x, np.asarray(y, float), False, t)
    return _scatter(x, y, reserved=kt)[:2]


def pooled_repeats(groups, y, relative: bool = True):
    """Pooled within-group variance of ``y`` (n,) (relative to each group's mean when
    ``relative``; ``groups`` (n,) labels): (sd, dof), (0, 0) without repeats."""
    ss, dof = 0.0, 0
    groups = np.asarray(groups)
    for g in np.unique(groups):
        v = np.asarray(y, float)[groups == g]
        if v.size > 1:
            r = v / v.mean() - 1.0 if relative else v
            ss += float(np.sum((r - r.mean()) ** 2))
            dof += v.size - 1
    return (math.sqrt(ss / dof), dof) if dof else (0.0, 0)


def _plural(n, word):
    return f"{n} {word}{'' if n == 1 else 's'}"


def time_separable(level_ids, run_order, amplitude=None) -> bool:
    """Whether a change with time can be told from one with amplitude: the mean run
    order of each level, the levels taken in order of amplitude (the mean of
    ``amplitude`` per level; default the level ids' order), is not strictly monotone.
    A level run twice in a row (or both of its runs at the same end of the test)
    leaves it monotone: the repeat measures the repeatability, not a drift across the
    test, and a drift fitted there would bend with amplitude."""
    level_ids = np.asarray(level_ids)
    labels = np.unique(level_ids)
    t = np.asarray(run_order, float)
    tm = np.array([np.mean(t[level_ids == g]) for g in labels])
    if amplitude is not None:
        a = np.asarray(amplitude, float)
        tm = tm[np.argsort([np.mean(a[level_ids == g]) for g in labels], kind="stable")]
    dt = np.diff(tm)
    return not (np.all(dt > 0) or np.all(dt < 0))


@dataclass(frozen=True)
class _Scatter:
    """One channel's repeatability as judged so far: the relative variance ``s2`` on
    ``nu`` dof, its ``words`` and ``kind`` (:class:`NoiseModel`)."""

    s2: float
    nu: float
    words: str
    kind: str


def _repeatability(x, y, rel: bool, level_ids, t) -> tuple[np.ndarray, _Scatter]:
    """``y`` (n,) with its run-order term (over the rows ``t``) taken out, and its
    scatter: the repeats, pooled with the level means' scatter about a smooth curve
    when they have fewer than :data:`MIN_REPEAT_DOF` dof, or that scatter alone."""
    labels = np.unique(level_ids)
    # a step or drift with run order is found on the rows (a repeat run later
    # differs by it) and taken out of the repeats and of the level means alike
    y0 = y
    y, stepped, kt = _without_run_order(x, y, rel, t)
    s_r, nu_r = pooled_repeats(level_ids, y, relative=rel)
    # a term that differs between a level's repeats was fitted on them too
    shift = np.log(y / y0) if rel else y - y0
    within = kt and any(np.ptp(shift[level_ids == g]) > 1e-12 for g in labels)
    n_rep = sum(int(np.sum(level_ids == g) > 1) for g in labels)
    means = np.array([np.mean(y[level_ids == g]) for g in labels])
    xm = np.array([np.mean(x[level_ids == g]) for g in labels])
    ym = np.log(means) if rel else means
    s_s, nu_s = _scatter(xm, ym, reserved=kt)[:2]
    curve_words = f"scatter about a smooth curve ({nu_s} dof)" + (
        f" with {stepped} in run order taken out" if stepped else "")
    if nu_r >= MIN_REPEAT_DOF:
        nu = nu_r - kt if within else nu_r
        s2 = s_r**2 * nu_r / nu
        words, kd = f"repeats of {_plural(n_rep, 'level')} ({nu} dof)" + (
            f" with {stepped} in run order taken out" if within else ""), "repeats"
    elif nu_r > 0:
        nu = nu_r + nu_s
        s2 = (nu_r * s_r**2 + nu_s * s_s**2) / nu
        words = (f"repeats of {_plural(n_rep, 'level')} ({nu_r} dof) pooled with the "
                 f"{curve_words}")
        kd = "repeats+smooth"
    else:
        s2, nu = s_s**2, nu_s
        words, kd = curve_words, "smooth"
    return y, _Scatter(s2, nu, words, kd)


def _judged(c: str, sc: _Scatter, id_rel2: float, prior: RepeatabilityPrior | None,
            cap: bool, assumed: dict) -> tuple[float, _Scatter, str]:
    """The relative repeatability sd of channel ``c`` judged against its identification
    noise ``id_rel2`` and ``prior`` (setting ``assumed[c]`` where it has one), the
    scatter as judged, the words of a conflict with the prior."""
    s2, nu, words, kd = sc.s2, sc.nu, sc.words, sc.kind
    r_rel = math.sqrt(max(0.0, s2 - id_rel2)) if nu else 0.0
    pooled, conflict = False, ""
    within = bool(nu and id_rel2 > 0 and chi2_dist.sf(nu * s2 / id_rel2, nu) > SCATTER_P)
    if prior is not None and prior.rel_sd.get(c) and within:
        assumed[c] = prior.record(c, used=False)        # no repeatability shown
    elif prior is not None and prior.rel_sd.get(c):
        rep2, nu_post, assumed[c], said = pool(prior, c, s2 if nu else 0.0, nu, id_rel2,
                                               may_cap=cap and kd != "repeats")
        if rep2 is None:
            conflict = said
        else:
            r_rel, pooled = math.sqrt(rep2), True
            tag = "+capped" if assumed[c]["capped"] else ""
            kd, words = ((f"{kd}+{prior.kind}{tag}", words + said) if nu
                         else (prior.kind, said.strip()))
            nu = nu_post
    if not pooled and r_rel and within:
        r_rel = 0.0
        words += (f" exceeds it by {math.sqrt(s2 / id_rel2):.2f} times, within chance: "
                  f"p = {chi2_dist.sf(nu * s2 / id_rel2, nu):.2g}")
    return r_rel, _Scatter(s2, nu, words, kd), conflict


def _identification_only(has_id: bool, sc: _Scatter) -> _Scatter:
    """The judged scatter of a channel left without a repeatability part."""
    words = (("identification only" if has_id else "floor only")
             + ((f" (the {sc.words})" if " within chance" in sc.words else
                 f" (the {sc.words} does not exceed it)") if sc.nu else
                " (too few levels for a scatter)"))
    return _Scatter(sc.s2, math.inf, words, "identification")


def noise_model(abscissa, values: dict, stds: dict, level_ids, run_order=None,
                floors: dict | None = None, model_error: dict | None = None,
                prior: RepeatabilityPrior | None = RIG_REPEATABILITY,
                cap: bool = True) -> NoiseModel:
    """Identification uncertainty plus the test's repeatability (module doc).

    Parameters
    ----------
    abscissa : (n,) excitation or response amplitude of each row (> 0; its log is the
        smooth curve's variable)
    values : {channel: (n,)} omega2 (rad^2/s^2), zeta (fraction), other channels
        (absolute, e.g. a log response amplitude)
    stds : {channel: (n,) or None} the identification's standard uncertainties
    level_ids : (n,) level label of each row (rows sharing it are repeats)
    run_order : (n,) chronological order; when it is not monotone in amplitude a step
        or a drift with it is not taken as repeatability (:func:`smooth_scatter`)
    floors : overrides of :data:`FLOORS`; model_error : {channel: (n,)} added in
        quadrature to an estimated (not identification) part.
    prior : the assumed repeatability, pooled with an estimated repeatability where the
        scatter does not contradict it (not where the scatter stays within a known
        identification noise; :mod:`inverse.judge.prior`); None: the data alone.
    cap : a scatter far above the prior, without repeats of its own, is judged against
        the prior (:func:`inverse.judge.prior.pool`); False: it stays the noise.
    """
    floors = {**FLOORS, **(floors or {})}
    model_error = model_error or {}
    level_ids = np.asarray(level_ids)
    x = np.log(np.asarray(abscissa, float))
    ident, rep, total, source, dof, kind, floor, assumed = {}, {}, {}, {}, {}, {}, {}, {}
    rows_t = (np.asarray(run_order, float) if run_order is not None
              and time_separable(level_ids, run_order, x) else None)
    for c, y in values.items():
        y = np.asarray(y, float)
        rel = c in _RELATIVE
        scale = np.abs(y) if rel else np.ones_like(y)
        idn = np.zeros_like(y) if stds.get(c) is None else np.asarray(stds[c], float)
        y, sc = _repeatability(x, y, rel, level_ids, rows_t)
        id_rel2 = float(np.mean((idn / scale) ** 2))
        r_rel, sc, conflict = _judged(c, sc, id_rel2, prior, cap, assumed)
        r = r_rel * scale
        if r_rel > 0 and c in model_error:
            r = np.sqrt(r**2 + np.asarray(model_error[c], float) ** 2)
        if r_rel == 0.0:
            sc = _identification_only(stds.get(c) is not None, sc)
        fl = floors.get(c, _DEFAULT_FLOOR) * (float(np.median(np.abs(y))) if rel else 1.0)
        ident[c], rep[c], floor[c] = idn, r, fl
        total[c] = np.maximum(np.sqrt(idn**2 + r**2), fl)
        source[c], dof[c], kind[c] = sc.words + conflict, float(sc.nu), sc.kind
    return NoiseModel(ident, rep, total, source, dof, kind, floor, assumed)
