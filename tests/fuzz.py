"""Property-based fuzzing (hypothesis) of the file readers.

Readers: :func:`ident.measured.read_measured` (measured-data CSV),
:func:`ident.frf_files.read_frf_csv` (FRF CSV) and :func:`ident.frf_files.read_frf_uff`
(UFF 58). Inputs: random bytes; a valid file cut at any byte; byte mutations of a valid
file (bytes replaced, inserted, deleted); line mutations (a line dropped or repeated, two
lines swapped, a field replaced by an extreme number or by garbage, a field dropped).

The only outcomes allowed:

* ``InputError`` with one line that starts with the file name, or
* a result that keeps the reader's contract, checked here independently of the reader
  (finite values, ranges, shapes, orderings), and, for a valid file cut at a byte, equals
  the uncut file's reading on every complete line or data set. (A cut inside the *last
  number* of a text file leaves a shorter number that no reader can tell from a real one;
  the check allows exactly that and nothing else.)

Anything else (another exception, a traceback, a result breaking the contract) fails.

The test suite runs a bounded number of examples per reader (``tests/test_fuzz.py``). The
long run, at least 10,000 inputs per reader::

    .venv/bin/python tests/fuzz.py --examples 10000            # all readers
    .venv/bin/python tests/fuzz.py --examples 10000 --reader uff
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from ident.errors import InputError  # noqa: E402
from ident.frf_files import FRFSet, read_frf_csv, read_frf_uff, write_frf_csv, write_frf_uff  # noqa: E402
from ident.measured import read_measured  # noqa: E402

READERS = ("measured", "frf_csv", "uff")

#: Field texts that stress number parsing: extremes, specials, garbage.
EXTREME_FIELDS = ["nan", "inf", "-inf", "1e309", "-1e309", "1e-320", "5e-324", "0", "-0",
                  "1e308", "-1e308", "9" * 400, "", " ", "0x10", "1_000", "1e", "--1",
                  "\u00a0", "1,5", "\"2\"", "NaN", "Infinity", "1e-300", "2.5e-7",
                  "123456789012345678901234567890", "-1", "0.99999999999999999", "1.0"]


# ------------------------------------------------------------------------ seed files

def measured_seeds() -> list[bytes]:
    """The shipped measured data and a file with every optional column."""
    shipped = (ROOT / "cases/data/double_beam_measured.csv").read_bytes()
    rows = ["level,excitation,omega2,zeta,mode,response_amplitude,run_order,omega2_std,"
            "zeta_std,control,x_note"]
    for k in range(1, 7):
        rows.append(f"{k},{0.5 * 2 ** k},{2.5e6 - 30 * k},{0.0128 + 1e-5 * k},1,"
                    f"{1e-6 * 2 ** k},{7 - k},{10.0 + k},{1e-5},force,n{k}")
    return [shipped, ("\n".join(rows) + "\n").encode()]


def frf_set(n_lines: int = 24, n_points: int = 2) -> FRFSet:
    """A small 2-mode receptance set (deterministic)."""
    f = (np.linspace(40.0, 60.0, n_lines) if n_lines < 40
         else np.arange(40.0, 40.0 + 0.5 * n_lines, 0.5))
    w = 2 * np.pi * f[:, None]
    wn = 2 * np.pi * np.array([45.0, 55.0])
    phi = np.array([[1.0, 0.7], [0.6, -0.9]])[:n_points]
    H = (phi[:, None, :] * phi[0] / (wn**2 - w**2 + 2j * 0.02 * wn * w)).sum(axis=2).T
    return FRFSet(f, H, [f"{p + 1}+Z" for p in range(n_points)], "receptance", 2.5, "1+Z")


def frf_csv_seed() -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "s.csv"
        write_frf_csv(p, frf_set())
        return p.read_bytes()


def uff_seed() -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "s.uff"
        s = frf_set(n_lines=40)
        write_frf_uff(p, s)
        return p.read_bytes()


# ------------------------------------------------------------------------ contracts

def _one_line_error(exc: InputError, path: Path) -> None:
    msg = str(exc)
    assert "\n" not in msg, f"multi-line error: {msg!r}"
    assert msg.startswith(str(path)), f"error does not name the file: {msg!r}"


def check_measured(data) -> None:
    """The measured-data contract (docs/formats/measured-data.md), checked here."""
    n = len(data.level)
    for name in ("excitation", "omega2", "zeta", "mode", "run_order"):
        assert np.shape(getattr(data, name)) == (n,), name
    assert np.all(np.isfinite(data.excitation)) and np.all(data.excitation > 0)
    assert np.all(np.isfinite(data.omega2)) and np.all(data.omega2 > 0)
    assert np.all((data.zeta > 0) & (data.zeta < 1))
    assert np.all(data.level >= 1)
    for opt in ("response_amplitude", "omega2_std", "zeta_std"):
        v = getattr(data, opt)
        if v is not None:
            assert np.shape(v) == (n,) and np.all(np.isfinite(v)) and np.all(v > 0), opt
    pairs = set(zip(data.mode.tolist(), data.level.tolist()))
    assert len(pairs) == n, "duplicate (mode, level)"
    for m in np.unique(data.mode):
        sel = np.flatnonzero(data.mode == m)
        assert sel.size >= 4
        order = sel[np.argsort(data.level[sel])]
        held = data.held_amplitude[order]
        assert np.all(np.diff(held) > 0), "held amplitude must rise with the level"


def check_frf(s) -> None:
    """The FRF-set contract: >= 2 lines, frequencies > 0 strictly increasing, finite."""
    assert s.freq_hz.ndim == 1 and s.freq_hz.size >= 2
    assert np.all(np.isfinite(s.freq_hz)) and s.freq_hz[0] > 0
    assert np.all(np.diff(s.freq_hz) > 0)
    assert s.frf.shape == (s.freq_hz.size, len(s.points)) and len(s.points) >= 1
    assert np.all(np.isfinite(s.frf))
    if s.excitation is not None:
        assert math.isfinite(s.excitation) and s.excitation > 0


def check_truncated_measured(data, full, text: bytes) -> None:
    """Rows read from a cut file equal the uncut file's; in the last row, if the cut
    fell inside it, every column but the header's last one."""
    n = len(data.level)
    assert n <= len(full.level)
    last_col = text.split(b"\n")[0].decode("utf-8", "replace").split(",")[-1].strip()
    short = not text.endswith((b"\n", b"\r"))
    for name in ("level", "excitation", "omega2", "zeta", "mode"):
        a, b = getattr(data, name), getattr(full, name)[:n]
        if short and name == last_col:
            a, b = a[:-1], b[:-1]
        assert np.array_equal(a, b), f"{name} differs from the uncut file"


