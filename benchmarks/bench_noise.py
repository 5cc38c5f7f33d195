"""The judge's repeatability without repeats, against planted seeded truth.

(a) estimated sd / true sd of the scatter about the model-free curve
    (:func:`inverse.judge.smooth_scatter`) on the planted power-law series of
    ``tests/test_judge_noise.py`` (random exponents 0.1-2, sums, bends at the top, 4-12
    levels at ratios 1.15-2.6), with a shuffled run order, also with a step or a warm-up
    drift with run order planted (30 noise sd);
(b) the false ``unexplained`` rate of the one-mode diagnosis on plain micro-slip Iwan
    series (exact describing function, random chi, 4-12 levels at ratios 1.15-2.6,
    repeatability 0.02-0.1 % in frequency and 1-5 % in damping, no repeats, run order
    ascending or shuffled), without and with repeats (the lowest level again at the
    end, a middle one after it).

Both parts share forms with the judge, so they measure self-consistency, not power:
(a)'s power laws are among the curve families of the noise model, and (b)'s series are
the diagnosis' own base model (exact four-parameter Iwan describing function), with
the repeatability drawn in the range the brief gives. The false-alarm rate on data
made apart is that of ``benchmarks/bench_diagnose.py`` (``none`` series of a Jenkins
bank without a Dirac share, and gen_dev's).

Usage::

    python benchmarks/bench_noise.py [--series 1000] [--diagnoses 20] [--seed 19]
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def ratios(seed: int, n_series: int, kind: str | None) -> np.ndarray:
    """(n_series, 2) estimated / true sd of ln omega2 and ln zeta."""
    from test_judge_noise import _ratios

    def effect(t, sd):
        if kind == "step":
            return np.where(t >= t.size // 2, -30 * sd, 0.0)
        return -30 * sd * (1 - np.exp(-t / 1.5))
    return _ratios(seed, n_series, None if kind is None else effect)


def micro_slip_series(rng, repeats: bool = False):
    """A plain micro-slip series (no hidden effect) with planted repeatability; with
    ``repeats``, the lowest level is run again at the end and a middle one after it
    (each run its own repeatability draw)."""
    from ident.modal_data import MeasuredData
    from joints.describing import describing_function
    from joints.iwan import IwanParameters

    n = int(rng.integers(4, 13))
    chi = rng.uniform(-0.9, -0.1)
    joint = IwanParameters.from_density(R=6e5, chi=chi, phi_max=1e-4, S=0.0)
    w0, z0 = 2 * np.pi * rng.uniform(40, 900), rng.uniform(5e-4, 5e-3)
    top = rng.uniform(0.2, 0.8) * joint.phi_max
    level = np.arange(1, n + 1)
    a = top / rng.uniform(1.15, 2.6) ** np.arange(n)[::-1]
    order = rng.permutation(n) + 1 if rng.random() < 0.5 else np.arange(1, n + 1)
    if repeats:
        again = np.array([0, n // 2])
        level, a = np.r_[level, level[again]], np.r_[a, a[again]]
        order = np.r_[order, n + 1, n + 2]
        n = level.size
    k_in, k_q = describing_function(joint, a)
    omega2 = w0**2 - (joint.K_T - k_in)
    zeta = z0 * w0 / np.sqrt(omega2) + k_q / (2 * omega2)
    omega2 = omega2 + k_q * zeta     # what identification returns: |pole|^2 (docs/judge.md)
    s_f, s_z = rng.uniform(2e-4, 1e-3), rng.uniform(0.01, 0.05)
    omega2 = omega2 * (1 + s_f * rng.standard_normal(n)) ** 2
    zeta = zeta * (1 + s_z * rng.standard_normal(n))
    force = 2 * zeta * omega2 * a
    return MeasuredData(level=level, excitation=force, omega2=omega2,
                        zeta=zeta, mode=np.ones(n, int), run_order=order,
                        response_amplitude=a * (1 + 0.005 * rng.standard_normal(n)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--series", type=int, default=1000)
    ap.add_argument("--diagnoses", type=int, default=20)
    ap.add_argument("--seed", type=int, default=19)
    args = ap.parse_args()
    q = [0.1, 0.25, 0.5, 0.75, 0.9]
    print(f"(a) estimated / true repeatability sd, quantiles {q}")
    for kind in (None, "step", "drift"):
        r = ratios(args.seed, args.series if kind is None else args.series // 3, kind)
        for j, ch in enumerate(("ln omega2", "ln zeta")):
            if kind and j:
                continue
            print(f"  {kind or 'no run-order effect':20s} {ch:10s} "
                  + " ".join(f"{v:5.2f}" for v in np.quantile(r[:, j], q)))
    if args.diagnoses:
        from tqdm import tqdm

        from inverse.diagnose import diagnose
        for repeats in (False, True):
            rng = np.random.default_rng(args.seed)
            causes = [diagnose(micro_slip_series(rng, repeats))["cause"]
                      for _ in tqdm(range(args.diagnoses), desc="diagnoses")]
            print(f"(b) plain micro-slip with repeatability, "
                  f"{'2 repeated levels' if repeats else 'no repeats'}: "
                  f"{causes.count('unexplained')}/{len(causes)} unexplained, "
                  f"{causes.count('none')}/{len(causes)} none "
                  f"({', '.join(f'{c} {causes.count(c)}' for c in sorted(set(causes)))})")


if __name__ == "__main__":
    main()
