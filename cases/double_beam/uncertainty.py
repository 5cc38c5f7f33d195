"""Monte Carlo over the identified joint parameters: how uncertain are the predictions?

``iwanfe estimate`` fits chi and ``|kappa1| B`` to the damping growth between levels
(paper eq. 33-35, :mod:`inverse.estimate`) and gives linearized (delta-method) Student-t
intervals. This module propagates the same fit uncertainty through the *nonlinear FE
model* instead of the closed form (eq. 43, 46): every sample is a joint of the double
beam (:mod:`cases.double_beam.study`) driven through the stepped-sine levels, and
the spread of the simulated natural frequency and damping ratio per level is reported
beside the estimator's closed-form interval and the measurement.

Sampling (one task of :func:`runs.executor.run_sweep` per sample)
---------------------------------------------------------------
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
they are not, which is the point of the sweep. Each task draws with its own
``np.random.default_rng(seed)`` from :func:`runs.executor.task_seeds`, so the samples are
bitwise the same on every executor, and ``task_seeds(seed, n)[i]`` does not depend on
``n``: a run with more samples extends a finished one.

An Iwan joint needs ``-1 < chi < 0`` (``0 < p < 1``); a draw outside is rejected and
redrawn from the task's generator, i.e. the distribution is truncated to the Iwan range
(its mass there, ``F_nu((1 - p^)/sigma_p) - F_nu(-p^/sigma_p)``, is reported as
``admissible_fraction``). With the shipped data (levels 1-7, 3 dof) about a fifth of the
t mass lies outside.

Joint of a sample (paper eq. 36, 37): ``chi = p - 1``, ``|kappa1| B = Kt / p`` at level 1
and ``R~ = |kappa1| B / ((|kappa1|/R) B~(chi))`` with the estimator's ``B~`` (FE mode,
linear-inverse slips at level 1); then exactly :func:`~cases.double_beam.study.
joint_setup` with these ``chi, R`` overrides (the viscous damping is re-chosen so that
level 1 has the measured damping ratio, eq. 2 of :mod:`inverse.estimate`). The *nominal*
sample is the study without overrides, i.e. :func:`~cases.double_beam.study.
run_study` at the same settings.

Per sample: :func:`~cases.double_beam.study.nonlinear_model`, the HB stepped-sine
campaign (:func:`runs.stepped_sine.run_campaign`, serial inside the task) and the per-level
modal data (:func:`~cases.double_beam.study.identify_campaign`). The reported
frequency ``Omega/(2 pi)`` (Hz) and damping ratio are the **modal filter**'s
(``D = phi_d / (phi^T M x)`` at the root of ``Re D``; identification-free and exact for
the linear structure): on smooth simulated FRFs of some samples the LSCF identification
with the study's options picks a wrong pole (zeta 2.6-4 times the modal filter's, e.g.
chi = -0.845, level 8). The LSCF values are stored per sample and the samples where they
disagree with the modal filter by more than :data:`LSCF_DISAGREEMENT` are counted.

Per-sample settings (:data:`SAMPLE_STUDY`): 8 Jenkins sliders per octave and 128 AFT
samples per period instead of 16 and 256, everything else as ``reproduce double-beam``
(0.5 Hz lines over 236-268 Hz, 10 levels, 40 modes, 7 odd harmonics). Measured on the
nominal joint and on chi = -0.845, -0.59, -0.068 (from no glue slip to macro-slip at
level 8): modal-filter frequency within 5e-6 and damping ratio within 3e-4 relative of
the default settings, at about 40 % of the cost (tests/test_uncertainty.py checks the
nominal). The 0.5 Hz lines are kept on purpose: with 1 Hz lines the harmonic-balance
continuation failed at the top level of strongly softening samples. A sample whose
simulation fails (no harmonic-balance convergence, even after the retries of
:func:`simulate_fe` with lower first lines) is kept with its reason and excluded from
the quantiles (the report gives the count).

Store: one ``sample_XXXXX.npz`` (and ``nominal.npz``) per finished sample, written as it
finishes, in ``samples-<hash12>/`` under the output directory, with a manifest; the hash
(SHA-256) covers the per-sample settings, seed, distribution, measured data and FE model
(not the number of samples). A rerun loads the finished samples and computes only the
missing ones; the result is bitwise that of an uninterrupted run.

SI units: Hz, rad^2/s^2, N, m; damping ratios as fractions.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp
from scipy import stats

from cases.double_beam.study import (
    DoubleBeamStudy,
    identify_campaign,
    joint_setup,
    level_campaign,
    measured_levels,
    mode_weights,
    nonlinear_model,
    source_estimate,
)
from inverse.iwan_modal import r_tilde
from runs.executor import ExecutorSpec, run_sweep, task_seeds
from runs.store import open_manifest
from fe.harmonic_balance import HBSettings

__all__ = [
    "DISTRIBUTIONS",
    "SAMPLE_STUDY",
    "DEFAULT_SAMPLES",
    "DEFAULT_SEED",
    "DEFAULT_CONFIDENCE",
    "ParameterDistribution",
    "UncertaintySettings",
    "SweepInputs",
    "SampleResult",
    "SampleStore",
    "UncertaintyReport",
    "simulate_fe",
    "sweep_hash",
    "run_samples",
    "run_uncertainty",
]

FORMAT = "iwanfe-uncertainty/1"
DISTRIBUTIONS = ("t", "normal")
#: Per-sample simulation: coarser Jenkins banks and AFT grid than ``reproduce`` (module
#: docstring), no weak-joint reruns.
SAMPLE_STUDY = DoubleBeamStudy(sliders_per_octave=8, hb=HBSettings(n_time=128),
                               weak_joint_scales=())
DEFAULT_SAMPLES = 80
DEFAULT_SEED = 1
#: Central interval of the Monte Carlo and level of the delta-method t-interval (5-95 %).
DEFAULT_CONFIDENCE = 0.90
#: Relative zeta difference LSCF vs modal filter above which a sample is counted.
LSCF_DISAGREEMENT = 0.1
#: Downward extensions (Hz) of the first line for the retries of a failed campaign.
RETRY_EXTENSIONS_HZ = (10.0, 20.0)
#: The failures a sample may end with (kept as its status, excluded from quantiles).
SAMPLE_FAILURES = (RuntimeError, ValueError, FloatingPointError, np.linalg.LinAlgError)


# =========================================================================== sampling


def _cholesky2(cov) -> np.ndarray:
    """Lower-triangular ``L`` with ``L L^T = cov`` for a symmetric positive semidefinite
    2x2 matrix (closed form, no LAPACK: the same bits on every machine and thread count;
    a zero variance gives a zero column)."""
    c = np.asarray(cov, dtype=float)
    l11 = math.sqrt(max(c[0, 0], 0.0))
    l21 = c[1, 0] / l11 if l11 > 0 else 0.0
    l22 = math.sqrt(max(c[1, 1] - l21 * l21, 0.0))
    return np.array([[l11, 0.0], [l21, l22]])


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
        rng = np.random.default_rng(seed)
        L = self.factor
        lo, hi = self.p_bounds
        for n in range(1, self.max_draws + 1):
            z = rng.standard_normal(2)
            s = 1.0 if math.isinf(self.dof) else math.sqrt(self.dof / rng.chisquare(self.dof))
            x = np.array([self.mean[0] + s * (L[0, 0] * z[0]),
                          self.mean[1] + s * (L[1, 0] * z[0] + L[1, 1] * z[1])])
            if lo < x[0] < hi:
                return x, n
        raise ValueError(f"no draw with {lo:g} < chi + 1 < {hi:g} in {self.max_draws} tries: "
                         f"the fit puts almost no mass in the Iwan range")

    def to_dict(self) -> dict:
        return {"coordinates": ["chi + 1", "ln(Kt) = ln((chi + 1) |kappa1| B)"],
                "mean": self.mean, "cov": self.cov,
                "dof": None if math.isinf(self.dof) else self.dof,
                "kind": "normal" if math.isinf(self.dof) else "t",
                "p_bounds": list(self.p_bounds),
                "admissible_fraction": self.admissible_fraction()}


# =========================================================================== settings


@dataclass(frozen=True)
class UncertaintySettings:
    """Settings of the Monte Carlo sweep.

    Parameters
    ----------
    study : DoubleBeamStudy
        Data, fit levels, force scale and the per-sample simulation (default
        :data:`SAMPLE_STUDY`); its ``chi``/``R`` overrides must be unset.
    n_samples : int
        Samples (each one nonlinear simulation) besides the nominal one.
    seed : int
        Root seed of :func:`runs.executor.task_seeds`.
    confidence : float
        Central interval of the samples (quantiles ``(1 -+ confidence)/2``) and level
        of the estimator's delta-method t-interval.
    distribution : {"t", "normal"}
        (1) with the fit's degrees of freedom, or normal with the same covariance.
    """

    study: DoubleBeamStudy = field(default_factory=lambda: SAMPLE_STUDY)
    n_samples: int = DEFAULT_SAMPLES
    seed: int = DEFAULT_SEED
    confidence: float = DEFAULT_CONFIDENCE
    distribution: str = "t"

    def __post_init__(self):
        if isinstance(self.n_samples, bool) or int(self.n_samples) != self.n_samples \
                or self.n_samples < 1:
            raise ValueError(f"samples must be an integer >= 1, got {self.n_samples!r}")
        if isinstance(self.seed, bool) or int(self.seed) != self.seed or self.seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")
        if not 0 < self.confidence < 1:
            raise ValueError(f"confidence must lie in (0, 1), got {self.confidence!r}")
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got "
                             f"{self.distribution!r}")
        if self.study.chi is not None or self.study.R is not None:
            raise ValueError("the sampled study must not override chi or R")

    @property
    def quantiles(self) -> tuple[float, float]:
        a = 0.5 * (1.0 - self.confidence)
        return a, 1.0 - a


@dataclass(frozen=True)
class SweepInputs:
    """What every task receives once (the ``shared`` object of :func:`run_sweep`).

    ``simulate(inputs, p, ln_kt) -> dict`` of named arrays/numbers is the per-sample
    model (module level, picklable by reference); ``p = ln_kt = None`` is the nominal.
    """

    model: object
    data: object
    study: DoubleBeamStudy
    distribution: ParameterDistribution
    simulate: Callable


def simulate_fe(inputs: SweepInputs, p=None, ln_kt=None) -> dict:
    """The nonlinear FE prediction of one joint sample (module docstring).

    Parameters
    ----------
    inputs : SweepInputs
    p, ln_kt : float or None
        ``chi + 1`` and ``ln((chi+1) |kappa1| B)``; None: the study's own estimate.

    Returns
    -------
    dict
        ``frequency_hz``, ``zeta`` (modal filter), ``lscf_frequency_hz``, ``lscf_zeta``,
        ``slip_over_phi_max`` (largest joint slip at resonance / phi_max), all
        (n_levels,); ``chi``, ``R`` (N m^-(chi+2)), ``phi_max`` (m), ``zeta_viscous``,
        ``first_line_hz`` (Hz).

    Notes
    -----
    When the harmonic-balance campaign fails (Newton from the linear guess at the first
    line of a level deep in macro-slip), it is rerun with the lines started
    :data:`RETRY_EXTENSIONS_HZ` lower (same spacing and top line; the identification
    band follows), where the linear guess is closer; ``first_line_hz`` records the
    start. On the failing sample of the shipped data (chi = -0.75, level 10 failing at
    236 Hz) the retry converged and levels 1-9 moved by < 2e-13 relative (frequency
    and damping ratio).
    """
    from runs.stepped_sine import run_campaign

    model, data, study = inputs.model, inputs.data, inputs.study
    src = source_estimate(model, data, study)
    if p is not None:
        chi = p - 1.0
        R = r_tilde(math.exp(ln_kt) / p, chi, src.case.B_of_chi(chi))   # eq. 36, 37
        study = dataclasses.replace(study, chi=chi, R=R)
    setup = joint_setup(model, data, study, source=src)
    red, bank = nonlinear_model(model, setup, study)
    lo, hi = study.band_hz
    starts = [0.0] + [e for e in RETRY_EXTENSIONS_HZ if lo - e > 0]
    for k, extension in enumerate(starts):
        if extension:
            study = dataclasses.replace(study, band_hz=(lo - extension, hi))
        try:
            res = run_campaign(red, bank, level_campaign(model, setup, study), progress=False,
                               executor="serial")
            break
        except RuntimeError:
            if k == len(starts) - 1:
                raise
    phi, weights = mode_weights(model, setup)
    ident, mf = identify_campaign(model, setup, study, res, phi, weights)
    return {"frequency_hz": mf.frequency_hz, "zeta": mf.zeta,
            "lscf_frequency_hz": ident.frequency_hz, "lscf_zeta": ident.zeta,
            "slip_over_phi_max": np.nanmax(mf.slip, axis=1) / setup.phi_max,
            "chi": setup.chi, "R": setup.R, "phi_max": setup.phi_max,
            "zeta_viscous": setup.zeta_viscous, "first_line_hz": study.band_hz[0]}


# =========================================================================== samples


@dataclass
class SampleResult:
    """One sample: ``index`` (-1: nominal), the drawn ``p``, ``ln_kt`` and ``n_draws``,
    the per-sample model's ``values`` (float arrays), ``status`` ("ok" or "failed: ..."),
    ``elapsed`` (s, not part of the result's bits) and ``loaded`` (from the store)."""

    index: int
    p: float
    ln_kt: float
    n_draws: int
    values: dict
    status: str
    elapsed: float = 0.0
    loaded: bool = False

    def __post_init__(self):
        self.values = {k: np.asarray(v, dtype=float) for k, v in self.values.items()}

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def chi(self) -> float:
        return self.p - 1.0

    @property
    def kappa1_B(self) -> float:
        """``|kappa1| B`` at level 1 (rad^2/s^2)."""
        return math.exp(self.ln_kt) / self.p

    def same_bits(self, other: "SampleResult") -> bool:
        """Bitwise equality of everything computed (not ``elapsed``/``loaded``)."""
        def bits(x):
            return np.asarray(x, dtype=float).tobytes()
        return (self.index == other.index and bits(self.p) == bits(other.p)
                and bits(self.ln_kt) == bits(other.ln_kt) and self.n_draws == other.n_draws
                and self.status == other.status and self.values.keys() == other.values.keys()
                and all(bits(v) == bits(other.values[k]) for k, v in self.values.items()))

    def to_npz(self, path: Path) -> None:
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, index=self.index, p=self.p, ln_kt=self.ln_kt, n_draws=self.n_draws,
                 status=self.status, elapsed=self.elapsed,
                 **{f"value_{k}": v for k, v in self.values.items()})
        os.replace(tmp, path)

    @classmethod
    def from_npz(cls, path: Path) -> "SampleResult":
        with np.load(path) as d:
            values = {k[6:]: d[k] for k in d.files if k.startswith("value_")}
            return cls(int(d["index"]), float(d["p"]), float(d["ln_kt"]), int(d["n_draws"]),
                       values, str(d["status"]), float(d["elapsed"]), loaded=True)


