"""The model summary of a case file (``iwanfe case check FILE``): mass, first modes, the
joint elements with their stiffness shares, each joint interface's law with the kind of
each of its parameters, and the kind of every parameter (given, calibrated, fitted,
default with its source). SI units, Hz."""
from __future__ import annotations

import numpy as np

from casefile.laws import DESCRIPTION, LAWS
from casefile.nonlinear import missing_joint_parameters

_ARRAYS = {"material": "materials", "beam": "beams", "support": "supports",
           "interface": "interfaces", "mass": "masses", "sensor": "sensors"}
_SINGLE = {"mesh": {"element_size": "element_size"}, "damping": {"zeta": "zeta"}}


def parameter_value(cf, address: str):
    """The value behind a ``kinds`` address (``beam.0.section.1.z``, ``mesh.element_size``)."""
    parts = address.split(".")
    if parts[0] in _SINGLE:
        return getattr(cf, _SINGLE[parts[0]][parts[1]])
    if parts[0] in ("measured", "drive"):
        return getattr(getattr(cf, parts[0]), parts[1])
    item = getattr(cf, _ARRAYS[parts[0]])[int(parts[1])]
    if parts[2] == "section":
        item, parts = item.sections[int(parts[3])], parts[2:]
    v = getattr(item, parts[2])
    return list(v) if isinstance(v, tuple) else v


def joint_laws(cf) -> list[dict]:
    """Per joint interface: its ``law``, what it is, and ``kt`` and the law's own keys
    with ``value`` (None: left out), ``unit`` and ``kind`` (given, calibrated, fitted)."""
    out = []
    for i, itf in enumerate(cf.interfaces):
        if itf.tangential != "joint":
            continue
        keys = [("kt", "N/m")] + [(k.name, k.unit) for k in LAWS[itf.law]]
        out.append({"interface": i, "law": itf.law, "description": DESCRIPTION[itf.law],
                    "parameters": [{"key": k, "value": getattr(itf, k), "unit": u,
                                    "kind": cf.kinds.get(f"interface.{i}.{k}", ("given",))[0]}
                                   for k, u in keys]})
    return out


def case_summary(cf, built, calibration, n_modes: int = 6) -> dict:
    """The summary as a dict (module docstring); ``built``: :class:`BuiltCase` of the
    calibrated file, ``calibration``: the report of :func:`casefile.calibrate.calibrate`."""
    model = built.model
    omega, shapes = model.modes(min(n_modes + 3, model.n_free - 2))
    order = model.bending_order(omega, shapes)
    rigid = omega <= 1e-3 * omega.max()
    modes = []
    for i in np.flatnonzero(~rigid)[:n_modes]:
        modes.append({"index": int(i + 1), "frequency_hz": float(omega[i] / (2 * np.pi)),
                      "kind": model.classify_mode(shapes[:, i]), "bending_order": int(order[i]),
                      "joint_energy_share": model.glue_slip_participation(shapes[:, i])})
    params = [{"parameter": a, "value": parameter_value(cf, a), "kind": k, "source": s}
              for a, (k, s) in sorted(cf.kinds.items())]
    left = {k: cf.kinds.get(k, ("fitted",))[0] for k in missing_joint_parameters(cf)}
    return {
        "case": cf.name, "description": cf.description, "file": str(cf.path),
        "mass_kg": model.mass, "n_nodes": built.n_nodes, "n_free_dofs": model.n_free,
        "n_rigid_body_modes": int(np.sum(rigid)),
        "modes": modes, "joints": built.joint_table,
        "joint_stiffness_total": float(model.joint_stiffness.sum()),
        "parameters": params, "calibration": calibration,
        "joint_laws": joint_laws(cf),
        "fitted_by_update": [k for k, kind in left.items() if kind == "fitted"],
        "assumed_by_update": [k for k, kind in left.items() if kind == "assumed"],
    }


def format_summary(s: dict) -> str:
    """Human-readable summary."""
    lines = [f"case {s['case']} ({s['file']})", f"  {s['description']}",
             f"mass {s['mass_kg']:.6g} kg (strips + point masses); {s['n_nodes']} nodes, "
             f"{s['n_free_dofs']} free DOFs, {s['n_rigid_body_modes']} rigid-body modes",
             "first elastic modes:",
             f"  {'index':>5} {'freq_Hz':>11}  {'kind':<20} {'bend#':>5} {'joint_energy':>12}"]
    for m in s["modes"]:
        lines.append(f"  {m['index']:>5} {m['frequency_hz']:11.4f}  {m['kind']:<20} "
                     f"{m['bending_order'] or '-':>5} {m['joint_energy_share']:12.3e}")
    lines.append(f"joint elements ({len(s['joints'])}, stuck stiffness total "
                 f"{s['joint_stiffness_total']:.6g} N/m):")
    for j in s["joints"]:
        lines.append(f"  interface {j['interface']}  x = {j['x_m']:.6g} m  share "
                     f"{j['share']:.4f}  k = {j['k_N_per_m']:.6g} N/m")
    for law in s.get("joint_laws", []):
        keys = ", ".join(f"{p['key']} = " + ("-" if p["value"] is None else f"{p['value']:.6g}"
                                              + ("" if p["unit"] == "1" else f" {p['unit']}"))
                         + f" {p['kind']}" for p in law["parameters"])
        lines.append(f"joint law of interface {law['interface']}: {law['law']} "
                     f"({law['description']} per joint element): {keys}")
    cal = s["calibration"]
    if cal:
        for p in cal["parameters"]:
            lines.append(f"calibrated {p['parameter']}: {p['initial']:.6g} -> {p['calibrated']:.9g}"
                         + (" (at a bound)" if p["at_bound"] else ""))
        for t in cal["targets"]:
            lines.append(f"  bending mode {t['bending_mode']}: {t['initial_hz']:.4f} Hz -> "
                         f"{t['calibrated_hz']:.4f} Hz (measured {t['frequency_hz']:g} Hz)")
    lines.append("parameters:")
    for p in s["parameters"]:
        v = p["value"]
        v = "-" if v is None else (f"{v:.6g}" if isinstance(v, float) else str(v))
        lines.append(f"  {p['parameter']:<28} {v:<22} {p['kind']}"
                     + (f" ({p['source']})" if p["source"] else ""))
    return "\n".join(lines)
