"""Round-off robustness of the pipeline under different BLAS configurations.

The same input files are identified, estimated and diagnosed, and the main job is run,
in fresh ``iwanfe`` processes under several BLAS configurations (OpenBLAS kernel chosen
with ``OPENBLAS_CORETYPE``, number of BLAS threads); every number of every other
configuration is compared with the first's:

- a number that comes with a standard deviation (``omega2``/``omega2_std``,
  ``zeta``/``zeta_std`` of the identified tables; ``predicted``/``sd``;
  ``X``/``X_interval`` as a 95 % interval, half-width / 1.96): |difference| in units of
  the first configuration's standard deviation;
- any other number: its relative difference (``|a - b| / max(|a|, |b|)``);
- verdicts (``cause``, ``also``, ``unexplained``, ``ambiguous``, ``model``, ``verdict*``),
  the structure (modes per level, rows of the tables, exit status) and the words
  (warnings, pole-selection notes, statements, with their numbers masked; the numbers
  in them are counted apart) for equality.

This is a self-consistency check: it measures how far the last bits of the arithmetic
move the answers, not how close they are to any truth and not how fast anything runs.
Acceptance (issue "Same data, same answer on every machine"): every identified omega2
and zeta within 0.01 of its own standard deviation of the first configuration's, equal
verdicts and causes, equal structure. The script always exits 0; it prints PASS or
FAIL.

Input data, made once by this process and read by every configuration:

- ``series``: ``python docs/examples.py --make-series`` (response control, 8 levels,
  one planted linear mode per level);
- ``uff``: ``python docs/examples.py --make-uff`` (4 points, 3 modes, one set);
- ``chain-test``: the force-controlled narrow-band series of
  ``tests/test_series_identify.py::test_force_controlled_narrow_band_one_track_and_warnings``
  (one mass, an Iwan joint to the ground, 8 levels up to 0.6 phi_max, seed 5);
- ``chain-sN``: the same recipe on the drawn SDOF chains of that test file (``sdof(N)``);
- ``beam-frf``: the FRF files of ``iwanfe reproduce double-beam`` (10 force-controlled
  levels, level 10 in macro-slip), identified with the options of docs/commands.md;
- ``shipped``: ``cases/data/double_beam_measured.csv`` (estimate and diagnose only).

Workloads (``--workloads``): ``identify`` (``iwanfe identify FILES --out T.csv --json``),
``estimate`` and ``diagnose`` (``TABLE --json``, on each configuration's own identified
tables and the shipped data), ``loop`` (``iwanfe loop --case double-beam --json`` and
``iwanfe diagnose --case double-beam --json``). Configurations (``--configs``): names
joined by ``,``; each is ``default`` or ``+``-joined parts ``threadsN``
(``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=N``) and an OpenBLAS core name
(``OPENBLAS_CORETYPE``), e.g. ``Haswell+threads2``. ``default`` sets no variable (the
CLI then runs BLAS on one thread). A probe in each configuration prints the kernel
(``architecture``) and thread count threadpoolctl reports, and says when a configuration
did not take effect or ran the same BLAS as the first.

    .venv/bin/python benchmarks/blas_repro.py                           # all, 8-10 min
    .venv/bin/python benchmarks/blas_repro.py --workloads identify --configs default,Haswell
    .venv/bin/python benchmarks/blas_repro.py --compare-only            # re-read the last run
"""
from __future__ import annotations

import os

#: variables that choose the BLAS kernel or its threads: the children get none of the
#: caller's, only their configuration's
BLAS_VARS = ("OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS", "GOTO_NUM_THREADS", "OPENBLAS_VERBOSE")
CHILD_BASE = {k: v for k, v in os.environ.items() if k not in BLAS_VARS}
# this process (data generation only) on one thread, as the other benchmarks
for _v in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import csv  # noqa: E402
import difflib  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import re  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
IWANFE = [str(Path(PY).parent / "iwanfe")] if (Path(PY).parent / "iwanfe").exists() else \
    [PY, "-c", "import sys; from cli.main import main; sys.exit(main())"]
SHIPPED = ROOT / "cases" / "data" / "double_beam_measured.csv"
MARKER = "blas_repro_manifest.json"

THRESHOLD_SD = 0.01
WORKLOADS = ("identify", "estimate", "diagnose", "loop")
DEFAULT_CONFIGS = "default,Haswell,threads1,threads2"
DEFAULT_CHAINS = "1,2"
#: keys whose values are verdicts: must be equal
VERDICT_KEYS = {"cause", "also", "unexplained", "ambiguous", "ambiguity", "closest_miss",
                "rivals", "candidate", "model", "verdict", "named"}
