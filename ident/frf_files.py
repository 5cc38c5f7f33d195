"""FRF files: one FRF set (one reference, one or more response points) per file.

CSV format (written and read here; ``docs/formats/measured-data.md``, "FRF files of a
stepped-sine series")::

    # quantity = receptance
    # control = force
    # run_order = 3
    # excitation = 2.5
    # reference = 1+Z
    freq_hz,re_1+Z,im_1+Z,re_7+Z,im_7+Z,force

* optional leading ``# key = value`` lines, keys ``quantity`` (receptance | mobility |
  accelerance), ``control`` (``force``: the level held a drive amplitude; ``response``:
  it held the drive-point response amplitude), ``run_order`` (integer >= 1, when the
  level was measured), ``excitation`` (> 0: the level held: the drive amplitude, force or
  voltage, under force control; the drive-point response amplitude, in the unit of the
  FRF's response, under response control), ``reference`` (label of the drive point)
  and ``test`` (``stepped-sine`` default, or ``random``: H1 averaged over a random
  record, ``excitation`` its drive RMS; :mod:`ident.frf_header`);
* then one header line: ``freq_hz`` (Hz, strictly increasing, > 0; any spacing) and,
  for every response point ``P``, the pair ``re_P`` / ``im_P`` (real and imaginary part
  of the FRF in SI units: m/N, m/s/N or m/s^2/N). The label ``P`` is any text without
  a comma; points keep the order of their ``re_`` columns. One optional ``force``
  column: the measured force amplitude at the reference on that line (N, > 0); one
  optional ``coherence`` column (0..1, of an averaged estimate: a random test). No
  other columns.

Errors are :class:`ident.errors.InputError` ``FILE:LINE:COLUMN: message`` (1-based line,
column name), like the measured-data reader.

UFF 58 (universal file, via pyuff): every data set 58 with function type 4 (FRF) is a
response point; all must share the reference node/direction and the abscissa.
Point label = ``"<node><+|-><X|Y|Z|RX|RY|RZ>"`` (``"<node>"`` for a scalar direction).
Quantity from the ordinate specific data type (8 displacement -> receptance,
11 velocity -> mobility, 12 acceleration -> accelerance). The keys ``excitation``,
``control``, ``run_order``, ``reference`` and ``test`` may stand in the ID lines of the first data
set as ``key=value`` (the writer puts them in ID line 4); ``reference`` there overrides
the label built from the reference node. A universal file has no force column.
"""
from __future__ import annotations

import contextlib
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ident.errors import InputError, text_file
from ident.frf_header import (CONTROLS, FRF_TESTS, HEADER_KEYS, header_values,
                              id_line_values, parse_control, parse_excitation,
                              parse_run_order, parse_test)
from ident.poles import QUANTITIES
from ident.uff_sets import read_uff_sets

_UFF_ORDINATE = {8: "receptance", 11: "mobility", 12: "accelerance"}
_UFF_ORDINATE_CODE = {v: k for k, v in _UFF_ORDINATE.items()}
_DIRS = {1: "+X", 2: "+Y", 3: "+Z", 4: "+RX", 5: "+RY", 6: "+RZ",
         -1: "-X", -2: "-Y", -3: "-Z", -4: "-RX", -5: "-RY", -6: "-RZ"}
_DIR_CODE = {v: k for k, v in _DIRS.items()}
_LABEL = re.compile(r"^(\d+)([+-]R?[XYZ])?$")


