"""Mesh convergence studies.

1. A single clamped-free strip (the double beam's strip: 350 x 50 x 1 mm, E = 70 GPa,
   rho = 2700 kg/m^3) of 2-D frame elements against the analytic Euler-Bernoulli
   frequencies ``omega_n = (beta_n L)^2 sqrt(E I / (rho A L^4))``, with ``beta_n L`` the
   roots of ``1 + cos(x) cosh(x) = 0`` computed here by Brent's method (e.g. Blevins,
   *Formulas for Natural Frequency and Mode Shape*, table 8-1). Cubic Hermite elements with
   consistent mass have eigenvalue error ``O(h^(2(p + 1 - m)))`` with p = 3, m = 2
   (Strang & Fix, *An Analysis of the Finite Element Method*, 1973, thm. 6.1), i.e.
   ``h^4`` for ``omega^2`` and hence for ``omega``; the observed rate is the least-squares
   slope of ``log(error)`` against ``log(h)`` over the meshes whose error is above the
   round-off floor.
2. The double beam's measured mode (4th in-phase bending) under refinement of the strip
   mesh and, separately, of the number of joint elements in the glued zone: frequency and
   glue-slip participation, with the change relative to the finest mesh.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from fe.assembly import assemble, free_dofs, restrict
from fe.beam import Section, frame_mass, frame_stiffness
from fe.mesh import DofMap, line_mesh
from fe.modal import normal_modes

STRIP = Section(E=70.0e9, rho=2700.0, width=0.05, thickness=1.0e-3)
STRIP_LENGTH = 0.35
CANTILEVER_ELEMENTS = (2, 4, 8, 16, 32, 64, 128, 256, 512)
#: an error counts as truncation if above this many times its round-off bound (the
#: componentwise bound of cases.case_convergence.roundoff_floor: the same on every
#: machine; the two-shift sample of the round-off moved by 100x between BLAS kernels)
ROUNDOFF_MARGIN = 3.0
DOUBLE_BEAM_ELEMENT_SIZES = (0.02, 0.01, 0.005, 0.0025, 0.00125)
DOUBLE_BEAM_JOINTS = (2, 3, 5, 9, 17, 33)


def cantilever_beta_l(n_modes: int) -> np.ndarray:
    """First ``n_modes`` roots of ``1 + cos(x) cosh(x) = 0`` (clamped-free beam).

    Written as ``cos(x) + 1/cosh(x) = 0`` to avoid overflow; root n is the only sign
    change in ``[(n - 1) pi, n pi]`` (``[0.5, pi]`` for n = 1), where ``cos`` changes sign
    once and ``1/cosh`` < 0.09.
    """
    def f(x):
        return np.cos(x) + 1.0 / np.cosh(x)

    return np.array([brentq(f, (n - 1) * np.pi + 1e-9 if n > 1 else 0.5, n * np.pi,
                            xtol=1e-15, rtol=1e-15)
                     for n in range(1, n_modes + 1)])


def cantilever_frequencies_analytic(section: Section, length: float, n_modes: int) -> np.ndarray:
    """Analytic clamped-free Euler-Bernoulli natural frequencies, rad/s."""
    bl = cantilever_beta_l(n_modes)
    return bl**2 * np.sqrt(section.EI / (section.mass_per_length * length**4))


def cantilever_model(section: Section, length: float, n_elements: int):
    """Clamped-free frame of ``n_elements`` equal elements: (K, M) over the free DOFs."""
    mesh = line_mesh(np.linspace(0.0, length, n_elements + 1))
    dm = DofMap(mesh.n_nodes)
    dofs = dm.element_dofs(mesh.elements)
    K = assemble(frame_stiffness(mesh.element_length, section.EA, section.EI), dofs, dm.n_dofs)
    M = assemble(frame_mass(mesh.element_length, section.mass_per_length), dofs, dm.n_dofs)
    free = free_dofs(dm.n_dofs, dm.node_dofs([0]).ravel())
    return restrict(K, free), restrict(M, free), free, dm


def cantilever_bending_frequencies(section: Section, length: float, n_elements: int,
                                   n_modes: int, sigma: float = -1.0, floor: bool = False):
    """Lowest ``n_modes`` bending frequencies (rad/s) of the FE cantilever.

    ``sigma`` is the shift-invert shift (rad^2/s^2) of :func:`fe.modal.normal_modes`.
    Axial modes (no transverse displacement) are skipped; NaN where the mesh has fewer
    bending modes than asked. With ``floor``: ``(omega, bound)``, ``bound`` the round-off
    bound of each frequency (:func:`cases.case_convergence.roundoff_floor`).
    """
    K, M, free, dm = cantilever_model(section, length, n_elements)
    k = min(free.size, n_modes + 2)  # the first axial mode (3.6 kHz) is above bending mode 6
    omega, shapes = normal_modes(K, M, k, sigma=sigma, dense_below=2 * k + 2)
    is_axial = np.zeros(dm.n_dofs, dtype=bool)
    is_axial[0::3] = True
    axial = is_axial[free]
    bending = np.linalg.norm(shapes[~axial], axis=0) > np.linalg.norm(shapes[axial], axis=0)
    out, bound = np.full(n_modes, np.nan), np.full(n_modes, np.nan)
    wb = omega[bending][:n_modes]
    out[: wb.size] = wb
    if not floor:
        return out
    from cases.case_convergence import roundoff_floor

    bound[: wb.size] = roundoff_floor(K, wb, shapes[:, bending][:, :n_modes])
    return out, bound


def observed_rate(h: np.ndarray, err: np.ndarray, usable: np.ndarray, n_fit: int = 3) -> float:
    """Least-squares slope of log(err) vs log(h) over the ``n_fit`` finest usable meshes.

    ``usable`` marks meshes whose error is truncation, not round-off; NaN if fewer than
    two usable meshes.
    """
    h, err = np.asarray(h, float), np.asarray(err, float)
    idx = np.flatnonzero(np.asarray(usable) & np.isfinite(err) & (err > 0))
    idx = idx[np.argsort(h[idx])][:n_fit]
    if idx.size < 2:
        return float("nan")
    return float(np.polyfit(np.log(h[idx]), np.log(err[idx]), 1)[0])


def cantilever_study(elements=CANTILEVER_ELEMENTS, n_modes: int = 6,
                     section: Section = STRIP, length: float = STRIP_LENGTH) -> dict:
    """Relative frequency error of the FE cantilever vs the analytic one.

    The round-off of each computed frequency is sampled as the largest relative change
    when the eigen-solution is repeated with two other shifts (``0.5 omega_1^2`` and
    ``-1e4`` rad^2/s^2, i.e. differently conditioned factorizations:
    ``roundoff_estimate``) and bounded by :func:`cases.case_convergence.roundoff_floor`
    (``roundoff_floor``); an error is *truncation* when it exceeds ``ROUNDOFF_MARGIN``
    times the bound, else *round-off* (decided on the bound, so the same on every
    machine). Rates are fitted over the three finest truncation meshes.

    Returns a dict with ``elements``, ``element_size_m``, ``beta_L``, ``analytic_hz``,
    ``relative_error`` (one list of per-mode errors per mesh, NaN where unresolved),
    ``roundoff_estimate`` and ``roundoff_floor`` (same shape), ``truncation`` (bool, same
    shape), ``rate`` (observed rate per mode),
    ``finest_error`` and ``finest_limited_by`` ('truncation' or 'round-off' per mode),
    ``best_error`` and ``best_elements`` (smallest error per mode and its mesh).
    """
    elements = [int(n) for n in elements]
    exact = cantilever_frequencies_analytic(section, length, n_modes)
    sigmas = (-1.0, 0.5 * exact[0] ** 2, -1.0e4)
    err, roundoff, bound = [], [], []
    for n in elements:
        first, b = cantilever_bending_frequencies(section, length, n, n_modes, sigmas[0],
                                                  floor=True)
        runs = [first] + [cantilever_bending_frequencies(section, length, n, n_modes, s)
                          for s in sigmas[1:]]
        err.append(np.abs(runs[0] / exact - 1.0))
        roundoff.append(np.max([np.abs(r / runs[0] - 1.0) for r in runs[1:]], axis=0))
        bound.append(b)
    err, roundoff, bound = np.array(err), np.array(roundoff), np.array(bound)
    truncation = err > ROUNDOFF_MARGIN * bound
    h = length / np.array(elements, float)
    rate = np.array([observed_rate(h, err[:, j], truncation[:, j]) for j in range(n_modes)])
    return {
        "elements": elements,
        "element_size_m": h,
        "beta_L": cantilever_beta_l(n_modes),
        "analytic_hz": exact / (2 * np.pi),
        "relative_error": err,
        "roundoff_estimate": roundoff,
        "roundoff_floor": bound,
        "truncation": truncation,
        "rate": rate,
        "finest_error": err[-1],
        "finest_limited_by": ["truncation" if t else "round-off" for t in truncation[-1]],
        "best_error": np.nanmin(err, axis=0),
        "best_elements": [elements[i] for i in np.nanargmin(err, axis=0)],
    }


def joint_spacing(n_joints, glue_length: float | None = None) -> np.ndarray:
    """Spacing (m) of ``n_joints`` joint elements spread evenly over the glued zone,
    ``glue_length / (n - 1)`` (default: the shipped double beam's glue length)."""
    if glue_length is None:
        from cases.double_beam.model import DoubleBeamConfig

        glue_length = DoubleBeamConfig().glue_length
    return glue_length / (np.asarray(n_joints, float) - 1.0)


def _measured_mode(model):
    from cases.double_beam.model import MEASURED_BENDING_ORDER

    omega, shapes = model.modes(MEASURED_BENDING_ORDER + 6)
    order = model.bending_order(omega, shapes)
    i = int(np.flatnonzero(order == MEASURED_BENDING_ORDER)[0])
    return omega[i] / (2 * np.pi), model.glue_slip_participation(shapes[:, i])


def _double_beam_mesh_case(cfg) -> dict:
    """One mesh of :func:`double_beam_study` (module level: a task of
    :func:`runs.executor.run_sweep`)."""
    from cases.double_beam.model import build_double_beam

    model = build_double_beam(cfg)
    f, p = _measured_mode(model)
    return {"element_size_m": cfg.element_size, "n_joints": cfg.n_joints,
            "n_free_dofs": model.n_free, "frequency_hz": f, "glue_slip": p}


def double_beam_study(element_sizes=DOUBLE_BEAM_ELEMENT_SIZES, joints=DOUBLE_BEAM_JOINTS,
                      progress: bool = False, executor=None) -> dict:
    """Measured-mode frequency and glue-slip participation under mesh refinement.

    The strip element size is refined with the default number of joints, and the number
    of joints with the default element size. ``relative_change`` is against the finest
    mesh of each sweep. The meshes are independent tasks of
    :func:`runs.executor.run_sweep` on ``executor`` (default serial; an
    :class:`runs.executor.ExecutorSpec` or its kind); the results do not depend on it.
    """
    from cases.double_beam.model import DoubleBeamConfig
    from runs.executor import run_sweep

    base = DoubleBeamConfig()
    cases = [("element_size", replace(base, element_size=s)) for s in element_sizes]
    cases += [("joints", replace(base, n_joints=n)) for n in joints]
    cases += [("default", base)]
    rows = run_sweep(_double_beam_mesh_case, [cfg for _, cfg in cases],
                     executor=executor or "serial", progress=progress,
                     desc="double-beam meshes", unit="mesh", chunksize=1)
    out = {"element_size": [], "joints": [], "default": []}
    for (kind, _), row in zip(cases, rows):
        out[kind].append(row)

    def sweep(rows, key, h):
        f = np.array([r["frequency_hz"] for r in rows])
        p = np.array([r["glue_slip"] for r in rows])
        df, dp = f / f[-1] - 1.0, p / p[-1] - 1.0
        usable = np.arange(f.size) < f.size - 2  # the last two are too close to the reference
        return {key: [r[key] for r in rows],
                "n_free_dofs": [r["n_free_dofs"] for r in rows],
                "frequency_hz": f, "glue_slip": p,
                "frequency_relative_change": df,
                "glue_slip_relative_change": dp,
                "frequency_rate": observed_rate(h, np.abs(df), usable),
                "glue_slip_rate": observed_rate(h, np.abs(dp), usable)}

    es = sweep(out["element_size"], "element_size_m", np.array(element_sizes, float))
    js = sweep(out["joints"], "n_joints", joint_spacing(joints, base.glue_length))
    d = out["default"][0]
    # default-mesh error: against the finest of both sweeps (each refines one ingredient)
    f_ref = es["frequency_hz"][-1] + js["frequency_hz"][-1] - d["frequency_hz"]
    p_ref = es["glue_slip"][-1] + js["glue_slip"][-1] - d["glue_slip"]
    return {
        "mode": "in-phase bending mode 4 (the measured mode)",
        "element_size_sweep": es,
        "joint_sweep": js,
        "default": {**d, "frequency_error_estimate": d["frequency_hz"] / f_ref - 1.0,
                    "glue_slip_error_estimate": d["glue_slip"] / p_ref - 1.0},
    }


def convergence_report(progress: bool = False, executor=None) -> dict:
    """Both studies in one JSON-able dict (keys ``cantilever`` and ``double_beam``);
    ``executor`` runs the double-beam meshes (:func:`double_beam_study`)."""
    return {"cantilever": cantilever_study(),
            "double_beam": double_beam_study(progress=progress, executor=executor)}
