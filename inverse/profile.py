"""Profile likelihood of updated parameters: intervals, and which ones the data determine.

For a parameter ``theta_i`` the profile is ``chi2_p(t) = min chi2(theta)`` over the other
free parameters with ``theta_i = t`` (eq. 1 of :mod:`inverse.update`), computed on a grid
by continuation (each grid point starts from its neighbour's optimum). With known noise
the likelihood-ratio interval at confidence ``c`` is ``{t : chi2_p(t) - chi2_min <=
q_c s^2}`` (Wilks; ``q_c`` the chi-square(1) quantile, 3.84 at 95 %), where ``s^2 =
max(1, chi2_min/dof)`` widens it when the model misfits the data beyond their noise (the
intervals are then conditional on a model known to be wrong, and say so).

A parameter is *determined* when its interval closes on both sides inside the grid,
*bounded below/above* when only one side closes, *not determined* when the profile stays
under the threshold over the whole grid (e.g. the glue stiffness of a joint that never
leaves micro-slip), *failed* when a fit of the profile failed before its side closed
(counted in ``failed_points``; never read as "open"). At a bound of the parameter
(:func:`bounded_interval`) that side of the interval is the bound itself. The grid branches
(one per parameter and direction) are independent tasks of :func:`runs.executor.run_sweep`;
with a ``store`` (directory, digest of the problem) every finished branch is written there
as it finishes (``branch_<hash>.json``, atomically) and a rerun of the same problem loads it
instead of recomputing.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import chi2 as chi2_dist

from inverse.fe_selection import fit_together
from inverse.update import Fit, UpdateProblem
from runs.executor import run_sweep
from runs.jsonio import to_jsonable
from runs.store import open_manifest

__all__ = ["ProfilePoint", "Profile", "threshold", "profile_branch", "stored_branch",
           "run_profiles", "linear_grid", "bounded_interval"]


@dataclass
class ProfilePoint:
    """One grid point: the parameter ``value``, the profiled ``chi2``, every parameter
    ``values`` of that optimum (None where the fit failed), ``problem.describe`` of
    them (``extra``) and whether its fit ``converged`` (:attr:`inverse.update.Fit.
    converged`; an unconverged point's chi2 may be too high)."""

    value: float
    chi2: float
    values: dict | None = None
    extra: dict | None = None
    converged: bool = True


@dataclass
class Profile:
    """The profile of one parameter, its interval and status (module docstring)."""

    name: str
    best: float
    chi2_min: float
    threshold: float
    points: list = field(default_factory=list)

    def __post_init__(self):
        self.points = sorted(self.points, key=lambda p: p.value)
        low = min(self.points, key=lambda p: p.chi2, default=None)
        if low is not None and low.chi2 < self.chi2_min:   # the grid found a better optimum
            self.best, self.chi2_min = low.value, low.chi2

    @property
    def delta(self) -> np.ndarray:
        return np.array([p.chi2 - self.chi2_min for p in self.points])

    def _cross(self, side: int):
        """Interval end on ``side`` (-1 lower, +1 upper) by linear interpolation of the
        profile between the last grid point inside and the first outside; None if the
        profile stays inside to the end of the grid."""
        pts = [p for p in self.points if (p.value - self.best) * side > 0]
        pts.sort(key=lambda p: abs(p.value - self.best))
        prev_v, prev_d = self.best, 0.0
        for p in pts:
            if p.values is None:          # a failed fit closes nothing: "failed"
                return "failed"
            d = p.chi2 - self.chi2_min
            if d > self.threshold:
                t = (self.threshold - prev_d) / (d - prev_d) if d != prev_d else 1.0
                return prev_v + t * (p.value - prev_v)
            prev_v, prev_d = p.value, d
        return None

    @property
    def interval(self) -> tuple:
        """(lower, upper); None where the profile never leaves the threshold or a fit
        failed before it did (:attr:`failed_sides`)."""
        return tuple(None if e == "failed" else e for e in (self._cross(-1), self._cross(+1)))

    @property
    def failed_sides(self) -> list:
        """The sides (``lower``, ``upper``) a failed fit left open."""
        return [w for w, s in (("lower", -1), ("upper", +1)) if self._cross(s) == "failed"]

    @property
    def failed_points(self) -> int:
        return sum(p.values is None for p in self.points)

    @property
    def unconverged_points(self) -> int:
        """Points whose fit gave a chi2 but did not converge."""
        return sum(p.values is not None and not p.converged for p in self.points)

    @property
    def status(self) -> str:
        if self.failed_sides:
            return "failed (" + ", ".join(self.failed_sides) + " side)"
        lo, hi = self.interval
        if lo is not None and hi is not None:
            return "determined"
        if lo is not None:
            return "bounded below"
        if hi is not None:
            return "bounded above"
        return "not determined"

    def inside(self) -> list:
        """Grid points (and the best) whose chi2 is within the threshold."""
        return [p for p in self.points if p.values is not None
                and p.chi2 - self.chi2_min <= self.threshold]

    def to_dict(self) -> dict:
        lo, hi = self.interval
        return {"best": self.best, "interval": [lo, hi], "status": self.status,
                "threshold": self.threshold, "failed_points": self.failed_points,
                "unconverged_points": self.unconverged_points,
                "grid": [{"value": p.value, "delta_chi2": p.chi2 - self.chi2_min}
                         for p in self.points]}


def bounded_interval(profile: Profile, lower: float, upper: float, side) -> tuple:
    """The profile interval of a parameter whose optimum sits on its ``side`` bound
    (``"lower"``/``"upper"``, else the plain interval): that end is the bound."""
    lo, hi = profile.interval
    if side == "lower":
        lo = lower
    elif side == "upper":
        hi = upper
    return lo, hi


def threshold(best: Fit, confidence: float = 0.95) -> float:
    """``q_c s^2`` of the module docstring."""
    return float(chi2_dist.ppf(confidence, 1)) * best.misfit_scale


def linear_grid(best: Fit, name: str, param, n: int = 6, width: float = 3.0):
    """Outward grid branches (down, up) of ``n`` points to ``width`` linearized standard
    errors (misfit-scaled, at least the parameter's ``step``), clipped to its bounds."""
    se = best.std_error(name)
    se = param.step if not (math.isfinite(se) and se > 0) else se
    x = best.values[name]
    offs = width * se * np.arange(1, n + 1) / n
    down = [max(x - o, param.lower) for o in offs]
    up = [min(x + o, param.upper) for o in offs]
    tiny = 1e-6 * param.step          # a branch starting on a bound has no points

    def dedup(v):
        return [a for i, a in enumerate(v)
                if abs(a - x) > tiny and a not in v[:i]]

    return dedup(down), dedup(up)


def profile_branch(task, problem: UpdateProblem) -> list:
    """One branch of a profile: ``task = (name, grid, start, free, level, stop,
    bounds)``; ``grid`` ordered outward from the optimum ``start`` (all values);
    ``free`` the other fitted parameters. Each point is fitted from its neighbour's
    optimum and from ``start``, the two fits together from the simulator's warm starts
    (:func:`inverse.fe_selection.fit_together`), the better kept (optimizer tolerance
    1e-6: chi2 to about 1e-6 relative). The first point past ``level`` (chi2 at the
    interval's edge) is bracketed by 2 bisections; a branch still under ``level`` at the
    end of its grid goes on with doubling steps (at most 4) inside ``bounds``; it stops
    after the first point past ``stop`` or at a failed fit."""
    name, grid, start, free, level, stop, bounds = task
    if hasattr(problem.simulate, "reset"):   # no warm start from an earlier task
        problem.simulate.reset()
    others = [f for f in free if f != name]
    cur, prev_v, prev_c = dict(start), float(start[name]), -math.inf
    grid = [float(v) for v in grid]
    out = []

    def at(v, st):
        # two starts: the neighbour's optimum and the overall one (a sharp feature such
        # as a macro-slip onset makes the profile multimodal)
        fits = fit_together(problem, [dict(free=others, start=s, fixed={name: v}, tol=1e-6)
                                      for s in (st, start)], cold=False)[0]
        f = min(fits, key=lambda f: (not f.success, f.chi2))
        if not f.success:
            return ProfilePoint(v, f.chi2)
        extra = problem.figures(f.values)
        if extra is None and problem.describe is not None:   # its figures failed: counted
            return ProfilePoint(v, f.chi2)
        return ProfilePoint(v, f.chi2, dict(f.values), extra, f.converged)

    i, extended = 0, 0
    while i < len(grid):
        p = at(grid[i], cur)
        out.append(p)
        if p.values is None:
            break
        if p.chi2 > level >= prev_c:
            lo_v, lo_vals, hi_v = prev_v, cur, p.value
            for _ in range(2):
                m = at(0.5 * (lo_v + hi_v), lo_vals)
                out.append(m)
                if m.values is None:
                    break
                if m.chi2 > level:
                    hi_v = m.value
                else:
                    lo_v, lo_vals = m.value, m.values
        cur, prev_v, prev_c = p.values, p.value, p.chi2
        if p.chi2 > stop:
            break
        i += 1
        if i == len(grid) and p.chi2 <= level and extended < 4 and len(grid) > 1:
            nxt = grid[-1] + 2.0 * (grid[-1] - grid[-2])
            nxt = min(max(nxt, bounds[0]), bounds[1])
            if nxt != grid[-1]:
                grid.append(nxt)
                extended += 1
    return out


def _branch_path(store, task) -> Path:
    key = hashlib.sha256(json.dumps(to_jsonable(task), sort_keys=True).encode()).hexdigest()
    return Path(store[0]) / f"branch_{key[:16]}.json"


def stored_branch(task, problem: UpdateProblem) -> list:
    """:func:`profile_branch` through the store named in the task's last item."""
    *inner, store = task
    path = _branch_path(store, inner)
    if path.exists():
        return [ProfilePoint(**p) for p in json.loads(path.read_text())]
    out = profile_branch(tuple(inner), problem)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(to_jsonable([asdict(p) for p in out])))
    os.replace(tmp, path)
    return out


