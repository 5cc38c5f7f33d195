"""Model updating: a simulator's parameters fitted to measured omega^2 and zeta per level.

The simulator is any callable ``simulate(values) -> (omega2, zeta)`` giving the natural
frequency squared (rad^2/s^2) and damping ratio of one mode at every level of a test
series (e.g. the nonlinear FE double beam, :mod:`feloop.levels`), warm-started from its
last call or not; optionally with ``simulate.batch(values_list, warm=None) -> (outputs,
warm_after)``: every set of the list from the warm starts ``warm[i]`` (None: its own,
which a batch leaves as they are), per set ``(omega2, zeta)`` or the exception of a
failed simulation, and its warm starts after it (the difference Jacobian's columns in
one call; :func:`inverse.fe_selection.fit_together`). The parameters are named, bounded
scalars (:class:`Parameter`). The fit is weighted least squares, i.e. Gaussian maximum
likelihood with known noise levels (:class:`NoiseModel`)::

    chi2(theta) = sum_{v in fit} [((omega2_v(theta) - omega2_v) / s_omega2,v)^2
                                 + ((zeta_v(theta) - zeta_v) / s_zeta,v)^2],        (1)

minimized by :func:`scipy.optimize.least_squares` (trust-region reflective, bounds,
finite-difference Jacobian in the parameters scaled by their ``step``). A simulator
that fails (no steady state) returns a large residual, so the optimizer steps back;
every such failure is counted (``UpdateProblem.failures``, ``Fit.failed_simulations``)
and a fit whose optimum still holds one is not a success.

Bounds. A free parameter within ``1e-4 step`` of a bound at the optimum is *at its
bound* (``Fit.at_bound``); the covariance ``(J^T J)^-1`` is then taken over the other
free parameters only, with the bound one held (zero variance): a linearized interval
is wrong at a bound (the likelihood is cut there), its interval is a profile
(:mod:`inverse.profile`), and prediction intervals hold it at the bound.
Bounds that do not enclose a non-empty interval, or an optimizer error, raise
:class:`InternalError` (a failure of the program, not of the input).
AICc (known noise): ``chi2 + 2k + 2k(k+1)/(n-k-1)`` with ``n`` the number of residuals,
``k`` the number of fitted parameters.

Convergence (``Fit.converged``): the Gauss-Newton decrement of :mod:`inverse.decrement`
at the returned optimum, ``g_F^T (J_F^T J_F)^+ g_F`` with ``g = J^T r`` from the
optimizer's last Jacobian (taken at the returned point) over the free parameters
``F`` (a parameter at its bound, in the sense of ``at_bound`` or of the optimizer's
active set, with the gradient pushing outward, is held), at most
:data:`~inverse.decrement.ACCEPT_TOL` = 1e-2 chi2 units (the parameters within 0.1
standard errors of the optimum; the fit aims at :data:`~inverse.decrement.DECREMENT_TOL`
= 1e-4, the margin of :mod:`inverse.decrement`), and no failed simulation there. It is
the criterion of every fit of the diagnosis, and it is statistical.
Why not scipy's own stop: its ``ftol``/``xtol`` tests are relative changes between
iterates; ``xtol`` (status 3) is met when the trust region has shrunk, also far from
an optimum (a finite-difference Jacobian across a failed simulation, a parameter a
hair inside its bound with the gradient pushing on), and ``success`` is True for it;
``max_nfev`` (status 0) may stop a fit that is at its optimum. The optimizer's
``status`` and ``success`` are kept and reported beside ``converged``. Its Jacobian
(forward differences, ``diff_step`` 1e-6 of the parameter steps) carries the
simulator's round-off (steady states to 1e-12, warm-started) into ``g`` at 1e-6 /
1e-12 amplification, which alone can lift the decrement over the tolerance at an
optimum; so a decrement over the tolerance is taken again with central differences of
:data:`inverse.decrement.CHECK_STEP` = 1e-3 step (``2k`` more simulations, only then; ``O(h^2)`` = 1e-6
truncation, round-off amplified 1e3 times less), and that one decides.

Noise: the :class:`NoiseModel` given to the problem, in the FE loop the totals of the one
judge's noise model (:func:`inverse.judge.noise_model`, via
:func:`feloop.select.fe_noise`): the identification's stds plus the test's
repeatability, the same noise as the one-mode diagnosis.
"""
from __future__ import annotations

