"""FE-level check of the double beam: measured vs simulated absolute frequency.

The diagnosis (:mod:`inverse.diagnose`) looks at how the measured mode changes with the
force; this module looks at where it is. It takes the *uncalibrated* double-beam model
(:mod:`cases.double_beam.model` with ``clamp_length = 0``, every other default), compares the
frequency of the measured mode (4th in-phase bending, :data:`MEASURED_BENDING_ORDER`)
with the measurement (omega^2 = 2.50677e6 rad^2/s^2 at level 1, 252.0 Hz) and, for each
candidate cause of the gap, varies one physical parameter:

==========================  =========================  ====================================
candidate (parameter)       plausible range            source / reason
==========================  =========================  ====================================
glue layer (K_T, N/m)       1e7 .. rigid (1e12)        not measured; a thin rigid epoxy bond
                                                       gives ~1e10 (G b L_g / t_g), rigid is
                                                       the upper limit. Rigid glue caps the
                                                       mode: it cannot close the gap
clamp (grip length, m)      0 .. 30 mm                 not given by the paper; typical
                                                       clamp jaws hold 10-30 mm of strip.
                                                       A *compliant* clamp (finite root
                                                       rotational spring) can only lower
                                                       every frequency: the model's rigid
                                                       clamp is already the upper bound, so
                                                       the only clamp effect that raises f
                                                       is a shorter free length (the grip)
attachment masses (scale    0 .. 2.5 x (0 .. 12.5 g)   exciter + force gauge 2 g, three
on 2 g + 3 x 1 g)                                      accelerometers 1 g each (assumed);
                                                       masses >= 0, so no attachment at
                                                       all is the upper bound on f
Young's modulus E (Pa)      68 .. 73 GPa               handbook values of wrought aluminium
                                                       alloys
density rho (kg/m^3)        2660 .. 2800               handbook values of wrought aluminium
                                                       alloys; with E only E/rho matters
                                                       (24.3 .. 27.4e6 m^2/s^2) up to the
                                                       attachments and the glue
strip thickness h (m)       0.95 .. 1.05 mm            not in the issue's list, added: the
(extra)                                                nominal 1 mm sheet with a rolling
                                                       tolerance of about +/- 0.05 mm
                                                       (EN 485-4 class)
==========================  =========================  ====================================

For each candidate: the log sensitivity ``d ln f / d ln p`` of the measured mode
(central difference in ``ln p`` with step :data:`LOG_STEP`; the eigenvalues are
accurate to ~1e-7, so the step error is ~1e-5), the value that alone would put the
mode at the measurement (Brent's method) if one exists in the physically possible
range, whether it lies in the plausible range, and the frequencies the fix predicts for
the other bending modes 2, 3 and 5 (the in-band neighbours). The clamp's sensitivity is
taken with respect to the free length ``L = length - grip`` (the grip is 0 in the
uncalibrated model, so ``ln grip`` has no nominal value).

Two exact identities hold for the model and are checked by the tests: all stiffness is
proportional to E except K_T, so ``S_E + S_KT = 1/2``; all mass is proportional to rho
except the attachments, so ``S_rho + S_mass = -1/2``.

What one measured mode can and cannot separate: every candidate that can reach the
measured frequency explains it exactly, with one parameter, so the single mode gives no
evidence between them; only plausibility (priors on the parameter) can rank them.
Candidates that cannot reach it at all (glue, masses) are excluded by the mode alone.
E and rho cannot be separated by any number of modes (they enter as E/rho, apart from
the small glue and attachment terms); a second mode separates candidates whose fixes
predict different frequencies for it: the spread of the predicted mode-2, -3 and -5
frequencies across the reachable fixes is reported in ``discrimination``.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from cases.double_beam.model import (
    MEASURED_BENDING_ORDER,
    UNCALIBRATED_CLAMP_LENGTH,
    DoubleBeamConfig,
    build_double_beam,
)

MEASURED_OMEGA2 = 2.50677e6  # rad^2/s^2, paper Table 4, level 1
LOG_STEP = 0.02  # central-difference step in ln p
RIGID_GLUE = 1.0e12  # N/m: the 4th mode is within 1e-6 of its K_T -> inf limit
OTHER_ORDERS = (2, 3, 5)
ORDERS = (2, 3, 4, 5)
_DEFAULT = DoubleBeamConfig()
_BASE_MASSES = (_DEFAULT.exciter_mass, _DEFAULT.sensor_mass)


def bending_frequencies(config: DoubleBeamConfig, orders=ORDERS) -> dict[int, float]:
    """Frequencies (Hz) of the given in-phase bending orders, one eigen-solve."""
    model = build_double_beam(config)
    omega, shapes = model.modes(max(orders) + 8)
    order = model.bending_order(omega, shapes)
    out = {}
    for k in orders:
        i = np.flatnonzero(order == k)
        if i.size == 0:
            raise ValueError(f"in-phase bending mode {k} not found")
        out[int(k)] = float(omega[i[0]] / (2 * np.pi))
    return out


def _mass_scale(config, a):
    return replace(config, exciter_mass=a * _BASE_MASSES[0], sensor_mass=a * _BASE_MASSES[1])


# name -> (cause, parameter, unit, nominal(config), set(config, p), physical bounds
#          (lo, hi) for the root search, plausible (lo, hi), plausible source)
CANDIDATES = {
    "glue": dict(
        cause="glue layer", parameter="K_T (stuck tangential glue stiffness)", unit="N/m",
        get=lambda c: c.glue_tangential_stiffness,
        set=lambda c, p: replace(c, glue_tangential_stiffness=p),
        physical=(1.0e5, RIGID_GLUE), plausible=(1.0e7, RIGID_GLUE),
        source="not measured; rigid epoxy ~1e10 N/m, rigid glue (1e12) is the upper "
               "limit of the stiffening"),
    "clamp": dict(
        cause="clamp (grip length / free length)", parameter="grip (strip length held "
        "in the clamp; sensitivity w.r.t. free length)", unit="m",
        get=lambda c: c.length - c.grip,  # free length (sensitivity variable)
        set=lambda c, L: replace(c, length=c.grip + L),  # strip length beyond the grip
        physical=(0.0, 0.2 * _DEFAULT.length), plausible=(0.0, 0.030),
        source="not given by the paper; typical clamp jaws hold 10-30 mm. A compliant "
               "clamp (root rotational spring) only lowers f: the rigid clamp is the "
               "upper bound"),
    "mass": dict(
        cause="sensor / exciter mass", parameter="scale on the attachment masses "
        "(2 g exciter, 3 x 1 g accelerometers)", unit="-",
        get=lambda c: 1.0, set=_mass_scale,
        physical=(0.0, 10.0), plausible=(0.0, 2.5),
        source="assumed 2 g + 3 x 1 g; masses >= 0, so none at all bounds f from above"),
    "E": dict(
        cause="material: Young's modulus", parameter="E", unit="Pa",
        get=lambda c: c.E, set=lambda c, p: replace(c, E=p),
        physical=(40e9, 150e9), plausible=(68e9, 73e9),
        source="handbook, wrought aluminium alloys 68-73 GPa"),
    "rho": dict(
        cause="material: density", parameter="rho", unit="kg/m^3",
        get=lambda c: c.rho, set=lambda c, p: replace(c, rho=p),
        physical=(1000.0, 5000.0), plausible=(2660.0, 2800.0),
        source="handbook, wrought aluminium alloys 2660-2800 kg/m^3"),
    "thickness": dict(
        cause="geometry: strip thickness (extra)", parameter="h", unit="m",
        get=lambda c: c.thickness, set=lambda c, p: replace(c, thickness=p),
        physical=(0.5e-3, 2.0e-3), plausible=(0.95e-3, 1.05e-3),
        source="nominal 1 mm sheet, rolling tolerance about +/- 0.05 mm"),
}


def _f4(config):
    return bending_frequencies(config, (MEASURED_BENDING_ORDER,))[MEASURED_BENDING_ORDER]


def log_sensitivity(config: DoubleBeamConfig, name: str, step: float = LOG_STEP) -> float:
    """``d ln f4 / d ln p`` of candidate ``name`` by a central difference in ``ln p``."""
    c = CANDIDATES[name]
    p0 = c["get"](config)
    fp = _f4(c["set"](config, p0 * np.exp(step)))
    fm = _f4(c["set"](config, p0 * np.exp(-step)))
    return float((np.log(fp) - np.log(fm)) / (2 * step))


def _candidate(config, name, target_hz):
    c = CANDIDATES[name]
    lo, hi = c["physical"]
    if name == "clamp":  # search in grip, report grip
        def f_of(grip):
            return _f4(replace(config, clamp_length=grip))
        nominal = config.grip
    else:
        def f_of(p):
            return _f4(c["set"](config, p))
        nominal = c["get"](config)
    f_lo, f_hi = f_of(lo), f_of(hi)
    reachable = (f_lo - target_hz) * (f_hi - target_hz) <= 0
    rec = {
        "cause": c["cause"], "parameter": c["parameter"], "unit": c["unit"],
        "nominal": float(nominal),
        "log_sensitivity": log_sensitivity(config, name),
        "physical_range": [float(lo), float(hi)],
        "frequency_at_range_ends_hz": [float(f_lo), float(f_hi)],
        "plausible_range": [float(v) for v in c["plausible"]],
        "plausible_source": c["source"],
        "reachable": bool(reachable),
        "required_value": None, "plausible": False, "predicted_modes_hz": None,
    }
    if name == "clamp":
        rec["sensitivity_parameter"] = "free length L = length - grip"
    if reachable:
        tol = 1e-9 * max(abs(lo), abs(hi))
        p = float(brentq(lambda q: f_of(q) - target_hz, lo, hi, xtol=tol, rtol=1e-12))
        cfg = replace(config, clamp_length=p) if name == "clamp" else c["set"](config, p)
        fr = bending_frequencies(cfg)
        rec["required_value"] = p
        rec["relative_change"] = (p / nominal - 1) if nominal else None
        rec["plausible"] = bool(c["plausible"][0] <= p <= c["plausible"][1])
        rec["predicted_modes_hz"] = {str(k): fr[k] for k in ORDERS}
    else:
        best = max(f_lo, f_hi)
        rec["best_frequency_hz"] = float(best)
        rec["note"] = (f"cannot reach {target_hz:.1f} Hz: at most {best:.1f} Hz over "
                       f"{c['unit']} in [{lo:.4g}, {hi:.4g}]")
    return rec


def double_beam_fe_check(measured_omega2: float = MEASURED_OMEGA2) -> dict:
    """Measured vs simulated frequency of the double beam's measured mode, by cause.

    On the uncalibrated model (no grip, all other defaults). See the module docstring
    for the candidates, their plausible ranges and what one mode can separate.
    """
    target = float(np.sqrt(measured_omega2) / (2 * np.pi))
    config = DoubleBeamConfig(clamp_length=UNCALIBRATED_CLAMP_LENGTH)
    base = bending_frequencies(config)
    f4 = base[MEASURED_BENDING_ORDER]
    cands = {name: _candidate(config, name, target) for name in CANDIDATES}
    reach = [n for n, r in cands.items() if r["reachable"]]
    plaus = [n for n in reach if cands[n]["plausible"]]
    disc = {}
    for k in OTHER_ORDERS:
        by = {n: cands[n]["predicted_modes_hz"][str(k)] for n in reach}
        if by:
            v = np.array(list(by.values()))
            disc[str(k)] = {"by_candidate_hz": by, "min_hz": float(v.min()),
                            "max_hz": float(v.max()), "spread_hz": float(v.max() - v.min()),
                            "spread_relative": float((v.max() - v.min()) / v.mean())}
    # ratios f_k / f_4 are what a second mode tests once the first is fitted
    statement = (
        f"One measured mode ({target:.1f} Hz) vs {f4:.1f} Hz simulated "
        f"({100 * (f4 / target - 1):+.1f} %). Every candidate that reaches it "
        f"({', '.join(reach) or 'none'}) explains it exactly with one parameter, so the "
        f"mode alone gives no evidence between them; only the plausibility of the "
        f"required value ranks them (plausible: {', '.join(plaus) or 'none'}). "
        f"Excluded by the mode alone (cannot reach it at all): "
        f"{', '.join(n for n in cands if n not in reach) or 'none'}. "
        "E and rho enter only as E/rho (up to glue and attachment terms): no set of "
        "frequencies separates them. A second measured mode separates candidates whose "
        "fixes predict different frequencies for it; see 'discrimination' (the spread "
        "must exceed the model's own error on frequency ratios to be usable).")
    if disc:
        k_best = max(disc, key=lambda k: disc[k]["spread_relative"])
        statement += (f" Largest relative spread: mode {k_best} "
                      f"({disc[k_best]['min_hz']:.1f}-{disc[k_best]['max_hz']:.1f} Hz, "
                      f"{100 * disc[k_best]['spread_relative']:.2f} %).")
        if max(d["spread_relative"] for d in disc.values()) < 0.01:
            statement += (
                " All reachable fixes are near-uniform frequency scalings: their "
                "predictions for modes 2, 3 and 5 differ by under 1 %, less than the "
                "likely model-form error of a beam model on frequency ratios, so a second "
                "bending mode would barely separate them; direct measurements would "
                "(grip length, strip thickness with a micrometer, E/rho from a free-free "
                "strip, weighed attachments).")
    return {
        "model": "double beam, uncalibrated (clamp_length = 0, other defaults)",
        "measured_bending_order": MEASURED_BENDING_ORDER,
        "measured_omega2": float(measured_omega2),
        "measured_hz": target,
        "simulated_hz": f4,
        "simulated_omega2": float((2 * np.pi * f4) ** 2),
        "gap_hz": float(target - f4),
        "gap_relative": float(f4 / target - 1),
        "uncalibrated_modes_hz": {str(k): base[k] for k in ORDERS},
        "candidates": cands,
        "reachable": reach,
        "plausible_fixes": plaus,
        "discrimination": disc,
        "statement": statement,
    }


def format_fe_check(r: dict) -> list[str]:
    """Short text lines for the diagnose table output."""
    lines = [f"FE check ({r['model']}): mode {r['measured_bending_order']} measured "
             f"{r['measured_hz']:.1f} Hz, simulated {r['simulated_hz']:.1f} Hz "
             f"({100 * r['gap_relative']:+.1f} %)"]
    for n, c in r["candidates"].items():
        if c["reachable"]:
            m = c["predicted_modes_hz"]
            tail = (f"needs {c['required_value']:.4g} {c['unit']} "
                    f"({'plausible' if c['plausible'] else 'implausible'}); modes 2/3/5 -> "
                    f"{m['2']:.1f}/{m['3']:.1f}/{m['5']:.1f} Hz")
        else:
            tail = f"cannot reach (max {c['best_frequency_hz']:.1f} Hz)"
        lines.append(f"  {n:10s} dlnf/dlnp {c['log_sensitivity']:+.4f}  {tail}")
    return lines


def format_fe_check_md(r: dict) -> str:
    """Markdown section for report.md."""
    rows = []
    for n, c in r["candidates"].items():
        if c["reachable"]:
            m = c["predicted_modes_hz"]
            req = f"{c['required_value']:.4g} {c['unit']}"
            ok = "yes" if c["plausible"] else "no"
            modes = f"{m['2']:.1f} / {m['3']:.1f} / {m['5']:.1f}"
        else:
            req, ok, modes = f"unreachable (max {c['best_frequency_hz']:.1f} Hz)", "no", ""
        pr = c["plausible_range"]
        rows.append(f"| {n} | {c['log_sensitivity']:+.4f} | {req} | {pr[0]:.4g}-{pr[1]:.4g} "
                    f"| {ok} | {modes} |")
    return f"""## FE-level check (absolute frequency)

Model: {r['model']}. Measured mode (bending order {r['measured_bending_order']}):
measured {r['measured_hz']:.2f} Hz, simulated {r['simulated_hz']:.2f} Hz
({100 * r['gap_relative']:+.2f} %).

| candidate | d ln f / d ln p | value closing the gap alone | plausible range | plausible | modes 2 / 3 / 5 (Hz) |
| --- | --- | --- | --- | --- | --- |
{chr(10).join(rows)}

{r['statement']}
"""
