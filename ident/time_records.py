"""Time records of a free-decay test (CSV, UFF 58 time data): read and write.

``docs/formats/measured-data.md``, "Other test types", ``free-decay``. CSV::

    # test = free-decay
    # quantity = displacement
    # reference = 3
    time_s,3,7

optional ``# key = value`` lines (``test``: ``free-decay``, the default of a time
record; ``quantity``: ``displacement`` (m), ``velocity`` (m/s) or ``acceleration``
(m/s^2), default displacement; ``reference``: the point whose amplitude is the
abscissa, default the first), then a header ``time_s`` (s, uniformly sampled,
increasing) and one column per point (any label without a comma). UFF: data sets 58
with function type 1 (time response), abscissa in s, one per point, the same axis;
quantity from the ordinate data type (8/11/12); ``test=``/``reference=`` keys may stand
in the ID lines. Errors are :class:`ident.errors.InputError`, one line.
"""
from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ident.errors import InputError, text_file
from ident.uff_sets import read_uff_sets

QUANTITIES = ("displacement", "velocity", "acceleration")
_UFF_CODE = {8: "displacement", 11: "velocity", 12: "acceleration"}
KEYS = ("test", "quantity", "reference")
#: Largest distance of a sample time from the fitted uniform grid, in time steps
#: (rounded printed times pass; a dropped or doubled sample does not).
UNIFORM_TOLERANCE = 0.25


@dataclass
class TimeRecord:
    """A free-decay record: ``time_s`` (n,), ``signals`` (n, n_points) in SI units of
    ``quantity``, ``points`` labels, the ``reference`` point's index, ``source``."""

    time_s: np.ndarray
    signals: np.ndarray
    points: list
    quantity: str = "displacement"
    reference: int = 0
    source: str = ""

    def __post_init__(self):
        self.time_s = np.asarray(self.time_s, float)
        self.signals = np.asarray(self.signals, float)
        if self.signals.ndim == 1:
            self.signals = self.signals[:, None]
        self.points = [str(p) for p in self.points]
        where = self.source or "time record"
        if self.signals.shape != (self.time_s.size, len(self.points)):
            raise InputError(f"{where}: signals have shape {self.signals.shape}, expected "
                             f"({self.time_s.size}, {len(self.points)})")
        if self.quantity not in QUANTITIES:
            raise InputError(f"{where}: quantity must be one of {', '.join(QUANTITIES)}, "
                             f"got {self.quantity!r}")
        if not (np.all(np.isfinite(self.time_s)) and np.all(np.isfinite(self.signals))):
            raise InputError(f"{where}: non-finite time or signal value")
        if self.time_s.size < 16:
            raise InputError(f"{where}: {self.time_s.size} samples; a decay needs many more")
        k = np.arange(self.time_s.size)
        dt, t0 = np.polyfit(k, self.time_s, 1)
        off = np.abs(self.time_s - (t0 + dt * k)).max()
        if np.any(np.diff(self.time_s) <= 0) or not off < UNIFORM_TOLERANCE * dt:
            raise InputError(f"{where}: time_s must increase in uniform steps (a sampled "
                             f"record; a sample is {off / dt:.3g} steps off the uniform grid)")
        self.time_s = t0 + dt * k      # printed times carry rounding: the grid they state

    @property
    def sample_rate(self) -> float:
        """Samples per second, Hz."""
        return (self.time_s.size - 1) / (self.time_s[-1] - self.time_s[0])


def _reference_index(points, reference, where) -> int:
    if reference is None:
        return 0
    if str(reference) not in points:
        raise InputError(f"{where}: reference point {reference!r} not among the columns "
                         f"({', '.join(points)})")
    return points.index(str(reference))


def read_time_csv(path, reference=None) -> TimeRecord:
    """Read a CSV time record (module doc); ``reference`` overrides the file's."""
    src = str(path)
    meta, rows, header = {}, [], None
    with text_file(Path(path), src) as fh:
        for lineno, text in enumerate(fh, start=1):
            s = text.strip()
            if not s:
                continue
            if header is None and s.startswith("#"):
                key, eq, value = (t.strip() for t in s[1:].partition("="))
                if not eq or key not in KEYS:
                    raise InputError(f"{src}:{lineno}: header line must read '# key = value' "
                                     f"with key one of {', '.join(KEYS)}")
                meta[key] = value
                continue
            fields = [t.strip() for t in s.split(",")]
            if header is None:
                header = fields
                if header[0] != "time_s" or len(header) < 2:
                    raise InputError(f"{src}:{lineno}: header must read time_s,<point>,...")
                continue
            if len(fields) != len(header):
                raise InputError(f"{src}:{lineno}: row has {len(fields)} fields, header has "
                                 f"{len(header)}")
            try:
                rows.append([float(t) for t in fields])
            except ValueError:
                raise InputError(f"{src}:{lineno}: not a number in {s[:60]!r}") from None
    if header is None:
        raise InputError(f"{src}: no header line time_s,<point>,...")
    if meta.get("test", "free-decay").lower() != "free-decay":
        raise InputError(f"{src}: a time record is a free-decay test, the file says "
                         f"test = {meta['test']}")
    values = np.array(rows, float).reshape(-1, len(header))
    points = header[1:]
    return TimeRecord(values[:, 0], values[:, 1:], points,
                      meta.get("quantity", "displacement").lower(),
                      _reference_index(points, reference or meta.get("reference"), src), src)


