"""The cost of ``update --case double-beam`` on response-amplitude rows against the
shipped stepped-sine data: CPU time of one serial run each (the work, whatever the load
of a shared machine) on the shipped data (force route), the planted free-decay series
and the planted random series of ``tests/fe_response_synth.py`` (response and Rayleigh
routes), with chi fitted against the planted value.

Usage::

    python benchmarks/bench_fe_response_update.py      # about 2-4 minutes
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import fe_response_synth as synth  # noqa: E402

from cases.double_beam.fe_levels import DoubleBeamLevels  # noqa: E402
from feloop.update import UpdateSettings, run_update  # noqa: E402
from ident.measured import write_measured  # noqa: E402


def _run(path):
    t, c = time.perf_counter(), time.process_time()
    r = run_update(UpdateSettings(data_path=path), DoubleBeamLevels.from_data)
    return time.process_time() - c, time.perf_counter() - t, r


def main() -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        series = {"free-decay": synth.series("free-decay"),
                  "random": synth.series("random", amplitudes=synth.AMPLITUDES / 3)}
        paths = {"shipped stepped sine": None}
        for name, data in series.items():
            paths[name] = str(Path(tmp) / f"{name}.csv")
            write_measured(paths[name], data)
        for name, path in paths.items():
            cpu, wall, r = _run(path)
            rows.append((name, cpu, wall, r["fit"].values["chi"], r["candidate"],
                         r["fit"].failed_simulations))
    base = rows[0][1]
    print(f"{'series':22s} {'CPU s':>7s} {'wall s':>7s} {'CPU ratio':>9s} {'chi':>8s}  "
          f"candidate (failed simulations); planted chi {synth.CHI}")
    for name, cpu, wall, chi, cand, failed in rows:
        print(f"{name:22s} {cpu:7.1f} {wall:7.1f} {cpu / base:9.2f} {chi:8.4f}  "
              f"{cand} ({failed})")


if __name__ == "__main__":
    main()
