"""The one judge of a fit: the noise model, the fit test and the model-selection rule
shared by every command that judges a fit (``diagnose``, ``diagnose --case``, ``update``;
``docs/formats/diagnosis.md``, "Noise has two parts").

Noise model (:func:`noise_model`), per channel (``omega2``, ``zeta``; any other channel,
e.g. the log response amplitude, the same way on an absolute scale):

* **identification** -- the table's ``omega2_std`` / ``zeta_std`` (0 without them);
* **repeatability** -- the scatter between runs of one level. Where the data hold
  repeats (rows sharing a level), the pooled within-level variance of the relative
  values ``y / mean_level(y) - 1`` (``nu = sum_g (n_g - 1)`` degrees of freedom).
  Otherwise, and added to repeats of fewer than :data:`MIN_REPEAT_DOF` degrees of
  freedom, the scatter of the level means (``ln y``) about a *model-free* smooth curve
  of the amplitude (:func:`smooth_scatter`): of several curve families (lines and
  parabolas in the log amplitude, one or two power laws of amplitude with exponents
  from a grid, a Muntz polynomial) the one with the least leave-one-out error (PRESS,
  Allen 1974), ``sigma^2 = RSS / (n - k)`` with a grid exponent counted as a parameter;
  when the run order is not monotone in amplitude (:func:`time_separable`, the rule that
  also decides whether a drift with time can be tested), a step between two runs or a drift
  with time is taken out where it lowers the leave-one-out error by
  :data:`~inverse.judge.noise.RUN_ORDER_GAIN` (a change with time is not repeatability).
  That term is found over the rows, so a level run again later differs by it, and it
  is taken out of the repeats and the level means alike; its parameters count against
  the curve's degrees of freedom, and against the repeats' when they serve alone and
  the term differs between runs of one level.
  The curve is not the model being judged: a misfit of that model
  cannot hide as noise. Both estimates measure the *total* scatter; the repeatability
  is what exceeds the identification's part, ``rep^2 = s^2 - mean(ident^2)``, when it
  exceeds it significantly: ``nu s^2 / mean(ident^2)`` above the ``1 -``
  :data:`~inverse.judge.noise.SCATTER_P` quantile of chi-square(nu); else 0 (an estimate
  on a few dof exceeds a correct identification noise in half the series by chance,
  and would trade known noise for one on those few dof).
* **assumed** -- a rig repeats a level to about 0.05 % in frequency and 3 % in damping
  (:data:`RIG_REPEATABILITY`, or what the user states): a prior of 2 dof pooled with
  the estimate (Smyth 2004's moderated variance, :mod:`inverse.judge.prior`) wherever a
  repeatability is estimated (not where the scatter stays within a known
  identification noise, above) and the scatter does not contradict it (two-sided
  chi-square at 5 %); its dof add to the estimate's. The words say whether it was used.
* **total** ``= sqrt(identification^2 + repeatability^2)``, floored at
  :data:`FLOORS` (the digits a table prints). ``dof`` is ``inf`` when the repeatability
  part is 0 (the identification's stds are taken as known), else the estimate's.

Fit test (:func:`fit_test`): with known noise ``chi2 ~ chi-square(N - k)``; with an
estimated repeatability ``(chi2 / (N - k)) ~ F(N - k, nu)``, ``nu`` the channels' degrees
of freedom combined by moment matching (Satterthwaite 1946):
``nu = N^2 / sum_c (n_c^2 / nu_c)`` over the ``n_c`` rows of each estimated channel,
``N`` the rows of every channel (a known channel adds no variance to the estimate).

Selection (:func:`select`): the IC of a candidate is ``chi2 + 2k + T n_causes``
(``T`` = :data:`T_CAUSE`, prior odds ``e^-3`` per cause, :mod:`inverse.diagnose`);
Akaike weights ``w_i ~ exp(-IC_i / 2)``. The information criterion takes the noise as
known; with a noise estimated on ``nu`` degrees of freedom a candidate's drop of chi2
from the base model, ``q`` parameters more, is ``q F(q, nu)`` under no effect, far
heavier-tailed than ``chi-square(q)`` at small ``nu`` (``P(F(2, 3) > 5) = 0.11``
against ``P(chi2_2 > 10) = 0.007``). The drop enters the IC at its known-noise
equivalent of equal tail probability (:func:`known_noise_equivalent`), so a cause is
named at the same false-alarm rate whatever the noise's degrees of freedom (the causes'
ICs are raised together, by the shift the best eligible cause needs, so that they keep
their chi2 differences among themselves). The ``nu``
of a drop is that of the channels it comes from (:func:`drop_dof`: Satterthwaite with
each channel weighted by its share of the drop): a force shortfall found in the
response channel alone is judged on that channel's few degrees of freedom, not on all
channels pooled. A candidate is *eligible* when its fit test
gives ``p >= P_UNEXPLAINED``, it is not excluded (a refuted base model, an inactive
extension) and, if it names a cause, its held-out gain exceeds 1 (a gain over failed
folds is None: not eligible) and, for several causes, that of each of its causes alone
(where known: the added cause must predict unseen levels better). A series too short to
leave a level out (the candidate has as many parameters as the data without one
level) has no gain to measure: there the candidate is judged by its fit test and its
IC alone, and the report says the gain is ``n/a`` and why (``unexplained`` would be
false when it brings the data within their noise, and ``none`` when the base model is
refuted or its IC far worse). The named
explanation is the eligible candidate of
largest weight; none eligible: ``unexplained``, with the closest miss and why it
missed. ``ambiguous`` when another eligible candidate has at least
:data:`W_AMBIGUOUS` of the named one's weight.

Power (:mod:`inverse.judge.power`): for an effect of known size, the most any test
could detect (:func:`detection_bound`) and what this rule names when the cause's form
is right (:func:`naming_power`); ``benchmarks/bench_diagnose.py`` prints both.
"""
from __future__ import annotations

from inverse.judge.bounds import Bounded, at_bound
from inverse.judge.noise import (FLOORS, MIN_REPEAT_DOF, NoiseModel, noise_model,
                                 pooled_repeats, smooth_scatter, time_separable)
from inverse.judge.power import detection_bound, naming_power
from inverse.judge.prior import RIG_REPEATABILITY, RepeatabilityPrior, prior_for
from inverse.judge.selection import (P_UNEXPLAINED, T_CAUSE, W_AMBIGUOUS, Candidate, FitTest,
                                     Selection, drop_dof, drop_for_known_noise,
                                     effective_dof,
                                     fit_test, known_noise_equivalent, select)

__all__ = ["P_UNEXPLAINED", "T_CAUSE", "W_AMBIGUOUS", "MIN_REPEAT_DOF", "FLOORS",
           "NoiseModel", "noise_model", "smooth_scatter", "pooled_repeats", "time_separable",
           "FitTest", "fit_test", "effective_dof", "drop_dof", "known_noise_equivalent",
           "drop_for_known_noise",
           "Candidate", "Selection", "select", "Bounded", "at_bound", "detection_bound",
           "naming_power", "RIG_REPEATABILITY", "RepeatabilityPrior", "prior_for"]
