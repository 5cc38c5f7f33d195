"""Case-file timing: a bolted lap-joint cantilever of 400 elements and 10 joints.

Prints, as medians over repetitions (thread CPU time, wall clock in brackets):
* ``modes``: the whole ``iwanfe modes --case FILE`` path in-process (read and check the
  file, build the FE model, the modes in a band with kinds and joint-slip shares); target
  <= 1 s; and the command itself in a fresh interpreter (CPU and wall clock, the imports
  of every command's modules included: ``cli.main`` registers them all);
* the 10-level FE campaign on the exact describing-function path
  (:func:`cases.virtual_test.campaign`: phase resonance of mode 1 at 10 force
  levels); target <= 0.1 s; the nonlinear model's build (reduced basis) apart.

    .venv/bin/python benchmarks/bench_case_file.py
"""
from __future__ import annotations

import os

for _v in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

BOLTS = 10
CASE = """[case]
name = "bench-lap-400"
description = "bolted lap cantilever, 400 elements, 10 joints (benchmark)"
[[material]]
name = "steel"
E = 200e9
rho = 7850.0
[[beam]]
name = "lower"
material = "steel"
x = [0.0, 0.597]
width = 0.03
thickness = 0.006
z = 0.0
[[beam]]
name = "upper"
material = "steel"
x = [0.399, 0.996]
width = 0.03
thickness = 0.006
z = 0.006
[[support]]
beam = "lower"
kind = "clamp"
x = [0.0, 0.0]
[[interface]]
beams = ["lower", "upper"]
x = [0.399, 0.597]
normal = "tied"
tangential = "joint"
joints_at = [{joints}]
law = "iwan4"
kt = 5.0e7
chi = -0.5
fs = 500.0
beta = 1.0
[drive]
beam = "lower"
x = 0.099
[[sensor]]
beam = "upper"
x = 0.996
label = "tip"
[damping]
zeta = 0.001
[mesh]
element_size = {h}
"""


def _median(fn, repeat: int):
    cpu, wall, out = [], [], None
    for _ in range(repeat):
        t0, w0 = time.thread_time(), time.perf_counter()
        out = fn()
        cpu.append(time.thread_time() - t0)
        wall.append(time.perf_counter() - w0)
    return float(np.median(cpu)), float(np.median(wall)), out


def main() -> int:
    from cases.virtual_test import campaign
    from cases.mode_report import mode_report
    from cases.registry import resolve_case

    joints = ", ".join(f"{0.417 + 0.018 * k:.3f}" for k in range(BOLTS))   # on the 3 mm grid
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "lap400.toml"
        path.write_text(CASE.format(joints=joints, h=0.003))   # 200 + 200 = 400 elements
        case = resolve_case(str(path))
        model = case.fe_model()
        n_el = sum(s.n_nodes - 1 for s in model.strip_meshes)
        print(f"case: {n_el} elements, {model.joint_stiffness.size} joints, "
              f"{model.n_free} free DOFs")
        cpu, wall, rep = _median(lambda: mode_report(resolve_case(str(path)), band=(0, 2000)), 5)
        print(f"modes (read + build + modes 0-2000 Hz, {len(rep['modes'])} modes): "
              f"{cpu:.3f} s [{wall:.3f} s]   target <= 1 s")
        import resource

        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        w0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "cli.main", "modes", "--case", str(path),
                        "--band", "0", "2000"], check=True, capture_output=True, cwd=ROOT)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        child = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        print(f"iwanfe modes --case FILE in a fresh interpreter: {child:.3f} s CPU "
              f"[{time.perf_counter() - w0:.3f} s], imports of every command included")
        cpu, wall, nc = _median(lambda: case.nonlinear_model(mode=1), 3)
        print(f"nonlinear model build (reduced basis, {nc.model.n_reduced} vectors): "
              f"{cpu:.3f} s [{wall:.3f} s]")
        cpu, wall, res = _median(lambda: campaign(nc), 7)
        print(f"10-level FE campaign, exact DF path: {cpu * 1e3:.1f} ms [{wall * 1e3:.1f} ms]   "
              f"target <= 100 ms; f = {np.sqrt(res.omega2[0]) / 2 / np.pi:.3f} -> "
              f"{np.sqrt(res.omega2[-1]) / 2 / np.pi:.3f} Hz, zeta {res.zeta[0]:.2e} -> "
              f"{res.zeta[-1]:.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
