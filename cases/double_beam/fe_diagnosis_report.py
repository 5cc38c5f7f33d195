"""Wording and files of the FE-level diagnosis (``iwanfe diagnose ... --case double-beam``).

:func:`add_fe_diagnosis` runs :func:`cases.double_beam.fe_diagnosis.fe_diagnosis` on the
diagnosed mode and puts ``fe_levels`` and ``fe`` into the diagnosis result;
:func:`format_fe` gives its text lines, :func:`write_fe_files` its markdown section and
the figure ``fe_levels.png`` (measured vs base FE vs extended FE per level).
"""
from __future__ import annotations

import copy
import hashlib
import math
from pathlib import Path

import numpy as np

__all__ = ["add_fe_diagnosis", "format_fe", "write_fe_files"]

_DONE: dict = {}   # FE diagnoses of this process, by a digest of their data


def _digest(d) -> str:
    h = hashlib.sha256()
    for a in (d.level, d.excitation, d.omega2, d.zeta, d.run_order, d.omega2_std, d.zeta_std):
        h.update(b"-" if a is None else np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()


def add_fe_diagnosis(result: dict, data, out=None) -> dict:
    """Add ``fe_levels`` and ``fe`` (FE cause, gains, held-out errors) to ``result``;
    with ``out`` also write :func:`write_fe_files`. Returns ``result``."""
    from cases.double_beam.fe_diagnosis import fe_diagnosis

    mode = result.get("mode")
    d = data.for_mode(int(mode)) if mode is not None else data
    key = _digest(d)
    if key not in _DONE:                     # the same data diagnosed again: reuse
        _DONE[key] = fe_diagnosis(d)
    result.update(copy.deepcopy(_DONE[key]))
    if out is not None:
        write_fe_files(result, Path(out))
    return result


def format_fe(fe: dict) -> list:
    """Text lines of the FE-level diagnosis."""
    lines = [f"FE level (double beam refitted; fit levels {fe['fit_levels']}, held out "
             f"{fe['held_out_levels']}):",
             f"  FE cause: {fe['cause']}" + (f" + {', '.join(fe['also'])}" if fe["also"] else ""),
             f"  cross-validated: base error {fe['base_error']:.3g}, extended "
             f"{fe['extended_error']:.3g}, gain {fe['gain']:.3g}",
             f"  held out: base error {fe['base_error_held_out']:.3g}, extended "
             f"{fe['extended_error_held_out']:.3g}, gain_held_out {fe['gain_held_out']:.3g} "
             f"({fe['error_measure']})"]
    for c, e in fe["evidence"].items():
        cv = f", cv gain {e['cv_gain']:.3g}" if "cv_gain" in e else ""
        lines.append(f"  {c:26s} dAICc {e['delta_aicc']:8.2f}, chi2 {e['chi2']:8.2f}{cv}")
    if fe["reading"]:
        lines.append("  extended FE parameters: " + ", ".join(
            f"{k} = {v:.4g}" for k, v in fe["reading"].items()))
    lines.append("  level  base err [Hz]  ext err [Hz] (+/- 1 sd)  base err zeta [%]  "
                 "ext err zeta [%] (+/- 1 sd)")
    for r in fe["held_out"]:
        lines.append(f"  {r['level']:5d} {r['base_error_hz']:+14.4f} {r['extended_error_hz']:+13.4f} "
                     f"({r['extended_sd_hz']:.4f}) {100 * r['base_error_zeta_rel']:+17.3f} "
                     f"{100 * r['extended_error_zeta_rel']:+16.3f} "
                     f"({100 * r['extended_sd_zeta_rel']:.3f})")
    lines.append("  " + acceptance_text(fe))
    return lines


def acceptance_text(fe: dict) -> str:
    """Whether the extended FE model predicts the held-out levels within the issue's
    tolerances, and if not, whether the fit levels could have told (prediction sd)."""
    a = fe["acceptance"]
    if not fe["held_out"]:
        return "no held-out levels"
    if a["met"]:
        return (f"extended FE model within {a['tolerance_hz']} Hz and "
                f"{100 * a['tolerance_zeta_rel']:.1f} % at every held-out level")
    worst = max(fe["held_out"], key=lambda r: abs(r["extended_error_hz"]))
    reach = [r["level"] for r in fe["held_out"]
             if 1.96 * r["extended_sd_hz"] > a["tolerance_hz"]
             or 1.96 * r["extended_sd_zeta_rel"] > a["tolerance_zeta_rel"]]
    text = (f"not within {a['tolerance_hz']} Hz / {100 * a['tolerance_zeta_rel']:.1f} %: worst "
            f"level {worst['level']}, {worst['extended_error_hz']:+.4f} Hz")
    if reach:
        text += (f"; at level(s) {reach} the 95 % prediction half-width from the fit levels "
                 f"alone already exceeds the tolerance (the data's noise makes it unreachable "
                 f"there)")
    z = ", ".join(f"{r['level']}: {r['extended_error_hz'] / r['extended_sd_hz']:+.1f} / "
                  f"{r['extended_error_zeta_rel'] / r['extended_sd_zeta_rel']:+.1f}"
                  for r in fe["held_out"] if r["extended_sd_hz"] > 0)
    if z:
        text += f"; errors in prediction sd (frequency / zeta) at level {z}"
    return text


def write_fe_files(result: dict, out: Path) -> list:
    """``fe_levels.png`` and ``fe_diagnosis.md`` in ``out``."""
    from viz.level_models import plot_level_models

    out.mkdir(parents=True, exist_ok=True)
    fe, rows = result["fe"], result["fe_levels"]
    lv = np.array([r["level"] for r in rows])
    f = np.array([r["measured"]["frequency_hz"] for r in rows])
    z = np.array([r["measured"]["zeta"] for r in rows])
    s_om2 = np.asarray(fe["noise"]["sigma_omega2"], dtype=float)
    s_z = np.asarray(fe["noise"]["sigma_zeta"], dtype=float)
    models = {"base FE": ([r["base"]["frequency_hz"] for r in rows],
                          [r["base"]["zeta"] for r in rows]),
              f"extended FE ({fe['cause']})": ([r["extended"]["frequency_hz"] for r in rows],
                                               [r["extended"]["zeta"] for r in rows])}
    png = out / "fe_levels.png"
    plot_level_models(lv, f, z, s_om2 / (8 * math.pi ** 2 * f), s_z, models,
                      [r["held_out"] for r in rows],
                      title=f"measured vs base FE vs extended FE ({fe['cause']})", path=png)
    md = out / "fe_diagnosis.md"
    md.write_text("# FE-level diagnosis (double beam)\n\n" + "\n".join(
        ("    " + ln) for ln in format_fe(fe)) + "\n\n![FE levels](fe_levels.png)\n",
        encoding="utf-8")
    return [png, md]