@dataclass
class FRFSet:
    """FRFs of one reference at one excitation level.

    Attributes
    ----------
    freq_hz : (n,) frequencies, Hz.
    frf : (n, n_points) complex FRFs (SI: m/N, m/s/N or m/s^2/N).
    points : list of response-point labels (n_points).
    quantity : "receptance", "mobility", "accelerance" or None if unknown.
    excitation : the level this set held (module doc: drive amplitude under force
        control, drive-point response amplitude under response control) or None.
    reference : drive-point label or None.
    source : file name ("" if built in memory).
    control : "force", "response" or None (not stated).
    run_order : chronological order of the level (int >= 1) or None.
    force : (n,) measured force amplitude at the reference per line (N) or None.
    test : "stepped-sine", "random" or None (not stated: stepped sine).
    coherence : (n,) ordinary coherence at the drive point per line, or None.
    """

    freq_hz: np.ndarray
    frf: np.ndarray
    points: list
    quantity: str | None = None
    excitation: float | None = None
    reference: str | None = None
    source: str = ""
    control: str | None = None
    run_order: int | None = None
    force: np.ndarray | None = None
    test: str | None = None
    coherence: np.ndarray | None = None

    def __post_init__(self):
        self.freq_hz = np.asarray(self.freq_hz, float)
        self.frf = np.asarray(self.frf, complex)
        if self.frf.ndim == 1:
            self.frf = self.frf[:, None]
        self.points = [str(p) for p in self.points]
        if self.frf.shape != (self.freq_hz.size, len(self.points)):
            raise ValueError(f"frf shape {self.frf.shape} does not match "
                             f"({self.freq_hz.size} frequencies, {len(self.points)} points)")
        if self.quantity is not None and self.quantity not in QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, "
                             f"got {self.quantity!r}")
        if self.test is not None and self.test not in FRF_TESTS:
            raise ValueError(f"test must be one of {', '.join(FRF_TESTS)}, got {self.test!r}")
        if self.control is not None and self.control not in CONTROLS:
            raise ValueError(f"control must be force or response, got {self.control!r}")
        for name in ("force", "coherence"):
            v = getattr(self, name)
            if v is not None:
                setattr(self, name, np.asarray(v, float))
                if getattr(self, name).shape != self.freq_hz.shape:
                    raise ValueError(f"{name} has shape {np.shape(v)}, one value per "
                                     f"frequency ({self.freq_hz.size}) is needed")


def _fail(source, line, column, message):
    raise InputError(f"{source}:{line}:{column}: {message}")


# ------------------------------------------------------------------------------- CSV

