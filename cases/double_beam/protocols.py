"""Which solver drives the double-beam campaign, and Newmark checked against harmonic balance.

``iwanfe reproduce double-beam`` runs the stepped sine by harmonic balance (``"hb"``,
:class:`runs.campaign.HBProtocol`); ``--protocol newmark`` runs the same lines, levels,
reduced model and Jenkins banks by time integration (:class:`runs.campaign.NewmarkProtocol`,
HHT alpha = 0: the average-acceleration rule, frequency pre-warped) and identifies each
level as the harmonic-balance run does; :func:`protocol_comparison` then puts both
side by side.

Both solve the same discrete model (same basis, same banks), so what can separate them:

* the steady state. Each line is integrated until periodic: the change of the
  first harmonic between periods, extrapolated geometrically over the remaining
  transient, below :data:`NEWMARK_TOL` relative. A line change excites every mode, and
  the lowest (10 Hz, 1.28 % damping) decays over ~300 periods of the drive, so the
  state is not carried from the previous line: every line starts on the harmonic-balance
  orbit of that line (:meth:`fe.newmark.NewmarkState.periodic`), and only the small
  difference between the two steady states has to decay (measured, all 65 lines:
  10 periods per line at level 7 and 41 at level 9 against 400 with the state carried
  from rest, whose drift bound is also less reliable: 2.5e-6 off at tol 1e-7). That
  difference decays with the mode's own damping (250-330 periods on the resonant lines
  of level 9), so after each period the next one starts from a Newton step on the
  period map (:mod:`fe.newmark_period`: the monodromy of the model linearized on the
  line's orbit, Broyden-updated): 5 periods per line at levels 1-9 and 11 at level 10
  (36 before), the same steady states and identified values;
* the time step: :data:`NEWMARK_STEPS` steps per period, the trapezoidal rule's
  frequency error removed by pre-warping (exact for the linear part). In macro-slip the
  joint force is far from smooth and the structure's higher modes answer its high
  harmonics, which the rule warps: at level 10 (2.6 phi_max) the identified frequency
  moves by 2.0e-5, 1.6e-5, 4.9e-6, 2.1e-6 (relative) from 256, 512, 1024, 2048 steps
  to the harmonic balance with 63 harmonics; levels that reach macro-slip therefore
  take :data:`NEWMARK_MACRO_STEPS`;
* harmonic truncation: harmonic balance keeps the odd harmonics to 7 (the study's
  ``hb``), the integration all of them. In micro-slip this is invisible; at level 10 the
  7 harmonics put the identified frequency 5.6e-6 and the damping ratio 3.5e-3 from 63
  harmonics (receptance up to 0.9 % near resonance): there the harmonic-balance run is
  the less accurate of the two, and this is what is left of the difference.

Measured on the default study (``benchmarks/bench_newmark_campaign.py``): identified
frequencies within 1.1e-6 (levels 1-9) and 7.7e-6 (level 10), damping ratios within
3.5e-5 (levels 1-9) and 3.6e-3 (level 10), relative.
"""
from __future__ import annotations

import numpy as np

from fe.harmonic_balance import HBSettings
from runs.campaign import HBProtocol, NewmarkProtocol

__all__ = ["PROTOCOLS", "NEWMARK_STEPS", "NEWMARK_MACRO_STEPS", "NEWMARK_TOL", "FREQUENCY_TARGET",
           "ZETA_TARGET", "campaign_protocol", "protocol_comparison"]

#: Solvers of the campaign (``--protocol``).
PROTOCOLS = ("hb", "newmark")
#: Time steps per drive period (micro-slip levels; levels that reach macro-slip) and the
#: periodicity tolerance of the Newmark protocol (module docstring).
NEWMARK_STEPS = 256
NEWMARK_MACRO_STEPS = 2048
NEWMARK_TOL = 1e-5
#: Acceptance of the comparison (issue 13): relative differences of the identified
#: natural frequency and damping ratio, Newmark against harmonic balance.
FREQUENCY_TARGET = 1e-5
ZETA_TARGET = 5e-3


def campaign_protocol(name: str, hb: HBSettings):
    """The campaign protocol of ``name`` (:data:`PROTOCOLS`); ``hb`` the study's
    harmonic-balance settings (also the orbit every Newmark line starts on)."""
    if name == "hb":
        return HBProtocol(hb)
    if name == "newmark":
        return NewmarkProtocol(steps_per_period=NEWMARK_STEPS, tol=NEWMARK_TOL, hb_start=hb,
                               macro_steps_per_period=NEWMARK_MACRO_STEPS, period_newton=True)
    raise ValueError(f"protocol must be one of {', '.join(PROTOCOLS)}, got {name!r}")