#: keys that are timings, not results
SKIP_KEYS = {"seconds", "elapsed", "elapsed_s", "wall_s", "cpu_s", "time_s"}
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
Z95 = 1.959963984540054


# --------------------------------------------------------------------------- configs

def parse_config(name: str) -> dict:
    """Environment of a configuration name (see the module doc)."""
    env = {}
    for part in name.split("+"):
        m = re.fullmatch(r"threads(\d+)", part)
        if part == "default":
            continue
        if m:
            env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = m.group(1)
        elif re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", part):
            env["OPENBLAS_CORETYPE"] = part
        else:
            raise SystemExit(f"blas_repro: --configs: cannot read {part!r} in {name!r}")
    return env


PROBE = r"""
import json, sys
import cli.main          # the CLI's own defaults (one BLAS thread unless set)
import numpy, scipy, scipy.linalg, threadpoolctl
a = numpy.random.default_rng(0).standard_normal((200, 200))
(a @ a).sum(); scipy.linalg.lu_factor(a)
blas = numpy.show_config(mode="dicts")["Build Dependencies"]["blas"]
out = {"numpy": numpy.__version__, "scipy": scipy.__version__,
       "numpy_blas": blas.get("name"), "numpy_blas_version": blas.get("version"),
       "pools": [{k: p.get(k) for k in ("internal_api", "prefix", "filepath", "version",
                                           "architecture", "num_threads")}
                 for p in threadpoolctl.threadpool_info() if p.get("user_api") == "blas"]}
try:
    import ident.identify as ii
    out["identify_one_thread"] = hasattr(ii, "_one_blas_thread")
except Exception as e:  # pragma: no cover
    out["identify_one_thread"] = repr(e)
print(json.dumps(out))
"""


def probe(env: dict, cwd: Path) -> dict:
    r = subprocess.run([PY, "-c", PROBE], env=env, cwd=cwd, capture_output=True, text=True,
                       timeout=300)
    if r.returncode != 0:
        return {"error": r.stderr.strip().splitlines()[-1:] or ["probe failed"]}
    info = json.loads(r.stdout.strip().splitlines()[-1])
    info["stderr"] = r.stderr.strip()
    return info


def _owner(pool: dict) -> str:
    """Which package ships a BLAS library (numpy.libs/... -> numpy)."""
    parent = Path(str(pool.get("filepath", ""))).parent.name
    return parent.removesuffix(".libs") if parent.endswith(".libs") else pool["prefix"]


def kernel_text(info: dict) -> str:
    if "error" in info:
        return f"probe failed: {info['error']}"
    return "; ".join(f"{_owner(p)}: {p['internal_api']} {p['version']} {p['architecture']} "
                     f"x{p['num_threads']}" for p in sorted(info["pools"], key=_owner))


def kernel_key(info: dict):
    return tuple(sorted((_owner(p), p["architecture"], p["num_threads"])
                        for p in info.get("pools", [])))


def config_effect(name: str, env: dict, info: dict) -> list:
    """Notes where the probe shows a configuration did not take effect."""
    notes = []
    if "error" in info:
        return [f"{name}: probe failed"]
    pools = info["pools"]
    if info.get("numpy_blas") and "openblas" not in str(info["numpy_blas"]).lower():
        notes.append(f"{name}: numpy's BLAS is {info['numpy_blas']}, not OpenBLAS: "
                     "OPENBLAS_CORETYPE means nothing to it")
    for p in pools:
        if p["internal_api"] != "openblas":
            notes.append(f"{name}: {_owner(p)}'s BLAS is {p['internal_api']}, not OpenBLAS")
    want = env.get("OPENBLAS_CORETYPE")
    if want:
        off = [p for p in pools if str(p["architecture"]).lower() != want.lower()]
        if off:
            notes.append(f"{name}: OPENBLAS_CORETYPE={want} did not take effect: "
                         + ", ".join(f"{_owner(p)} runs {p['architecture']}" for p in off))
    want_t = env.get("OPENBLAS_NUM_THREADS")
    if want_t:
        off = [p for p in pools if str(p["num_threads"]) != want_t]
        if off:
            notes.append(f"{name}: OPENBLAS_NUM_THREADS={want_t} did not take effect: "
                         + ", ".join(f"{_owner(p)} x{p['num_threads']}" for p in off))
    return notes


# ------------------------------------------------------------------------------ data

def _run_checked(argv, cwd, env=None):
    r = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=1800)
    if r.returncode != 0:
        raise SystemExit(f"blas_repro: {' '.join(map(str, argv))} failed:\n{r.stderr[-2000:]}")
    return r


