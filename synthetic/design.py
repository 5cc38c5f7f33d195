"""Drawing one test: the structure, its levels and runs, and the hidden mechanisms sized
to a visibility in noise units (ranges in the package doc).

Sizing: every mechanism's ``strength`` is set by bisection so that the predicted
visibility (:func:`predicted_visibility`: the backbone at each run's resonance with
and without it, :func:`.rig.resonance`, in units of the run's noise: the planted
repeatability and the identification sd of a noisy sizing pass without the hidden
mechanisms) meets a target
drawn log-uniformly in [5, 40]; the honest visibility, from identifying noise-free
FRFs with and without it, is measured afterwards (:mod:`.measure`) and stored.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from synthetic import mechanisms as mx
from synthetic.first_harmonic import SliderBank
from synthetic.rig import Structure, resonance

__all__ = ["Plan", "TooLarge", "draw_structure", "draw_plan", "draw_exciter", "add_mechanism",
           "predicted_visibility", "logu"]

VIS_TARGET = (5.0, 40.0)


class TooLarge(ValueError):
    """A drawn size is implausible or cannot be reached: the caller draws again."""


def logu(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


@dataclass
class Plan:
    """The test: ``control``; ``held`` per level (force-drive level, volts for a
    voltage drive, or amplitude m); ``lines`` per level (rad/s); chronological
    ``runs`` as (level index, :class:`.mechanisms.Run`, repeat flag); FRF noise
    ``eps_m``, ``eps_a``; ``force_column``, ``force_noise``; repeatability sds
    ``s_f`` (relative frequency) and ``s_z`` (relative damping); ``sigma_id`` the
    identification sd (omega2, zeta) of each run without the hidden mechanisms."""

    control: str
    held: np.ndarray
    runs: list
    eps_m: float
    eps_a: float
    force_column: bool
    force_noise: float
    s_f: float
    s_z: float
    run_kind: str
    lines: list = field(default_factory=list)
    sigma_id: tuple = (1.0, 1.0)
    grid: str = "per-level"
    n_lines: int = 40


def draw_structure(rng, macro: str | None):
    """The mode and its micro-slip joint. ``macro`` = "tapered-edge" gives the joint an
    edge it passes at the top (returned as a mechanism). Returns (structure, truth,
    x_top m, tapered-edge mechanism or None)."""
    f0, zeta0 = logu(rng, 15.0, 800.0), logu(rng, 0.0015, 0.02)
    chi = rng.uniform(-0.9, -0.1)
    w0, x_top = 2 * math.pi * f0, logu(rng, 1e-6, 1e-4)
    growth = logu(rng, 0.3, 3.0)                  # joint damping at the top / zeta0
    core = SliderBank(1.0, chi, 1e6 * x_top)      # the power law, nowhere near its end
    dk1, kq1 = core.loss(np.array([x_top]))
    R = 2 * w0**2 * growth * zeta0 / kq1[0]
    if R * dk1[0] > 0.04 * w0**2:                 # frequency drop at most 4 % of omega^2
        R = 0.04 * w0**2 / dk1[0]
    x_slip = rng.uniform(0.2, 0.9)                # top slip / phi_max in micro-slip
    edge = None
    if macro == "tapered-edge":
        phi_m = x_top / rng.uniform(1.15, 2.5)
        edge = mx.TaperedEdge(phi_t=phi_m * rng.uniform(0.55, 0.85), phi_m=phi_m,
                              taper=rng.uniform(0.5, 2.0))
        x_slip = x_top / phi_m
    joint = SliderBank(R, chi, x_top / x_slip if edge is None else 1e6 * x_top)
    neighbour = None
    if rng.random() < 0.4:
        ratio = rng.uniform(0.4, 0.7) if rng.random() < 0.5 else rng.uniform(1.5, 2.5)
        neighbour = (ratio * w0, rng.uniform(0.3, 1.0) * rng.choice([-1.0, 1.0]))
    st = Structure(w0, zeta0, joint, neighbour=neighbour)
    truth = dict(f0=f0, zeta0=zeta0, chi=chi, R=R, x_top=x_top, top_slip_over_phi_max=x_slip,
                 joint_growth=growth, neighbour=neighbour)
    return st, truth, x_top, edge


def _run_order(rng, n, timed):
    kinds = ["shuffled", "interleaved"] + ([] if timed else ["ascending", "descending"])
    kind = str(rng.choice(kinds))
    if kind == "ascending":
        return list(range(n)), kind
    if kind == "descending":
        return list(range(n))[::-1], kind
    if kind == "interleaved":          # odd levels going up, even levels coming down
        return list(range(0, n, 2)) + list(range(n - 1 - (n % 2 == 1), 0, -2)), kind
    return [int(v) for v in rng.permutation(n)], kind


def draw_plan(rng, st, n, control, x_top, timed, rep_on, n_repeats, force_exciter=None):
    """Levels, run order (with ``n_repeats`` repeated levels), repeatability, noise."""
    ratio = rng.uniform(1.15, 1.6)
    rel = np.sort(ratio ** (np.arange(n) - (n - 1.0)) * np.exp(0.03 * rng.standard_normal(n)))
    rel /= rel[-1]
    order, kind = _run_order(rng, n, timed)
    seq = [(v, False) for v in order]
    for r in range(n_repeats):
        if r == 0:
            seq.append((0, True))                       # the lowest level again at the end
        else:
            v = int(rng.integers(1, n))
            first = [s[0] for s in seq].index(v)
            seq.insert(int(rng.integers(first + 1, len(seq) + 1)), (v, True))
    s_f = logu(rng, 2e-4, 1e-3) if rep_on else 0.0
    s_z = rng.uniform(0.01, 0.05) if rep_on else 0.0
    dur = rng.uniform(0.7, 1.3, len(seq))
    start = np.concatenate([[0.0], np.cumsum(dur)[:-1]]) / dur.sum()
    runs = [(v, mx.Run(k + 1, float(start[k]), float(s_f * rng.standard_normal()),
                       float(s_z * rng.standard_normal())), rep)
            for k, (v, rep) in enumerate(seq)]
    plan = Plan(control, rel.copy(), runs, eps_m=logu(rng, 5e-4, 8e-3),
                eps_a=logu(rng, 1e-4, 3e-3), force_column=bool(rng.random() < 0.85),
                force_noise=rng.uniform(0.0, 5e-3), s_f=s_f, s_z=s_z, run_kind=kind,
                grid=str(rng.choice(["per-level", "fixed"])), n_lines=int(rng.integers(25, 91)))
    nominal = mx.Run(1)
    if control == "response":
        plan.held = x_top * rel
    else:
        _, w2, zeta, _ = resonance(st, "response", x_top, nominal)
        if force_exciter is not None:
            st.exciter = force_exciter
        g = st.exciter.nominal_gain(st.omega0)
        plan.held = x_top * 2 * zeta * w2 / g * rel          # the top level reaches ~x_top
        if isinstance(st.exciter, mx.AmplifierClipping):     # knee relative to the top
            st.exciter.v_s *= float(plan.held[-1])
    return plan


def predicted_visibility(st, mech, plan, base=None):
    """Range over the runs of the change ``mech`` makes in (omega2, zeta) at
    resonance, each in units of the run's noise (identification and repeatability);
    the larger of the two. ``base``: the values without it (computed if None)."""
    def values(s):
        out = np.array([resonance(s, plan.control, plan.held[v], run)[1:3]
                        for v, run, _ in plan.runs])
        return out
    with_ = values(st)
    without = values(st.without(mech)) if base is None else base
    u_w = np.hypot(plan.sigma_id[0], 2 * plan.s_f * with_[:, 0])
    u_z = np.hypot(plan.sigma_id[1], plan.s_z * with_[:, 1])
    dw, dz = (with_[:, 0] - without[:, 0]) / u_w, (with_[:, 1] - without[:, 1]) / u_z
    return float(max(np.ptp(dw), np.ptp(dz)))


def _size(st, mech, plan, target, nominal, sign=1.0, upper=None):
    """Set ``mech.strength`` (bisection in log) so the predicted visibility is ``target``."""
    base = np.array([resonance(st.without(mech), plan.control, plan.held[v], run)[1:3]
                     for v, run, _ in plan.runs])
    lo, hi = math.log(nominal * 1e-4), math.log(upper if upper else nominal * 1e4)
    mech.strength = sign * math.exp(hi)
    if predicted_visibility(st, mech, plan, base) < target:
        raise TooLarge(f"{mech.family}: visibility {target:.0f} not reachable")
    for _ in range(16):
        mid = 0.5 * (lo + hi)
        mech.strength = sign * math.exp(mid)
        lo, hi = (lo, mid) if predicted_visibility(st, mech, plan, base) > target else (mid, hi)
    mech.strength = sign * math.exp(0.5 * (lo + hi))
    return predicted_visibility(st, mech, plan, base)


def add_mechanism(rng, family, st, plan, x_top, truth, edge=None):
    """Draw the shape of ``family``, add it to ``st`` and size it; records in ``truth``."""
    w0, z0 = st.omega0, st.zeta0
    target = logu(rng, *VIS_TARGET)
    sign, upper, size = 1.0, None, True
    if family == "slip-ring":
        hi = x_top / rng.uniform(1.2, 3.0)
        m, nominal = mx.SlipRing(lo=hi * rng.uniform(0.4, 0.8), hi=hi), 0.01 * w0**2
        upper = 0.3 * w0**2
    elif family == "tapered-edge":
        m, size = edge, False
    elif family == "snubber-squeeze-film":
        m, nominal = mx.SnubberFilm(gap=x_top * rng.uniform(0.25, 0.7)), 2 * z0 * w0
    elif family == "lazan-knee":
        m = mx.LazanKnee(x_knee=x_top * rng.uniform(0.5, 1.0), n1=rng.uniform(2.2, 2.6),
                         n2=rng.uniform(6.0, 8.0))
        nominal = 2 * z0 * w0**2
    elif family in ("power-spring", "softening-spring"):
        a = (rng.uniform(2.5, 4.0) if family == "softening-spring" else
             rng.uniform(1.5, 2.2) if rng.random() < 0.5 else rng.uniform(5.5, 7.0))
        m, nominal = mx.PowerSpring(a=a, x_ref=x_top), 1e-3 * w0**2
        if family == "softening-spring":
            m.family, m.cause, sign, upper = "softening-spring", "unexplained", -1.0, 0.1 * w0**2
    elif family == "hertz-stop":
        m, nominal = mx.HertzStop(gap=x_top * rng.uniform(0.1, 0.6)), 1e-2 * w0**2
    elif family == "capped-dashpot":
        m = mx.CappedDashpot(x_cap=x_top * rng.uniform(0.15, 0.5), w_cap=w0)
        nominal, upper = 2 * z0 * w0, 20 * z0 * w0
    elif family == "temperature-step":
        ts = sorted(run.t for _, run, _ in plan.runs)
        k = int(rng.integers(max(1, len(ts) // 3), max(2, (2 * len(ts)) // 3 + 1)))
        m, nominal = mx.TemperatureStep(t_step=0.5 * (ts[k - 1] + ts[k])), 1e-3
        sign = float(rng.choice([-1.0, 1.0]))
    elif family in ("room-cycle", "damping-drift"):
        cls = mx.RoomCycle if family == "room-cycle" else mx.DampingDrift
        m = cls(ramp=rng.uniform(-2.0, 2.0), period=rng.uniform(0.7, 2.0),
                phase=rng.uniform(0, 2 * math.pi))
        nominal = 1e-3 if family == "room-cycle" else 0.1
        sign = float(rng.choice([-1.0, 1.0])) if family == "room-cycle" else 1.0
        upper = 0.05 if family == "room-cycle" else 3.0
    elif family == "bolt-loosening-step":
        ts = sorted(run.t for _, run, _ in plan.runs)
        k = int(rng.integers(max(1, len(ts) // 3), max(2, (2 * len(ts)) // 3 + 1)))
        m = mx.BoltLoosening(t_step=0.5 * (ts[k - 1] + ts[k]), kt_share=rng.uniform(0.1, 0.5))
        nominal, upper = 0.05, 0.7
    elif family in ("shaker-impedance", "amplifier-clipping"):
        m, size = st.exciter, False          # drawn with the plan (draw_exciter)
    else:
        raise ValueError(f"unknown family {family!r}")
    if m is not st.exciter:
        st.mechanisms.append(m)
    vis = _size(st, m, plan, target, nominal, sign, upper) if size else None
    truth.setdefault("mechanisms", []).append(dict(
        family=family, cause=m.cause, target_visibility=target if size else None,
        predicted_visibility=vis, parameters={k: v for k, v in vars(m).items()
                                              if isinstance(v, (int, float, bool))}))
    return m


def draw_exciter(rng, family, st, zeta_top):
    """The voltage drive of a force-shortfall family (sizes in the package doc)."""
    w0 = st.omega0
    if family == "shaker-impedance":
        c_e = rng.uniform(0.5, 4.0) * 2 * zeta_top * w0   # back-EMF damping vs the mode's
        tau = rng.uniform(0.05, 0.4) / w0
        m_a = rng.uniform(0.02, 0.15)
        return mx.ShakerImpedance(Bl=math.sqrt(c_e), R_c=1.0, L=tau, m_a=m_a,
                                  k_a=m_a * (w0 * rng.uniform(0.05, 0.3)) ** 2,
                                  c_a=0.01 * m_a * w0)
    x = rng.uniform(0.6, 1.4)                            # top volts / clipping knee
    return mx.AmplifierClipping(g=1.0, v_s=1.0 / x)
