"""The double-beam report's files: figures, ``simulated_measured.csv``, one FRF file per
level, ``report.json`` and ``report.md`` (:func:`write_report`).
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from cases.double_beam.markdown import markdown
from cases.double_beam.report import DoubleBeamReport
from ident.measured import write_measured

__all__ = ["write_simulated_csv", "write_frf_files", "write_report"]


def write_simulated_csv(rep: DoubleBeamReport, path) -> Path:
    """The simulated per-level modal data as a measured-data CSV (spec: measured-data.md)."""
    path = Path(path)
    write_measured(path, rep.simulated)
    return path


def write_frf_files(rep: DoubleBeamReport, out) -> list[Path]:
    """The simulated receptance at the response DOF, one FRF CSV per level.

    ``out/level_XX.csv`` (:func:`ident.frf_files.write_frf`, 17 significant digits) with
    ``# quantity = receptance`` (m/N), ``# excitation = <drive V>`` and one point
    ``acc1`` (Acc. 1, the response DOF), so that the simulated campaign goes through
    the same identification as measured FRFs::

        iwanfe identify results/double-beam/frf/level_*.csv --band 240 264 --out modal.csv

    (``identify``'s default options differ from the study's, see
    :mod:`cases.double_beam.settings`, so its zeta agrees with ``simulated_measured.csv`` to
    about 1e-4 relative, not bitwise.)
    """
    from ident.frf_files import FRFSet, write_frf

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    camp = rep.campaign
    paths = []
    for i, (level, volts) in enumerate(zip(rep.measured.level, rep.measured.excitation)):
        path = out / f"level_{int(level):02d}.csv"
        write_frf(path, FRFSet(camp.frequency_hz, camp.receptance[i, :, int(rep.response_dof)],
                               points=["acc1"], quantity="receptance",
                               excitation=float(volts), reference="drive"))
        paths.append(path)
    return paths


def write_report(rep: DoubleBeamReport, out, t_start: float | None = None) -> list[Path]:
    """Write figures, ``simulated_measured.csv``, ``frf/level_XX.csv``
    (:func:`write_frf_files`), ``report.json`` and ``report.md``.

    Parameters
    ----------
    rep : DoubleBeamReport
    out : path
        Output directory (created).
    t_start : float, optional
        ``time.perf_counter()`` at the start of the run, for the wall time in the report.

    Returns
    -------
    list of Path (also stored in ``rep.files``)
    """
    import json

    from runs.jsonio import to_jsonable
    from viz.double_beam_plots import plot_joint_levels, plot_level_comparison
    from viz.frf_plots import plot_frf_levels
    from viz.logslope import plot_estimate

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    m, s, su = rep.measured, rep.simulated, rep.setup
    preds = {f"{k} (fit {rep.study.fit_levels})": {
        "omega2": [p["omega2"] for p in e.predictions], "zeta": [p["zeta"] for p in e.predictions]}
        for k, (e, _, _) in rep.successful_estimates("measured").items()}
    path = out / "levels_measured_vs_simulated.png"
    plot_level_comparison(m.level, {"omega2": m.omega2, "zeta": m.zeta},
                          {"omega2": s.omega2, "zeta": s.zeta}, preds, rep.study.fit,
                          title="Double beam, mode at 252 Hz: measured (paper Tables 3-6), "
                                "simulated (FE + Iwan glue), estimated", path=path)
    files.append(path)
    slip = rep.identification.slip / su.phi_max
    j = int(np.nanargmax(slip[0]))
    path = out / "joint_slips_and_damping.png"
    mf = rep.modal_filter
    plot_joint_levels(m.level, slip, slip[0, j] * m.excitation / m.excitation[0], mf.delta_c,
                      mf.delta_c_decoupled,
                      title=f"Iwan glue joints: chi = {su.chi:.4f}, R = {su.R:.4g}, "
                            f"phi_max = {su.phi_max:.4g} m", path=path)
    files.append(path)
    camp = rep.campaign
    w = 2 * np.pi * camp.frequency_hz
    acc = -(w ** 2)[None, :] * camp.receptance[:, :, int(rep.response_dof)]
    path = out / "frf_levels.png"
    f0 = su.omega_n / (2 * math.pi)
    plot_frf_levels(camp.frequency_hz, acc, camp.force,
                    zooms=[(f0 - 6.0, f0 + 6.0, "half-power region")],
                    title=f"Simulated accelerance at Acc. 1, {camp.force.size} levels "
                          f"({su.force_scale:g} N/V)", ylabel="|accelerance| (m/s^2/N)", path=path)
    files.append(path)
    for which, tag in (("measured", "measured"), ("lscf", "simulated")):
        for k, (e, _, _) in rep.successful_estimates(which).items():
            path = out / f"fig8_{tag}_{k}.png"
            plot_estimate(e, str(path), title=f"Fig. 8, {tag} data, method {k}")
            files.append(path)
    path = write_simulated_csv(rep, out / "simulated_measured.csv")
    files.append(path)
    files += write_frf_files(rep, out / "frf")
    files += [out / "report.json", out / "report.md"]
    rep.files = files
    wall = None if t_start is None else time.perf_counter() - t_start
    rep.timings["wall_time"] = wall
    (out / "report.json").write_text(json.dumps(to_jsonable(rep.to_dict()), indent=1))
    (out / "report.md").write_text(markdown(rep, files, wall))
    return files
