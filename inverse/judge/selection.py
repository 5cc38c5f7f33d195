"""The fit test and the one model-selection rule (the module doc of
:mod:`inverse.judge`, "Fit test" and "Selection")."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, special, stats

from inverse.judge.noise import NoiseModel

__all__ = ["P_UNEXPLAINED", "T_CAUSE", "W_AMBIGUOUS", "FitTest", "fit_test", "effective_dof",
           "shared_drop_dof",
           "known_noise_equivalent", "drop_for_known_noise", "Candidate", "Selection",
           "select"]

#: Tail probability below which a fit leaves the data outside their noise.
P_UNEXPLAINED = 1e-3
#: Information-criterion cost of each cause a candidate adds.
T_CAUSE = 6.0
#: Weight ratio to the named explanation from which another one makes it ambiguous.
W_AMBIGUOUS = 1.0 / 3.0


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
    n_all = sum(len(v) for v in noise.total.values())    # known channels count in N
    return n_all**2 / sum(n**2 / nu for n, nu in est)


def drop_dof(base: "Candidate", cand: "Candidate", noise: NoiseModel) -> float:
    """Degrees of freedom of the noise behind the chi2 drop from ``base`` to ``cand``
    (module doc): Satterthwaite over the channels, each weighted by its share of the
    drop, ``(sum_c d_c)^2 / sum_c (d_c^2 / nu_c)`` with ``d_c`` the positive part of
    the channel's drop (a drop made in a channel whose noise was estimated on few
    degrees of freedom is as uncertain as that estimate). :func:`effective_dof` when
    either candidate lacks ``chi2_by_channel`` or nothing drops."""
    if base.chi2_by_channel is None or cand.chi2_by_channel is None:
        return effective_dof(noise)
    d = {c: max(0.0, base.chi2_by_channel[c] - cand.chi2_by_channel.get(c, 0.0))
         for c in base.chi2_by_channel}
    if not 0.0 < sum(d.values()) < math.inf:
        return effective_dof(noise)
    return shared_drop_dof(d, noise.dof)


def shared_drop_dof(drops: dict, dof: dict) -> float:
    """Satterthwaite degrees of freedom of a chi2 drop shared over channels,
    ``(sum_c d_c)^2 / sum_c (d_c^2 / nu_c)`` (``drops`` {channel: d_c >= 0}, ``dof``
    {channel: nu_c}; inf or None: known, adds nothing)."""
    den = sum(v**2 / dof[c] for c, v in drops.items()
              if dof.get(c) is not None and not math.isinf(dof[c]))
    return math.inf if den == 0.0 else sum(drops.values()) ** 2 / den


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
    (failed fits or folds; a fold whose fit did not converge is a failed fold), ``excluded`` (a reason it may not be named, or None),
    ``chi2_by_channel`` (``{channel: chi2}``, optional: the drop's degrees of freedom,
    :func:`drop_dof`), ``gain_untestable`` (why no held-out gain can be measured on
    these data at all, e.g. as many parameters as data without one level; not a
    failure: the candidate is then judged by its fit test and IC alone, module doc)."""

    causes: tuple
    n_params: int
    chi2: float
    n_data: int
    gain: float | None = None
    failures: int = 0
    excluded: str | None = None
    chi2_by_channel: dict | None = None
    gain_untestable: str | None = None

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

    def verdict_json(self, failures=None) -> dict:
        """The verdict alone (a second verdict's JSON): ``cause``, ``also``, ``model``
        (the candidate named, the closest one when unexplained), ``unexplained``,
        ``fit_test`` and, when given, ``failures``."""
        out = {"cause": self.cause, "also": self.also, "model": self.best,
               "unexplained": self.unexplained, "fit_test": self.tests[self.best].to_json()}
        if failures is not None:
            out["failures"] = failures
        return out


def _why_not(c: Candidate, test: FitTest, p_min: float):
    if c.excluded:
        return c.excluded
    if test.p_value is None:
        return test.test
    if test.p_value < p_min:
        return f"outside the noise (p = {test.p_value:.2g} < {p_min:g}, {test.test})"
    if c.causes and c.gain is None and not c.gain_untestable:
        return ("no held-out gain (failed folds)" if c.failures
                else "no held-out gain (not computed)")
    if c.causes and c.gain is not None and c.gain <= 1.0:
        return f"held-out gain {c.gain:.3g} <= 1"
    return None


def _second_cause_idle(c: Candidate, cands: dict):
    """Why a candidate of several causes may not be named although its held-out gain
    exceeds 1: not above the gain of one of its causes alone (when that is known), so
    the added cause does not predict unseen levels better (module doc); else None."""
    if len(c.causes) < 2 or c.gain is None:
        return None
    for cause in c.causes:
        alone = cands.get(cause)
        if alone is not None and alone.gain is not None and c.gain <= alone.gain:
            return (f"held-out gain {c.gain:.3g} not above {cause} alone "
                    f"({alone.gain:.3g}): the second cause does not predict unseen levels "
                    f"better")
    return None


