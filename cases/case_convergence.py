"""Mesh convergence of any case with an FE strip model, against its own finest mesh.

The case's element size is halved ``levels - 1`` times (no finer than
:func:`cases.mode_report.min_element_size`); the first elastic modes of every mesh are
compared with the finest mesh's (no closed form exists for a jointed assembly), with the
observed rate ``log2(e_k / e_{k+1})`` of the last two coarse meshes (4 expected for the
cubic Hermite element). Calibrated parameters are re-calibrated on each mesh. Hz.
"""
from __future__ import annotations

import numpy as np

from cases.mode_report import min_element_size


def case_convergence(case, levels: int = 4, n_modes: int = 6) -> dict:
    """Frequencies per mesh, their relative change against the finest, observed rates."""
    cf = case.file
    length = max(b.x[1] - b.x[0] for b in cf.beams)
    sizes = [cf.element_size / 2**k for k in range(levels)]
    sizes = [h for h in sizes if h >= min_element_size(length)]
    if len(sizes) < 3:
        raise ValueError(f"case {case.name!r}: element size {cf.element_size:g} m leaves fewer "
                         f"than 3 meshes above the round-off limit")
    freqs, dofs = [], []
    for h in sizes:
        model = case.fe_model(element_size=h)
        omega, _ = model.modes(n_modes + 3)
        elastic = omega[omega > 1e-3 * omega.max()][:n_modes]
        freqs.append(elastic / (2 * np.pi))
        dofs.append(model.n_free)
    n = min(len(f) for f in freqs)
    F = np.array([f[:n] for f in freqs])
    change = np.abs(F / F[-1] - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = np.log2(change[-3] / change[-2])
    return {"case": case.name, "element_size_m": sizes, "n_free_dofs": dofs,
            "frequency_hz": F.tolist(), "relative_change_vs_finest": change.tolist(),
            "rate": rate.tolist(), "reference": "the finest mesh (no closed form)"}


def format_case_convergence(r: dict) -> str:
    n = len(r["frequency_hz"][0])
    lines = [f"{r['case']}: first elastic modes under mesh refinement, against "
             f"{r['reference']}",
             f"{'elem_mm':>8} {'dofs':>6} " + " ".join(f"{'mode ' + str(j + 1):>12}" for j in range(n))]
    for h, d, f, c in zip(r["element_size_m"], r["n_free_dofs"], r["frequency_hz"],
                          r["relative_change_vs_finest"]):
        lines.append(f"{1e3 * h:8.3f} {d:6d} " + " ".join(f"{v:12.4f}" for v in f))
        lines.append(f"{'':8} {'':6} " + " ".join(f"{v:12.2e}" for v in c))
    lines.append(f"{'rate':>15} " + " ".join(f"{v:12.2f}" for v in r["rate"]))
    return "\n".join(lines)
