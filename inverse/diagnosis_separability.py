"""Which causes this test design can tell apart: a confusion analysis on the series' own
levels, run order and noise.

For each testable cause A, a noise-free series is built from the base fit plus A's
signature (:func:`signature`) scaled so that A is *just* detectable: the base model
misses it by ``chi2 = T + 2 q_A`` (``q_A`` A's extra parameters), i.e. A beats the
base by the naming threshold ``T`` of :mod:`inverse.diagnose` in AIC. Every other single cause B is
fitted to that series; A and B cannot be separated when B reaches at least the
ambiguity fraction of A's weight there (``IC_B - IC_A < 2 ln(1/w)``), i.e. the
measurement would call a just-detectable A ambiguous with B (or name B). A cause whose
model cannot be fitted (too few data, no response column) is untestable.

Signatures (typical shapes, on the base fit's chi and hysteretic stiffness):
``macro-slip`` top slip 2 phi_max with Dirac weight beta = 1; ``nonproportional-
amplitude`` a steady shortfall of 20 % per decade of excitation (log s -> 0.8 log s);
``geometric-hardening`` omega2 + s^2; ``thermal-drift`` omega2 + t_run;
``quadratic-damping`` zeta + s.
"""
from __future__ import annotations

from dataclasses import replace
import numpy as np

from inverse.diagnosis_fit import fit_model
from inverse.diagnosis_models import CAUSES, Model, Observations, slip_shapes
from inverse.diagnosis_params import physical_parameters
from inverse.iwan_modal import kappa1_per_R, kappa_ratio

__all__ = ["signature", "separability", "separating_measurement", "SEPARATING_MEASUREMENT"]

_REPEAT = ("repeat the lowest level at the end of the test (or shuffle the run order): "
           "drift follows time, not amplitude")
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


#: What strengthens the evidence for (or against) one cause.
MORE_EVIDENCE = {
    "macro-slip": "add levels above the top one (macro-slip grows fast past phi_max)",
    "nonproportional-amplitude": "measure the force reaching the structure (force "
                                 "transducer) or run under response control",
    "geometric-hardening": "add levels above the top one (hardening grows with amplitude "
                           "squared or faster)",
    "thermal-drift": _REPEAT,
    "quadratic-damping": "add levels above the top one (the added damping grows faster "
                         "than the Iwan power law)",
}


def _advice(a: str, b: str) -> str:
    if "thermal-drift" in (a, b):
        return _REPEAT
    return SEPARATING_MEASUREMENT.get(frozenset((a, b)), "add levels above the top one")


def separating_measurement(a: tuple, b: tuple) -> str:
    """What measurement would separate explanation ``a`` from ``b`` (cause tuples)."""
    only_a = [c for c in a if c not in b]
    only_b = [c for c in b if c not in a]
    if only_a and only_b:
        return f"{only_a[0]} vs {only_b[0]}: " + _advice(only_a[0], only_b[0])
    c = (only_a or only_b)[0]
    return f"whether {c} is there: " + MORE_EVIDENCE[c]


def signature(cause: str, obs: Observations, base_params: dict):
    """Change of (omega2, zeta, log response) at every level that ``cause`` adds to
    the base fit (module doc), in the channels' units, unscaled."""
    s, w2, p = obs.s, obs.omega2, base_params["chi"] + 1.0
    chi = p - 1.0
    K1 = max(base_params["kappa1_B"] * s[0] ** -p,
             2.0 * base_params["omega2_0"] * float(np.ptp(obs.zeta)), 1e-300)
    zero = np.zeros(obs.n)
    if cause == "geometric-hardening":
        return s**2, zero, zero
    if cause == "thermal-drift":
        return np.asarray(obs.t_run, float), zero, zero
    if cause == "quadratic-damping":
        return zero, s, zero
    if cause == "nonproportional-amplitude":
        ds = s ** (0.8 * p) - s**p
        return -kappa_ratio(chi, "exact") * K1 * ds, 0.5 * K1 * ds / w2, -0.2 * np.log(s)
    x_top, beta = 2.0, 1.0                                           # macro-slip
    U = K1 / (kappa1_per_R(chi) * x_top**p)
    x = x_top * s
    P1, P2, Q1, Q2 = slip_shapes(x, chi)
    P1m = kappa1_per_R(chi) * x**p
    S = beta * U / p
    d_om = -(U * (P2 - kappa_ratio(chi, "exact") * P1m) + S * Q2)
    return d_om, 0.5 * (U * (P1 - P1m) + S * Q1) / w2, zero


def _with_data(obs, omega2, zeta, log_r):
    return replace(obs, omega2=omega2, zeta=zeta, log_r=log_r)


def _ic(fit, t_cause):
    return None if fit.aic is None else fit.aic + t_cause * len(fit.model.causes)


def separability(obs: Observations, fits: dict, models: list, unavailable: dict,
                 t_cause: float, w_ambiguous: float) -> dict:
    """Pairs of causes this design cannot separate, and untestable causes.

    Returns ``{"inseparable": [{"causes": [A, B], "mimics": ..., "measurement": ...}],
    "untestable": {cause: reason}}``."""
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
    bp = physical_parameters(base, obs, 1.0)
    n = obs.n
    pred = [v - base.residual[i * n:(i + 1) * n] * obs.sigma[ch]
            for i, (ch, v) in enumerate(zip(obs.channels, (obs.omega2, obs.zeta, obs.log_r)))]
    confused = {}
    for a in singles:
        eff = signature(a, obs, bp)
        e = np.concatenate([eff[i] / obs.sigma[ch] for i, ch in enumerate(obs.channels)])
        if not np.any(e):
            continue
        scale = 1.0 / np.linalg.norm(e)
        ka = fits[a].n_params
        need = t_cause + 2.0 * (ka - base.n_params)

        def synth(c):
            vals = [pred[i] + c * eff[i] for i in range(len(obs.channels))]
            return _with_data(obs, vals[0], vals[1], vals[2] if obs.log_r is not None else None)

        miss = fit_model(Model(), synth(scale), start=base.theta, iters=10).chi2
        if miss <= 0:
            continue
        data_a = synth(scale * np.sqrt(need / miss))
        ic_a = _ic(fit_model(Model((a,)), data_a, n_starts=1, iters=12), t_cause)
        for b in singles:
            if b == a:
                continue
            ic_b = _ic(fit_model(Model((b,)), data_a, n_starts=1, iters=12), t_cause)
            if ic_b - ic_a < 2.0 * np.log(1.0 / w_ambiguous):
                confused.setdefault(frozenset((a, b)), []).append(f"{b} mimics {a}")
    inseparable = [{"causes": sorted(k, key=CAUSES.index), "mimics": v,
                    "measurement": _advice(*sorted(k))} for k, v in confused.items()]
    return {"inseparable": inseparable, "untestable": untestable}
