"""Peak memory of the largest default runs, each in a fresh child process.

Runs ``iwanfe reproduce lumped``, ``iwanfe reproduce double-beam`` and ``iwanfe
uncertainty`` (default settings, serial, output to a temporary directory, no progress
bars) one after the other as ``python -m cli.main ...`` and prints each child's peak
resident set size (``ru_maxrss`` from ``os.wait4``; KiB on Linux) in MiB, with its wall time
and exit status. A command that fails (e.g. a target not implemented yet) is reported with
the last line of its stderr and skipped. Only the child process itself is measured: with
``--workers`` the workers' memory would not be included, so the default serial runs
are measured.

Usage::

    python benchmarks/bench_memory.py                   # all targets (about 2 minutes)
    python benchmarks/bench_memory.py --targets lumped
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

TARGETS = {  # name -> iwanfe arguments (the output directory is appended)
    "lumped": ["reproduce", "lumped"],
    "double-beam": ["reproduce", "double-beam"],
    "uncertainty": ["uncertainty"],
}


def peak_rss(argv: list[str], cwd: str) -> tuple[int, float, float, str]:
    """Run ``argv``; return (exit status, peak RSS in MiB, wall seconds, stderr tail)."""
    with tempfile.TemporaryFile() as err, tempfile.TemporaryFile() as out:
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, cwd=cwd, stdout=out, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = [ln for ln in err.read().decode(errors="replace").splitlines() if ln.strip()]
    kib = usage.ru_maxrss if sys.platform != "darwin" else usage.ru_maxrss / 1024
    return proc.returncode, kib / 1024.0, wall, (lines[-1] if lines else "")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--targets", default=",".join(TARGETS),
                    help=f"comma-separated subset of {', '.join(TARGETS)}")
    args = ap.parse_args(argv)
    targets = [t for t in args.targets.split(",") if t]
    bad = [t for t in targets if t not in TARGETS]
    if bad:
        ap.error(f"unknown target {bad[0]!r}; choose from {', '.join(TARGETS)}")
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    _, base, _, _ = peak_rss([sys.executable, "-c", "import numpy, scipy, numba, cli.main"],
                             repo)
    print(f"peak resident memory (ru_maxrss of the child process), Python "
          f"{sys.version.split()[0]}; baseline 'import numpy, scipy, numba, cli.main': "
          f"{base:.0f} MiB")
    print(f"{'command':48s} {'peak MiB':>9} {'wall s':>8}  status")
    worst = None
    for target in targets:
        with tempfile.TemporaryDirectory() as out:
            cmd = [sys.executable, "-m", "cli.main", *TARGETS[target], "--out", out,
                   "--no-progress"]
            code, mib, wall, tail = peak_rss(cmd, repo)
        name = "iwanfe " + " ".join(TARGETS[target])
        if code != 0:
            print(f"{name:48s} {'-':>9} {wall:8.1f}  skipped: exit {code}: {tail[:120]}")
            continue
        print(f"{name:48s} {mib:9.0f} {wall:8.1f}  ok")
        worst = max(worst or 0.0, mib)
    if worst is not None:
        print(f"largest default run: {worst:.0f} MiB peak")
    return 0


if __name__ == "__main__":
    sys.exit(main())
