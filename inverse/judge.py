"""The one judge of a fit: the noise model, the fit test and the model-selection rule
shared by every command that judges a fit (``diagnose``, ``diagnose --case``, ``update``;
``shared/spec/diagnosis.md``, "Noise has two parts").

Noise model (:func:`noise_model`), per channel (``omega2``, ``zeta``; any other channel,
e.g. the log response amplitude, the same way on an absolute scale):

* **identification** -- the table's ``omega2_std`` / ``zeta_std`` (0 without them);
* **repeatability** -- the scatter between runs of one level. Where the data hold
  repeats (rows sharing a level), the pooled within-level variance of the relative
  values ``y / mean_level(y) - 1`` (``nu = sum_g (n_g - 1)`` degrees of freedom).
  Otherwise, and added to repeats of fewer than :data:`MIN_REPEAT_DOF` degrees of
  freedom, the scatter of the level means (``ln y``) about a *model-free* smooth curve
  of the amplitude (:func:`smooth_scatter`): a Muntz polynomial in the relative
  amplitude, plus a quadratic trend in run order when the run order is not monotone in
  amplitude (a drift with time is not repeatability), ``sigma^2 = RSS / (n - rank)``;
  with too few levels for that, the difference-based estimator of Gasser, Sroka &
  Jennen-Steinmetz (1986) with local quadratic contrasts. The curve is not the model being judged: a misfit of that model
  cannot hide as noise. Both estimates measure the *total* scatter; the repeatability
  is what exceeds the identification's part, ``rep^2 = max(0, s^2 - mean(ident^2))``.
* **total** ``= sqrt(identification^2 + repeatability^2)``, floored at
  :data:`FLOORS` (the digits a table prints). ``dof`` is ``inf`` when the repeatability
  part is 0 (the identification's stds are taken as known), else the estimate's.

Fit test (:func:`fit_test`): with known noise ``chi2 ~ chi-square(N - k)``; with an
estimated repeatability ``(chi2 / (N - k)) ~ F(N - k, nu)``, ``nu`` the channels' degrees
of freedom combined by moment matching (Satterthwaite 1946):
``nu = N_est^2 / sum_c (n_c^2 / nu_c)`` over the ``n_c`` rows of each estimated channel,
``N_est = sum_c n_c``.

Selection (:func:`select`): the IC of a candidate is ``chi2 + 2k + T n_causes``
(``T`` = :data:`T_CAUSE`, prior odds ``e^-3`` per cause, :mod:`inverse.diagnose`);
Akaike weights ``w_i ~ exp(-IC_i / 2)``. A candidate is *eligible* when its fit test
gives ``p >= P_UNEXPLAINED``, it is not excluded (a refuted base model, an inactive
extension) and, if it names a cause, its held-out gain exceeds 1 (a gain over failed
folds is None: not eligible). The named explanation is the eligible candidate of
largest weight; none eligible: ``unexplained``, with the closest miss and why it
missed. ``ambiguous`` when another eligible candidate has at least
:data:`W_AMBIGUOUS` of the named one's weight.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import stats

__all__ = ["P_UNEXPLAINED", "T_CAUSE", "W_AMBIGUOUS", "MIN_REPEAT_DOF", "FLOORS",
           "NoiseModel", "noise_model", "smooth_scatter", "pooled_repeats", "FitTest",
           "fit_test", "effective_dof", "Candidate", "Selection", "select", "Bounded", "at_bound"]

#: Tail probability below which a fit leaves the data outside their noise.
P_UNEXPLAINED = 1e-3
#: Information-criterion cost of each cause a candidate adds.
T_CAUSE = 6.0
#: Weight ratio to the named explanation from which another one makes it ambiguous.
W_AMBIGUOUS = 1.0 / 3.0
#: Repeats with fewer degrees of freedom are pooled with the smooth-curve scatter.
MIN_REPEAT_DOF = 6
#: Noise floors: relative for omega2 and zeta, absolute for other channels.
FLOORS = {"omega2": 1e-9, "zeta": 1e-7}
_DEFAULT_FLOOR = 1e-2
_RELATIVE = ("omega2", "zeta")


@dataclass
class NoiseModel:
    """Noise per channel and row: ``identification``, ``repeatability``, ``total`` (each
    ``{channel: (n,)}`` in the channel's units), ``source`` (words per channel), ``dof``
    (per channel, ``math.inf`` when known) and ``kind`` (``repeats``, ``smooth``,
    ``repeats+smooth`` or ``identification``)."""

    identification: dict
    repeatability: dict
    total: dict
    source: dict
    dof: dict
    kind: dict = field(default_factory=dict)
    floor: dict = field(default_factory=dict)

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

    def has_identification(self) -> bool:
        """Whether any channel has an identification part."""
        return any(np.any(v > 0) for v in self.identification.values())

    def to_json(self, values: dict) -> dict:
        """``{channel: {source, identification_rel, repeatability_rel, total_rel, dof}}``
        (median relative sd; absolute for channels that are not relative)."""
        out = {}
        for c in self.total:
            scale = np.abs(values[c]) if c in _RELATIVE else 1.0
            rel = lambda a: float(np.median(a / scale))  # noqa: E731
            out[c] = {"source": self.source[c], "kind": self.kind.get(c),
                      "identification_rel": rel(self.identification[c]),
                      "repeatability_rel": rel(self.repeatability[c]),
                      "total_rel": rel(self.total[c]),
                      "relative": c in _RELATIVE,
                      "dof": None if math.isinf(self.dof[c]) else float(self.dof[c])}
        return out


def _contrast(x):
    """Unit contrast over the points ``x`` (k,) orthogonal to polynomials of degree
    ``k - 2`` (the last left singular vector of the Vandermonde matrix)."""
    V = np.vander(x - x.mean(), len(x) - 1, increasing=True)
    q, _ = np.linalg.qr(V, mode="complete")
    return q[:, -1]


def _residual_scatter(B, y):
    """(sd, dof) of ``y`` about its least-squares projection on the columns of ``B``."""
    coef, _, rank, _ = np.linalg.lstsq(B, y, rcond=1e-10)
    dof = B.shape[0] - int(rank)
    return float(np.sqrt(np.sum((y - B @ coef) ** 2) / dof)), dof


def smooth_scatter(x, y, t=None):
    """Scatter of ``y`` (n,) about a model-free smooth curve over ``x`` (n,), the log
    amplitude, distinct ``x`` (module doc): (sd, degrees of freedom).

    The curve: a Muntz polynomial in the relative amplitude ``s = exp(x - max x)``,
    ``1, ln s, s^(1/3), s^(2/3), s`` (any power law of amplitude to a few 1e-4 of its
    range: the local-polynomial alternative leaves 1e-2 at level ratios of 2.5), plus
    ``t, t^2`` of the run order ``t`` (when given: a drift with time is not scatter),
    when that leaves at least 3 degrees of freedom. Otherwise local quadratic contrasts
    over windows of four points (linear over three when n = 3), one degree of freedom
    each, projected on those blind to the trend in ``t`` when given (two fewer);
    (0, 0) for n < 3."""
    order = np.argsort(x, kind="stable")
    x, y = np.asarray(x, float)[order], np.asarray(y, float)[order]
    n = x.size
    if n < 3:
        return 0.0, 0
    sr = np.exp(x - x.max())
    cols = [np.ones(n), x - x.mean(), sr ** (1 / 3), sr ** (2 / 3), sr]
    if t is not None:
        tt = np.asarray(t, float)[order]
        tt = (tt - tt.mean()) / (np.ptp(tt) or 1.0)
        cols += [tt, tt**2]
    if n - len(cols) >= 3:
        return _residual_scatter(np.column_stack(cols), y)
    w = 4 if n >= 4 else 3
    C = np.zeros((n - w + 1, n))
    for i in range(n - w + 1):
        C[i, i:i + w] = _contrast(x[i:i + w])
    if t is None or C.shape[0] <= 3:
        d = C @ y
        return float(np.sqrt(np.mean(d**2))), int(d.size)
    T = C @ np.column_stack(cols[-2:])                     # the trend in t seen by C
    _, sv, vt = np.linalg.svd(T.T)
    A = vt[int(np.sum(sv > 1e-9 * max(sv.max(), 1e-300))):].T   # combinations blind to it
    Q, sv2, _ = np.linalg.svd(C.T @ A, full_matrices=False)
    d = Q[:, sv2 > 1e-9 * sv2.max()].T @ y
    return float(np.sqrt(np.mean(d**2))), int(d.size)


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


def noise_model(abscissa, values: dict, stds: dict, level_ids, run_order=None,
                floors: dict | None = None, model_error: dict | None = None) -> NoiseModel:
    """Identification uncertainty plus the test's repeatability (module doc).

    Parameters
    ----------
    abscissa : (n,) excitation or response amplitude of each row (> 0; its log is the
        smooth curve's variable)
    values : {channel: (n,)} omega2 (rad^2/s^2), zeta (fraction), other channels
        (absolute, e.g. a log response amplitude)
    stds : {channel: (n,) or None} the identification's standard uncertainties
    level_ids : (n,) level label of each row (rows sharing it are repeats)
    run_order : (n,) chronological order; when it is not monotone in amplitude the
        smooth-curve scatter is made blind to a quadratic drift with time
    floors : overrides of :data:`FLOORS`; model_error : {channel: (n,)} added in
        quadrature to an estimated (not identification) part.
    """
    floors = {**FLOORS, **(floors or {})}
    model_error = model_error or {}
    level_ids = np.asarray(level_ids)
    x = np.log(np.asarray(abscissa, float))
    ident, rep, total, source, dof, kind, floor = {}, {}, {}, {}, {}, {}, {}
    labels = np.unique(level_ids)
    tm = None
    if run_order is not None:
        tm = np.array([np.mean(np.asarray(run_order, float)[level_ids == g])
                       for g in labels])
        dt = np.diff(tm[np.argsort([np.mean(x[level_ids == g]) for g in labels])])
        tm = None if np.all(dt > 0) or np.all(dt < 0) else tm
    for c, y in values.items():
        y = np.asarray(y, float)
        rel = c in _RELATIVE
        scale = np.abs(y) if rel else np.ones_like(y)
        idn = np.zeros_like(y) if stds.get(c) is None else np.asarray(stds[c], float)
        s_r, nu_r = pooled_repeats(level_ids, y, relative=rel)
        n_rep = sum(int(np.sum(level_ids == g) > 1) for g in labels)
        means = np.array([np.mean(y[level_ids == g]) for g in labels])
        xm = np.array([np.mean(x[level_ids == g]) for g in labels])
        s_s, nu_s = smooth_scatter(xm, np.log(means) if rel else means, tm)
        if nu_r >= MIN_REPEAT_DOF:
            s2, nu = s_r**2, nu_r
            words, kd = f"repeats of {_plural(n_rep, 'level')} ({nu_r} dof)", "repeats"
        elif nu_r > 0:
            nu = nu_r + nu_s
            s2 = (nu_r * s_r**2 + nu_s * s_s**2) / nu
            words = (f"repeats of {_plural(n_rep, 'level')} ({nu_r} dof) pooled with the "
                     f"scatter about a smooth curve ({nu_s} dof)")
            kd = "repeats+smooth"
        else:
            s2, nu = s_s**2, nu_s
            words, kd = f"scatter about a smooth curve ({nu_s} dof)", "smooth"
        id_rel2 = float(np.mean((idn / scale) ** 2))
        r_rel = math.sqrt(max(0.0, s2 - id_rel2)) if nu else 0.0
        r = r_rel * scale
        if r_rel > 0 and c in model_error:
            r = np.sqrt(r**2 + np.asarray(model_error[c], float) ** 2)
        if r_rel == 0.0:
            has_id = stds.get(c) is not None
            words = (("identification only" if has_id else "floor only")
                     + (f" (the {words} does not exceed it)" if nu else
                        " (too few levels for a scatter)"))
            kd, nu = "identification", math.inf
        fl = floors.get(c, _DEFAULT_FLOOR) * (float(np.median(np.abs(y))) if rel else 1.0)
        ident[c], rep[c], floor[c] = idn, r, fl
        total[c] = np.maximum(np.sqrt(idn**2 + r**2), fl)
        source[c], dof[c], kind[c] = words, float(nu), kd
    return NoiseModel(ident, rep, total, source, dof, kind, floor)


@dataclass
class FitTest:
    """Is a fit within the noise? ``p_value`` (None when ``dof <= 0``), ``dof``
    (``N - k``), ``denominator_dof`` (inf: chi-square), ``test`` (words),
    ``rms_standardized`` (``sqrt(chi2 / N)``)."""

    p_value: float | None
    dof: int
    denominator_dof: float
    test: str
    rms_standardized: float

    def passes(self, p_min: float = P_UNEXPLAINED) -> bool:
        return self.p_value is not None and self.p_value >= p_min

    def to_json(self) -> dict:
        return {"p_value": self.p_value, "dof": self.dof, "test": self.test,
                "rms_standardized": self.rms_standardized,
                "denominator_dof": (None if math.isinf(self.denominator_dof)
                                    else self.denominator_dof)}


def effective_dof(noise: NoiseModel) -> float:
    """Degrees of freedom of the noise's estimated part, channels combined (module doc;
    inf when every channel is known)."""
    est = [(len(noise.total[c]), noise.dof[c]) for c in noise.total
           if not math.isinf(noise.dof[c])]
    if not est:
        return math.inf
    n_est = sum(n for n, _ in est)
    return n_est**2 / sum(n**2 / nu for n, nu in est)


def fit_test(chi2: float, n_data: int, n_params: int, noise: NoiseModel) -> FitTest:
    """Chi-square test with known noise, F test with an estimated repeatability
    (module doc)."""
    dof = int(n_data - n_params)
    rms = float(np.sqrt(chi2 / max(n_data, 1)))
    nu = effective_dof(noise)
    if dof <= 0:
        return FitTest(None, dof, nu, f"none possible ({n_data} data, {n_params} "
                                      f"parameters)", rms)
    if math.isinf(nu):
        return FitTest(float(stats.chi2.sf(chi2, dof)), dof, nu,
                       f"chi-square, {dof} dof (noise known: identification)", rms)
    return FitTest(float(stats.f.sf(chi2 / dof, dof, nu)), dof, nu,
                   f"F({dof}, {nu:.3g}) (repeatability estimated)", rms)


@dataclass
class Candidate:
    """One explanation: ``causes`` (() for the base model), ``n_params``, ``chi2`` on
    ``n_data`` data, held-out ``gain`` (None: folds failed or too few data), ``failures``
    (failed fits or folds), ``excluded`` (a reason it may not be named, or None)."""

    causes: tuple
    n_params: int
    chi2: float
    n_data: int
    gain: float | None = None
    failures: int = 0
    excluded: str | None = None

    @property
    def name(self) -> str:
        return "+".join(self.causes) if self.causes else "none"


@dataclass
class Selection:
    """The rule's answer: ``cause``, ``also``, ``best`` (candidate name, the closest
    one when ``unexplained``), ``weights`` and ``tests`` per candidate, ``eligible``,
    ``ambiguous`` with its ``rivals``, ``unexplained`` and the ``closest_miss``
    (candidate, p_value, gain, why) when no candidate is eligible."""

    cause: str
    also: list
    best: str
    weights: dict
    tests: dict
    eligible: list
    rivals: list
    unexplained: bool
    closest_miss: dict | None = None
    why_not: dict = field(default_factory=dict)

    @property
    def ambiguous(self) -> bool:
        return bool(self.rivals)


def _why_not(c: Candidate, test: FitTest, p_min: float):
    if c.excluded:
        return c.excluded
    if test.p_value is None:
        return test.test
    if test.p_value < p_min:
        return f"outside the noise (p = {test.p_value:.2g} < {p_min:g}, {test.test})"
    if c.causes and c.gain is None:
        return ("no held-out gain (failed folds)" if c.failures
                else "no held-out gain (too few levels)")
    if c.causes and c.gain <= 1.0:
        return f"held-out gain {c.gain:.3g} <= 1"
    return None


def select(candidates, noise: NoiseModel, t_cause: float = T_CAUSE,
           p_min: float = P_UNEXPLAINED, w_ambiguous: float = W_AMBIGUOUS) -> Selection:
    """The one model-selection rule (module doc) over ``candidates``
    (:class:`Candidate`; the base model has ``causes = ()``)."""
    cands = {c.name: c for c in candidates}
    ic = {k: c.chi2 + 2 * c.n_params + t_cause * len(c.causes) for k, c in cands.items()
          if c.n_data > c.n_params}
    lo = min(ic.values()) if ic else 0.0
    raw = {k: math.exp(-(v - lo) / 2) for k, v in ic.items()}
    tot = sum(raw.values()) or 1.0
    weights = {k: raw.get(k, 0.0) / tot for k in cands}
    tests = {k: fit_test(c.chi2, c.n_data, c.n_params, noise) for k, c in cands.items()}
    why = {k: _why_not(c, tests[k], p_min) for k, c in cands.items()}
    eligible = [k for k in cands if why[k] is None]
    if eligible:
        best = max(eligible, key=weights.get)
        causes = cands[best].causes
        if len(causes) > 1:
            causes = tuple(sorted(causes, key=lambda c: -weights.get(c, 0.0)))
        cause, also = (causes[0], list(causes[1:])) if causes else ("none", [])
        rivals = [k for k in eligible if k != best
                  and weights[k] >= w_ambiguous * weights[best]]
        return Selection(cause, also, best, weights, tests, eligible, rivals, False,
                         None, {k: v for k, v in why.items() if v})
    pool = [k for k in cands if not cands[k].excluded] or list(cands)
    best = max(pool, key=lambda k: (tests[k].p_value or 0.0, weights[k]))
    miss = {"candidate": best, "p_value": tests[best].p_value,
            "rms_standardized": tests[best].rms_standardized,
            "gain": cands[best].gain, "why": why[best]}
    return Selection("unexplained", [], best, weights, tests, [], [], True, miss,
                     {k: v for k, v in why.items() if v})


@dataclass
class Bounded:
    """A fitted parameter with its bounds: ``at_bound`` and which bound, and its
    interval with the kind of interval (``profile``, ``covariance``, ...). In JSON an
    infinite bound is null."""

    name: str
    value: float
    lower: float
    upper: float
    at_bound: bool
    which: str | None = None
    interval: tuple | None = None
    interval_kind: str | None = None

    def to_json(self) -> dict:
        fin = lambda v: float(v) if np.isfinite(v) else None  # noqa: E731
        return {"value": self.value, "lower_bound": fin(self.lower),
                "upper_bound": fin(self.upper),
                "at_bound": self.at_bound, "which_bound": self.which,
                "interval": None if self.interval is None else list(self.interval),
                "interval_kind": self.interval_kind}


def at_bound(value: float, lower: float, upper: float, rtol: float = 1e-3):
    """``(on a bound?, "lower"/"upper"/None)``: within ``rtol`` of the range (of
    ``|value|`` for an infinite range) of a bound."""
    span = upper - lower
    tol = rtol * (span if np.isfinite(span) and span > 0 else max(abs(value), 1.0))
    if np.isfinite(lower) and value <= lower + tol:
        return True, "lower"
    if np.isfinite(upper) and value >= upper - tol:
        return True, "upper"
    return False, None
