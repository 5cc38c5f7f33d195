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
  optional ``coherence`` column (0..1, of an averaged estimate: a random test); one
  optional ``force_psd`` column (a random test: the drive's one-sided autospectrum
  ``G_ff`` per line, > 0, in the excitation's unit^2/Hz, as the analyser averaged it
  for the H1; :func:`ident.random_frf.mode_response_rms` takes the mode's response RMS
  from it). No other columns.

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
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ident.errors import InputError
from ident.frf_csv import (force_and_coherence, force_psd_column, header_columns, header_keys,
                           numeric_table, read_text)
from ident.frf_header import CONTROLS, FRF_TESTS, header_values, id_line_values
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
    force_psd : (n,) one-sided autospectrum of the drive per line (excitation unit^2/Hz;
        a random test), or None.
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
    force_psd: np.ndarray | None = None

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
        for name in ("force", "coherence", "force_psd"):
            v = getattr(self, name)
            if v is not None:
                setattr(self, name, np.asarray(v, float))
                if getattr(self, name).shape != self.freq_hz.shape:
                    raise ValueError(f"{name} has shape {np.shape(v)}, one value per "
                                     f"frequency ({self.freq_hz.size}) is needed")


# ------------------------------------------------------------------------------- CSV

def read_frf_csv(path) -> FRFSet:
    """Read an FRF CSV file (format in the module docstring; steps in :mod:`ident.frf_csv`)."""
    path = Path(path)
    src = str(path)
    text = read_text(path, src)
    cols = header_columns(text)
    values, lines = numeric_table(text)
    freq = values[:, 0]
    frf = (values[:, [cols.re_col[p] for p in cols.points]]
           + 1j * values[:, [cols.im_col[p] for p in cols.points]])
    force, coherence = force_and_coherence(src, cols, values, lines)
    keys = header_keys(text)
    return FRFSet(freq, frf, cols.points, keys["quantity"], keys["excitation"],
                  keys["reference"], src, keys["control"], keys["run_order"], force,
                  keys["test"], coherence, force_psd_column(src, cols, values, lines))


def write_frf_csv(path, frfset: FRFSet) -> None:
    """Write an FRF set as CSV (17 significant digits: exact round trip)."""
    for p in frfset.points:
        if "," in p or not p:
            raise ValueError(f"point label {p!r} cannot be used as a CSV column name")
    lines = [f"# {key} = {text}" for key, text in header_values(frfset)]
    names = ["freq_hz"] + [f"{k}_{p}" for p in frfset.points for k in ("re", "im")]
    n_pts = len(frfset.points)
    extras = [(k, v) for k, v in (("force", frfset.force), ("coherence", frfset.coherence),
                                  ("force_psd", frfset.force_psd)) if v is not None]
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
    if any(v is not None for v in (frfset.force, frfset.coherence, frfset.force_psd)):
        raise ValueError("a universal file has no force column (nor coherence, force_psd); "
                         "write CSV to keep it")
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
