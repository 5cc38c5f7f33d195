"""Mesh convergence of any case with an FE strip model, against its own finest mesh.

The case's element size is halved ``levels - 1`` times (no finer than
:func:`cases.mode_report.min_element_size`); the first elastic modes of every mesh are
compared with the finest mesh's (no closed form exists for a jointed assembly), with the
observed rate ``log2(e_k / e_{k+1})`` of the last two coarse meshes (4 expected for the
cubic Hermite element, 2 where the axial bar elements take part, as in a jointed lap).
Calibrated parameters are re-calibrated on each mesh. Hz. A mode whose change does not
fall steadily under refinement (a negative, missing or below-1 rate, or a change that
grows) is warned about (:func:`convergence_warnings`): a spectrum that does not converge
is a defect of the model or of the solver, not a result.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from cases.mode_report import min_element_size
from fe.modal import normal_modes

#: a change counts as mesh (truncation) error when above this many times its round-off
#: bound (:func:`roundoff_floor` of the mesh plus the finest's); the realized round-off of
#: the lap cantilever's meshes (6 shifts, 2 BLAS kernels) stays below 0.3 of the bound, so
#: the noise of a change at the threshold is below a tenth of it: the verdict cannot flip
#: between machines unless the change sits within that tenth of the threshold
FLOOR_MARGIN = 3.0
#: two shifts disagreeing by more than this (relative): the eigen-solution is unreliable
ROUNDOFF_LIMIT = 1e-4


def roundoff_floor(K, omega, shapes) -> np.ndarray:
    """The round-off bound of each frequency (relative): ``eps kappa / 2`` with the
    componentwise condition ``kappa = |phi|^T |K| |phi| / lambda`` of the eigenvalue
    ``lambda = omega^2`` (mass-normalized ``phi``): a perturbation ``|dK| <= eps |K|``
    moves ``lambda`` by at most ``eps |phi|^T |K| |phi|`` to first order, ``omega`` by half
    that relative. It sees the cancellation of stiff joint and tie terms in ``phi^T K phi``
    that the round-off comes from, and it is the same on every machine (a mode shape's
    round-off moves it in its 6th digit, not its decade)."""
    phi = np.abs(np.asarray(shapes, float))
    absK = abs(K) if sp.issparse(K) else np.abs(np.asarray(K, float))
    energy = np.einsum("ij,ij->j", phi, absK @ phi)
    return np.finfo(float).eps * energy / (2.0 * np.asarray(omega, float) ** 2)


def case_convergence(case, levels: int = 4, n_modes: int = 6) -> dict:
    """Frequencies per mesh, their relative change against the finest, observed rates, the
    round-off estimate of each frequency (relative change when the eigen-solution is
    repeated at another shift, ``-4 lambda_e``: a differently conditioned factorization)
    and the warnings of :func:`convergence_warnings`."""
    cf = case.file
    length = max(b.x[1] - b.x[0] for b in cf.beams)
    sizes = [cf.element_size / 2**k for k in range(levels)]
    sizes = [h for h in sizes if h >= min_element_size(length)]
    if len(sizes) < 3:
        raise ValueError(f"case {case.name!r}: element size {cf.element_size:g} m leaves fewer "
                         f"than 3 meshes above the round-off limit")
    freqs, again, floors, dofs = [], [], [], []
    for h in sizes:
        model = case.fe_model(element_size=h)
        omega, shapes = model.modes(n_modes + 3)
        is_elastic = omega > 1e-3 * omega.max()
        shift = -4.0 * float(omega[is_elastic][0]) ** 2
        other, _ = normal_modes(model.K, model.M, min(n_modes + 3, model.n_free - 2), sigma=shift)
        freqs.append(omega[is_elastic][:n_modes] / (2 * np.pi))
        again.append(other[is_elastic][:n_modes] / (2 * np.pi))
        floors.append(roundoff_floor(model.K, omega[is_elastic][:n_modes],
                                     shapes[:, is_elastic][:, :n_modes]))
        dofs.append(model.n_free)
    n = min(len(f) for f in freqs)
    F = np.array([f[:n] for f in freqs])
    roundoff = np.abs(np.array([f[:n] for f in again]) / F - 1)
    floor = np.array([f[:n] for f in floors])
    change = np.abs(F / F[-1] - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = np.log2(change[-3] / change[-2])
    return {"case": case.name, "element_size_m": sizes, "n_free_dofs": dofs,
            "frequency_hz": F.tolist(), "relative_change_vs_finest": change.tolist(),
            "roundoff_estimate": roundoff.tolist(), "roundoff_floor": floor.tolist(),
            "rate": rate.tolist(), "reference": "the finest mesh (no closed form)",
            "warnings": convergence_warnings(change, rate, roundoff, sizes, floor)}


def convergence_warnings(change, rate, roundoff, sizes, floor=None) -> list[str]:
    """One line per mode that does not converge, or converges to round-off.

    ``change`` (n_meshes, n_modes): relative change against the finest mesh (coarsest
    first); ``rate`` the observed rate per mode; ``roundoff`` the round-off estimate of
    each frequency (two shifts); ``sizes`` the element sizes (m); ``floor`` the round-off
    bound of each frequency (:func:`roundoff_floor`; default ``roundoff``). A mode is
    warned about (``WARNING``) when two shifts disagree by more than
    :data:`ROUNDOFF_LIMIT` on a mesh (the eigen-solution is unreliable there), or when its
    changes above round-off (:func:`resolved_changes`) do not fall at every refinement or
    fall slower than rate 1 (the cubic element gives 4, the axial bar 2). A mode whose
    changes are all within round-off is noted as converged.
    """
    change, roundoff = np.asarray(change, float), np.asarray(roundoff, float)
    above = resolved_changes(change, roundoff if floor is None else floor)
    out = []
    for j in range(change.shape[1]):
        c, r = change[:-1, j], roundoff[:, j]
        head = f"WARNING mode {j + 1}: "
        if np.max(r) > ROUNDOFF_LIMIT:
            k = int(np.argmax(r))
            out.append(head + f"two eigen-solutions differ by {r[k]:.1e} at {1e3 * sizes[k]:g} mm "
                       f"elements: round-off, not mesh error; do not trust its frequency")
            continue
        resolved = above[:, j]
        if not resolved.any():
            out.append(f"mode {j + 1}: changes within round-off on every mesh: converged "
                       f"(its rate is not defined)")
            continue
        cr = c[resolved]
        steady = resolved[:cr.size].all() and np.all(np.diff(cr) < 0)
        fit = np.log2(cr[-2] / cr[-1]) if cr.size > 1 else np.inf
        if not (steady and fit >= 1.0):
            out.append(head + f"does not converge (rate {rate[j]:.2f}, expected 2 to 4; changes "
                       + ", ".join(f"{v:.1e}" for v in c) + "): the model depends on the "
                       "mesh; do not trust its frequency")
    return out


def resolved_changes(change, floor) -> np.ndarray:
    """(n_meshes - 1, n_modes) bool: the changes against the finest mesh above round-off,
    more than :data:`FLOOR_MARGIN` times the round-off bound of the mesh plus the
    finest's (``floor``: :func:`roundoff_floor` per mesh and mode)."""
    change, floor = np.asarray(change, float), np.asarray(floor, float)
    return change[:-1] > FLOOR_MARGIN * (floor[:-1] + floor[-1])


