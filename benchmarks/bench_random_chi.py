"""chi recovered from simulated random-excitation series (issue 41, random part).

Six single-DOF Iwan oscillators (:func:`cases.random_series.sdof_iwan`) with seeded
joints whose chi, beta, K_T, F_S, frequency, viscous damping, band and levels are drawn
here (seeds 4101-4106; chi fixed per series at -0.15 .. -0.85, the rest drawn), none of
them the draws of ``tests/test_random_test.py`` (seed 2121, beta 0.5, K_T 1e5) or
``tests/test_random_series.py``. Each series is simulated by the project's random time
integration (:func:`cases.random_series.simulate_random_series`: band-limited Gaussian
drive, Newmark, Welch H1 written as ``# test = random`` FRF files), identified from its
files (:func:`ident.series.load_series`, as ``iwanfe estimate FILES`` does) and chi
estimated by :func:`inverse.estimate.estimate` (methods ``exact`` and ``paper``, the
command's default).

Printed per series: the planted chi, the estimate with its 95 % interval, ``|error|``;
the count within 0.05. Diagnostics beside them: the identified response RMS of each
level over the simulated one (``level_XX.json``), and chi with the simulated slip RMS
as abscissa (the identified damping, the true amplitude: what is left is the damping's
error), and the identified damping over the Rayleigh-expectation model at the simulated
slip RMS (:func:`cases.random_series.sdof_rayleigh_prediction`).

``python benchmarks/bench_random_chi.py [--levels 6] [--duration 150] [--out DIR]``
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from cases.random_series import (RandomSeries, sdof_iwan, sdof_rayleigh_prediction,  # noqa: E402
                                 simulate_random_series)
from ident.series import load_series  # noqa: E402
from inverse.estimate import estimate  # noqa: E402
from joints.iwan import IwanParameters  # noqa: E402

CHIS = (-0.15, -0.3, -0.45, -0.6, -0.75, -0.85)
SEEDS = (4101, 4102, 4103, 4104, 4105, 4106)
TOLERANCE = 0.05


def draw(seed: int, chi: float, n_levels: int) -> dict:
    """One series' joint, oscillator, band and levels from ``seed`` (module doc)."""
    rng = np.random.default_rng(seed)
    joint = IwanParameters(chi=chi, K_T=rng.uniform(5e4, 3e5), F_S=rng.uniform(40.0, 400.0),
                           beta=rng.uniform(1.0, 5.0))
    k_lin = joint.K_T * rng.uniform(3.0, 12.0)
    f0 = rng.uniform(60.0, 160.0)
    mass = (k_lin + joint.K_T) / (2 * np.pi * f0) ** 2
    zeta = rng.uniform(0.003, 0.008)
    width = rng.uniform(50.0, 100.0)
    lo = rng.uniform(0.003, 0.01)
    hi = lo * rng.uniform(12.0, 25.0)
    return dict(joint=joint, k_lin=k_lin, mass=mass, zeta=zeta, width=width,
                slip=joint.phi_max * np.geomspace(lo, hi, n_levels), seed=seed * 10)


def drive_rms(d: dict) -> np.ndarray:
    """Drive RMS (N) whose stuck-joint linear response has the planned slip RMS: a drive
    of PSD RMS^2/B (per Hz) gives sigma^2 = S / (8 zeta w^3 m^2) (per Hz, one-sided)."""
    k = d["k_lin"] + d["joint"].K_T
    w = np.sqrt(k / d["mass"])
    per_newton = np.sqrt(1.0 / d["width"] / (8 * d["zeta"] * w ** 3 * d["mass"] ** 2))
    return d["slip"] / per_newton


def run_series(d: dict, out: Path, duration: float, resolution=0.1) -> dict:
    model, bank = sdof_iwan(d["joint"], d["k_lin"], d["mass"], d["zeta"])
    w0 = float(model.omega[0])
    f0 = w0 / (2 * np.pi)
    series = RandomSeries(rms=tuple(drive_rms(d)), band_hz=(f0 - d["width"] / 2,
                                                            f0 + d["width"] / 2),
                          omega_ref=w0, duration=duration, seed=d["seed"],
                          resolution_hz=resolution)
    paths = simulate_random_series(model, bank, np.ones(1), np.eye(1), ["1"], series, out)
    data = load_series(paths)
    meta = [json.loads(p.with_suffix(".json").read_text()) for p in paths]
    slip = np.array([m["slip_rms_m"][0] for m in meta])
    resp = np.array([m["response_rms_m"][0] for m in meta])
    order = np.argsort(data.level)
    rows = {"exact": estimate(data, method="exact"), "paper": estimate(data, method="paper"),
            "true_abscissa": estimate(data, method="amplitude", amplitude=slip[order])}
    pred = sdof_rayleigh_prediction(d["joint"], d["k_lin"], d["mass"], float(model.C[0, 0]),
                                    slip)
    return dict(est=rows, amp_ratio=data.response_amplitude[order] / resp,
                zeta_ratio=data.zeta[order] / pred["zeta"],
                joint_share=(pred["zeta"] - d["zeta"]) / pred["zeta"],
                n_avg=meta[0]["n_averages"], warnings=data.warnings)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, default=6, help="levels per series")
    ap.add_argument("--duration", type=float, default=150.0, help="record per level (s)")
    ap.add_argument("--resolution", type=float, default=0.1, help="H1 line spacing (Hz)")
    ap.add_argument("--out", default=None, help="keep the FRF files here (default: temp)")
    args = ap.parse_args(argv)
    root = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="bench_random_chi_"))
    t0 = time.perf_counter()
    hits = {"exact": 0, "paper": 0, "true_abscissa": 0}
    print(f"{args.levels} levels per series, {args.duration:g} s per level, lines "
          f"{args.resolution:g} Hz apart, files in {root}")
    print(f"{'seed':>5} {'chi':>6} {'beta':>5} {'exact (95 %)':>26} {'|err|':>6} "
          f"{'paper':>7} {'|err|':>6} {'true-abs':>8} {'|err|':>6}  resp RMS id/sim  "
          "zeta id/Rayleigh  joint share of zeta")
    for seed, chi in zip(SEEDS, CHIS):
        d = draw(seed, chi, args.levels)
        r = run_series(d, root / f"series_{seed}", args.duration, args.resolution)
        e = {k: v.chi for k, v in r["est"].items()}
        err = {k: abs(v - chi) for k, v in e.items()}
        for k in hits:
            hits[k] += err[k] <= TOLERANCE
        iv = r["est"]["exact"].chi_interval
        print(f"{seed:5d} {chi:6.2f} {d['joint'].beta:5.2f} {e['exact']:8.4f} "
              f"({iv[0]:7.3f} .. {iv[1]:6.3f}) {err['exact']:6.3f} {e['paper']:7.4f} "
              f"{err['paper']:6.3f} {e['true_abscissa']:8.4f} {err['true_abscissa']:6.3f}  "
              f"{r['amp_ratio'].min():.4f}-{r['amp_ratio'].max():.4f}  "
              f"{r['zeta_ratio'].min():.4f}-{r['zeta_ratio'].max():.4f}  "
              f"{r['joint_share'].min():.3f}-{r['joint_share'].max():.3f}")
    print(f"within {TOLERANCE}: exact {hits['exact']} of {len(SEEDS)}, paper {hits['paper']} "
          f"of {len(SEEDS)}, with the simulated slip RMS as abscissa "
          f"{hits['true_abscissa']} of {len(SEEDS)}; {time.perf_counter() - t0:.0f} s wall")
    return 0


if __name__ == "__main__":
    sys.exit(main())