def check_truncated_frf(s, full, text: bytes, binary_sets: bool) -> None:
    n = s.freq_hz.size
    if binary_sets:   # UFF: whole data sets only, every line of each
        assert s.points == full.points[:len(s.points)]
        assert np.array_equal(s.freq_hz, full.freq_hz)
        assert np.array_equal(s.frf, full.frf[:, :len(s.points)])
        return
    assert s.points == full.points and n <= full.freq_hz.size
    short = not text.endswith((b"\n", b"\r"))
    assert np.array_equal(s.freq_hz[:n - 1 if short else n], full.freq_hz[:n - 1 if short else n])
    good = s.frf[:n - 1] if short else s.frf
    assert np.array_equal(good, full.frf[:good.shape[0]])
    if short:   # the last line: all but its last number exact
        assert s.freq_hz[-1] == full.freq_hz[n - 1] or len(s.points) == 0
        assert np.array_equal(s.frf[-1, :-1], full.frf[n - 1, :-1])
        assert s.frf[-1, -1].real == full.frf[n - 1, -1].real


# ------------------------------------------------------------------------ strategies

def _mutations(seed: bytes):
    """Byte-level and line-level mutations of ``seed``."""
    n = len(seed)
    lines = seed.split(b"\n")
    pos = st.integers(0, max(n - 1, 0))
    line = st.integers(0, max(len(lines) - 1, 0))
    replace = st.tuples(st.just("replace"), pos, st.binary(min_size=1, max_size=8))
    insert = st.tuples(st.just("insert"), pos, st.binary(min_size=1, max_size=8))
    delete = st.tuples(st.just("delete"), pos, st.integers(1, 64))
    drop = st.tuples(st.just("drop"), line, st.just(0))
    dup = st.tuples(st.just("dup"), line, st.just(0))
    swap = st.tuples(st.just("swap"), line, line)
    field = st.tuples(st.just("field"), line, st.tuples(st.integers(0, 12),
                                                         st.sampled_from(EXTREME_FIELDS)))
    unfield = st.tuples(st.just("unfield"), line, st.integers(0, 12))
    return st.lists(st.one_of(replace, insert, delete, drop, dup, swap, field, unfield),
                    min_size=1, max_size=4)


