"""Measuring a drawn test: the lines, every run's FRF with noise, the project's
identification of the series, and the honest visibility of each mechanism.

The series goes through :func:`ident.series.identify_series` (one mode per level, as
``--modes 1``; the band-sensitivity check skipped for speed, it only adds warnings)
and :func:`ident.series_table.series_table`, as ``iwanfe diagnose FILE...`` would take
the files. A repeated level is identified on its own and joins the table as a row of
the same ``level`` with its own ``run_order`` (``measured-data.md``, Repeats).

Visibility (stored in the truth): every run simulated noise-free with all mechanisms
and with one taken out, each level identified (:func:`ident.identify.identify`, relative
weighting: noise-free FRFs need no noise model); the
range over the runs of the change in omega2 and in zeta, each in units of the run's
noise ``sqrt(sigma_id^2 + sigma_rep^2)`` (``sigma_id`` the noisy identification's std
of that row, ``sigma_rep`` the planted repeatability: ``2 s_f omega2``, ``s_z zeta``).
"""
from __future__ import annotations

import math

import numpy as np

from synthetic.rig import noisy, resonance, solve_level
from ident.errors import InputError
from ident.frf_files import FRFSet
from ident.identify import identify
from ident.modal_data import MeasuredData
from ident.series import identify_series
from ident.series_table import series_table

__all__ = ["place_lines", "simulate_runs", "identify_table", "honest_visibility",
           "concat", "Refused"]


class Refused(ValueError):
    """The draw cannot be measured (a fold, an identification refused): draw again."""


def place_lines(rng, st, plan):
    """Lines per level (rad/s): +-(2.5-5) loaded half-power bandwidths about each
    level's predicted resonance, or one grid over all levels."""
    n_bw = rng.uniform(2.5, 5.0)
    bands = []
    for v in range(plan.held.size):
        run = next(r for vv, r, _ in plan.runs if vv == v)
        _, w2, _, z_loaded = resonance(st, plan.control, plan.held[v], run)
        w = math.sqrt(w2)
        hw = n_bw * max(z_loaded, 1e-4) * w
        bands.append((w - hw, w + hw))
    if plan.grid == "fixed":
        lo, hi = min(b[0] for b in bands), max(b[1] for b in bands)
        n = int(plan.n_lines * min(3.0, (hi - lo) / np.mean([b[1] - b[0] for b in bands])))
        plan.lines = [np.linspace(lo, hi, max(n, plan.n_lines))] * plan.held.size
    else:
        plan.lines = [np.linspace(lo, hi, plan.n_lines) for lo, hi in bands]


def simulate_runs(rng, st, plan, with_noise=True):
    """Every run of the plan: dict(v, run, repeat, freq_hz, frf, force, x_peak).
    Raises :class:`Refused` on a fold (several steady states on a line)."""
    out = []
    for v, run, rep in plan.runs:
        W = plan.lines[v]
        H, F, X, fold = solve_level(st, W, plan.control, plan.held[v], run)
        if fold:
            raise Refused(f"level {v + 1}: several steady states")
        if with_noise:
            H = noisy(rng, H, plan.eps_m, plan.eps_a)
            F = F * (1 + plan.force_noise * rng.standard_normal(F.shape))
        out.append(dict(v=v, run=run, repeat=rep, freq_hz=W / (2 * math.pi), frf=H,
                        force=F, x_peak=float(X.max())))
    return out


def _set(s, plan):
    return FRFSet(s["freq_hz"], s["frf"], ["1"], quantity="receptance",
                  excitation=float(plan.held[s["v"]]), reference="1",
                  source=f"level_{s['v'] + 1:02d}" + ("_repeat" if s["repeat"] else ""),
                  control=plan.control, run_order=int(s["run"].k),
                  force=s["force"] if plan.force_column else None)