def read_time_uff(path, reference=None) -> TimeRecord:
    """Read the time responses (data sets 58, function type 1) of a universal file."""
    src = str(path)
    sets = [s for s in read_uff_sets(path, 58) if int(s.get("func_type", 0)) == 1]
    if not sets:
        raise InputError(f"{src}: no time response (data set 58, function type 1)")
    t = np.asarray(sets[0]["x"], float)
    for k, s in enumerate(sets[1:], start=2):
        if np.shape(s["x"]) != t.shape or not np.allclose(s["x"], t, rtol=1e-9, atol=0):
            raise InputError(f"{src}: record {k} has a different time axis than record 1")
    points = [f"{int(s['rsp_node'])}" + ("" if int(s.get("rsp_dir", 0)) == 0
                                          else f"{int(s['rsp_dir']):+d}") for s in sets]
    codes = {int(s.get("ordinate_spec_data_type", 0)) for s in sets}
    quantity = _UFF_CODE.get(codes.pop(), "displacement") if len(codes) == 1 else "displacement"
    ids = " ".join(str(sets[0].get(f"id{i}", "")) for i in range(1, 6))
    keys = dict(kv.split("=", 1) for kv in ids.split() if "=" in kv)
    if keys.get("test", "free-decay").lower() != "free-decay":
        raise InputError(f"{src}: a time record is a free-decay test, the file says "
                         f"test = {keys['test']}")
    data = np.stack([np.real(np.asarray(s["data"])) for s in sets], axis=1)
    return TimeRecord(t, data, points, quantity,
                      _reference_index(points, reference or keys.get("reference"), src), src)


def read_time_record(path, reference=None) -> TimeRecord:
    """CSV (``.csv``) or universal file (``.uff``, ``.unv``, ``.uf``) time record."""
    ext = Path(path).suffix.lower()
    return read_time_uff(path, reference) if ext in (".uff", ".unv", ".uf") \
        else read_time_csv(path, reference)


def write_time_csv(path, record: TimeRecord) -> None:
    """Write a CSV time record (17 significant digits)."""
    lines = ["# test = free-decay", f"# quantity = {record.quantity}",
             f"# reference = {record.points[record.reference]}",
             ",".join(["time_s"] + record.points)]
    table = np.column_stack([record.time_s, record.signals])
    lines += [",".join(repr(float(v)) for v in row) for row in table]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_time_uff(path, record: TimeRecord) -> None:
    """Write a time record as ASCII UFF data sets 58, function type 1 (one per point,
    point labels must be node numbers)."""
    import pyuff

    code = {v: k for k, v in _UFF_CODE.items()}[record.quantity]
    dt = float(np.mean(np.diff(record.time_s)))
    dsets = [dict(type=58, binary=0, func_type=1, id1="iwanfe time record",
                  id4=f"test=free-decay reference={record.points[record.reference]}",
                  rsp_node=int(p), rsp_dir=0, ref_node=int(record.points[record.reference]),
                  ref_dir=0, rsp_ent_name="iwanfe", ref_ent_name="iwanfe",
                  abscissa_spacing=1, abscissa_spec_data_type=17,
                  ordinate_spec_data_type=code, orddenom_spec_data_type=0,
                  x=record.time_s[0] + dt * np.arange(record.time_s.size),
                  data=record.signals[:, j].copy())
             for j, p in enumerate(record.points)]
    Path(path).unlink(missing_ok=True)
    with contextlib.redirect_stdout(io.StringIO()):
        pyuff.UFF(str(path)).write_sets(dsets, mode="overwrite")


def is_time_record(path) -> bool:
    """True for a CSV whose header starts ``time_s`` or that says ``# test =
    free-decay``, and for a universal file holding time responses (function type 1)."""
    path = Path(path)
    if path.suffix.lower() in (".uff", ".unv", ".uf"):
        try:
            return any(int(s.get("func_type", 0)) == 1 for s in read_uff_sets(path, 58))
        except InputError:
            return False
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            for line in fh:
                s = line.strip().replace(" ", "").lower()
                if not s:
                    continue
                if s.startswith("#test=free-decay") or s.startswith("time_s"):
                    return True
                if not s.startswith("#"):
                    return False
    except OSError as exc:
        raise InputError(f"{path}: {exc.strerror or exc}") from None
    return False
