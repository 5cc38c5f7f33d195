"""Random stepped-sine series of one jointed mode with hidden effects, identified from
their FRFs: the test data of the diagnosis (tests and ``benchmarks/bench_diagnose.py``).

A label names what is hidden: ``none``, a cause of the catalogue, two causes
``"a+b"``, or an effect outside the catalogue (:data:`OUT_OF_CATALOGUE`, or
``out-of-catalogue`` for a random one). Everything else is drawn from the seed and
never shown to the diagnosis: level count 5-12, level ratio 1.25-2 (jittered), force or
response control (response for 40 % of the series that can have it), natural
frequency 20-500 Hz, viscous damping ratio 0.2-2 %, chi in (-0.85, -0.15), Dirac weight
beta 0.2-5, FRF noise 0.02-0.5 % with 31-81 lines, the run order (shuffled, ascending,
or up-and-down; never ascending when the hidden effect follows time), the joint's
damping growth (15-400 identification standard deviations of a linear level; for a
preload loss 40-100 % of the largest allowed; frequency drop at most 8 % of omega^2), the top slip 0.3-0.9 phi_max (more for macro-slip), and each effect's
family and size. Sizes are in units of the identification's standard uncertainty at
the top level (a sizing pass identifies the top level without effects; for macro-slip
a second pass at the macro-slip amplitude): 15-120
(macro-slip departure from the power law 15-200; force shortfall 8-40 % at the top;
out-of-catalogue effects 20-150).

Families (wider than the diagnosis's extensions): hardening by a power-law spring
(exponent 2.5-5), a cubic + quintic pair or a contact past a gap; added damping by a
power-law damper (exponent 1.4-3.5) or a damper with an onset that saturates; drift
linear in the run order or an exponential warm-up, either sign; the shortfall steady
per step, an amplifier that saturates, or a voltage drive with back-EMF that also
saturates. Outside the catalogue: ``damping-falls`` (a damping treatment whose loss
falls with amplitude), ``softening`` (a softening power-law spring, no dissipation),
``preload-loss`` (the bolt preload relaxes with run order, 20-60 % over the test: slip
strengths and stuck stiffness fall, :class:`cases.synthetic_series.mode.JointedMode`;
its damping change must reach 15 stds at some level, else after 40 draws the series is
drawn under response control).
"""
from __future__ import annotations

import math
import zlib

import numpy as np

from cases.synthetic_series.hidden import TooLarge, add_effects
from cases.synthetic_series.levels import SyntheticSeries, force_for, noisy, simulate_levels
from cases.synthetic_series.mode import JointedMode, level_frf
from ident.identify import identify
from joints.describing import describing_function, kappa1, kappa2_exact
from joints.iwan import IwanParameters

__all__ = ["CATALOGUE", "OUT_OF_CATALOGUE", "SyntheticSeries", "generate_series", "truth_of"]

CATALOGUE = ("macro-slip", "nonproportional-amplitude", "geometric-hardening",
             "thermal-drift", "quadratic-damping")
OUT_OF_CATALOGUE = ("damping-falls", "softening", "preload-loss")
_PHI_MAX = 1e-4


def truth_of(label: str) -> tuple:
    """The causes a diagnosis should name for ``label``: () for ``none``,
    ("unexplained",) outside the catalogue, else the catalogue ids."""
    if label == "none":
        return ()
    if label == "out-of-catalogue" or label in OUT_OF_CATALOGUE:
        return ("unexplained",)
    causes = tuple(label.split("+"))
    bad = [c for c in causes if c not in CATALOGUE]
    if bad or len(causes) > 2 or len(set(causes)) < len(causes):
        raise ValueError(f"unknown label {label!r}: none, a cause of "
                         f"{', '.join(CATALOGUE)}, two joined by '+', out-of-catalogue "
                         f"or one of {', '.join(OUT_OF_CATALOGUE)}")
    return causes