def _chain_series(path: Path, chain, fractions, seed, noise=0.005):
    """The recipe of tests/test_series_identify.py::write_series (force control; the band
    follows the resonance, 41 lines of 0.05 Hz)."""
    import numpy as np
    from frf_series_synth import band_lines, noisy, simulate_level, write_level

    rng = np.random.default_rng(seed)
    path.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, frac in enumerate(fractions):
        A = frac * chain.joint.phi_max
        lam = chain.frozen_modes(A)[0]
        z = -lam.real / abs(lam)
        held = A * 2 * z * abs(lam) ** 2 * chain.m[0]
        lev = simulate_level(chain, held, "force", band_lines(abs(lam) / (2 * np.pi)))
        H, F = noisy(lev, rng, noise)
        p = path / f"level_{k + 1:02d}.csv"
        write_level(p, lev, H, F, run_order=len(fractions) - k)
        paths.append(str(p))
    return paths


def _drawn_sdof(seed):
    """tests/test_series_identify.py::sdof: one mass, spring, dashpot, Iwan joint."""
    import numpy as np
    from frf_series_synth import JointedChain
    from joints.iwan import IwanParameters

    rng = np.random.default_rng(seed)
    w0 = 2 * np.pi * 80.0
    k_total = w0 ** 2
    share = rng.uniform(0.1, 0.3)
    joint = IwanParameters(chi=rng.uniform(-0.7, -0.3), K_T=share * k_total,
                           F_S=share * k_total * rng.uniform(0.5e-4, 2e-4),
                           beta=rng.uniform(0.5, 2.0))
    return JointedChain(m=[1.0], k=[(1 - share) * k_total],
                        c=[2 * rng.uniform(0.003, 0.006) * w0], joint=joint)


def make_data(data: Path, chains, need_beam: bool) -> dict:
    """Writes every input once; returns {dataset: (files, extra identify options)}."""
    import numpy as np

    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
    from frf_series_synth import JointedChain
    from joints.iwan import IwanParameters

    data.mkdir(parents=True, exist_ok=True)
    sets = {}
    t0 = time.perf_counter()
    _run_checked([PY, str(ROOT / "docs" / "examples.py"), "--make-series", str(data / "series")],
                 ROOT)
    sets["series"] = (sorted(map(str, (data / "series").glob("level_*.csv"))), [])
    _run_checked([PY, str(ROOT / "docs" / "examples.py"), "--make-uff", str(data / "set.uff")],
                 ROOT)
    sets["uff"] = ([str(data / "set.uff")], [])
    w0 = 2 * np.pi * 80.0
    joint = IwanParameters(chi=-0.5, K_T=0.2 * w0 ** 2, F_S=0.2e-4 * w0 ** 2, beta=1.0)
    chain = JointedChain(m=[1.0], k=[0.8 * w0 ** 2], c=[2 * 0.005 * w0], joint=joint)
    fr = np.geomspace(0.01, 0.6, 8)
    sets["chain-test"] = (_chain_series(data / "chain-test", chain, fr, 5), [])
    for s in chains:
        sets[f"chain-s{s}"] = (_chain_series(data / f"chain-s{s}", _drawn_sdof(s), fr,
                                             1000 + s), [])
    if need_beam:
        _run_checked(IWANFE + ["reproduce", "double-beam", "--out", str(data / "beam"),
                               "--no-progress"], data)
        sets["beam-frf"] = (sorted(map(str, (data / "beam" / "frf").glob("level_*.csv"))),
                            ["--band", "236", "268", "--weighting", "uniform",
                             "--no-pseudo-modes"])
    print(f"data: {', '.join(f'{k} ({len(v[0])} file(s))' for k, v in sets.items())} "
          f"in {data} ({time.perf_counter() - t0:.0f} s, made once)", flush=True)
    return sets


# ------------------------------------------------------------------------------ runs

def plan(sets: dict, workloads) -> list:
    """[(workload, label, argv with {cfg} for the configuration's folder, table or None,
    needs)]: the identified table a run writes / needs."""
    runs = []
    tables = {}
    if "identify" in workloads:
        for name, (files, opts) in sets.items():
            table = f"{{cfg}}/ident/{name}.csv"
            runs.append(("identify", name, ["identify", *files, *opts, "--out", table,
                                            "--json"], table, None))
            if name != "uff":            # one level: nothing to estimate
                tables[name] = table
    for wl in ("estimate", "diagnose"):
        if wl not in workloads:
            continue
        for name, table in tables.items():
            runs.append((wl, name, [wl, table, "--json"], None, table))
        runs.append((wl, "shipped", [wl, str(SHIPPED), "--json"], None, None))
    if "loop" in workloads:
        runs.append(("loop", "loop double-beam", ["loop", "--case", "double-beam", "--out",
                                                  "{cfg}/loop", "--json", "--no-progress"],
                     None, None))
        runs.append(("loop", "diagnose --case double-beam",
                     ["diagnose", "--case", "double-beam", "--json"], None, None))
    return runs


