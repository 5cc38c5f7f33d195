"""Monte Carlo over identified joint parameters: distribution, samples, resumable store.

The estimator's least-squares fit of eq. 3 of :mod:`inverse.estimate` gives ``x^ = (p^,
ln Kt^)`` with ``p = chi + 1`` and ``Kt = p |kappa1| B`` (its own parametrization, in
which it linearizes), the covariance ``C = s^2 (J^T J)^-1`` and ``nu = n - 2`` residual
degrees of freedom. Under the linearized Gaussian regression ``x`` given the data is a
bivariate Student t with ``nu`` degrees of freedom, centre ``x^`` and scale ``C`` (the
pivot behind the estimator's t-intervals; the posterior under a flat prior)::

    x = x^ + L z sqrt(nu / w),   z ~ N(0, I_2),   w ~ chi^2_nu,   L L^T = C      (1)

(``distribution="normal"``: ``w = nu``, i.e. ``x ~ N(x^, C)``). For every linear
function ``g = a . x`` the draws are ``g(x^) + sqrt(a^T C a) T_nu``: their quantiles are
exactly the delta-method t-interval of :mod:`inverse.estimate`; for nonlinear predictions
they are not, which is the point of the sweep. Each sample is one task of
:func:`runs.executor.run_sweep` and draws with its own ``np.random.default_rng(seed)``
from :func:`runs.executor.task_seeds`, so the samples are bitwise the same on every
executor, and ``task_seeds(seed, n)[i]`` does not depend on ``n``: a run with more
samples extends a finished one.

An Iwan joint needs ``-1 < chi < 0`` (``0 < p < 1``); a draw outside is rejected and
redrawn from the task's generator, i.e. the distribution is truncated to the Iwan range
(its mass there, ``F_nu((1 - p^)/sigma_p) - F_nu(-p^/sigma_p)``, is reported as
``admissible_fraction``).

:class:`FitDistribution` is (1) for the free parameters of a model-updating fit
(:class:`inverse.update.Fit`, e.g. ``update``'s selected FE model), truncated to the
parameters' bounds instead.

What a sample computes is the caller's per-sample model (``SweepInputs.simulate``, e.g.
:func:`cases.double_beam.uncertainty.simulate_fe`); a sample that fails with one of
:data:`SAMPLE_FAILURES` is kept with its reason.

Finished samples go to a resumable store (:class:`inverse.sample_store.SampleStore`)
named by :func:`sweep_hash`, which covers the per-sample settings, seed, distribution,
measured data, FE model and the per-sample model's name (not the number of samples). A
rerun loads the finished samples and computes only the missing ones; the result is
bitwise that of an uninterrupted run.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
from scipy import stats

from inverse.sample_store import FORMAT, SampleResult, SampleStore, describe
from runs.executor import ExecutorSpec, run_sweep, task_seeds

__all__ = [
    "DISTRIBUTIONS",
    "SAMPLE_FAILURES",
    "ParameterDistribution",
    "FitDistribution",
    "SweepInputs",
    "sweep_hash",
    "run_samples",
]

DISTRIBUTIONS = ("t", "normal")
#: The failures a sample may end with (kept as its status, excluded from quantiles).
SAMPLE_FAILURES = (RuntimeError, ValueError, FloatingPointError, np.linalg.LinAlgError)


def _cholesky2(cov) -> np.ndarray:
    """Lower-triangular ``L`` with ``L L^T = cov`` for a symmetric positive semidefinite
    2x2 matrix (closed form, no LAPACK: the same bits on every machine and thread count;
    a zero variance gives a zero column)."""
    c = np.asarray(cov, dtype=float)
    l11 = math.sqrt(max(c[0, 0], 0.0))
    l21 = c[1, 0] / l11 if l11 > 0 else 0.0
    l22 = math.sqrt(max(c[1, 1] - l21 * l21, 0.0))
    return np.array([[l11, 0.0], [l21, l22]])


def truncated_draw(seed, mean, factor, dof, admissible, max_draws):
    """One draw of ``mean + s L z`` (``z`` standard normal, ``s = sqrt(dof / chi2_dof)``,
    1 for ``dof = inf``: a multivariate Student t) from ``np.random.default_rng(seed)``,
    redrawn until ``admissible(x)``: (x, number of draws), or None after ``max_draws``."""
    rng = np.random.default_rng(seed)
    for n in range(1, max_draws + 1):
        z = rng.standard_normal(len(mean))
        s = 1.0 if math.isinf(dof) else math.sqrt(dof / rng.chisquare(dof))
        x = mean + s * (factor @ z)
        if admissible(x):
            return x, n
    return None


@dataclass(frozen=True)
class ParameterDistribution:
    """Distribution (1) of ``x = (p, ln Kt)``, ``p = chi + 1``, ``Kt = p |kappa1| B``.

    Attributes
    ----------
    mean : (2,) ``(p^, ln Kt^)`` of the fit (``Kt`` in rad^2/s^2).
    cov : (2, 2) scale matrix ``C`` (the fit's linearized covariance).
    dof : float
        Student-t degrees of freedom ``nu``; ``math.inf`` for the normal distribution.
    p_bounds : (lo, hi)
        Admissible open range of ``p`` (Iwan: ``0 < chi + 1 < 1``); draws outside are
        rejected.
    max_draws : int
        Draws per sample before giving up (``ValueError``).
    """

    mean: np.ndarray
    cov: np.ndarray
    dof: float
    p_bounds: tuple = (0.0, 1.0)
    max_draws: int = 100000

    def __post_init__(self):
        m = np.asarray(self.mean, dtype=float).reshape(2)
        c = np.asarray(self.cov, dtype=float).reshape(2, 2)
        if not (np.all(np.isfinite(m)) and np.all(np.isfinite(c))):
            raise ValueError("parameter distribution: mean and covariance must be finite")
        if not np.allclose(c, c.T, rtol=1e-12, atol=0) or c[0, 0] < 0 or c[1, 1] < 0 \
                or np.linalg.det(c) < -1e-12 * max(c[0, 0] * c[1, 1], 1e-300):
            raise ValueError("parameter distribution: covariance must be symmetric positive "
                             "semidefinite")
        if not self.dof > 0:
            raise ValueError(f"parameter distribution: dof must be > 0, got {self.dof!r}")
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "cov", c)
        object.__setattr__(self, "dof", float(self.dof))

    @classmethod
    def from_fit(cls, fit, kind: str = "t", scale: float = 1.0) -> "ParameterDistribution":
        """From a :class:`inverse.estimate.PowerLawFit` (``p``, ``ln_kt``, ``cov``, ``dof``).

        ``kind`` ``"t"`` (Student, the fit's dof) or ``"normal"``; ``scale`` multiplies
        the standard deviations (``scale**2`` the covariance; 0 gives the nominal point).
        """
        if kind not in DISTRIBUTIONS:
            raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, "
                             f"got {kind!r}")
        if fit.cov is None or fit.dof < 1:
            raise ValueError("the fit has no residual degrees of freedom (2 points): no "
                             "covariance to sample from; fit more levels")
        return cls(mean=np.array([fit.p, fit.ln_kt]), cov=scale ** 2 * np.asarray(fit.cov),
                   dof=float(fit.dof) if kind == "t" else math.inf)

    @property
    def factor(self) -> np.ndarray:
        """``L`` of (1), lower triangular."""
        return _cholesky2(self.cov)

    def admissible_fraction(self) -> float:
        """Probability mass of the untruncated distribution with ``p`` in ``p_bounds``."""
        sd = math.sqrt(self.cov[0, 0])
        if sd == 0:
            return float(self.p_bounds[0] < self.mean[0] < self.p_bounds[1])
        d = stats.norm if math.isinf(self.dof) else stats.t(self.dof)
        lo, hi = ((b - self.mean[0]) / sd for b in self.p_bounds)
        return float(d.cdf(hi) - d.cdf(lo))

    def draw(self, seed) -> tuple[np.ndarray, int]:
        """One admissible draw of (1) from ``np.random.default_rng(seed)``.

        Returns
        -------
        (x (2,), n_draws)
            The draw and the number of draws it took (rejections + 1).
        """
        lo, hi = self.p_bounds
        got = truncated_draw(seed, np.asarray(self.mean, float), self.factor, self.dof,
                             lambda x: lo < x[0] < hi, self.max_draws)
        if got is not None:
            return got
        raise ValueError(f"no draw with {lo:g} < chi + 1 < {hi:g} in {self.max_draws} tries: "
                         f"the fit puts almost no mass in the Iwan range")

    def to_dict(self) -> dict:
        return {"coordinates": ["chi + 1", "ln(Kt) = ln((chi + 1) |kappa1| B)"],
                "mean": self.mean, "cov": self.cov,
                "dof": None if math.isinf(self.dof) else self.dof,
                "kind": "normal" if math.isinf(self.dof) else "t",
                "p_bounds": list(self.p_bounds),
                "admissible_fraction": self.admissible_fraction()}

    def arguments(self, x, nominal: bool) -> tuple:
        """The per-sample model's arguments after ``inputs``: ``(p, ln_kt)``, or
        ``(None, None)`` for the nominal sample."""
        return (None, None) if nominal else (float(x[0]), float(x[1]))

    def joint(self, x) -> tuple:
        """``(p, ln_kt)`` of a draw (kept with the sample)."""
        return float(x[0]), float(x[1])

    def hashed(self) -> tuple:
        """The arrays :func:`sweep_hash` covers."""
        return (self.mean, self.cov, np.array([self.dof]),
                np.array(self.p_bounds, dtype=float))


@dataclass(frozen=True)
class FitDistribution:
    """Eq. (1) for the free parameters of a model-updating fit (:class:`inverse.update.
    Fit`, e.g. ``update``'s selected FE model) that are not on a bound: ``x = x^ + L z
    sqrt(nu / w)``, ``L L^T = C`` the fit's covariance times its misfit scale
    (:attr:`inverse.update.Fit.misfit_scale`), ``nu`` its residual dof (``math.inf``:
    normal); the parameters on a bound and the fixed ones are held (``fixed``), as the
    fit's prediction intervals hold them. A draw outside a parameter's bounds (the
    domain the model is fitted in, e.g. ``-1 < chi < 0``, ``zeta_v > 0``) is rejected
    and redrawn: the distribution is truncated to that domain, and the fraction of
    draws kept estimates its mass there.

    Parameters are named (``names``); a sample is the full parameter dict
    (:meth:`values`), whose ``chi`` and ``ln_dc1`` give the ``(p, ln_kt)`` kept with it
    (NaN for a joint law without them, :mod:`feloop.joint_forms`).
    """

    names: tuple
    mean: np.ndarray
    cov: np.ndarray
    dof: float
    lower: np.ndarray
    upper: np.ndarray
    fixed: dict
    max_draws: int = 100000

    @classmethod
    def from_fit(cls, fit, parameters: dict, kind: str = "t") -> "FitDistribution":
        """From a :class:`inverse.update.Fit` and its problem's ``parameters``
        (:class:`inverse.update.Parameter`, for the bounds)."""
        if kind not in DISTRIBUTIONS:
            raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, "
                             f"got {kind!r}")
        names = tuple(n for n in fit.free if not fit.at_bound.get(n))
        if fit.cov is None or fit.dof < 1 or not names:
            raise ValueError("the fit has no covariance of a parameter inside its bounds "
                             "to sample from")
        idx = [fit.free.index(n) for n in names]
        cov = np.asarray(fit.cov)[np.ix_(idx, idx)] * fit.misfit_scale
        return cls(names, np.array([fit.values[n] for n in names]), cov,
                   float(fit.dof) if kind == "t" else math.inf,
                   np.array([parameters[n].lower for n in names], dtype=float),
                   np.array([parameters[n].upper for n in names], dtype=float),
                   {k: float(v) for k, v in fit.values.items() if k not in names})

    @property
    def factor(self) -> np.ndarray:
        """``L`` with ``L L^T = C`` (symmetric square root; a zero variance gives a
        zero column)."""
        w, v = np.linalg.eigh(np.asarray(self.cov, dtype=float))
        return v * np.sqrt(np.maximum(w, 0.0))

    def draw(self, seed) -> tuple[np.ndarray, int]:
        """One draw inside the bounds from ``np.random.default_rng(seed)``; (x, draws)."""
        got = truncated_draw(seed, self.mean, self.factor, self.dof,
                             lambda x: np.all((self.lower <= x) & (x <= self.upper)),
                             self.max_draws)
        if got is not None:
            return got
        raise ValueError(f"no draw inside the parameters' bounds in {self.max_draws} tries")

    def values(self, x) -> dict:
        """The full parameter dict of a draw ``x``."""
        return {**self.fixed, **{k: float(v) for k, v in zip(self.names, x)}}

    def arguments(self, x, nominal: bool) -> tuple:
        return (self.values(x),)

    def joint(self, x) -> tuple:
        """``(chi + 1, ln K)`` of an Iwan joint's draw; NaN for a law without chi."""
        v = self.values(x)
        if "chi" not in v:
            return math.nan, math.nan
        p = v["chi"] + 1.0
        return p, math.log(p) + v["ln_dc1"]

    def hashed(self) -> tuple:
        held = sorted(self.fixed)
        return (self.mean, self.cov, np.array([self.dof]), self.lower, self.upper,
                np.array(held + list(self.names)), np.array([self.fixed[k] for k in held]))

    def to_dict(self) -> dict:
        sd = np.sqrt(np.diag(self.cov))
        return {"parameters": list(self.names), "mean": self.mean, "cov": self.cov,
                "sd": sd, "dof": None if math.isinf(self.dof) else self.dof,
                "kind": "normal" if math.isinf(self.dof) else "t",
                "lower": self.lower, "upper": self.upper, "held": dict(self.fixed)}


@dataclass(frozen=True)
class SweepInputs:
    """What every task receives once (the ``shared`` object of :func:`run_sweep`).

    ``simulate(inputs, p, ln_kt) -> dict`` of named arrays/numbers is the per-sample
    model (module level, picklable by reference); ``p = ln_kt = None`` is the nominal.
    ``model`` (``M``, ``K``, ``slip_matrix``, ``joint_stiffness``, ``drive_dof``,
    ``response_dof``), ``data`` (:class:`ident.measured.MeasuredData`) and ``study`` (a
    dataclass of the per-sample settings with a ``data_path`` field) are what
    :func:`sweep_hash` hashes.
    """

    model: object
    data: object
    study: object
    distribution: ParameterDistribution
    simulate: Callable


def _sample_task(task, inputs: SweepInputs) -> SampleResult:
    """One sample as a task of :func:`run_sweep`: ``task = (index, seed)``, ``seed`` a
    ``SeedSequence`` or None (the nominal sample)."""
    index, seed = task
    t0 = time.perf_counter()
    dist = inputs.distribution
    x, n_draws = (dist.mean, 0) if seed is None else dist.draw(seed)
    args = dist.arguments(x, seed is None)
    p, ln_kt = dist.joint(x)
    try:
        with np.errstate(all="ignore"):
            values, status = inputs.simulate(inputs, *args), "ok"
    except SAMPLE_FAILURES as exc:
        values, status = {}, f"failed: {type(exc).__name__}: {str(exc).splitlines()[0]}"
    return SampleResult(int(index), float(p), float(ln_kt), int(n_draws), values, status,
                        time.perf_counter() - t0)


def sweep_hash(inputs: SweepInputs, seed: int) -> str:
    """SHA-256 over everything a sample depends on: per-sample settings, seed,
    distribution, measured data, FE model and the per-sample model's name (not the
    number of samples, see the module docstring)."""
    h = hashlib.sha256()

    def add(a):
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype}{a.shape}".encode())
        h.update(a.tobytes())

    m = inputs.model
    for mat in (m.M, m.K, m.slip_matrix):
        c = sp.csr_matrix(mat)
        c.sort_indices()
        for a in (c.data, c.indices, c.indptr, np.array(c.shape)):
            add(a)
    add(np.asarray(m.joint_stiffness, dtype=float))
    add(np.array([int(m.drive_dof), int(m.response_dof)]))
    d = inputs.data
    for a in (d.level, d.excitation, d.omega2, d.zeta):
        add(np.asarray(a, dtype=float))
    for a in inputs.distribution.hashed():
        add(a)
    study = dataclasses.replace(inputs.study, data_path=None)   # the data are hashed above
    sim = f"{inputs.simulate.__module__}.{inputs.simulate.__qualname__}"
    h.update(json.dumps({"study": describe(study), "seed": int(seed), "simulate": sim},
                        sort_keys=True).encode())
    h.update(FORMAT.encode())
    return h.hexdigest()


def run_samples(inputs: SweepInputs, n_samples: int, seed: int, store: SampleStore | None = None,
                executor: str | ExecutorSpec = "serial", progress: bool = True,
                on_sample: Callable[[SampleResult], None] | None = None
                ) -> tuple[SampleResult, list[SampleResult]]:
    """The nominal sample and samples ``0 .. n_samples-1``, each a task of
    :func:`runs.executor.run_sweep` (seeds :func:`runs.executor.task_seeds`).

    Finished samples in ``store`` are loaded, the others computed and saved as each one
    finishes (``on_sample(result)`` is called after the save; an exception raised there
    interrupts the sweep with every finished sample stored).

    Returns
    -------
    (nominal, samples in index order)
    """
    indices = [-1] + list(range(int(n_samples)))
    done = store.load(indices) if store is not None else {}
    seeds = task_seeds(seed, n_samples)
    tasks = [(i, None if i < 0 else seeds[i]) for i in indices if i not in done]

    def finish(k: int, res: SampleResult) -> None:
        done[tasks[k][0]] = res
        if store is not None:
            store.save(res)
        if on_sample is not None:
            on_sample(res)

    run_sweep(_sample_task, tasks, executor=executor, shared=inputs, progress=progress,
              desc="monte carlo", unit="sample", chunksize=1, on_result=finish)
    return done[-1], [done[i] for i in range(int(n_samples))]