def format_case_convergence(r: dict) -> str:
    """The table of :func:`case_convergence`: a change above round-off
    (:func:`resolved_changes`) to two digits, one within it reads ``round-off``, a rate
    from one ``-`` (decided on the round-off bound, the same on every machine)."""
    n = len(r["frequency_hz"][0])
    ok = resolved_changes(r["relative_change_vs_finest"],
                          r.get("roundoff_floor", r["roundoff_estimate"]))
    ok = np.vstack([ok, np.ones((1, n), bool)])              # the finest: 0 by definition
    lines = [f"{r['case']}: first elastic modes under mesh refinement, against "
             f"{r['reference']}; changes within {FLOOR_MARGIN:g} x their round-off bound "
             f"read round-off",
             f"{'elem_mm':>8} {'dofs':>6} "
             + " ".join(f"{'mode ' + str(j + 1):>12}" for j in range(n))]
    for h, d, f, c, k in zip(r["element_size_m"], r["n_free_dofs"], r["frequency_hz"],
                             r["relative_change_vs_finest"], ok):
        lines.append(f"{1e3 * h:8.3f} {d:6d} " + " ".join(f"{v:12.4f}" for v in f))
        lines.append(f"{'':8} {'':6} " + " ".join(f"{v:12.1e}" if good else f"{'round-off':>12}"
                                                  for v, good in zip(c, k)))
    rated = ok[-3] & ok[-2]
    lines.append(f"{'rate':>15} " + " ".join(f"{v:12.1f}" if good else f"{'-':>12}"
                                             for v, good in zip(r["rate"], rated)))
    lines += r["warnings"]
    return "\n".join(lines)