def _logu(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _run_order(rng, n, timed):
    kind = rng.choice(["shuffled", "up-down"] if timed else ["shuffled", "ascending",
                                                            "up-down"])
    if kind == "ascending":
        return np.arange(1, n + 1), kind
    if kind == "up-down":       # odd levels going up, even levels coming down
        seq = list(range(0, n, 2)) + list(range(n - 1 - (n % 2 == 1), 0, -2))
        run = np.empty(n, int)
        run[seq] = np.arange(1, n + 1)
        return run, kind
    return rng.permutation(n) + 1, kind


def _lines(mode, x_top, n_lines):
    """Lines covering the resonance from the lowest to the top amplitude (rad/s)."""
    k_in, k_q = describing_function(mode.joint, np.array([1e-9, x_top]))
    w_lo = np.sqrt(mode.omega2_lin + k_in)
    z = (mode.c0 + k_q / w_lo) / (2 * w_lo)
    lo = min(w_lo * (1 - 5 * z)) * 0.995
    hi = max(w_lo * (1 + 5 * z)) * 1.002
    return np.linspace(lo, hi, n_lines)


def _sigma_at(rng, mode, W, x, eps, control):
    """Identification std (omega2, zeta) of a level at amplitude ``x`` under
    ``control`` (a sizing pass: the structure without its hidden effects)."""
    held = x if control == "response" else force_for(mode, x)
    H, _, _, _ = level_frf(mode, W, control, held)
    Hn = noisy(rng, H, eps)
    with np.errstate(all="ignore"):
        mode1 = identify(W / (2 * np.pi), Hn, n_modes=1).modes[0]   # ValueError: redraw
    return mode1.omega2_std, mode1.zeta_std


def _macro_x_top(joint, omega0, target, sig, x_max=3.0):
    """Top slip (units of phi_max) where the exact describing function departs from
    the micro-slip power law by ``target`` identification stds (None if never)."""
    def dev(x):
        A = x * joint.phi_max
        k_in, k_q = describing_function(joint, A)
        p = joint.chi + 1
        dw = joint.K_T - kappa2_exact(joint.R, joint.chi) * A**p - k_in
        dz = (k_q + kappa1(joint.R, joint.chi) * A**p) / (2 * omega0**2)
        return max(abs(dw) / sig[0], abs(dz) / sig[1])
    if dev(x_max) < target:
        return None
    lo, hi = 1.0, x_max
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if dev(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def _attempt(rng, causes, ooc, n, control):
    f0, zeta0, chi = _logu(rng, 20, 500), _logu(rng, 0.002, 0.02), rng.uniform(-0.85, -0.15)
    beta, eps, n_lines = _logu(rng, 0.2, 5.0), _logu(rng, 2e-4, 5e-3), int(rng.integers(31, 82))
    omega0, p = 2 * math.pi * f0, chi + 1
    x_top = rng.uniform(0.3, 0.9)
    # joint: damping growth at the top in stds of a linear level, frequency drop <= 8 %
    weak = IwanParameters.from_density(1e-9, chi, _PHI_MAX, 0.0)
    linear = JointedMode(omega0**2 - weak.K_T, 2 * zeta0 * omega0, weak)
    sig0 = _sigma_at(rng, linear, _lines(linear, 1e-9, n_lines), 1e-9, eps, control)
    tie = kappa2_exact(1.0, chi) / -kappa1(1.0, chi)
    dz_top = min(_logu(rng, 15.0, 400) * sig0[1], 0.04 / tie, 3 * zeta0)
    if ooc == "preload-loss":      # a run-order damping change needs a strong joint
        dz_top = min(0.04 / tie, 3 * zeta0) * rng.uniform(0.4, 1.0)
    x_micro = 1.0 if "macro-slip" in causes else x_top
    R = 2 * omega0**2 * dz_top / (-kappa1(1.0, chi) * (x_micro * _PHI_MAX) ** p)
    joint = IwanParameters.from_density(R, chi, _PHI_MAX, beta * R * _PHI_MAX**p / p)
    mode = JointedMode(omega0**2 - joint.K_T, 2 * zeta0 * omega0, joint)
    if mode.omega2_lin <= 0.1 * omega0**2:
        return None
    W = _lines(mode, x_top * _PHI_MAX, n_lines)
    sig = _sigma_at(rng, mode, W, x_top * _PHI_MAX, eps, control)
    truth = dict(f0=f0, zeta0=zeta0, chi=chi, beta=beta, eps=eps, n_lines=n_lines, R=R,
                 dzeta_top_joint=dz_top, sigma_omega2_top=sig[0], sigma_zeta_top=sig[1])
    if "macro-slip" in causes:         # sized in the noise of the macro-slip top level
        target = _logu(rng, 15, 200)
        x_top = _macro_x_top(joint, omega0, target, sig)
        if x_top is None:
            return None
        W = _lines(mode, x_top * _PHI_MAX, n_lines)
        sig = _sigma_at(rng, mode, W, x_top * _PHI_MAX, eps, control)
        x_top = _macro_x_top(joint, omega0, target, sig)
        if x_top is None:
            return None
        W = _lines(mode, x_top * _PHI_MAX, n_lines)
        truth.update(sigma_omega2_top=sig[0], sigma_zeta_top=sig[1])
    X_top = x_top * _PHI_MAX
    truth["x_top"] = x_top
    ratio = rng.uniform(1.25, 2.0)
    rel = np.sort(ratio ** (np.arange(n) - (n - 1.0)) * np.exp(0.03 * rng.standard_normal(n)))
    rel /= rel[-1]
    run, truth["run_kind"] = _run_order(rng, n, "thermal-drift" in causes
                                        or ooc == "preload-loss")
    try:
        exciter, scale = add_effects(rng, mode, causes, ooc, X_top, sig, rel, truth, run)
    except TooLarge:
        return None
    if mode.c0 <= 0:
        return None
    truth.update(level_ratio=ratio, held_relative=rel)
    return dict(mode=mode, exciter=exciter, scale=scale, W=W, run=run, X_top=X_top,
                rel=rel, eps=eps, truth=truth)


def generate_series(label: str, seed: int, n_levels: int | None = None,
                    control: str | None = None) -> SyntheticSeries:
    """Simulate and identify one series hiding ``label`` (module doc).

    ``n_levels`` and ``control`` fix what is otherwise drawn. The seed and the label
    set every random draw; the same pair gives the same series."""
    causes = truth_of(label)
    ooc = None
    rng = np.random.default_rng([int(seed), zlib.crc32(label.encode())])
    if causes == ("unexplained",):
        ooc = label if label in OUT_OF_CATALOGUE else str(rng.choice(OUT_OF_CATALOGUE))
        causes = ()
    n = int(n_levels or rng.integers(5, 13))
    if control is None:
        control = ("force" if "nonproportional-amplitude" in causes or rng.random() < 0.6
                   else "response")
    if control == "response" and "nonproportional-amplitude" in causes:
        raise ValueError("nonproportional-amplitude needs force control")
    for attempt in range(80):
        if attempt == 40 and ooc == "preload-loss" and control == "force":
            control = "response"   # too distorted under force control to see it
        try:
            drawn = _attempt(rng, causes, ooc, n, control)
        except (ValueError, IndexError, np.linalg.LinAlgError):
            drawn = None
        if drawn is None:
            continue
        series = simulate_levels(rng, drawn, control)
        if series is not None and "macro-slip" in causes and series.truth["x_peak"][-1] < 1.02:
            series = None                  # the shortfall kept the joint in micro-slip
        if series is not None:
            series.truth.update(label=label, causes=truth_of(label), ooc=ooc, seed=seed,
                                control=control, n_levels=n, attempts=attempt + 1)
            return series
    raise RuntimeError(f"could not draw a series for {label!r}, seed {seed}")