def run_profiles(problem: UpdateProblem, best: Fit, grids: dict, free,
                 confidence: float = 0.95, executor="serial", progress: bool = False,
                 stop_factor: float = 2.0, store=None) -> dict:
    """Profiles of every parameter in ``grids`` (``name -> (down, up)`` branches, each
    ordered outward from ``best``), the other ``free`` parameters refitted. ``store``:
    ``(directory, digest)`` of the problem, or None (module docstring).

    Returns
    -------
    dict name -> Profile
    """
    thr = threshold(best, confidence)
    stop = best.chi2 + stop_factor * thr
    bounds = {n: (problem.parameters[n].lower, problem.parameters[n].upper) for n in grids}
    tasks = [(name, list(branch), dict(best.values), tuple(free), best.chi2 + thr, stop,
              bounds[name])
             for name, branches in grids.items() for branch in branches if len(branch)]
    func = profile_branch
    if store is not None:
        open_manifest(store[0], store[1], {"what": "profile branches"}, "profile store")
        tasks = [t + (tuple(map(str, store)),) for t in tasks]
        func = stored_branch
    results = run_sweep(func, tasks, executor=executor, shared=problem,
                        progress=progress, desc="profiles", unit="branch")
    if hasattr(problem.simulate, "reset"):   # as in a branch: no warm start from one
        problem.simulate.reset()
    extra = problem.figures(best.values)
    pts: dict = {name: [ProfilePoint(best.values[name], best.chi2, dict(best.values), extra)]
                 for name in grids}
    for task, branch in zip(tasks, results):
        pts[task[0]].extend(branch)
    return {name: Profile(name, best.values[name], best.chi2, thr, pts[name])
            for name in grids}
