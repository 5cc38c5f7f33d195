"""Time of a two-mode update against one mode's (issue 41: "a two-mode update <= 2x the
one-mode update's time"), side by side in one run, on the shipped two-mode case
docs/case-files/bolted-lap-jenkins-modes.toml (the double beam's data hold one mode).

Timed (CPU medians of the thread, one thread, repetitions interleaved):

* ``update --modes 2``: the one-joint route on mode 2 alone;
* ``update --modes 2,1``: one joint over modes 2 and 1;
* ``update`` (mode 2): the one-mode update with the judge's causes, profiles and
  cross-validation, the command a user runs on one mode.

``python benchmarks/bench_modes_update.py [REPEATS]``
"""
from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cases.registry import resolve_case  # noqa: E402

CASE = ROOT / "docs" / "case-files" / "bolted-lap-jenkins-modes.toml"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    repeats = int(argv[0]) if argv else 5
    case = resolve_case(str(CASE))
    runs = {
        "update --modes 2": lambda: case.require("update_modes")(fit_modes=(2,)),
        "update --modes 2,1": lambda: case.require("update_modes")(fit_modes=(2, 1)),
        "update (mode 2, causes judged)": lambda: case.require("update")(mode_label=2),
    }
    cpu = {k: [] for k in runs}
    wall = {k: [] for k in runs}
    out = {}
    for _ in range(repeats):
        for name, run in runs.items():
            t0, w0 = time.thread_time(), time.perf_counter()
            out[name] = run()
            cpu[name].append(time.thread_time() - t0)
            wall[name].append(time.perf_counter() - w0)
    med = {k: float(np.median(v)) for k, v in cpu.items()}
    for k in runs:
        print(f"{k:34s} {med[k]:7.2f} s CPU ({np.median(wall[k]):.2f} s wall)")
    two, one = med["update --modes 2,1"], med["update --modes 2"]
    print(f"two modes / one mode, the same route: {two / one:.2f}x (target <= 2)")
    print(f"two modes / the one-mode update with causes: "
          f"{two / med['update (mode 2, causes judged)']:.2f}x")
    F = {k: out[k]["fit"].joint()["F_S"] for k in ("update --modes 2", "update --modes 2,1")}
    print("F_S fitted: " + ", ".join(f"{k}: {v:.4g} N" for k, v in F.items())
          + " (the table was simulated with 200 N)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