def _relative(a, b):
    return np.asarray(a, dtype=float) / np.asarray(b, dtype=float) - 1.0


def protocol_comparison(levels, newmark: tuple, hb: tuple, newmark_result,
                        hb_result, steps) -> dict:
    """Per-level identified frequency and damping of the Newmark run beside the
    harmonic-balance run's (``newmark``, ``hb``: ``(LevelIdentification,
    ModalFilterLevels)`` each), relative differences (Newmark / HB - 1), the largest of
    them against :data:`FREQUENCY_TARGET` and :data:`ZETA_TARGET`, and both campaigns'
    cost (``*_result``: :class:`runs.campaign.CampaignResult`; ``steps``: the Newmark
    steps per period of each level).
    """
    (nl, nf), (hl, hf) = newmark, hb
    rows = []
    for i, lv in enumerate(levels):
        rows.append({
            "level": int(lv),
            "frequency_hz": {"hb": float(hl.frequency_hz[i]), "newmark": float(nl.frequency_hz[i]),
                             "relative_difference": float(_relative(nl.frequency_hz[i],
                                                                    hl.frequency_hz[i]))},
            "zeta": {"hb": float(hl.zeta[i]), "newmark": float(nl.zeta[i]),
                     "relative_difference": float(_relative(nl.zeta[i], hl.zeta[i]))},
            "modal_filter": {
                "frequency_relative_difference": float(_relative(nf.frequency_hz[i],
                                                                 hf.frequency_hz[i])),
                "zeta_relative_difference": float(_relative(nf.zeta[i], hf.zeta[i]))},
            "periods_per_line_mean": float(np.mean(newmark_result.work[i])),
            "steps_per_period": int(steps[i]),
        })
    df = max(abs(r["frequency_hz"]["relative_difference"]) for r in rows)
    dz = max(abs(r["zeta"]["relative_difference"]) for r in rows)
    return {
        "levels": rows,
        "max_frequency_relative_difference": df,
        "max_zeta_relative_difference": dz,
        "frequency_target": FREQUENCY_TARGET, "zeta_target": ZETA_TARGET,
        "met": bool(df <= FREQUENCY_TARGET and dz <= ZETA_TARGET),
        "newmark": {"steps_per_period": NEWMARK_STEPS,
                    "steps_per_period_macro_slip": NEWMARK_MACRO_STEPS, "tol": NEWMARK_TOL,
                    "start": "harmonic-balance orbit of each line, then Newton on the "
                             "period map (fe.newmark_period)",
                    "campaign_s": float(np.sum(newmark_result.elapsed)),
                    "levels_computed": int(np.sum(newmark_result.computed)),
                    "periods_total": float(np.sum(newmark_result.work)),
                    "steps_total": float(np.sum(newmark_result.work.sum(axis=1)
                                                * np.asarray(steps)))},
        "hb": {"campaign_s": float(np.sum(hb_result.elapsed)),
               "levels_computed": int(np.sum(hb_result.computed)),
               "newton_iterations_total": float(np.sum(hb_result.work))},
    }


def comparison_lines(comp: dict) -> list[str]:
    """:func:`protocol_comparison` as a plain-text table (the command's output and
    ``report.md``)."""
    nm, hb = comp["newmark"], comp["hb"]
    out = ["Newmark vs harmonic balance (same reduced model, banks, lines and identification; "
           "rel. diff = Newmark/HB - 1):",
           " level   f HB (Hz)     f Newmark (Hz)   rel. diff   zeta HB %   zeta Newmark %  "
           "rel. diff   steps/period  periods/line"]
    for r in comp["levels"]:
        f, z = r["frequency_hz"], r["zeta"]
        out.append(f" {r['level']:>5}  {f['hb']:12.7f}  {f['newmark']:12.7f}  "
                   f"{f['relative_difference']:+10.2e}  {100 * z['hb']:9.6f}  "
                   f"{100 * z['newmark']:11.6f}     {z['relative_difference']:+10.2e}  "
                   f"{r['steps_per_period']:8d}      {r['periods_per_line_mean']:8.1f}")
    out.append(f" largest |rel. diff|: frequency {comp['max_frequency_relative_difference']:.2e} "
               f"(target {comp['frequency_target']:g}), damping "
               f"{comp['max_zeta_relative_difference']:.2e} (target {comp['zeta_target']:g}): "
               + ("met" if comp["met"] else "NOT met"))
    out.append(f" cost (seconds summed over the levels): Newmark "
               f"{nm['campaign_s']:.1f} s ({nm['levels_computed']} levels, {nm['steps_total']:.3g} "
               f"steps, the orbits it starts from included), harmonic balance "
               f"{hb['campaign_s']:.1f} s ({hb['levels_computed']} levels)")
    return out