def concat(a: MeasuredData, b: MeasuredData) -> MeasuredData:
    """Rows of ``a`` then ``b`` (annotation columns both have)."""
    def cat(x, y):
        return None if x is None or y is None else np.concatenate([x, y])
    keys = set(a.extra) & set(b.extra)
    return MeasuredData(
        level=cat(a.level, b.level), excitation=cat(a.excitation, b.excitation),
        omega2=cat(a.omega2, b.omega2), zeta=cat(a.zeta, b.zeta), mode=cat(a.mode, b.mode),
        run_order=cat(a.run_order, b.run_order),
        response_amplitude=cat(a.response_amplitude, b.response_amplitude),
        omega2_std=cat(a.omega2_std, b.omega2_std), zeta_std=cat(a.zeta_std, b.zeta_std),
        control=cat(a.control, b.control),
        extra={k: np.concatenate([a.extra[k], b.extra[k]]) for k in keys},
        warnings=list(a.warnings) + list(b.warnings), source=a.source)


def identify_table(sims, plan) -> MeasuredData:
    """The measured-data table of the noisy runs (module doc); repeats appended."""
    main = [s for s in sims if not s["repeat"]]
    main.sort(key=lambda s: s["v"])
    try:
        with np.errstate(all="ignore"):
            data = series_table(identify_series([_set(s, plan) for s in main], n_modes=1,
                                                check_band=False))
            if len(data) != len(main) or data.omega2_std is None:
                raise Refused("the identification lost a level or its stds")
            for s in (s for s in sims if s["repeat"]):
                row = series_table(identify_series([_set(s, plan)], n_modes=1,
                                                   check_band=False))
                row.level = np.array([s["v"] + 1])
                data = concat(data, row)
    except (InputError, ValueError, IndexError, np.linalg.LinAlgError) as exc:
        raise Refused(str(exc)) from None
    data.source = "synthetic"
    return data


def _identified(sims):
    out = []
    for s in sims:
        H = s["frf"]
        for tiny in (0.0, 1e-9, 1e-7):     # an exact FRF can make LSCF singular
            if tiny:
                H = s["frf"] * (1 + tiny * np.cos(np.arange(H.size) * 2.39996))
            try:
                with np.errstate(all="ignore"):
                    m = identify(s["freq_hz"], H, n_modes=1, weighting="relative").modes[0]
                break
            except (ValueError, IndexError, np.linalg.LinAlgError):
                m = None
        if m is None:
            raise Refused("a noise-free level could not be identified")
        out.append((m.omega2, m.zeta))
    return np.array(out)


def honest_visibility(st, plan, table, mechanisms):
    """Per mechanism: range of the identified change over the runs in noise units
    (module doc), and the noise-free identified values with and without it."""
    free = simulate_runs(None, st, plan, with_noise=False)
    full = _identified(free)
    rows = {(int(lv), int(ro)): i for i, (lv, ro) in enumerate(zip(table.level, table.run_order))}
    idx = [rows[(v + 1, run.k)] for v, run, _ in plan.runs]
    u_w = np.hypot(table.omega2_std[idx], 2 * plan.s_f * full[:, 0])
    u_z = np.hypot(table.zeta_std[idx], plan.s_z * full[:, 1])
    out = []
    for m in mechanisms:
        try:
            osims = simulate_runs(None, st.without(m), plan, with_noise=False)
            other = _identified(osims)
        except Refused:
            out.append(dict(family=m.family, visibility=None, reason="without it the "
                            "response folds"))
            continue
        dw, dz = (full[:, 0] - other[:, 0]) / u_w, (full[:, 1] - other[:, 1]) / u_z
        out.append(dict(family=m.family, visibility=float(max(np.ptp(dw), np.ptp(dz))),
                        visibility_omega2=float(np.ptp(dw)), visibility_zeta=float(np.ptp(dz)),
                        with_omega2=full[:, 0].tolist(), without_omega2=other[:, 0].tolist(),
                        with_zeta=full[:, 1].tolist(), without_zeta=other[:, 1].tolist(),
                        x_peak_with=[s["x_peak"] for s in free],
                        x_peak_without=[s["x_peak"] for s in osims]))
    return out, full