def read_frf_csv(path) -> FRFSet:
    """Read an FRF CSV file (format in the module docstring)."""
    path = Path(path)
    src = str(path)
    meta: dict[str, tuple[int, str]] = {}
    header = None
    rows = []
    with text_file(path, src) as fh:
        for lineno, text in enumerate(fh, start=1):
            s = text.strip()
            if not s:
                continue
            if header is None and s.startswith("#"):
                if "=" not in s:
                    _fail(src, lineno, 1, "comment line must read '# key = value'")
                key, value = (t.strip() for t in s[1:].split("=", 1))
                if key not in HEADER_KEYS:
                    _fail(src, lineno, key, "unknown key (known: " + ", ".join(HEADER_KEYS) + ")")
                meta[key] = (lineno, value)
                continue
            fields = [t.strip() for t in s.split(",")]
            if header is None:
                header, header_line = fields, lineno
            else:
                rows.append((lineno, fields))
    if header is None:
        _fail(src, 1, 1, "empty file: expected a header line")
    if header[0] != "freq_hz":
        _fail(src, header_line, header[0] or 1, "first column must be 'freq_hz'")
    points, re_col, im_col, extra_col = [], {}, {}, {}
    for j, name in enumerate(header[1:], start=1):
        if name in ("force", "coherence"):
            if name in extra_col:
                _fail(src, header_line, name, "duplicate column name")
            extra_col[name] = j
            continue
        part, _, label = name.partition("_")
        if part not in ("re", "im") or not label:
            _fail(src, header_line, name,
                  "unknown column: expected re_<point>, im_<point>, force or coherence")
        target = re_col if part == "re" else im_col
        if label in target:
            _fail(src, header_line, name, "duplicate column name")
        target[label] = j
        if part == "re":
            points.append(label)
    for label in points:
        if label not in im_col:
            _fail(src, header_line, f"re_{label}", f"no matching column im_{label}")
    for label in im_col:
        if label not in re_col:
            _fail(src, header_line, f"im_{label}", f"no matching column re_{label}")
    if not points:
        _fail(src, header_line, "freq_hz", "no FRF columns (re_<point>, im_<point>)")
    if len(rows) < 2:
        _fail(src, header_line + 1, "freq_hz", "fewer than 2 frequency lines")
    values = np.empty((len(rows), len(header)))
    for i, (lineno, fields) in enumerate(rows):
        if len(fields) != len(header):
            _fail(src, lineno, min(len(fields), len(header)) + 1,
                  f"row has {len(fields)} fields, header has {len(header)}")
        for j, t in enumerate(fields):
            try:
                v = float(t)
            except ValueError:
                _fail(src, lineno, header[j], f"not a number: {t!r}")
            if not math.isfinite(v):
                _fail(src, lineno, header[j], f"not a finite number: {t!r}")
            values[i, j] = v
    freq = values[:, 0]
    lines = np.array([ln for ln, _ in rows])
    bad = np.flatnonzero(freq <= 0)
    if bad.size:
        _fail(src, lines[bad[0]], "freq_hz", f"frequency must be > 0 Hz, got {freq[bad[0]]:g}")
    bad = np.flatnonzero(np.diff(freq) <= 0)
    if bad.size:
        _fail(src, lines[bad[0] + 1], "freq_hz", "frequencies must be strictly increasing")
    frf = values[:, [re_col[p] for p in points]] + 1j * values[:, [im_col[p] for p in points]]
    force = coherence = None
    if "coherence" in extra_col:
        coherence = values[:, extra_col["coherence"]]
        bad = np.flatnonzero((coherence < 0) | (coherence > 1))
        if bad.size:
            _fail(src, lines[bad[0]], "coherence",
                  f"coherence must be in [0, 1], got {coherence[bad[0]]:g}")
    if "force" in extra_col:
        force = values[:, extra_col["force"]]
        bad = np.flatnonzero(force <= 0)
        if bad.size:
            _fail(src, lines[bad[0]], "force", f"force must be > 0 N, got {force[bad[0]]:g}")

    quantity = excitation = reference = None
    if "quantity" in meta:
        ln, quantity = meta["quantity"]
        if quantity not in QUANTITIES:
            _fail(src, ln, "quantity", f"must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    if "excitation" in meta:
        ln, text = meta["excitation"]
        excitation = parse_excitation(text, f"{src}:{ln}:excitation")
    if "reference" in meta:
        reference = meta["reference"][1]
    control = run_order = None
    if "control" in meta:
        ln, text = meta["control"]
        control = parse_control(text, f"{src}:{ln}:control")
    if "run_order" in meta:
        ln, text = meta["run_order"]
        run_order = parse_run_order(text, f"{src}:{ln}:run_order")
    test = parse_test(meta["test"][1], f"{src}:{meta['test'][0]}:test") if "test" in meta else None
    return FRFSet(freq, frf, points, quantity, excitation, reference, src, control,
                  run_order, force, test, coherence)



def write_frf_csv(path, frfset: FRFSet) -> None:
    """Write an FRF set as CSV (17 significant digits: exact round trip)."""
    for p in frfset.points:
        if "," in p or not p:
            raise ValueError(f"point label {p!r} cannot be used as a CSV column name")
    lines = [f"# {key} = {text}" for key, text in header_values(frfset)]
    names = ["freq_hz"] + [f"{k}_{p}" for p in frfset.points for k in ("re", "im")]
    n_pts = len(frfset.points)
    extras = [(k, v) for k, v in (("force", frfset.force), ("coherence", frfset.coherence))
              if v is not None]
    table = np.empty((frfset.freq_hz.size, 1 + 2 * n_pts + len(extras)))
    table[:, 0] = frfset.freq_hz
    table[:, 1:2 * n_pts + 1:2] = frfset.frf.real
    table[:, 2:2 * n_pts + 1:2] = frfset.frf.imag
    for k, (name, v) in enumerate(extras):
        names.append(name)
        table[:, 1 + 2 * n_pts + k] = v
    lines.append(",".join(names))
    lines.extend(",".join(repr(float(v)) for v in row) for row in table)
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


# ------------------------------------------------------------------------------- UFF

def _label(node, direction) -> str:
    return f"{int(node)}{_DIRS.get(int(direction), '')}"


def _node_dir(label: str, default_node: int) -> tuple[int, int]:
    m = _LABEL.match(label)
    if not m:
        return default_node, 0
    return int(m.group(1)), _DIR_CODE.get(m.group(2), 0) if m.group(2) else 0


def read_frf_uff(path) -> FRFSet:
    """Read the FRFs (data sets 58, function type 4) of a universal file.

    A file cut inside a data set, or a data set 58 holding fewer values than its record 7
    announces, is refused (``FILE:LINE: data set K ...``): a truncated file must not give
    fewer response points or lines without a word."""
    src = str(path)
    sets = read_uff_sets(path, 58)    # whole data sets only (ident.uff_sets)
    sets = [s for s in sets if int(s.get("func_type", 0)) == 4]
    if not sets:
        raise InputError(f"{src}: no FRF (data set 58, function type 4) in the file")
    refs = {(int(s["ref_node"]), int(s["ref_dir"])) for s in sets}
    if len(refs) > 1:
        raise InputError(f"{src}: FRFs of {len(refs)} references; one FRF set per file "
                         "needs a single reference")
    x = np.asarray(sets[0]["x"], float)
    for k, s in enumerate(sets[1:], start=2):
        if np.shape(s["x"]) != x.shape or not np.allclose(s["x"], x, rtol=1e-9, atol=0):
            raise InputError(f"{src}: FRF {k} has a different frequency axis than FRF 1")
    frf = np.stack([np.asarray(s["data"], complex) for s in sets], axis=1)
    points = [_label(s["rsp_node"], s["rsp_dir"]) for s in sets]
    if len(set(points)) != len(points):
        raise InputError(f"{src}: duplicate response point in FRFs ({', '.join(points)})")
    codes = {int(s.get("ordinate_spec_data_type", 0)) for s in sets}
    quantity = _UFF_ORDINATE.get(codes.pop()) if len(codes) == 1 else None
    keys = id_line_values(sets[0], src)
    if np.any(np.diff(x) <= 0):
        raise InputError(f"{src}: frequencies must be strictly increasing")
    if x.size < 2 or not x[0] > 0:
        raise InputError(f"{src}: needs at least 2 frequencies, all > 0 Hz")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(frf))):
        raise InputError(f"{src}: non-finite frequency or FRF value")
    reference = keys.get("reference") or _label(*refs.pop())
    return FRFSet(x, frf, points, quantity, keys.get("excitation"), reference, src,
                  keys.get("control"), keys.get("run_order"), test=keys.get("test"))


