"""Blind benchmark of ``inverse.diagnose`` on fresh synthetic cases.

For every cause (``none`` included) ``--per-cause`` cases are simulated by
:mod:`cases.synthetic` (stepped-sine campaign of an Iwan oscillator with the hidden
effect, identification from the FRFs, paper-like noise) with seeds
``SEED, SEED+1, ...``; the diagnosis sees only the measured-data table. Prints every
case, the confusion matrix (rows: truth, columns: named cause), the blind accuracy,
the number of ``none`` cases called something else, whether every named cause has
gain > 1, and the timings.

Targets: accuracy >= 90 %, at most one false alarm per 10 ``none`` cases.

The cases are independent tasks of :func:`runs.executor.run_sweep` (each carries its
seed), so they run serially, in local processes or on a dask.distributed cluster with
the same results and a progress bar either way.

Usage::

    python benchmarks/bench_diagnose.py --seed 7001             # 60 cases, serial
    python benchmarks/bench_diagnose.py --seed 9000 --per-cause 20 --workers 2
    python benchmarks/bench_diagnose.py --seed 9000 --scheduler tcp://HOST:8786
    python benchmarks/bench_diagnose.py --seed 9000 --executor processes --workers 2
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from inverse.diagnose import diagnose
from cli.executor_options import add_executor_arguments, executor_from_args
from cases.synthetic import CAUSES, generate_case
from runs.executor import ExecutorSpec, run_sweep


def run_case(job):
    cause, seed = job
    t0 = time.perf_counter()
    case = generate_case(cause, seed)
    t1 = time.perf_counter()
    result = diagnose(case.data)
    t2 = time.perf_counter()
    return {
        "truth": cause, "seed": seed, "called": result["cause"], "gain": result["gain"],
        "effect": case.truth["effect_sigma"], "chi": case.truth["chi"],
        "chi_fit": result["parameters"]["chi"],
        "x_top": float(case.truth["slip_over_phi_max"][-1]),
        "response": case.data.response_amplitude is not None,
        "t_generate": t1 - t0, "t_diagnose": t2 - t1,
    }


def confusion(rows):
    m = np.zeros((len(CAUSES), len(CAUSES)), int)
    for r in rows:
        m[CAUSES.index(r["truth"]), CAUSES.index(r["called"])] += 1
    return m


def format_matrix(m) -> str:
    short = ["none", "macro", "nonprop", "harden", "drift", "quad"]
    head = "truth \\ called".rjust(16) + " " + " ".join(f"{s:>8}" for s in short)
    lines = [head]
    for i, s in enumerate(short):
        lines.append(f"{s:>16} " + " ".join(f"{v:8d}" for v in m[i]))
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, required=True, help="first seed (use a new one)")
    ap.add_argument("--per-cause", type=int, default=10, help="cases per cause")
    ap.add_argument("--jobs", type=int, default=1,
                    help="local worker processes (same as --executor processes --workers N)")
    ap.add_argument("--causes", default=",".join(CAUSES),
                    help="comma-separated subset of causes")
    ap.add_argument("--quiet", action="store_true", help="no per-case lines")
    add_executor_arguments(ap)
    args = ap.parse_args(argv)
    causes = args.causes.split(",")
    bad = [c for c in causes if c not in CAUSES]
    if bad:
        ap.error(f"unknown cause {bad[0]!r}; choose from {', '.join(CAUSES)}")
    try:
        spec = executor_from_args(args)
        if args.jobs > 1:
            if spec.kind != "serial":
                raise ValueError("give --jobs or the executor options, not both")
            spec = ExecutorSpec("processes", args.jobs)
    except ValueError as exc:
        ap.error(str(exc))
    jobs = [(c, args.seed + i) for c in causes for i in range(args.per_cause)]
    t0 = time.perf_counter()
    rows = run_sweep(run_case, jobs, executor=spec, desc="diagnosis cases", unit="case",
                     chunksize=1)
    wall = time.perf_counter() - t0
    if not args.quiet:
        print(f"{'truth':26s} {'seed':>6} {'called':26s} {'gain':>6} {'effect':>8} "
              f"{'x_top':>5} {'chi':>6} {'chi_fit':>7} resp")
        for r in rows:
            mark = "" if r["called"] == r["truth"] else "  <-- miss"
            print(f"{r['truth']:26s} {r['seed']:6d} {r['called']:26s} {r['gain']:6.2f} "
                  f"{r['effect']:8.3g} {r['x_top']:5.2f} {r['chi']:6.3f} {r['chi_fit']:7.3f} "
                  f"{'y' if r['response'] else 'n':>4}{mark}")
    m = confusion(rows)
    n = len(rows)
    correct = int(np.trace(m))
    none_fa = int(m[0].sum() - m[0, 0])
    n_none = int(m[0].sum())
    bad_gain = [r for r in rows if r["called"] != "none" and not r["gain"] > 1.0]
    chi_err = np.array([r["chi_fit"] - r["chi"] for r in rows])
    print()
    print(f"confusion matrix ({n} cases, seeds {args.seed}..{args.seed + args.per_cause - 1} "
          f"per cause)")
    print(format_matrix(m))
    print(f"blind accuracy: {correct}/{n} = {100.0 * correct / n:.1f} % (target >= 90 %)")
    print(f"none called otherwise: {none_fa}/{n_none} (target <= {max(1, n_none // 10)})")
    print(f"named causes with gain <= 1: {len(bad_gain)}")
    print(f"chi error (fit - truth): median {np.median(chi_err):+.4f}, "
          f"90th pct |err| {np.percentile(np.abs(chi_err), 90):.4f}")
    tg = np.array([r["t_generate"] for r in rows])
    td = np.array([r["t_diagnose"] for r in rows])
    print(f"time per case: generate {tg.mean():.2f} s, diagnose {td.mean():.2f} s "
          f"(max {td.max():.2f} s); wall {wall:.0f} s on {spec.describe()}")
    ok = correct >= 0.9 * n and none_fa <= max(1, n_none // 10) and not bad_gain
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
