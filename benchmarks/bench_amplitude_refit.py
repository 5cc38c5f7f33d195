"""Paired benchmark of ``--amplitude-refit`` (:mod:`ident.amplitude_poles`): the same
physical own-generator series (:mod:`synthetic`, generated and sized with
the linear identification, the default) identified linearly and with the refit, each
diagnosed on both noise paths. Prints the scores per identification and path, and the
singles whose verdict changed.

Usage::

    nice -n 5 python benchmarks/bench_amplitude_refit.py 80101 [SEED ...] [--workers 2]
        [--out FILE.json]
"""
from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from itertools import combinations  # noqa: E402

import numpy as np  # noqa: E402

from synthetic import (CATALOGUE, OUT_OF_CATALOGUE, generate_series,  # noqa: E402
                                    truth_of, without_stds)
from synthetic.measure import concat  # noqa: E402
from ident.frf_files import FRFSet  # noqa: E402
from ident.series import identify_series  # noqa: E402
from ident.series_table import series_table  # noqa: E402
from inverse.diagnose import diagnose  # noqa: E402

KEYS = ("linear, with std", "refit, with std", "linear, without std", "refit, without std")


def _refit_table(s):
    """The series' noisy FRFs identified with the refit (repeats appended)."""
    def frfset(r):
        return FRFSet(r["freq_hz"], np.reshape(r["frf"], (len(r["freq_hz"]), -1)), ["1"],
                      quantity="receptance", excitation=r["held"], reference="1",
                      source=f"level_{r['level']:02d}", control=r["control"],
                      run_order=r["run_order"], force=r["force"])
    main = sorted((r for r in s.frfs if not r["repeat"]), key=lambda r: r["level"])
    with np.errstate(all="ignore"):
        table = series_table(identify_series([frfset(r) for r in main], n_modes=1,
                                             check_band=False, amplitude_refit=True))
        for r in (r for r in s.frfs if r["repeat"]):
            row = series_table(identify_series([frfset(r)], n_modes=1, check_band=False,
                                               amplitude_refit=True))
            row.level = np.array([r["level"]])
            table = concat(table, row)
    return table


def run_case(job):
    label, seed = job
    s = generate_series(label, seed)
    out = {"label": label, "seed": seed}
    for ident_name, data in (("linear", s.data), ("refit", _refit_table(s))):
        for path, d in (("with std", data), ("without std", without_stds(data))):
            try:
                r = diagnose(d)
                out[f"{ident_name}, {path}"] = [r["cause"]] + list(r["also"])
            except Exception as exc:                    # noqa: BLE001 (counted, printed)
                out[f"{ident_name}, {path}"] = [f"error: {str(exc)[:60]}"]
    return out


def score(rows, key):
    """singles, pairs (both named), out of catalogue -> unexplained, none otherwise."""
    n = {k: [0, 0] for k in ("singles", "pairs", "ooc", "none otherwise")}
    for r in rows:
        t, got = truth_of(r["label"]), r[key]
        k = ("none otherwise" if t == () else "ooc" if t == ("unexplained",)
             else "singles" if len(t) == 1 else "pairs")
        ok = (got[0] != "none" if k == "none otherwise" else
              got[0] == "unexplained" if k == "ooc" else
              got[0] == t[0] if k == "singles" else set(got) == set(t))
        n[k][0] += int(ok)
        n[k][1] += 1
    return "  ".join(f"{k} {a}/{b}" for k, (a, b) in n.items())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("seeds", type=int, nargs="+")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, metavar="FILE.json",
                    help="also write every case's verdicts")
    args = ap.parse_args()
    jobs = []
    for seed in args.seeds:
        labels = (["none"] * 8 + [c for c in CATALOGUE for _ in range(3)]
                  + [f"{a}+{b}" for a, b in combinations(CATALOGUE, 2)]
                  + [o for o in OUT_OF_CATALOGUE for _ in range(2)])
        jobs += [(lab, seed * 1000 + i) for i, lab in enumerate(labels)]
    with ProcessPoolExecutor(args.workers) as ex:
        rows = list(ex.map(run_case, jobs))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(rows, fh, indent=1)
    for key in KEYS:
        print(f"{key:22s} {score(rows, key)}")
    print("singles whose verdict changed (linear -> refit, with std | without std):")
    for r in rows:
        t = truth_of(r["label"])
        if len(t) == 1 and t[0] != "unexplained" and (
                r[KEYS[0]] != r[KEYS[1]] or r[KEYS[2]] != r[KEYS[3]]):
            print(f"  {r['label']:26s} {r['seed']}  {r[KEYS[0]]} -> {r[KEYS[1]]} | "
                  f"{r[KEYS[2]]} -> {r[KEYS[3]]}")


if __name__ == "__main__":
    main()