def run_id(workload, label):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{workload}-{label}")


def execute(runs, configs, out: Path, manifest: dict):
    n = len(runs) * len(configs)
    k = 0
    for ci, name in enumerate(configs):
        env_add = parse_config(name)
        env = dict(CHILD_BASE, **env_add)
        env.pop("IWANFE_TRACEBACK", None)
        cdir = out / "configs" / name
        (cdir / "ident").mkdir(parents=True, exist_ok=True)
        info = probe(env, cdir)
        rec = manifest["configs"][name] = {"env": env_add, "probe": info, "runs": {}}
        print(f"[{name}] env {' '.join(f'{a}={b}' for a, b in env_add.items()) or '(none)'}: "
              f"{kernel_text(info)}", flush=True)
        t_cfg = time.perf_counter()
        for wl, label, argv, table, needs in runs:
            k += 1
            rid = run_id(wl, label)
            argv = [a.replace("{cfg}", str(cdir)) for a in argv]
            if needs is not None and not Path(needs.replace("{cfg}", str(cdir))).is_file():
                rec["runs"][rid] = {"rc": None, "skipped": "no identified table",
                                    "seconds": 0.0}
                print(f"  [{k}/{n}] {name}: {wl} {label}: skipped (no identified table)",
                      flush=True)
                continue
            t0 = time.perf_counter()
            with open(cdir / f"{rid}.json", "w") as so, open(cdir / f"{rid}.err", "w") as se:
                r = subprocess.run(IWANFE + argv, cwd=cdir, env=env, stdout=so, stderr=se,
                                   timeout=3600)
            dt = time.perf_counter() - t0
            err = (cdir / f"{rid}.err").read_text().strip().splitlines()
            err = [e.split("\r")[-1] for e in err]
            last = next((e for e in reversed(err) if "%|" not in e and e.strip()), "")
            rec["runs"][rid] = {"rc": r.returncode, "seconds": dt, "stderr_last": last[-300:]}
            status = "ok" if r.returncode == 0 else f"exit {r.returncode}: {last[-160:]}"
            print(f"  [{k}/{n}] {name}: {wl} {label}: {status} ({dt:.1f} s)", flush=True)
        rec["seconds"] = time.perf_counter() - t_cfg
        (out / MARKER).write_text(json.dumps(manifest, indent=1, default=str))


# ------------------------------------------------------------------------- comparing

def read_table(path: Path) -> dict:
    """A measured-data CSV as {"level L mode M": {column: value}}."""
    rows = {}
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    for row in csv.DictReader(lines):
        vals = {}
        for key, v in row.items():
            try:
                vals[key] = float(v) if v not in ("", None) else None
            except ValueError:
                vals[key] = v
        rows[f"level {row.get('level')} mode {row.get('mode')}"] = vals
    return rows


def load_doc(cdir: Path, workload, label, table) -> dict | None:
    rid = run_id(workload, label)
    f = cdir / f"{rid}.json"
    if not f.is_file() or not f.read_text().strip():
        return None
    try:
        doc = {"json": json.loads(f.read_text())}
    except json.JSONDecodeError as e:
        return {"unreadable": str(e)}
    if workload == "identify":
        # its "levels" are the rows of the --out table, compared from the table itself
        doc["json"].pop("levels", None)
    if table is not None:
        t = Path(table.replace("{cfg}", str(cdir)))
        if t.is_file():
            doc["table"] = read_table(t)
    return doc


def structure(workload, doc) -> str | None:
    """Modes per level and table rows of an identification (compared for equality)."""
    if workload != "identify" or not doc or "json" not in doc:
        return None
    sets = doc["json"].get("sets", [])
    per = [len(s.get("modes", [])) for s in sets]
    rows = len(doc.get("table", {}))
    modes = sorted({int(r["mode"]) for r in doc.get("table", {}).values()
                    if isinstance(r.get("mode"), float)})
    return f"modes per level {per}; table rows {rows}, modes {modes}"


