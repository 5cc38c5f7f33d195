"""The double-beam Monte Carlo sweep run and reported (``iwanfe uncertainty``).

:func:`run_uncertainty` draws the joints (:mod:`inverse.uncertainty`), runs
:func:`cases.double_beam.uncertainty.simulate_fe` per sample (resumable store
``samples-<hash12>/``) and returns an :class:`UncertaintyReport`: per level the
measurement, the nominal FE prediction, the Monte Carlo band and the estimator's
closed-form prediction with its delta-method interval.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from cases.double_beam.model import build_double_beam
from cases.double_beam.joint_setup import source_estimate
from cases.double_beam.settings import measured_levels
from cases.double_beam.uncertainty import UncertaintySettings, simulate_fe
from inverse.sample_store import SampleResult, SampleStore, describe
from inverse.uncertainty import ParameterDistribution, SweepInputs, run_samples, sweep_hash
from runs.executor import ExecutorSpec

__all__ = ["LSCF_DISAGREEMENT", "UncertaintyReport", "run_uncertainty"]

#: Relative zeta difference LSCF vs modal filter above which a sample is counted.
LSCF_DISAGREEMENT = 0.1


@dataclass
class UncertaintyReport:
    """Monte Carlo result and everything it is compared with (SI units, zeta fractions).

    ``source`` is the estimator's result (``exact`` method) at ``settings.confidence``:
    its ``predictions`` hold the closed-form (eq. 43, 46) values and delta-method
    intervals. ``nominal`` and ``samples`` are :class:`inverse.sample_store.SampleResult`.
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
        :func:`cases.double_beam.uncertainty.simulate_fe`)."""
        lo = self.settings.study.band_hz[0]
        return sum(bool(s.ok and "first_line_hz" in s.values and s.values["first_line_hz"] < lo)
                   for s in self.samples)

    @property
    def n_fallback(self) -> int:
        """Samples with a level whose steady states needed a fallback (``fallback_levels``
        of :func:`cases.double_beam.uncertainty.simulate_fe`)."""
        return sum(bool(s.ok and s.values.get("fallback_levels", 0) > 0) for s in self.samples)

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
            "per_sample_settings": {"study": describe(st.study),
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
            "n_retried_lower_start": self.n_retried, "n_with_fallback": self.n_fallback,
            "lscf_disagreements": self.lscf_disagreements(),
            "hash": self.digest, "store": self.store, "timings_s": self.timings,
        }


def run_uncertainty(settings: UncertaintySettings = UncertaintySettings(), out=None,
                    executor: str | ExecutorSpec = "serial", progress: bool = True, model=None,
                    simulate: Callable = simulate_fe,
                    on_sample: Callable[[SampleResult], None] | None = None
                    ) -> UncertaintyReport:
    """Run (or resume) the Monte Carlo sweep (:mod:`cases.double_beam.uncertainty`).

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
        Per-sample model (:class:`inverse.uncertainty.SweepInputs`); default
        :func:`cases.double_beam.uncertainty.simulate_fe`.
    on_sample : callable, optional
        ``on_sample(result)`` after each newly computed sample is stored.

    Returns
    -------
    UncertaintyReport
    """
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
                             "study": describe(st)})
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