import inspect
import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from inverse.decrement import (ACCEPT_TOL, DECREMENT_TOL, central_jacobian,
                               fit_decrement, flat_columns)

__all__ = ["SIMULATION_FAILURES", "InternalError", "Parameter", "NoiseModel", "UpdateProblem",
           "Fit", "fit"]

#: What a failed simulation raises (no steady state, a parameter set no model has, an
#: overflow): counted, never fatal.
SIMULATION_FAILURES = (RuntimeError, ValueError, ArithmeticError)
_FAILED = 1e4   # residual of a failed simulation, in noise units (counted, never reported)
#: A free parameter this close to a bound (in units of its step) is at the bound.
AT_BOUND_STEPS = 1e-4
class InternalError(RuntimeError):
    """A failure of the program (inconsistent bounds, an optimizer error), not of the
    input: the CLI reports it as an internal failure (exit status 1)."""


@dataclass(frozen=True)
class Parameter:
    """A fitted scalar: ``start`` value, bounds, a typical ``step`` (its scale in the
    optimizer and the profile grids), unit and one-line description."""

    name: str
    start: float
    lower: float = -math.inf
    upper: float = math.inf
    step: float = 1.0
    unit: str = ""
    description: str = ""


@dataclass
class NoiseModel:
    """Standard deviation of omega2 (rad^2/s^2) and zeta at every level, where it came
    from (``source``) and its degrees of freedom (None when given by the data)."""

    sigma_omega2: np.ndarray
    sigma_zeta: np.ndarray
    source: str
    dof: int | None = None

    def to_dict(self) -> dict:
        return {"sigma_omega2": self.sigma_omega2, "sigma_zeta": self.sigma_zeta,
                "source": self.source, "dof": self.dof}


@dataclass
class UpdateProblem:
    """Observed levels, their noise, which levels are fitted, the parameters, the
    simulator ``simulate(values: dict) -> (omega2 (L,), zeta (L,))`` and optionally
    ``describe(values) -> dict``, the figures to keep for a parameter set (e.g. its
    predictions; :mod:`inverse.profile` stores them with every profile point)."""

    simulate: object
    omega2: np.ndarray
    zeta: np.ndarray
    noise: NoiseModel
    fit_mask: np.ndarray
    parameters: dict
    fixed: dict = field(default_factory=dict)
    describe: object = None
    failures: int = 0

    def residuals(self, values: dict, mask=None) -> np.ndarray:
        """Eq. (1)'s residual vector on ``mask`` (default the fit levels); a failed
        simulation counts in ``failures`` and gives ``_FAILED`` per residual."""
        try:
            out = self.simulate(values)
        except SIMULATION_FAILURES as exc:
            out = exc
        return self.residuals_of(out, mask)

    def residuals_many(self, values: list, mask=None) -> list:
        """:meth:`residuals` of every parameter set of ``values``: simulated together
        by the simulator's ``batch`` where it has one (each set from its present warm
        start), else one after another."""
        batch = getattr(self.simulate, "batch", None)
        if batch is None:
            return [self.residuals(v, mask) for v in values]
        return [self.residuals_of(out, mask) for out in batch(values)[0]]

    def residuals_of(self, out, mask=None) -> np.ndarray:
        """:meth:`residuals` of a simulator's output ``out``: ``(omega2, zeta)``, or the
        exception of a failed simulation."""
        m = self.fit_mask if mask is None else np.asarray(mask, dtype=bool)
        if isinstance(out, BaseException):
            self.failures += 1
            return np.full(2 * int(m.sum()), _FAILED)
        om2, ze = out
        r = np.concatenate([(om2[m] - self.omega2[m]) / self.noise.sigma_omega2[m],
                            (ze[m] - self.zeta[m]) / self.noise.sigma_zeta[m]])
        if not np.all(np.isfinite(r)):
            self.failures += 1
        return np.where(np.isfinite(r), r, _FAILED)

    def figures(self, values: dict) -> dict | None:
        """``describe(values)`` (None without ``describe``); a failed simulation counts
        in ``failures`` and gives None, as in :meth:`residuals`."""
        if self.describe is None:
            return None
        try:
            return self.describe(values)
        except SIMULATION_FAILURES:
            self.failures += 1
            return None

    def chi2_by_channel(self, values: dict, mask=None) -> dict:
        """Eq. (1)'s chi2 per channel, ``{"omega2": .., "zeta": ..}``, on ``mask``
        (default the fit levels); ``{}`` when the simulation fails (counted in
        ``failures``)."""
        before = self.failures
        r = self.residuals(values, mask)
        if self.failures != before:
            return {}
        h = r.size // 2                       # the omega2 rows, then the zeta rows
        return {"omega2": float(r[:h] @ r[:h]), "zeta": float(r[h:] @ r[h:])}