def _num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _sd(parent: dict, key: str):
    """The standard deviation that comes with parent[key], if any: (sd, how)."""
    if not isinstance(parent, dict):
        return None
    for s in (f"{key}_std", f"{key}_sd"):
        v = parent.get(s)
        if _num(v) and v > 0 and math.isfinite(v):
            return v, s
    iv = parent.get(f"{key}_interval")
    if isinstance(iv, list) and len(iv) == 2 and all(_num(v) for v in iv) and iv[1] > iv[0]:
        return (iv[1] - iv[0]) / (2 * Z95), f"{key}_interval/3.92"
    if key in ("predicted", "value", "estimate", "mean"):
        for s in ("sd", "std", "std_error"):
            v = parent.get(s)
            if _num(v) and v > 0 and math.isfinite(v):
                return v, s
        iv = parent.get("interval")
        if isinstance(iv, list) and len(iv) == 2 and all(_num(v) for v in iv) and iv[1] > iv[0]:
            return (iv[1] - iv[0]) / (2 * Z95), "interval/3.92"
    return None


def _keyed(items: list) -> dict:
    """A list of dicts keyed by what names its items (level/mode, causes, level pair,
    file), so that a reordering does not compare apples with pears; else by index."""
    def key(i, it):
        if not isinstance(it, dict):
            return None
        if "level" in it and "mode" in it:
            return f"level {it['level']} mode {it['mode']}"
        if "level" in it:
            return f"level {it['level']}"
        if isinstance(it.get("causes"), list):
            return "+".join(map(str, it["causes"])) or "none"
        if "from_level" in it and "to_level" in it:
            return f"{it['from_level']}->{it['to_level']}"
        if isinstance(it.get("file"), str):
            return Path(it["file"]).name
        return None
    keys = [key(i, it) for i, it in enumerate(items)]
    if all(k is not None for k in keys) and len(set(keys)) == len(keys):
        return dict(zip(keys, items))
    return {str(i): it for i, it in enumerate(items)}


class Diff:
    def __init__(self, workload):
        self.workload = workload
        self.sd = []          # (ratio, path, a, b, sd, how, acceptance?)
        self.rel = []         # (rel, path, a, b)
        self.verdicts = []    # (path, a, b)
        self.words = []
        self.text_numbers = []
        self.structure = []
        self.numbers = self.identical = 0

    def compare(self, a, b, path="", parent=None, key=None, masks=()):
        if key in SKIP_KEYS:
            return
        if isinstance(a, dict) and isinstance(b, dict):
            for k in list(a) + [k for k in b if k not in a]:
                p = f"{path}.{k}" if path else str(k)
                if k not in a or k not in b:
                    if k not in SKIP_KEYS:
                        self._missing(p, k, k in a, k in b)
                    continue
                self.compare(a[k], b[k], p, a, k, masks)
            return
        if isinstance(a, list) and isinstance(b, list):
            if all(_num(x) for x in a + b) and len(a) == len(b):
                for i, (x, y) in enumerate(zip(a, b)):
                    self._numbers(x, y, f"{path}[{i}]", None, None)
                return
            if (a or b) and all(isinstance(x, str) for x in a + b) \
                    and key not in VERDICT_KEYS | {"causes"}:
                self._texts(a, b, path, masks)
                return
            ka, kb = _keyed(a), _keyed(b)
            if list(ka) != list(kb) and key in VERDICT_KEYS | {"causes"}:
                self.verdicts.append((path, _short(a), _short(b)))
                return
            for k in list(ka) + [k for k in kb if k not in ka]:
                p = f"{path}[{k}]"
                if k not in ka or k not in kb:
                    self._missing(p, key, k in ka, k in kb, ka.get(k, kb.get(k)))
                    continue
                self.compare(ka[k], kb[k], p, None, key, masks)
            return
        if _num(a) and _num(b):
            self._numbers(a, b, path, parent, key)
            return
        sa, sb = _mask_paths(a, masks[0]), _mask_paths(b, masks[1] if len(masks) > 1 else "")
        if sa == sb:
            return
        verdict = key in VERDICT_KEYS or (isinstance(key, str) and key.startswith("verdict"))
        if verdict:
            self.verdicts.append((path, _short(sa), _short(sb)))
        elif isinstance(sa, str) and isinstance(sb, str) and \
                NUMBER.sub("#", sa) == NUMBER.sub("#", sb):
            self.text_numbers.append((path, _short(sa), _short(sb)))
        else:
            self.words.append((path, _short(sa), _short(sb)))

    def _texts(self, a, b, path, masks):
        """Two lists of messages (warnings, statements), aligned on their words (numbers
        masked): a message one side has and the other not is a word mismatch, an aligned
        pair whose numbers differ counts as a number-in-text difference."""
        ma = [_mask_paths(x, masks[0] if masks else "") for x in a]
        mb = [_mask_paths(x, masks[1] if len(masks) > 1 else "") for x in b]
        sk_a, sk_b = [NUMBER.sub("#", x) for x in ma], [NUMBER.sub("#", x) for x in mb]
        sm = difflib.SequenceMatcher(a=sk_a, b=sk_b, autojunk=False)
        for op, i1, i2, j1, j2 in sm.get_opcodes():
            if op == "equal":
                for i, j in zip(range(i1, i2), range(j1, j2)):
                    if ma[i] != mb[j]:
                        self.text_numbers.append((f"{path}[{i}]", _short(ma[i]), _short(mb[j])))
                continue
            for i in range(i1, i2):
                self.words.append((f"{path}[{i}]", _short(ma[i]), "absent"))
            for j in range(j1, j2):
                self.words.append((f"{path}[{j}]", "absent", _short(mb[j])))

    def _missing(self, path, key, in_a, in_b, item=None):
        """A key or list item that one side has and the other not: words (a verdict's:
        a verdict mismatch); the modes and rows of an identification are compared apart."""
        what = ("present" if in_a else "absent", "present" if in_b else "absent")
        if item is not None and not isinstance(item, (dict, list)):
            what = (_short(item), "absent") if in_a else ("absent", _short(item))
        if key in VERDICT_KEYS:
            self.verdicts.append((path, *what))
        else:
            self.words.append((path, *what))

    def _numbers(self, a, b, path, parent, key):
        self.numbers += 1
        fa, fb = float(a), float(b)
        if fa == fb or (math.isnan(fa) and math.isnan(fb)):
            self.identical += 1
            return
        if not (math.isfinite(fa) and math.isfinite(fb)):
            self.words.append((path, a, b))
            return
        s = _sd(parent, key) if parent is not None else None
        if s is not None:
            acc = self.workload == "identify" and key in ("omega2", "zeta")
            self.sd.append((abs(fa - fb) / s[0], path, fa, fb, s[0], s[1], acc))
        else:
            self.rel.append((abs(fa - fb) / max(abs(fa), abs(fb)), path, fa, fb))


