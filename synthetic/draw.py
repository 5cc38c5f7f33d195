"""One series by label and seed: draw, size, measure, identify (package doc).

Labels: ``none``; a catalogue cause; two causes joined by ``+``; an out-of-catalogue
family (:data:`OUT_OF_CATALOGUE`) or ``out-of-catalogue`` (one drawn). The seed and
the label set every draw; the diagnosis sees only ``SyntheticSeries.data``.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from synthetic.design import (TooLarge, add_mechanism, draw_exciter, draw_plan,
                                           draw_structure)
from synthetic.mechanisms import Run
from synthetic.measure import (Refused, honest_visibility, identify_table,
                                            place_lines, simulate_runs)
from synthetic.rig import resonance
from ident.modal_data import MeasuredData

__all__ = ["CATALOGUE", "OUT_OF_CATALOGUE", "FAMILIES", "SyntheticSeries",
           "generate_series", "truth_of", "without_stds"]

CATALOGUE = ("macro-slip", "nonproportional-amplitude", "geometric-hardening",
             "thermal-drift", "quadratic-damping")
OUT_OF_CATALOGUE = ("bolt-loosening-step", "capped-dashpot", "softening-spring",
                    "damping-drift")
FAMILIES = {"macro-slip": ("slip-ring", "tapered-edge"),
            "nonproportional-amplitude": ("shaker-impedance", "amplifier-clipping"),
            "geometric-hardening": ("power-spring", "hertz-stop"),
            "thermal-drift": ("temperature-step", "room-cycle"),
            "quadratic-damping": ("snubber-squeeze-film", "lazan-knee")}
VIS_MIN = 3.0
_TIMED = ("thermal-drift", "bolt-loosening-step", "damping-drift")


@dataclass
class SyntheticSeries:
    """A generated series: the identified table the diagnosis sees, the noisy FRFs of
    every run (``frfs``: ``freq_hz``, ``frf``, ``force``, ``held``, ``run_order``,
    ``level``, ``repeat``, ``control``) and the hidden truth."""

    data: MeasuredData
    frfs: list
    truth: dict = field(default_factory=dict)


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


def without_stds(data: MeasuredData) -> MeasuredData:
    """The same table without ``omega2_std`` and ``zeta_std`` (the path of tables
    typed from a paper): the other noise path of the benchmark."""
    out = data.take(np.arange(len(data)))
    out.omega2_std = None
    out.zeta_std = None
    return out


def _sigma_id(rng, st, plan):
    """Identification sd (omega2, zeta) per run of the structure without its hidden
    mechanisms: the series simulated with noise and identified (the sizing pass)."""
    place_lines(rng, st, plan)
    data = identify_table(simulate_runs(rng, st, plan), plan)
    rows = {(int(lv), int(ro)): i for i, (lv, ro) in enumerate(zip(data.level, data.run_order))}
    idx = [rows[(v + 1, run.k)] for v, run, _ in plan.runs]
    return data.omega2_std[idx], data.zeta_std[idx]


def _attempt(rng, causes, ooc, n, control, rep_on, n_rep):
    fams = [str(rng.choice(FAMILIES[c])) for c in causes] + ([ooc] if ooc else [])
    macro = "tapered-edge" if "tapered-edge" in fams else None
    st, truth, x_top, edge = draw_structure(rng, macro)
    exc_fam = next((f for f in fams if f in FAMILIES["nonproportional-amplitude"]), None)
    exciter = None
    if exc_fam:
        exciter = draw_exciter(rng, exc_fam, st, resonance(st, "response", x_top, Run(1))[2])
    timed = any(c in _TIMED for c in causes) or ooc in _TIMED
    plan = draw_plan(rng, st, n, control, x_top, timed, rep_on, n_rep, exciter)
    plan.sigma_id = _sigma_id(rng, st, plan)
    order = sorted(fams, key=lambda f: f in ("shaker-impedance", "amplifier-clipping"))
    mechs = [add_mechanism(rng, f, st, plan, x_top, truth, edge) for f in order]
    place_lines(rng, st, plan)
    sims = simulate_runs(rng, st, plan)
    data = identify_table(sims, plan)
    vis, free = honest_visibility(st, plan, data, mechs)
    for rec, v in zip(truth.get("mechanisms", []), vis):
        rec.update(v)
        if v["visibility"] is None or v["visibility"] < VIS_MIN:
            raise Refused(f"{v['family']}: honest visibility {v['visibility']} < {VIS_MIN}")
    truth.update(families=fams, run_kind=plan.run_kind, repeatability=dict(
        on=rep_on, s_f=plan.s_f, s_z=plan.s_z,
        eps_f=[r.eps_f for _, r, _ in plan.runs], eps_z=[r.eps_z for _, r, _ in plan.runs]),
        n_repeats=n_rep, force_column=plan.force_column, eps_m=plan.eps_m, eps_a=plan.eps_a,
        grid=plan.grid, n_lines=plan.n_lines, noise_free_omega2=free[:, 0].tolist(),
        noise_free_zeta=free[:, 1].tolist(),
        run_level=[v + 1 for v, _, _ in plan.runs], run_order_k=[r.k for _, r, _ in plan.runs],
        run_time=[r.t for _, r, _ in plan.runs],
        x_peak=[s["x_peak"] for s in sims], fit_error=np.asarray(
            data.extra.get("x_fit_error", []), float).tolist())
    frfs = [dict(freq_hz=s["freq_hz"], frf=s["frf"], force=s["force"] if plan.force_column
                 else None, held=float(plan.held[s["v"]]), run_order=s["run"].k,
                 level=s["v"] + 1, repeat=s["repeat"], control=control) for s in sims]
    return SyntheticSeries(data, frfs, truth)


def generate_series(label: str, seed: int, n_levels: int | None = None,
                    control: str | None = None, repeatability: bool | None = None,
                    repeats: int | None = None) -> SyntheticSeries:
    """Simulate and identify one series hiding ``label`` (package doc).

    ``n_levels`` (4-12), ``control``, ``repeatability`` (per-run offsets on/off) and
    ``repeats`` (repeated levels, 0-2) fix what is otherwise drawn."""
    causes = truth_of(label)
    rng = np.random.default_rng([int(seed), zlib.crc32(label.encode()), 19])
    ooc = None
    if causes == ("unexplained",):
        ooc = label if label in OUT_OF_CATALOGUE else str(rng.choice(OUT_OF_CATALOGUE))
        causes = ()
    n = int(n_levels or rng.integers(4, 13))
    if not 4 <= n <= 12:
        raise ValueError(f"n_levels must be 4-12, got {n}")
    if control is None:
        control = ("force" if "nonproportional-amplitude" in causes or rng.random() < 0.7
                   else "response")
    if control == "response" and "nonproportional-amplitude" in causes:
        raise ValueError("nonproportional-amplitude needs force control")
    rep_on = bool(rng.random() < 0.5) if repeatability is None else bool(repeatability)
    n_rep = int(rng.choice([0, 0, 1, 2])) if repeats is None else int(repeats)
    failures = []
    for attempt in range(30):
        try:
            s = _attempt(rng, causes, ooc, n, control, rep_on, n_rep)
        except (TooLarge, Refused) as exc:
            failures.append(str(exc)[:80])
            continue
        s.truth.update(label=label, causes=truth_of(label), ooc=ooc, seed=seed,
                       control=control, n_levels=n, attempts=attempt + 1,
                       rejected=failures)
        return s
    raise RuntimeError(f"could not draw a series for {label!r}, seed {seed}: {failures[-3:]}")
