"""Coverage of a mode predicted from the joint fitted on another (issue 41): fit mode 2,
predict mode 1 of the bolted lap cantilever with Jenkins joints (docs/case-files/
bolted-lap-jenkins.toml, fs left to be fitted), over many seeded draws.

Each draw: a slip force uniform in [120, 320] N; modes 1 and 2 simulated by the Jenkins
bank's multi-harmonic stepped sine and identified by LSCF (:mod:`cases.stepped_sine_test`,
another route than the fit's first-harmonic describing function); then rig noise drawn
per draw (relative sd of frequency uniform in [0.005, 0.05] %, of zeta in [0.5, 3] %),
added to every level. The fit (``loop --fit-modes 2 --predict-modes 1``, Python API) sees
neither the slip force nor the noise level. Printed: per draw the fitted F_S and the
misses; over all draws the share of predicted levels (2..10, frequency and zeta) inside
their 95 % intervals, under the judge's default noise (assumed rig repeatability pooled)
and with the rig's repeatability stated as the draw's.

What it shares with the judge: the noise range is the brief's real-rig range, which is also
the judge's assumed rig prior (that part measures self-consistency); the simulation and the
fit share the case file's structure and the Jenkins law, not the solver.

``python benchmarks/bench_mode_prediction.py [DRAWS] [FIRST_SEED]``
"""
from __future__ import annotations

import math
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import cases.stepped_sine_test as sst  # noqa: E402
from cases.registry import resolve_case  # noqa: E402
from feloop.case_file import levels_builder  # noqa: E402
from feloop.modes_run import ModesSettings, run_modes  # noqa: E402
from ident.measured import write_measured  # noqa: E402
from ident.modal_data import MeasuredData  # noqa: E402

FILES = ROOT / "docs" / "case-files"
TOP_SLIP = 40.0


def _file(tmp, table, fs, mode, name):
    text = (FILES / "bolted-lap-jenkins.toml").read_text()
    text = re.sub(r"(?m)^fs = .*\n", "" if fs is None else f"fs = {fs!r}\n", text)
    text += f'\n[measured]\nfile = "{table.name}"\nmode = {mode}\n'
    (tmp / name).write_text(text)
    return tmp / name


def draw(seed: int, tmp: Path):
    rng = np.random.default_rng(seed)
    fs = float(rng.uniform(120.0, 320.0))
    sf, sz = float(rng.uniform(5e-5, 5e-4)), float(rng.uniform(5e-3, 3e-2))
    table = tmp / f"levels-{seed}.csv"
    shutil.copy(FILES / "bolted-lap-cantilever-levels.csv", table)
    parts = []
    sst.TOP_SLIP_OTHER = TOP_SLIP
    for mode in (1, 2):
        d = sst.simulate(resolve_case(str(_file(tmp, table, fs, mode, f"t{mode}.toml"))),
                         seed * 10 + mode)[0]
        n = d.omega2.size
        d.omega2 = d.omega2 * (1 + 2 * sf * rng.standard_normal(n))   # omega2: twice f's
        d.zeta = d.zeta * (1 + sz * rng.standard_normal(n))
        parts.append(d)
    write_measured(table, MeasuredData.concatenate(parts))
    return _file(tmp, table, None, 2, f"fit-{seed}.toml"), table, fs, (sf, sz)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    n = int(argv[0]) if argv else 50
    first = int(argv[1]) if len(argv) > 1 else 9101
    inside = {"default noise": [], "rig stated": []}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(first, first + n):
            try:
                path, table, fs, (sf, sz) = draw(seed, Path(tmp))
            except Exception as exc:     # the generator's own failure: not scored
                print(f"seed {seed}: not scored, the generator failed: {str(exc)[:100]}")
                continue
            cf = resolve_case(str(path)).file
            words = []
            for name, rig in (("default noise", None), ("rig stated", (sf, sz, 2.0))):
                r = run_modes(ModesSettings(str(table), (2,), (1,), rig_repeatability=rig),
                              levels_builder(cf))
                p = r["predicted"][1]
                rows = p.rows[1:]
                inside[name] += [abs(q["z_frequency"]) <= 1.959964 for q in rows]
                inside[name] += [abs(q["z_zeta"]) <= 1.959964 for q in rows]
                F = r["fit"].joint()["F_S"]
                words.append(f"{name}: F_S {F:.4g} N ({100 * (F / fs - 1):+.1f} %), "
                             f"{len(p.misses)} missed")
            print(f"seed {seed}: fs {fs:.4g} N, noise {100 * sf:.3f} % / {100 * sz:.2f} %; "
                  + "; ".join(words), flush=True)
    for name, v in inside.items():
        if v:
            print(f"coverage of the 95 % intervals ({name}): {100 * np.mean(v):.1f} % of "
                  f"{len(v)} predicted values (target 90-98 %)")
    print(f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
