"""The ``iwanfe ringdown`` report: simulate, identify, compare, write the files.

:func:`ringdown_report` runs :func:`cases.ringdown_study.simulate_ringdown` (the record,
written as it is computed), :func:`cases.ringdown_routes.identify_record` (the record
identified as a measured one, ``identified.csv``),
:func:`cases.ringdown_routes.compare_ringdown` (EPMC and the response-controlled virtual
test; the virtual test's campaign stored in the output folder, resumable) and draws
``ringdown.png`` (:mod:`viz.backbone_plot`); ``comparison.json`` is written last. SI
units: m, Hz.
"""
from __future__ import annotations

import json
import math
import time
from pathlib import Path

from runs.jsonio import to_jsonable

__all__ = ["ringdown_report"]


def ringdown_report(case_name, settings, out: Path, window, response_levels,
                    progress=True, model=None) -> dict:
    """Simulate, identify, compare and write the files (module docstring) for the case
    ``case_name`` and :class:`cases.ringdown_study.RingdownSettings` ``settings``;
    ``window`` (lo, hi) fractions of the start amplitude; ``response_levels`` held
    amplitudes of the virtual test (0: none); ``model``: an ``updated_model.json`` of
    the case (:mod:`feloop.updated_model`). Returns the report dict."""
    from cases.ringdown_routes import compare_ringdown, identify_record
    from cases.ringdown_study import RECORD_FILE, ringdown_case, simulate_ringdown

    t0 = time.perf_counter()
    case = ringdown_case(case_name, settings.mode, model)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=settings.cycles, unit="cycle", desc="ring-down", leave=False)
    try:
        rec, info = simulate_ringdown(case, settings, out, progress=bar)
    finally:
        if bar is not None:
            bar.close()
    f0 = info["omega0_rad_s"] / (2 * math.pi)
    ident = identify_record(out / RECORD_FILE, f0)
    _write_identified(out / "identified.csv", ident)
    # the start: the orbit's drive-point amplitude, or the largest identified one
    start_amp = float(info["start"].get("drive_amplitude_m", ident["amplitude"].max()))
    cmp = compare_ringdown(case, ident, start_amp, window[0], window[1], response_levels,
                           progress=progress, store=out)
    report = {"case": case.name, "mode": settings.mode, "record": info,
              "identification": {"method": ident["method"], "notes": ident["notes"]},
              "comparison": cmp, "files": [str(out / RECORD_FILE), str(out / "record.json"),
                                           str(out / "identified.csv"),
                                           str(out / "comparison.json"),
                                           str(out / "ringdown.png")]}
    _plot(out / "ringdown.png", case, ident, cmp, start_amp)
    report["elapsed_s"] = time.perf_counter() - t0
    tmp = out / "comparison.tmp"
    tmp.write_text(json.dumps(to_jsonable(report), indent=1))
    tmp.replace(out / "comparison.json")
    return report


def _write_identified(path: Path, ident: dict) -> None:
    from ident.measured import write_measured

    write_measured(path, ident["table"])


def _plot(path, case, ident, cmp, start_amp) -> None:
    from viz.backbone_plot import plot_backbones

    bb = cmp["backbone"]
    curves = [{"label": f"EPMC backbone ({bb['path']} path)", "style": "-",
               "amplitude": bb["amplitude_m"], "frequency_hz": bb["frequency_hz"],
               "zeta": bb["zeta"]},
              {"label": "ring-down, identified", "style": ".",
               "amplitude": ident["amplitude"], "frequency_hz": ident["frequency_hz"],
               "zeta": ident["zeta"]}]
    if cmp["response"]:
        r = cmp["response"]
        curves.append({"label": "response-controlled test (LSCF)", "style": "o",
                       "amplitude": [x["amplitude_m"] for x in r],
                       "frequency_hz": [x["frequency_hz"] for x in r],
                       "zeta": [x["zeta"] for x in r]})
    w = cmp["window"]
    plot_backbones(curves, xlabel="drive-point amplitude (m)", path=path,
                   title=f"{case.name}, mode {case.mode}: ring-down vs backbone",
                   marks=[(w["lo"] * start_amp, f"{w['lo']:g} x start"),
                          (w["hi"] * start_amp, f"{w['hi']:g} x start")])