def _mask_paths(x, folder):
    return x.replace(folder, "<cfg>") if isinstance(x, str) and folder else x


def _short(x, n=170):
    s = json.dumps(x, default=str) if not isinstance(x, str) else x
    return s if len(s) <= n else s[: n - 3] + "..."


def compare_all(out: Path, manifest: dict):
    configs = list(manifest["configs"])
    ref = configs[0]
    results = []          # (config, workload, label, Diff, notes)
    for name in configs[1:]:
        for wl, label, argv, table, needs in manifest["runs"]:
            rid = run_id(wl, label)
            d = Diff(wl)
            ra = manifest["configs"][ref]["runs"].get(rid, {})
            rb = manifest["configs"][name]["runs"].get(rid, {})
            if ra.get("rc") != rb.get("rc"):
                d.structure.append(("exit status", ra.get("rc"), rb.get("rc")))
            ca, cb = out / "configs" / ref, out / "configs" / name
            da, db = load_doc(ca, wl, label, table), load_doc(cb, wl, label, table)
            sa, sb = structure(wl, da), structure(wl, db)
            if sa != sb:
                d.structure.append(("modes/rows", sa, sb))
            if da is not None and db is not None:
                d.compare(da, db, masks=(str(ca), str(cb)))
            elif (da is None) != (db is None):
                d.structure.append(("output", "present" if da else "absent",
                                    "present" if db else "absent"))
            results.append((name, wl, label, d, (ra, rb)))
    return ref, results