def write_frf_uff(path, frfset: FRFSet) -> None:
    """Write an FRF set as ASCII universal file data sets 58 (one per response point).

    Ordinates are double precision (12 significant digits). Abscissae are limited by the
    format (E13.5): even spacing (within 1e-9) is stored as minimum and increment with 6
    significant digits each, uneven spacing (stepped sine) as every frequency with 6
    significant digits; use CSV when frequencies need more digits. (pyuff's binary
    writer is not used: it corrupted multi-set files in pyuff 2.5.8.)"""
    import pyuff

    f = frfset.freq_hz
    df = np.diff(f)
    even = bool(np.allclose(df, df[0], rtol=1e-9, atol=0)) if f.size > 1 else True
    ref_node, ref_dir = _node_dir(frfset.reference or "1", 1)
    code = _UFF_ORDINATE_CODE.get(frfset.quantity, 0)
    id4 = " ".join(f"{key}={text}" for key, text in header_values(frfset)
                   if key != "quantity" and (key != "reference"
                                             or _LABEL.match(frfset.reference) is None))
    id4 = id4 or "NONE"
    if len(id4) > 80:
        raise ValueError(f"UFF ID line too long for the keys ({id4!r}); use CSV")
    if frfset.force is not None or frfset.coherence is not None:
        raise ValueError("a universal file has no force column (nor coherence); write CSV "
                         "to keep it")
    dsets = []
    for j, label in enumerate(frfset.points):
        node, direction = _node_dir(label, j + 1)
        dsets.append(dict(
            type=58, binary=0, func_type=4, id1="iwanfe FRF", id2=label[:80],
            id4=id4, rsp_node=node, rsp_dir=direction, ref_node=ref_node, ref_dir=ref_dir,
            rsp_ent_name="iwanfe", ref_ent_name="iwanfe", abscissa_spacing=int(even),
            abscissa_spec_data_type=18, ordinate_spec_data_type=code,
            orddenom_spec_data_type=13, x=f.copy(), data=frfset.frf[:, j].copy()))
    Path(path).unlink(missing_ok=True)
    with contextlib.redirect_stdout(io.StringIO()):
        pyuff.UFF(str(path)).write_sets(dsets, mode="overwrite")


# --------------------------------------------------------------------------- dispatch

def read_frf(path) -> FRFSet:
    """Read an FRF set from CSV (``.csv``) or universal file (``.uff``, ``.unv``, other).

    The format is chosen by extension; files without a known extension are sniffed
    (a universal file starts with a ``-1`` delimiter line)."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".csv":
        return read_frf_csv(path)
    if ext in (".uff", ".unv", ".uf"):
        return read_frf_uff(path)
    with open(path, encoding="utf-8", errors="replace") as fh:
        first = fh.readline().strip()
    return read_frf_uff(path) if first == "-1" else read_frf_csv(path)


def write_frf(path, frfset: FRFSet) -> None:
    """Write CSV for ``.csv``, else a universal file."""
    if Path(path).suffix.lower() == ".csv":
        write_frf_csv(path, frfset)
    else:
        write_frf_uff(path, frfset)
