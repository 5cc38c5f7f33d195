"""One ring-down of the double beam's mode 4 over 500 cycles (issue 21: <= 2 s).

The FE double beam of ``iwanfe reproduce double-beam`` (45 reduced DOFs, 5 glue joints x
252 Jenkins sliders), started on its EPMC orbit (bank path) with the most loaded joint
at half its phi_max, integrated over 500 periods at 64 steps per period (the defaults of
``iwanfe ringdown``), with and without the energy balance. Prints the thread CPU time
[wall] of the start (one EPMC point), of the integration and the steps per second.
One thread (set before numpy is imported). Usage::

    python benchmarks/bench_ringdown.py
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import sys  # noqa: E402
import time  # noqa: E402

from cases.ringdown_study import RingdownSettings, ringdown_case, simulate_ringdown  # noqa: E402


def timed(fn):
    t0, w0 = time.thread_time(), time.perf_counter()
    out = fn()
    return out, time.thread_time() - t0, time.perf_counter() - w0


def main() -> int:
    case = ringdown_case("double-beam", 4)
    settings = RingdownSettings(mode=4, amplitude=0.5, cycles=500, steps_per_period=64)
    simulate_ringdown(case, RingdownSettings(mode=4, cycles=2))          # compile, caches
    (rec, info), cpu, wall = timed(lambda: simulate_ringdown(case, settings))
    n = rec.time_s.size - 1
    print(f"double beam mode 4: {case.model.n_reduced} reduced DOFs, {case.bank.n_joints} "
          f"joints x {case.bank.n_sliders} sliders, 500 cycles x 64 steps = {n} steps; "
          f"load average {os.getloadavg()[0]:.2f}; thread CPU time [wall]")
    print(f"  ring-down (EPMC start + integration + energy balance): {cpu:.2f} s [{wall:.2f}]"
          f"; integration alone {info['integration_s']:.2f} s wall; "
          f"{1e6 * cpu / n:.2f} us per step; target 2 s: {'met' if cpu <= 2 else 'NOT met'}")
    print(f"  energy balance: relative residual {info['energy_J']['relative_residual']:.2e}; "
          f"Newton iterations per step {info['newton_iterations'] / n:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