def report(out: Path, manifest: dict, top: int):
    configs = list(manifest["configs"])
    ref = configs[0]
    print(f"\n=== BLAS configurations (compared with the first, {ref}) ===")
    first = manifest["configs"][ref]["probe"]
    if "error" not in first:
        print(f"  numpy {first['numpy']} (built with BLAS {first['numpy_blas']} "
              f"{first['numpy_blas_version']}), scipy {first['scipy']}, "
              f"Python {(manifest.get('python') or '?').split()[0]}")
    keys = {}
    for name in configs:
        c = manifest["configs"][name]
        info = c["probe"]
        same = [o for o, kk in keys.items() if kk == kernel_key(info)]
        keys[name] = kernel_key(info)
        extra = f"  (same BLAS kernel and threads as {same[0]})" if same else ""
        print(f"  {name:<18} {kernel_text(info)}{extra}")
        for note in config_effect(name, c["env"], info):
            print(f"    NOTE {note}")
        if info.get("identify_one_thread") is True and name == ref:
            print("    NOTE ident.identify runs BLAS on one thread whatever the configuration "
                  "(threadpool_limits): threadsN changes only what runs outside it")
    if len(configs) < 2:
        print("one configuration: nothing to compare")
        return
    _, results = compare_all(out, manifest)

    print(f"\n=== largest differences per workload and configuration (vs {ref}) ===")
    print("  sd-ratio: |difference| / own sd (identify: omega2, zeta with their std columns = "
          f"the acceptance, < {THRESHOLD_SD}); rel: numbers without a sd")
    head = (f"  {'config':<16} {'workload':<9} {'ident sd':>9} {'other sd':>9} {'rel':>9} "
            f"{'identical':>15} {'verdict':>7} {'struct':>6} {'words':>5} {'txt#':>5}")
    print(head)
    fail = []
    agg = {}
    for name, wl, label, d, _ in results:
        a = agg.setdefault((name, wl), {"acc": [], "sd": [], "rel": [], "n": 0, "same": 0,
                                        "v": [], "s": [], "w": [], "t": 0})
        a["acc"] += [(r, f"{label}: {p}", x, y, s) for r, p, x, y, s, how, acc in d.sd if acc]
        a["sd"] += [(r, f"{label}: {p}", x, y, s) for r, p, x, y, s, how, acc in d.sd if not acc]
        a["rel"] += [(r, f"{label}: {p}", x, y) for r, p, x, y in d.rel]
        a["n"] += d.numbers
        a["same"] += d.identical
        a["v"] += [(label, *v) for v in d.verdicts]
        a["s"] += [(label, *v) for v in d.structure]
        a["w"] += [(label, *v) for v in d.words]
        a["t"] += len(d.text_numbers)
    for (name, wl), a in agg.items():
        mx = lambda L: max((r for r, *_ in L), default=0.0)  # noqa: E731
        acc = f"{mx(a['acc']):.3g}" if wl == "identify" else "-"
        print(f"  {name:<16} {wl:<9} {acc:>9} {mx(a['sd']):>9.3g} {mx(a['rel']):>9.2g} "
              f"{a['same']:>7}/{a['n']:<7} {len(a['v']):>7} {len(a['s']):>6} {len(a['w']):>5} "
              f"{a['t']:>5}")
        if wl == "identify" and mx(a["acc"]) >= THRESHOLD_SD:
            fail.append(f"{name}: identified omega2/zeta differ by up to {mx(a['acc']):.3g} sd")
        if a["v"]:
            fail.append(f"{name}: {len(a['v'])} verdict mismatch(es) in {wl}")
        if a["s"]:
            fail.append(f"{name}: {len(a['s'])} structure mismatch(es) in {wl}")

    print(f"\n=== per input (runs with any difference; sd = largest sd-ratio, identify: "
          "omega2/zeta) ===")
    for name in configs[1:]:
        mine = [(wl, label, d, rr) for n, wl, label, d, rr in results if n == name]
        same = [m for m in mine if not (m[2].sd or m[2].rel or m[2].verdicts or m[2].words
                                        or m[2].structure or m[2].text_numbers)]
        print(f"  {name}: {len(same)} of {len(mine)} runs bitwise identical to {ref}")
        for wl, label, d, rr in mine:
            if (wl, label, d, rr) in same:
                continue
            acc = [r for r, *_, is_acc in d.sd if is_acc] if wl == "identify" else \
                [r for r, *_ in d.sd]
            rel = max((r for r, *_ in d.rel), default=0.0)
            print(f"    {wl:<9} {label:<28} sd {max(acc, default=0.0):8.3g}  rel {rel:8.2g}  "
                  f"identical {d.identical}/{d.numbers}  verdict {len(d.verdicts)} "
                  f"struct {len(d.structure)} words {len(d.words)} txt# {len(d.text_numbers)}")

    for (name, wl), a in agg.items():
        lines = []
        for title, L, sd in (("identified omega2/zeta [sd]", a["acc"], True),
                             ("other numbers with a sd [sd]", a["sd"], True),
                             ("numbers without a sd [relative]", a["rel"], False)):
            if not L:
                continue
            lines.append(f"   {title}:")
            seen, shown = set(), []
            for item in sorted(L, key=lambda t: -t[0]):     # one line per number
                tag = (item[1].split(":", 1)[0], item[2], item[3])
                if tag not in seen:
                    seen.add(tag)
                    shown.append(item)
            for item in shown[:top]:
                r, where, x, y = item[:4]
                tail = f" (sd {item[4]:.3g})" if sd else ""
                lines.append(f"     {r:9.3g}  {where}: {x:.10g} -> {y:.10g}{tail}")
        for title, L in (("VERDICT mismatches", a["v"]), ("STRUCTURE mismatches", a["s"]),
                         ("word mismatches (numbers masked)", a["w"])):
            if L:
                lines.append(f"   {title} ({len(L)}):")
                lines += [f"     {lab}: {p}: {_short(x)}  |  {_short(y)}" for lab, p, x, y in L]
        if lines:
            print(f"\n-- {name} / {wl}")
            print("\n".join(lines))

    print("\n=== timings ===")
    for name in configs:
        c = manifest["configs"][name]
        per = {}
        for rid, r in c["runs"].items():
            wl = rid.split("-", 1)[0]
            per[wl] = per.get(wl, 0.0) + r.get("seconds", 0.0)
        crashed = [rid for rid, r in c["runs"].items() if r.get("rc") not in (0, None)]
        print(f"  {name:<18} {c.get('seconds', 0):6.0f} s  ("
              + ", ".join(f"{k} {v:.0f} s" for k, v in per.items()) + ")"
              + (f"  crashed: {', '.join(crashed)}" if crashed else ""))
    if "total_seconds" in manifest:
        print(f"  total {manifest['total_seconds']:.0f} s (data {manifest['data_seconds']:.0f} s)")
    crashes = sorted({rid for c in manifest["configs"].values() for rid, r in c["runs"].items()
                      if r.get("rc") not in (0, None)})
    for rid in crashes:
        rcs = {n: manifest["configs"][n]["runs"][rid].get("rc") for n in configs}
        msg = next((manifest["configs"][n]["runs"][rid].get("stderr_last") for n in configs
                    if rcs[n] not in (0, None)), "")
        print(f"  NOTE {rid} exits {rcs}: {msg}")
    print("\n" + ("PASS" if not fail else "FAIL") + f": acceptance (identified omega2/zeta "
          f"< {THRESHOLD_SD} sd; equal verdicts, causes and structure)")
    for f in fail:
        print(f"  {f}")