def known_noise_equivalent(delta_chi2: float, q: int, nu: float) -> float:
    """The chi-square drop with known noise that is as improbable as ``delta_chi2``
    with a noise estimated on ``nu`` degrees of freedom (module doc of
    :mod:`inverse.judge`, "Selection").

    Under no effect, ``delta_chi2`` of ``q`` added parameters is ``q F(q, nu)`` with
    an estimated noise and ``chi-square(q)`` with a known one; the drop is mapped
    through equal tail probability, ``chi2_q.isf(F_{q,nu}.sf(delta_chi2 / q))``.
    ``nu = inf`` or ``q <= 0`` or ``delta_chi2 <= 0``: unchanged."""
    if math.isinf(nu) or q <= 0 or delta_chi2 <= 0:
        return float(delta_chi2)
    tail = float(stats.f.logsf(delta_chi2 / q, q, nu))
    if not math.isfinite(tail):      # F_{q,nu} tail = I_y(nu/2, q/2), y = nu/(nu + drop):
        y, a, b = nu / (nu + delta_chi2), 0.5 * nu, 0.5 * q     # its leading term
        tail = (a * math.log(y) + (b - 1) * math.log1p(-y) - math.log(a)
                - float(special.betaln(a, b)))
    if tail > -700:
        return float(stats.chi2.isf(math.exp(tail), q))
    # beyond double precision: solve ln Q(q/2, x/2) = tail with the asymptotic upper
    # incomplete gamma, ln Q(a, z) ~ (a-1) ln z - z - ln Gamma(a) + ln(1 + (a-1)/z)
    h = 0.5 * q

    def log_sf(x):
        z = 0.5 * x
        return (h - 1) * math.log(z) - z - math.lgamma(h) + math.log1p((h - 1) / z)

    return float(optimize.brentq(lambda x: log_sf(x) - tail, 2.0 * q + 2.0,
                                 4.0 * abs(tail) + 100.0 * q))


def drop_for_known_noise(known_drop: float, q: int, nu: float) -> float:
    """The chi2 drop with a noise estimated on ``nu`` degrees of freedom whose
    known-noise equivalent is ``known_drop``: the inverse of
    :func:`known_noise_equivalent`, ``q F_{q,nu}.isf(chi2_q.sf(known_drop))``."""
    if math.isinf(nu) or q <= 0 or known_drop <= 0:
        return float(known_drop)
    return float(q * stats.f.isf(stats.chi2.sf(known_drop, q), q, nu))


def _information(cands: dict, noise: NoiseModel, t_cause: float,
                 nameable: set | None = None) -> dict:
    """``IC = chi2 + 2k + T n_causes`` of every candidate that can be fitted (module
    doc). With an estimated noise the causes' ICs are raised together, by as much as
    the best of them rises when its drop from the base model is taken at its
    known-noise equivalent: the base model against the causes is judged at the
    known-noise false-alarm rate, the causes among themselves by their chi2. "The best"
    is sought among the ``nameable`` causes when there are any: a pair that may not be
    named (its second cause idle) must not set the bar for the single cause that may."""
    ic = {k: c.chi2 + 2 * c.n_params + t_cause * len(c.causes) for k, c in cands.items()
          if c.n_data > c.n_params}
    base = cands.get("none")
    causes = [k for k in ic if k != "none"]
    if "none" not in ic or not causes:
        return ic
    causes = [k for k in causes if k in (nameable or ())] or causes
    drop = {k: base.chi2 - cands[k].chi2 for k in causes}
    mapped = [ic[k] + drop[k] - known_noise_equivalent(
        drop[k], cands[k].n_params - base.n_params, drop_dof(base, cands[k], noise))
        for k in causes]
    shift = max(0.0, min(mapped) - min(ic[k] for k in causes))
    return {k: v + (shift if k != "none" else 0.0) for k, v in ic.items()}


def select(candidates, noise: NoiseModel, t_cause: float = T_CAUSE,
           p_min: float = P_UNEXPLAINED, w_ambiguous: float = W_AMBIGUOUS) -> Selection:
    """The one model-selection rule (module doc) over ``candidates``
    (:class:`Candidate`; the base model has ``causes = ()``)."""
    cands = {c.name: c for c in candidates}
    tests = {k: fit_test(c.chi2, c.n_data, c.n_params, noise) for k, c in cands.items()}
    why = {k: _why_not(c, tests[k], p_min) or _second_cause_idle(c, cands)
           for k, c in cands.items()}
    eligible = [k for k in cands if why[k] is None]
    ic = _information(cands, noise, t_cause, set(eligible))
    lo = min(ic.values()) if ic else 0.0
    raw = {k: math.exp(-(v - lo) / 2) for k, v in ic.items()}
    tot = sum(raw.values()) or 1.0
    weights = {k: raw.get(k, 0.0) / tot for k in cands}
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
