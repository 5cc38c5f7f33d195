"""Which causes this test design can tell apart: a confusion analysis on the series' own
levels, run order and noise.

For each testable cause A, a noise-free series is built from the base fit plus A's
signature (:func:`signature`) scaled so that A is *just* detectable: the base model
misses it by ``chi2 = T + 2 q_A`` (``q_A`` A's extra parameters), i.e. A beats the
base by the naming threshold ``T`` of :mod:`inverse.diagnose` in AIC (with a noise
estimated on ``nu`` dof, by the drop whose known-noise equivalent that is). Every other
single cause B is fitted to that series; A and B cannot be separated when B reaches at
least the ambiguity fraction of A's weight there (``IC_B - IC_A < 2 ln(1/w)``), i.e. the
measurement would call a just-detectable A ambiguous with B (or name B). A cause whose
model cannot be fitted (too few data, no response column) is untestable.

Signatures (typical shapes, on the base fit's chi and hysteretic stiffness): each
cause's ``signature`` in :mod:`inverse.diagnosis.causes`.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from inverse.diagnosis.fit import MAX_ITERS, fit_model
from inverse.diagnosis.causes import CATALOGUE, CAUSES
from inverse.diagnosis.models import Model, Observations
from inverse.diagnosis.params import physical_parameters
from inverse.judge import drop_for_known_noise

__all__ = ["signature", "separability", "separating_measurement", "SEPARATING_MEASUREMENT"]
#: What measurement separates two causes (physics of their signatures).
SEPARATING_MEASUREMENT = {
    frozenset(("macro-slip", "nonproportional-amplitude")):
        "measure the response amplitude at the drive point or run the test under "
        "response control: macro-slip bends omega2 and zeta against the measured "
        "amplitude too, a force shortfall does not",
    frozenset(("macro-slip", "geometric-hardening")):
        "add levels above the top one: macro-slip lowers the frequency ever faster, "
        "hardening raises it",
    frozenset(("macro-slip", "quadratic-damping")):
        "add levels above the top one: past phi_max the damping ratio of macro-slip "
        "levels off (Coulomb) while the frequency keeps dropping; added damping keeps "
        "growing without a frequency drop",
    frozenset(("nonproportional-amplitude", "geometric-hardening")):
        "measure the response amplitude or run under response control: a shortfall "
        "slows the frequency drop against the excitation, not against the response",
    frozenset(("nonproportional-amplitude", "quadratic-damping")):
        "measure the response amplitude or run under response control: a shortfall "
        "bends the damping growth against the excitation, not against the response",
    frozenset(("geometric-hardening", "quadratic-damping")):
        "add levels above the top one: hardening moves the frequency, the added damping "
        "only the damping ratio; both grow faster than the Iwan power law",
}


def _advice(a: str, b: str) -> str:
    if "thermal-drift" in (a, b):
        return CATALOGUE["thermal-drift"].ADVICE
    return SEPARATING_MEASUREMENT.get(frozenset((a, b)), "add levels above the top one")


def separating_measurement(a: tuple, b: tuple) -> str:
    """What measurement would separate explanation ``a`` from ``b`` (cause tuples)."""
    only_a = [c for c in a if c not in b]
    only_b = [c for c in b if c not in a]
    if only_a and only_b:
        return f"{only_a[0]} vs {only_b[0]}: " + _advice(only_a[0], only_b[0])
    c = (only_a or only_b)[0]
    return f"whether {c} is there: " + CATALOGUE[c].ADVICE


def signature(cause: str, obs: Observations, base_params: dict):
    """Change of (omega2, zeta, log response) at every level that ``cause`` adds to
    the base fit (its file's ``signature``), in the channels' units, unscaled."""
    return CATALOGUE[cause].signature(obs, base_params)


def _with_data(obs, omega2, zeta, log_r):
    return replace(obs, omega2=omega2, zeta=zeta, log_r=log_r)


def _ic(fit, t_cause):
    return None if fit.aic is None else fit.aic + t_cause * len(fit.model.causes)


def separability(obs: Observations, fits: dict, models: list, unavailable: dict,
                 t_cause: float, w_ambiguous: float, nu: float = math.inf) -> dict:
    """Pairs of causes this design cannot separate, and untestable causes. ``nu``: the
    noise's degrees of freedom (a just-detectable cause then needs the larger drop
    whose known-noise equivalent is ``T + 2 q``, as :func:`inverse.judge.select` names
    it).

    Returns ``{"inseparable": [{"causes": [A, B], "mimics": ..., "measurement": ...}],
    "untestable": {cause: reason}, "unconverged_fits": n}`` (``n`` of its fits did not
    converge, :mod:`inverse.diagnosis.lm`)."""
    base = fits["none"]
    untestable = {m: r for m, r in unavailable.items() if "+" not in m}
    singles = []
    for m in models:
        if len(m.causes) == 1:
            f = fits[m.name]
            if f.aic is None:
                untestable[m.name] = (f"{f.n_data} data for {f.n_params} parameters: "
                                      "the criterion is undefined")
            else:
                singles.append(m.causes[0])
    bp = physical_parameters(base, obs)
    n = obs.n
    pred = [v - base.residual[i * n:(i + 1) * n] * obs.sigma[ch]
            for i, (ch, v) in enumerate(zip(obs.channels, (obs.omega2, obs.zeta, obs.log_r)))]
    confused, unconverged = {}, 0
    for a in singles:
        eff = signature(a, obs, bp)
        e = np.concatenate([eff[i] / obs.sigma[ch] for i, ch in enumerate(obs.channels)])
        if not np.any(e):
            continue
        scale = 1.0 / np.linalg.norm(e)
        ka = fits[a].n_params
        need = drop_for_known_noise(t_cause + 2.0 * (ka - base.n_params),
                                    ka - base.n_params, nu)

        def synth(c):
            vals = [pred[i] + c * eff[i] for i in range(len(obs.channels))]
            return _with_data(obs, vals[0], vals[1], vals[2] if obs.log_r is not None else None)

        unit = synth(scale)
        if np.any(unit.omega2 <= 0):              # no mode: nothing to tell apart
            continue
        miss_fit = fit_model(Model(), unit, start=base.theta, iters=MAX_ITERS)
        unconverged += not miss_fit.converged
        miss = miss_fit.chi2
        if miss <= 0:
            continue
        data_a = synth(scale * np.sqrt(need / miss))
        if np.any(data_a.omega2 <= 0):
            continue
        fit_a = fit_model(Model((a,)), data_a, n_starts=1, iters=MAX_ITERS)
        unconverged += not fit_a.converged
        ic_a = _ic(fit_a, t_cause)
        for b in singles:
            if b == a:
                continue
            fit_b = fit_model(Model((b,)), data_a, n_starts=1, iters=MAX_ITERS)
            unconverged += not fit_b.converged
            ic_b = _ic(fit_b, t_cause)
            if ic_b - ic_a < 2.0 * np.log(1.0 / w_ambiguous):
                confused.setdefault(frozenset((a, b)), []).append(f"{b} mimics {a}")
    inseparable = [{"causes": sorted(k, key=CAUSES.index), "mimics": v,
                    "measurement": _advice(*sorted(k))} for k, v in confused.items()]
    return {"inseparable": inseparable, "untestable": untestable,
            "unconverged_fits": unconverged}