# ------------------------------------------------------------------------------ main

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", default=DEFAULT_CONFIGS,
                    help=f"configurations, the first is the reference (default {DEFAULT_CONFIGS})")
    ap.add_argument("--workloads", default=",".join(WORKLOADS),
                    help="any of identify,estimate,diagnose,loop (estimate/diagnose use the "
                         "identified tables when identify runs, else only the shipped data)")
    ap.add_argument("--chains", default=DEFAULT_CHAINS,
                    help="seeds of the drawn SDOF chains ('' for none)")
    ap.add_argument("--no-beam", action="store_true",
                    help="no identification of the double beam's simulated FRFs")
    ap.add_argument("--out", default=str(ROOT / "results" / "blas_repro"),
                    help="folder of the run (emptied first; its own files only)")
    ap.add_argument("--top", type=int, default=5, help="largest differences listed per kind")
    ap.add_argument("--compare-only", action="store_true",
                    help="compare the outputs of the last run in --out again")
    args = ap.parse_args(argv)
    out = Path(args.out).resolve()

    if args.compare_only:
        manifest = json.loads((out / MARKER).read_text())
        report(out, manifest, args.top)
        return 0

    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    for c in configs:
        parse_config(c)
    workloads = [w.strip() for w in args.workloads.split(",") if w.strip()]
    bad = [w for w in workloads if w not in WORKLOADS]
    if bad:
        raise SystemExit(f"blas_repro: --workloads: unknown {bad}; choose from {WORKLOADS}")
    chains = [int(s) for s in args.chains.split(",") if s.strip()]
    if out.exists() and any(out.iterdir()) and not (out / MARKER).exists():
        raise SystemExit(f"blas_repro: {out} holds files of something else; choose --out")
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)

    t0 = time.perf_counter()
    sets = make_data(out / "data", chains, "identify" in workloads and not args.no_beam) \
        if "identify" in workloads else {}
    t_data = time.perf_counter() - t0
    runs = plan(sets, workloads)
    manifest = {"configs": {}, "runs": runs, "workloads": workloads, "python": sys.version}
    (out / MARKER).write_text(json.dumps(manifest, indent=1))
    print(f"{len(runs)} runs x {len(configs)} configurations, one at a time; outputs in {out}",
          flush=True)
    execute(runs, configs, out, manifest)
    manifest["total_seconds"] = time.perf_counter() - t0
    manifest["data_seconds"] = t_data
    (out / MARKER).write_text(json.dumps(manifest, indent=1, default=str))
    report(out, manifest, args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())