@dataclass
class Fit:
    """A fitted parameter set: ``values`` (every parameter, fixed ones included),
    ``free`` names, ``chi2`` (eq. 1), ``n`` residuals, ``cov`` (covariance of the free
    parameters from the Jacobian, ``(J^T J)^-1``, or None), evaluations, seconds,
    ``success`` (the optimizer's, and no failed simulation at the optimum) with its
    ``status`` and ``message``, ``converged`` with its Gauss-Newton ``decrement``
    (chi2 units; module docstring), ``feasible``: no failed simulation at the optimum
    (a fit that is feasible but not converged stopped short of it), ``flat``: the free
    parameters with no effect where it stopped (:data:`inverse.decrement.FLAT_EFFECT`: not determined
    there, held out of the decrement)."""

    values: dict
    free: tuple
    chi2: float
    n: int
    cov: np.ndarray | None
    nfev: int
    seconds: float
    success: bool
    message: str = ""
    at_bound: dict = field(default_factory=dict)
    failed_simulations: int = 0
    converged: bool = False
    decrement: float = math.inf
    status: int | None = None
    feasible: bool = True
    flat: tuple = ()

    @property
    def k(self) -> int:
        return len(self.free)

    @property
    def dof(self) -> int:
        return self.n - self.k

    @property
    def aicc(self) -> float:
        k, n = self.k, self.n
        return self.chi2 + 2 * k + (2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else math.inf)

    @property
    def misfit_scale(self) -> float:
        """``max(1, chi2/dof)``: how much larger than the noise the misfit is."""
        return max(1.0, self.chi2 / self.dof) if self.dof > 0 else 1.0

    def std_error(self, name: str) -> float:
        """Linearized standard error of a free parameter, scaled by the misfit (nan at
        a bound: its interval is a profile, module docstring)."""
        if self.cov is None or name not in self.free or self.at_bound.get(name):
            return math.nan
        i = self.free.index(name)
        return math.sqrt(max(self.cov[i, i], 0.0) * self.misfit_scale)

    def to_dict(self) -> dict:
        return {"values": dict(self.values), "free": list(self.free), "chi2": self.chi2,
                "n_residuals": self.n, "dof": self.dof, "aicc": self.aicc,
                "misfit_scale": self.misfit_scale, "evaluations": self.nfev,
                "seconds": self.seconds, "success": self.success,
                "converged": self.converged, "decrement": self.decrement,
                "status": self.status, "flat": list(self.flat),
                "failed_simulations": self.failed_simulations,
                "at_bound": {f: self.at_bound.get(f, False) for f in self.free},
                "std_error": {f: self.std_error(f) for f in self.free}}


def _bound_side(x: float, p: Parameter) -> str | bool:
    """``"lower"``/``"upper"`` when ``x`` is at that bound of ``p``, else False."""
    tol = AT_BOUND_STEPS * p.step
    if math.isfinite(p.lower) and x - p.lower <= tol:
        return "lower"
    if math.isfinite(p.upper) and p.upper - x <= tol:
        return "upper"
    return False


def _covariance(J: np.ndarray, held: np.ndarray) -> np.ndarray | None:
    """``(J^T J)^-1`` over the columns not ``held``; held rows/columns zero."""
    k = J.shape[1]
    cov = np.zeros((k, k))
    keep = np.flatnonzero(~held)
    if keep.size:
        try:
            cov[np.ix_(keep, keep)] = np.linalg.inv(J[:, keep].T @ J[:, keep])
        except np.linalg.LinAlgError:
            return None
    return cov


#: scipy's least_squares evaluates its difference Jacobian through a map it is given.
_MAP = "workers" in inspect.signature(least_squares).parameters