def apply_mutations(seed: bytes, ops) -> bytes:
    data = seed
    for kind, a, b in ops:
        if kind in ("replace", "insert", "delete"):
            a = min(a, len(data))
            if kind == "replace":
                data = data[:a] + b + data[a + len(b):]
            elif kind == "insert":
                data = data[:a] + b + data[a:]
            else:
                data = data[:a] + data[a + b:]
            continue
        lines = data.split(b"\n")
        if not lines:
            continue
        a = min(a, len(lines) - 1)
        if kind == "drop":
            del lines[a]
        elif kind == "dup":
            lines.insert(a, lines[a])
        elif kind == "swap":
            b = min(b, len(lines) - 1)
            lines[a], lines[b] = lines[b], lines[a]
        elif kind in ("field", "unfield"):
            sep = b"," if b"," in lines[a] else b" "
            fields = lines[a].split(sep)
            k = (b[0] if kind == "field" else b) % max(len(fields), 1)
            if kind == "field":
                if sep == b" ":   # UFF: fixed columns; put the text where a number was
                    fields[k] = b[1].encode("utf-8")[:max(len(fields[k]), 1)].rjust(len(fields[k]))
                else:
                    fields[k] = b[1].encode("utf-8")
            elif fields:
                del fields[k]
            lines[a] = sep.join(fields)
        data = b"\n".join(lines)
    return data


def inputs(seeds: list[bytes]):
    """(kind, bytes, seed index): random bytes, a cut, or mutations of a seed."""
    which = st.integers(0, len(seeds) - 1)
    rand = st.tuples(st.just("bytes"), st.binary(max_size=3000), st.just(-1))
    cut = which.flatmap(lambda i: st.tuples(st.just("cut"), st.integers(0, len(seeds[i])).map(
        lambda k, i=i: seeds[i][:k]), st.just(i)))
    mut = which.flatmap(lambda i: st.tuples(st.just("mutated"), _mutations(seeds[i]).map(
        lambda ops, i=i: apply_mutations(seeds[i], ops)), st.just(i)))
    return st.one_of(rand, cut, mut)


# ------------------------------------------------------------------------ one example

class Fuzzer:
    """Holds the seeds, their readings and a scratch folder; ``check(reader, example)``
    asserts the allowed outcomes for one input."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self.seeds = {"measured": measured_seeds(), "frf_csv": [frf_csv_seed()],
                      "uff": [uff_seed()]}
        self.read = {"measured": read_measured, "frf_csv": read_frf_csv, "uff": read_frf_uff}
        self.suffix = {"measured": ".csv", "frf_csv": ".csv", "uff": ".uff"}
        self.full = {name: [self._read(name, s) for s in seeds]
                     for name, seeds in self.seeds.items()}
        self.counts = {name: {"result": 0, "refused": 0} for name in READERS}

    def _read(self, name, data: bytes):
        path = self.folder / f"input_{name}{self.suffix[name]}"
        path.write_bytes(data)
        return self.read[name](path)

    def check(self, name: str, example) -> None:
        kind, data, i = example
        path = self.folder / f"input_{name}{self.suffix[name]}"
        path.write_bytes(data)
        try:
            result = self.read[name](path)
        except InputError as exc:
            _one_line_error(exc, path)
            self.counts[name]["refused"] += 1
            return
        self.counts[name]["result"] += 1
        if name == "measured":
            check_measured(result)
            if kind == "cut":
                check_truncated_measured(result, self.full[name][i], data)
        else:
            check_frf(result)
            if kind == "cut":
                check_truncated_frf(result, self.full[name][i], data, name == "uff")


def run(fuzzer: Fuzzer, name: str, examples: int, seed: int | None = None) -> None:
    """Hypothesis over ``examples`` inputs for reader ``name``."""

    @settings(max_examples=examples, deadline=None, database=None, derandomize=seed is not None,
              suppress_health_check=list(HealthCheck), print_blob=True)
    @given(inputs(fuzzer.seeds[name]))
    def prop(example):
        fuzzer.check(name, example)

    prop()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="fuzz the file readers (module docstring)")
    ap.add_argument("--examples", type=int, default=10_000, help="inputs per reader")
    ap.add_argument("--reader", choices=READERS + ("all",), default="all")
    args = ap.parse_args(argv)
    names = READERS if args.reader == "all" else (args.reader,)
    with tempfile.TemporaryDirectory(prefix="iwanfe-fuzz-") as tmp:
        fuzzer = Fuzzer(Path(tmp))
        for name in names:
            t0 = time.perf_counter()
            run(fuzzer, name, args.examples)
            c = fuzzer.counts[name]
            print(f"{name}: {c['result'] + c['refused']} inputs, {c['result']} read, "
                  f"{c['refused']} refused with one line, no other outcome "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
