"""An assumed repeatability of the test rig, pooled with the data's own estimate.

With 4-12 levels and no repeats the repeatability is estimated on 1-7 degrees of
freedom (:mod:`inverse.judge.noise`): an F test on so few is nearly powerless, and an
estimate on 1-2 dof can come out 20-30 times too small. What is known beforehand is
that a rig repeats a level to about 0.05 % in frequency and a few % in damping
(:data:`RIG_REPEATABILITY`: assumed, not measured). That knowledge is a scaled
inverse-chi-square prior on the repeatability variance, ``nu0`` degrees of freedom at
scale ``r0^2``; the data's estimate ``r^2`` on ``nu`` dof moves it to the posterior
(the moderated variance of Smyth 2004, eq. 5)::

    r_post^2 = (nu0 r0^2 + nu r^2) / (nu0 + nu),     nu_post = nu0 + nu

and tests with ``nu_post`` dof follow (Smyth 2004, eq. 6: the moderated t is
Student-t with ``nu0 + nu`` dof). ``nu0 = 2`` says "within a factor of about 2.5 of
``r0`` either way" (the spread of ``ln r`` is ``1 / sqrt(2 nu0)``).

A prior the data contradict is not used (a prior-data conflict check, Evans &
Moshonov 2006): the scatter ``s^2`` on ``nu`` dof against ``r0^2 + mean(ident^2)``,
two-sided at :data:`CONFLICT_P`. A rig that repeats 10 times better, or worse, than
assumed gets its own estimate. Where the identification's noise is known (std columns)
and the scatter does not exceed it significantly (:data:`inverse.judge.noise.SCATTER_P`,
session 11's rule), the noise stays the identification's, known: the data show no
repeatability there, and pooling a prior of 3 % into an identified zeta noise of 1-2 %
that 1-2 dof cannot tell apart from it lost more verdicts than it won (docs/judge.md,
session 12).

A scatter far *above* what a rig repeats, with no repeats of its own to measure the
repeatability (fewer than :data:`inverse.judge.noise.MIN_REPEAT_DOF` dof), is not
taken as noise: a level scattering about a smooth curve by several times a rig's
repeatability is more likely an effect the smooth curve does not follow (a drift in
run order, a bend) than the rig. "About 0.05 %" is read as within a factor
:data:`CAP_FACTOR` = 2: the scatter is tested one-sided against ``(2 r0)^2 +
mean(ident^2)`` at :data:`EXCESS_P`, and where it exceeds it the data are judged
against ``(2 r0)^2``, as known (``capped``): the largest repeatability of a typical
rig, so that a verdict holds against any of them. The words say so and how to state a
rig that repeats that poorly (``--rig-repeatability``). Repeats of their own keep
their estimate, however large.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from scipy.stats import chi2 as chi2_dist

__all__ = ["RepeatabilityPrior", "RIG_REPEATABILITY", "CONFLICT_P", "EXCESS_P", "CAP_FACTOR",
           "moderated", "pool", "prior_for"]

#: Two-sided level of the prior-data conflict check (module doc).
CONFLICT_P = 0.05
#: One-sided level above which a scatter without repeats is judged against the prior
#: (module doc): the fit test's level, :data:`inverse.judge.selection.P_UNEXPLAINED`.
EXCESS_P = 1e-3
#: "About" the assumed repeatability: within this factor (module doc).
CAP_FACTOR = 2.0


@dataclass(frozen=True)
class RepeatabilityPrior:
    """Run-to-run repeatability known before the test: relative sd per channel
    (``omega2``: twice the frequency's; ``zeta``), the prior's degrees of freedom ``dof``
    (module doc) and ``kind``: ``assumed`` (a typical rig) or ``stated`` (by the user)."""

    rel_sd: dict = field(default_factory=dict)
    dof: float = 2.0
    kind: str = "assumed"

    def words(self, channel: str) -> str:
        """The assumption in words, e.g. "0.05 % in frequency" (for ``omega2``)."""
        r = self.rel_sd[channel]
        what = (f"{50 * r:.3g} % in frequency" if channel == "omega2"
                else f"{100 * r:.3g} % in {'damping' if channel == 'zeta' else channel}")
        article = "an" if self.kind == "assumed" else "the"
        return f"{article} {self.kind} rig repeatability ({what}, {self.dof:g} dof)"

    def record(self, channel: str, used: bool, conflict_p=None, capped=False) -> dict:
        """What the noise model reports of it for one channel (JSON); ``capped_rel_sd``:
        the relative sd the data were judged against when capped (module doc)."""
        return {"rel_sd": self.rel_sd[channel], "dof": self.dof, "used": used,
                "conflict_p": conflict_p, "capped": capped,
                "capped_rel_sd": CAP_FACTOR * self.rel_sd[channel] if capped else None,
                "kind": self.kind}


#: A rig repeats a level to about 0.05 % in frequency (omega2: 0.1 %) and 3 % in
#: damping (the brief; assumed).
RIG_REPEATABILITY = RepeatabilityPrior({"omega2": 1e-3, "zeta": 0.03}, 2.0)


def prior_for(stated) -> RepeatabilityPrior | None:
    """The prior of what a user states of the rig
    (:attr:`ident.modal_data.MeasuredData.rig_repeatability`): None -> the typical rig
    :data:`RIG_REPEATABILITY`; ``(f, z, dof)`` relative sds of frequency and damping ->
    that (``omega2``: ``2 f``); all zero -> None (the data's estimate alone)."""
    if stated is None:
        return RIG_REPEATABILITY
    f, z, dof = (tuple(stated) + (RIG_REPEATABILITY.dof,))[:3]
    if f <= 0 and z <= 0:
        return None
    return RepeatabilityPrior({c: v for c, v in (("omega2", 2 * f), ("zeta", z)) if v > 0},
                              float(dof), "stated")


def moderated(s2: float, nu: float, ident2: float, r0: float, nu0: float):
    """Repeatability variance with the prior pooled in (module doc).

    Parameters
    ----------
    s2 : the data's total relative scatter variance, on ``nu`` dof (0, 0: none)
    ident2 : the identification's mean relative variance (0 when unknown)
    r0, nu0 : the prior's relative sd and dof

    Returns
    -------
    (rep2, dof, p): the posterior repeatability variance and its dof, and the
    conflict check's two-sided p (None when there is no scatter to check); ``rep2``
    None when the data contradict the prior (p < :data:`CONFLICT_P`).
    """
    if nu <= 0:
        return r0**2, float(nu0), None
    stat = nu * s2 / (r0**2 + ident2)
    p = min(1.0, 2.0 * min(chi2_dist.cdf(stat, nu), chi2_dist.sf(stat, nu)))
    if p < CONFLICT_P:
        return None, float(nu), p
    rep_hat2 = max(0.0, s2 - ident2)
    return (nu0 * r0**2 + nu * rep_hat2) / (nu0 + nu), float(nu0 + nu), p


def excess_p(s2: float, nu: float, ident2: float, r0: float) -> float:
    """One-sided p of a scatter ``s2`` on ``nu`` dof as large as it is, were the noise
    the identification's and a repeatability ``r0``."""
    return float(chi2_dist.sf(nu * s2 / (r0**2 + ident2), nu)) if nu > 0 else 1.0


def pool(prior: RepeatabilityPrior, channel: str, s2: float, nu: float, ident2: float,
         may_cap: bool = True):
    """:func:`moderated` for one channel of :func:`inverse.judge.noise_model`, with its
    record and words: (rep2 or None, dof, ``{rel_sd, dof, used, conflict_p, capped,
    kind}``, words to append to the scatter's: " pooled with ..." when used, "; the
    scatter is N times above/below ..., not pooled (p = ...)" when the data contradict
    it; the prior's own words when there is no scatter). Where ``may_cap`` (the
    scatter is not the repeats' alone), a scatter far above :data:`CAP_FACTOR` times
    the prior gives that variance on infinite dof (``capped``, module doc)."""
    r0 = prior.rel_sd[channel]
    rep2, dof, p = moderated(s2, nu, ident2, r0, prior.dof)
    if rep2 is not None:
        said = (f" pooled with {prior.words(channel)}" if p is not None
                else f"{prior.words(channel)} (too few levels for a scatter)")
        return rep2, dof, prior.record(channel, True, p), said
    ratio = (s2 / (r0**2 + ident2)) ** 0.5
    how = f"{ratio:.3g} times above" if ratio > 1 else f"{1 / ratio:.3g} times below"
    r_hi = CAP_FACTOR * r0
    above = excess_p(s2, nu, ident2, r_hi)
    if above < EXCESS_P and may_cap:
        said = (f"; the scatter is {how} {prior.words(channel)}, above {CAP_FACTOR:g} times "
                f"it at p = {above:.2g}: more than a rig repeats, so judged against "
                f"{CAP_FACTOR:g} times that repeatability as known (a rig that repeats so "
                f"poorly: state it with --rig-repeatability)")
        return r_hi**2, math.inf, prior.record(channel, True, p, capped=True), said
    said = f"; the scatter is {how} {prior.words(channel)}, not pooled (p = {p:.2g})"
    return None, dof, prior.record(channel, False, p), said