def _columns(problem: UpdateProblem, funs) -> dict:
    """The map of the optimizer's difference Jacobian: all columns in one ``funs`` call
    (the simulator's batch) when the simulator has one and scipy takes a map."""
    if _MAP and getattr(problem.simulate, "batch", None) is not None:
        return {"workers": lambda _fun, points: funs(list(points))}
    return {}


def fit(problem: UpdateProblem, free, start: dict | None = None, fixed: dict | None = None,
        max_nfev: int = 200, mask=None, tol: float = 1e-8) -> Fit:
    """Minimize eq. (1) over the ``free`` parameters from ``start`` (default: each
    parameter's ``start``), the others held at ``fixed`` / ``problem.fixed`` / start;
    ``tol``: the optimizer's ``xtol``, ``ftol`` and ``gtol``; whether the fit converged
    is decided apart from them (module docstring, ``Fit.converged``).

    Returns
    -------
    Fit
    """
    t0 = time.perf_counter()
    free = tuple(free)
    pars = [problem.parameters[f] for f in free]
    values = {name: p.start for name, p in problem.parameters.items()}
    values.update(problem.fixed)
    if start:
        values.update(start)
    if fixed:
        values.update(fixed)
    for p in pars:
        if not (math.isfinite(p.step) and p.step > 0):
            raise InternalError(f"internal failure: parameter {p.name} has step {p.step!r} "
                                f"(must be a positive number)")
        if not p.lower < p.upper:
            raise InternalError(f"internal failure: parameter {p.name} has bounds "
                                f"[{p.lower:.6g}, {p.upper:.6g}] that enclose nothing")
    x0 = np.array([min(max(values[f], p.lower), p.upper) for f, p in zip(free, pars)])
    step = np.array([p.step for p in pars])
    lo = np.array([(p.lower - x) / s for p, x, s in zip(pars, x0, step)])
    hi = np.array([(p.upper - x) / s for p, x, s in zip(pars, x0, step)])
    u0 = np.zeros(len(free))

    def at(u):
        v = dict(values)
        v.update({f: float(x + s * ui) for f, x, s, ui in zip(free, x0, step, u)})
        return v

    def fun(u):
        return problem.residuals(at(u), mask)

    def funs(us):          # a list of points at once (the simulator's batch)
        return problem.residuals_many([at(u) for u in us], mask)

    failed0 = problem.failures
    if not free:
        r = fun(u0)
        ok = bool(np.all(np.abs(r) < _FAILED))
        return Fit(values=values, free=free, chi2=float(r @ r), n=r.size, cov=None, nfev=1,
                   seconds=time.perf_counter() - t0, success=ok,
                   failed_simulations=problem.failures - failed0, converged=ok,
                   decrement=0.0, feasible=ok)   # nothing free: the evaluation is all
    try:
        res = least_squares(fun, u0, bounds=(lo, hi), method="trf", diff_step=1e-6,
                            x_scale=1.0, max_nfev=max_nfev, xtol=tol, ftol=tol, gtol=tol,
                            **_columns(problem, funs))
    except ValueError as exc:
        raise InternalError(f"internal failure: the fit of {', '.join(free)} stopped: "
                            f"{exc}") from exc
    best = at(res.x)
    side = {f: _bound_side(best[f], p) for f, p in zip(free, pars)}
    J = res.jac / step[None, :]
    cov = _covariance(J, np.array([bool(side[f]) for f in free]))
    r = res.fun
    ok = bool(np.all(np.abs(r) < _FAILED))
    width, Jd = hi - lo, res.jac
    bounds = [side[f] for f in free]
    dec, nfev = fit_decrement(Jd, r, res.active_mask, bounds, width), int(res.nfev)
    if ok and dec > DECREMENT_TOL:          # the optimizer's Jacobian may carry round-off
        Jd, extra = central_jacobian(funs, res.x, r, lo, hi)
        dec, nfev = fit_decrement(Jd, r, res.active_mask, bounds, width), nfev + extra
    flat = tuple(f for f, b in zip(free, flat_columns(np.asarray(Jd, float), width)) if b)
    return Fit(values=best, free=free, chi2=float(r @ r), n=r.size, cov=cov,
               nfev=nfev, seconds=time.perf_counter() - t0,
               success=bool(res.success) and ok,
               message=str(res.message), at_bound=side,
               failed_simulations=problem.failures - failed0,
               converged=ok and dec <= ACCEPT_TOL, decrement=dec, status=int(res.status),
               feasible=ok, flat=flat)