def _sample_task(task, inputs: SweepInputs) -> SampleResult:
    """One sample as a task of :func:`run_sweep`: ``task = (index, seed)``, ``seed`` a
    ``SeedSequence`` or None (the nominal sample)."""
    index, seed = task
    t0 = time.perf_counter()
    if seed is None:
        (p, ln_kt), n_draws = inputs.distribution.mean, 0
        args = (None, None)
    else:
        (p, ln_kt), n_draws = inputs.distribution.draw(seed)
        args = (float(p), float(ln_kt))
    try:
        with np.errstate(all="ignore"):
            values, status = inputs.simulate(inputs, *args), "ok"
    except SAMPLE_FAILURES as exc:
        values, status = {}, f"failed: {type(exc).__name__}: {str(exc).splitlines()[0]}"
    return SampleResult(int(index), float(p), float(ln_kt), int(n_draws), values, status,
                        time.perf_counter() - t0)


def _describe(obj):
    if dataclasses.is_dataclass(obj):
        return {"type": type(obj).__name__,
                **{f.name: _describe(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if isinstance(obj, (tuple, list)):
        return [_describe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


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
    dist = inputs.distribution
    for a in (dist.mean, dist.cov, np.array([dist.dof]), np.array(dist.p_bounds, dtype=float)):
        add(a)
    study = dataclasses.replace(inputs.study, data_path=None)   # the data are hashed above
    sim = f"{inputs.simulate.__module__}.{inputs.simulate.__qualname__}"
    h.update(json.dumps({"study": _describe(study), "seed": int(seed), "simulate": sim},
                        sort_keys=True).encode())
    h.update(FORMAT.encode())
    return h.hexdigest()


class SampleStore:
    """Directory of finished samples (``nominal.npz``, ``sample_XXXXX.npz``) and a
    ``manifest.json`` naming the sweep's hash; another sweep's directory raises
    ``ValueError``."""

    def __init__(self, directory, digest: str, description: dict | None = None):
        self.path = Path(directory)
        open_manifest(self.path, digest, {"format": FORMAT, **(description or {})},
                      "Monte Carlo sweep")

    def file(self, index: int) -> Path:
        return self.path / ("nominal.npz" if index < 0 else f"sample_{index:05d}.npz")

    def load(self, indices) -> dict[int, SampleResult]:
        """The stored samples among ``indices`` (unreadable files are recomputed)."""
        out = {}
        for i in indices:
            f = self.file(i)
            if f.exists():
                try:
                    out[i] = SampleResult.from_npz(f)
                except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
                    continue
        return out

    def save(self, result: SampleResult) -> None:
        result.to_npz(self.file(result.index))


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


# =========================================================================== report


@dataclass
class UncertaintyReport:
    """Monte Carlo result and everything it is compared with (SI units, zeta fractions).

    ``source`` is the estimator's result (``exact`` method) at ``settings.confidence``:
    its ``predictions`` hold the closed-form (eq. 43, 46) values and delta-method
    intervals. ``nominal`` and ``samples`` are :class:`SampleResult`.
    """

    settings: UncertaintySettings
    source: object
    distribution: ParameterDistribution
    measured: object
    nominal: SampleResult
    samples: list
    digest: str
    store: str | None
    timings: dict

    # ------------------------------------------------------------------ arrays
    @property
    def level(self) -> np.ndarray:
        return np.asarray(self.measured.level, dtype=int)

    @property
    def held_out(self) -> np.ndarray:
        return ~np.isin(self.level, self.settings.study.fit)

    def values(self, name: str) -> np.ndarray:
        """(n_samples, n_levels) of a per-sample quantity; NaN rows for failed samples."""
        L = self.level.size
        return np.array([s.values[name] if s.ok and name in s.values else np.full(L, np.nan)
                         for s in self.samples])

    def band(self, name: str) -> dict:
        """Per level: ``median``, ``lo``, ``hi`` (the central ``confidence`` interval) and
        ``n`` (samples with a finite value)."""
        v = self.values(name)
        n = np.isfinite(v).sum(axis=0)
        lo, hi = self.settings.quantiles
        q = np.full((3, v.shape[1]), np.nan)
        has = n > 0
        if has.any():
            q[:, has] = np.nanquantile(v[:, has], [lo, 0.5, hi], axis=0)
        return {"lo": q[0], "median": q[1], "hi": q[2], "n": n}

    def closed_form(self) -> dict:
        """The estimator's closed-form prediction and delta-method interval per level:
        ``frequency_hz`` (from omega^2), ``zeta`` and their ``*_lo``/``*_hi``."""
        pr = self.source.predictions

        def hz(om2):
            return np.sqrt(np.maximum(np.asarray(om2, dtype=float), 0.0)) / (2 * math.pi)

        return {"frequency_hz": hz([p["omega2"] for p in pr]),
                "frequency_hz_lo": hz([p["omega2_interval"][0] for p in pr]),
                "frequency_hz_hi": hz([p["omega2_interval"][1] for p in pr]),
                "zeta": np.array([p["zeta"] for p in pr]),
                "zeta_lo": np.array([p["zeta_interval"][0] for p in pr]),
                "zeta_hi": np.array([p["zeta_interval"][1] for p in pr])}

    @property
    def n_failed(self) -> int:
        return sum(not s.ok for s in self.samples)

    @property
    def n_retried(self) -> int:
        """Samples whose campaign needed lines below the study's band (see
        :func:`simulate_fe`)."""
        lo = self.settings.study.band_hz[0]
        return sum(bool(s.ok and "first_line_hz" in s.values and s.values["first_line_hz"] < lo)
                   for s in self.samples)

    @property
    def acceptance(self) -> float:
        """Samples over draws (the truncation's measured acceptance rate)."""
        draws = sum(s.n_draws for s in self.samples)
        return len(self.samples) / draws if draws else math.nan

    def macro_slip_fraction(self) -> np.ndarray:
        """Per level, the share of finished samples whose largest slip reaches phi_max."""
        s = self.values("slip_over_phi_max")
        ok = np.isfinite(s)
        return np.where(ok.sum(0) > 0, (s >= 1.0).sum(0) / np.maximum(ok.sum(0), 1), np.nan)

    def lscf_disagreements(self) -> int:
        """Samples where LSCF and the modal filter differ in zeta by more than
        :data:`LSCF_DISAGREEMENT` (relative) at some level, or LSCF found no mode."""
        a, b = self.values("lscf_zeta"), self.values("zeta")
        ok = np.array([s.ok for s in self.samples])
        with np.errstate(invalid="ignore", divide="ignore"):
            bad = ~(np.abs(a / b - 1.0) <= LSCF_DISAGREEMENT)
        return int((bad.any(axis=1) & ok).sum())

    def per_level(self) -> list[dict]:
        """One record per level: measured, nominal FE, Monte Carlo band, closed form."""
        m = self.measured
        f_meas = np.sqrt(np.asarray(m.omega2, dtype=float)) / (2 * math.pi)
        bf, bz = self.band("frequency_hz"), self.band("zeta")
        cf = self.closed_form()
        nom = self.nominal.values if self.nominal.ok else {}
        L = self.level.size
        nf = nom.get("frequency_hz", np.full(L, np.nan))
        nz = nom.get("zeta", np.full(L, np.nan))
        macro = self.macro_slip_fraction()
        rows = []
        for i in range(L):
            rows.append({
                "level": int(self.level[i]), "excitation": float(m.excitation[i]),
                "held_out": bool(self.held_out[i]),
                "measured_frequency_hz": float(f_meas[i]), "measured_zeta": float(m.zeta[i]),
                "nominal_frequency_hz": float(nf[i]), "nominal_zeta": float(nz[i]),
                "mc_frequency_hz": {"median": float(bf["median"][i]), "lo": float(bf["lo"][i]),
                                    "hi": float(bf["hi"][i])},
                "mc_zeta": {"median": float(bz["median"][i]), "lo": float(bz["lo"][i]),
                            "hi": float(bz["hi"][i])},
                "mc_n": int(bf["n"][i]), "mc_macro_slip_fraction": float(macro[i]),
                "closed_form_frequency_hz": float(cf["frequency_hz"][i]),
                "closed_form_frequency_hz_interval": [float(cf["frequency_hz_lo"][i]),
                                                      float(cf["frequency_hz_hi"][i])],
                "closed_form_zeta": float(cf["zeta"][i]),
                "closed_form_zeta_interval": [float(cf["zeta_lo"][i]), float(cf["zeta_hi"][i])],
            })
        return rows

    def failures(self) -> list[dict]:
        return [{"index": s.index, "chi": s.chi, "kappa1_B": s.kappa1_B, "status": s.status}
                for s in self.samples if not s.ok]

    def to_dict(self) -> dict:
        """Plain JSON form (``iwanfe uncertainty --json`` and ``uncertainty.json``)."""
        st, src = self.settings, self.source
        lo, hi = st.quantiles
        return {
            "case": "double-beam", "fit_levels": st.study.fit, "method": src.method,
            "n_samples": st.n_samples, "seed": st.seed, "confidence": st.confidence,
            "quantiles": [lo, hi],
            "estimate": {"chi": src.chi, "chi_interval": list(src.chi_interval),
                         "kappa1_B": src.kappa1_B, "kappa1_B_interval": list(src.kappa1_B_interval),
                         "R": src.R, "R_interval": list(src.R_interval or ()), "dof": src.dof,
                         "cov_chi1_ln_kappa1_B": src.fit.cov_kappa1_B},
            "distribution": {**self.distribution.to_dict(), "acceptance": self.acceptance},
            "per_sample_settings": {"study": _describe(st.study),
                                    "identification": "modal filter (LSCF kept per sample)"},
            "levels": self.per_level(),
            "nominal": {"status": self.nominal.status, **self.nominal.values},
            "samples": {"chi": [s.chi for s in self.samples],
                        "kappa1_B": [s.kappa1_B for s in self.samples],
                        "n_draws": [s.n_draws for s in self.samples],
                        "status": [s.status for s in self.samples],
                        "frequency_hz": self.values("frequency_hz"),
                        "zeta": self.values("zeta"),
                        "R": [float(s.values["R"]) if s.ok and "R" in s.values else None
                              for s in self.samples]},
            "n_failed": self.n_failed, "failures": self.failures(),
            "n_retried_lower_start": self.n_retried,
            "lscf_disagreements": self.lscf_disagreements(),
            "hash": self.digest, "store": self.store, "timings_s": self.timings,
        }


def run_uncertainty(settings: UncertaintySettings = UncertaintySettings(), out=None,
                    executor: str | ExecutorSpec = "serial", progress: bool = True, model=None,
                    simulate: Callable = simulate_fe,
                    on_sample: Callable[[SampleResult], None] | None = None
                    ) -> UncertaintyReport:
    """Run (or resume) the Monte Carlo sweep (module docstring).

    Parameters
    ----------
    settings : UncertaintySettings
    out : path, optional
        Parent of the sample store ``samples-<hash12>/``; None: nothing stored.
    executor : {"serial", "processes", "dask"} or runs.executor.ExecutorSpec
        Where the samples run (bitwise the same results).
    progress : bool
        Progress bar on stderr.
    model : cases.double_beam.model.DoubleBeamModel, optional
        Default :func:`cases.double_beam.model.build_double_beam`.
    simulate : callable
        Per-sample model (:class:`SweepInputs`); default :func:`simulate_fe`.
    on_sample : callable, optional
        ``on_sample(result)`` after each newly computed sample is stored.

    Returns
    -------
    UncertaintyReport
    """
    from cases.double_beam.model import build_double_beam

    t0 = time.perf_counter()
    st = settings.study
    model = build_double_beam() if model is None else model
    data = measured_levels(st)
    src = source_estimate(model, data, st, confidence=settings.confidence)
    dist = ParameterDistribution.from_fit(src.fit, settings.distribution)
    inputs = SweepInputs(model=model, data=data, study=st, distribution=dist, simulate=simulate)
    digest = sweep_hash(inputs, settings.seed)
    store = None
    if out is not None:
        store = SampleStore(Path(out) / f"samples-{digest[:12]}", digest,
                            {"seed": settings.seed, "distribution": settings.distribution,
                             "study": _describe(st)})
    t1 = time.perf_counter()
    nominal, samples = run_samples(inputs, settings.n_samples, settings.seed, store, executor,
                                   progress, on_sample)
    t2 = time.perf_counter()
    fresh = [s.elapsed for s in [nominal] + samples if not s.loaded]
    every = [s.elapsed for s in samples]
    timings = {"setup": t1 - t0, "sweep": t2 - t1,
               "executor": (executor.describe() if isinstance(executor, ExecutorSpec)
                            else str(executor)),
               "computed": len(fresh), "loaded": len(samples) + 1 - len(fresh),
               "per_sample_median": float(np.median(every)),
               "per_sample_mean": float(np.mean(every))}
    return UncertaintyReport(settings=settings, source=src, distribution=dist, measured=data,
                             nominal=nominal, samples=samples, digest=digest,
                             store=None if store is None else str(store.path), timings=timings)
