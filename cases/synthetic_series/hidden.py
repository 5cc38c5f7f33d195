"""The hidden effects of a synthetic series, drawn and sized (families and ranges in
:mod:`cases.synthetic_series.draw`). Sizes are in identification standard deviations
at the top level, ``sig = (sigma_omega2, sigma_zeta)``; ``X_top`` is the top modal
amplitude (m), ``rel`` the held levels relative to the top (increasing, last 1), ``run``
their run order. Sizes are those of the effect as realized on the levels: a drift over
the run; a preload loss (20-60 % of the preload lost over the test) must change the
joint damping by at least 15 stds at some level, or the draw is rejected."""
from __future__ import annotations

import math

import numpy as np

from cases.synthetic_series import effects as fx
from cases.synthetic_series.mode import Exciter, JointedMode

__all__ = ["add_effects", "TooLarge"]


class TooLarge(ValueError):
    """An effect of the drawn size would be implausible for the drawn structure."""


def _logu(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _gap_shape(X, gap):
    return fx.GapSpring(1.0, gap)(np.asarray(X, float), 0.0, 1.0)[0]


def _hardening(rng, dw, X):
    fam = str(rng.choice(["power", "cubic-quintic", "gap"]))
    if fam == "power":
        a = rng.uniform(2.5, 5.0)
        return fam, [fx.PowerSpring(dw / (fx.power_coefficient(a) * X ** (a - 1)), a)]
    if fam == "cubic-quintic":
        share = rng.uniform(0.2, 0.8)
        return fam, [fx.PowerSpring(share * dw / (0.75 * X**2), 3.0),
                     fx.PowerSpring((1 - share) * dw / (fx.power_coefficient(5.0) * X**4), 5.0)]
    gap = rng.uniform(0.2, 0.7) * X
    return fam, [fx.GapSpring(dw / float(_gap_shape(X, gap)), gap)]


def _damping(rng, dkq, w0, X):
    if rng.random() < 0.5:
        a = rng.uniform(1.4, 3.5)
        return f"power {a:.2f}", fx.PowerDamper(
            dkq / (w0 * fx.power_coefficient(a) * (w0 * X) ** (a - 1)), a)
    xs, m = _logu(rng, 0.3, 2.0) * X, rng.uniform(1.0, 3.0)
    u = (X / xs) ** m
    return f"onset-saturating m={m:.2f}", fx.ShapedDamper(dkq / (w0 * u / (1 + u)), xs, m)


def _shortfall(rng, rel, truth):
    """Nonproportional drive: (exciter or None, per-level force scale or None)."""
    sf = _logu(rng, 0.08, 0.4)
    kind = str(rng.choice(["steady", "saturation", "back-emf"]))
    truth.update(shortfall_top=sf, shortfall_kind=kind)
    if kind == "steady":
        e = -math.log(1 - sf) / math.log(1 / rel[0])
        truth["shortfall_exponent"] = e
        return None, rel ** (-e)
    a = rng.uniform(1.0, 4.0)
    v_s = 1.0 / ((1 - sf) ** -a - 1) ** (1 / a)
    return Exciter(v_s=v_s, a=a), None


def _preload_change(mode, rho, dzeta_top, rel, run, n, tau):
    """Largest change of the joint damping over the levels (each at its amplitude and
    its place in the run order) for a preload loss ``rho``: the joint damping of level
    ``v`` scales as ``rel_v^p (1 - rho f(run_v))^-p``."""
    p = mode.joint.chi + 1
    f = fx.run_shape(run, n, tau)
    return float(np.max(dzeta_top * rel**p * ((1 - rho * f) ** -p - 1)))


def add_effects(rng, mode: JointedMode, causes, ooc, X_top, sig, rel, truth, run):
    """Add the effects of ``causes`` (catalogue ids) or ``ooc`` to ``mode`` in place.

    Returns (exciter or None, force scale per level or None); records families and
    sizes in ``truth``. Raises :class:`TooLarge` when a size exceeds what the
    structure makes plausible (a frequency effect above 4 % of omega^2, an added
    damping above the top level's own damping ratio): the caller draws again."""
    w0, n = mode.omega0, rel.size
    zeta_top = mode.c0 / (2 * w0) + truth["dzeta_top_joint"]
    sized = ooc in ("softening", "damping-falls") or any(
        c != "nonproportional-amplitude" for c in causes)
    if sized and max(150 * sig[0] / w0**2 / 0.04, 150 * sig[1] / zeta_top) > 1.0:
        raise TooLarge("noise too large for plausible effect sizes")
    exciter, scale = None, None
    for c in causes:
        if c == "geometric-hardening":
            u = _logu(rng, 15, 120)
            truth["hardening_family"], springs = _hardening(rng, u * sig[0], X_top)
            mode.effects += springs
            truth["hardening_sigma"] = u
        elif c == "quadratic-damping":
            u = _logu(rng, 15, 120)
            truth["damping_family"], damper = _damping(rng, 2 * w0**2 * u * sig[1], w0, X_top)
            mode.effects.append(damper)
            truth["damping_sigma"] = u
        elif c == "thermal-drift":
            u = _logu(rng, 15, 120) * rng.choice([-1.0, 1.0])
            tau = None if rng.random() < 0.5 else rng.uniform(0.15, 0.8)
            mode.effects.append(fx.Drift(u * sig[0], n, tau))
            truth.update(drift_sigma=u, drift_tau=tau)
        elif c == "nonproportional-amplitude":
            exciter, scale = _shortfall(rng, rel, truth)
            if truth["shortfall_kind"] == "back-emf":
                exciter.c_e = rng.uniform(0.5, 4.0) * mode.c0
    u = _logu(rng, 20, 150)
    if ooc == "damping-falls":
        lo, hi = math.log(rel[0] * X_top), math.log(X_top)
        xs = math.exp(rng.uniform(lo + 0.25 * (hi - lo), lo + 0.75 * (hi - lo)))
        c_d = min(2 * w0 * u * sig[1], 0.8 * mode.c0)
        mode.effects.append(fx.ShapedDamper(c_d, xs, rng.uniform(1.0, 3.0), falling=True))
        mode.c0 -= c_d
        truth.update(ooc_sigma=c_d / (2 * w0 * sig[1]), ooc_x_s=xs / X_top)
    elif ooc == "softening":
        a = rng.uniform(2.5, 4.5)
        mode.effects.append(fx.PowerSpring(-u * sig[0] / (fx.power_coefficient(a)
                                                          * X_top ** (a - 1)), a))
        truth.update(ooc_sigma=u, ooc_exponent=a)
    elif ooc == "preload-loss":
        tau = None if rng.random() < 0.5 else rng.uniform(0.15, 0.8)
        rho = rng.uniform(0.2, 0.6)
        change = _preload_change(mode, rho, truth["dzeta_top_joint"], rel, run, n, tau)
        if change < 15 * sig[1]:
            raise TooLarge("the joint is too weak for a visible preload loss")
        mode.preload_loss = (rho, lambda r: fx.run_shape(r, n, tau))
        truth.update(ooc_sigma=change / sig[1], preload_rho=rho, preload_tau=tau)
    return exciter, scale
