"""The steps of reading an FRF CSV file (:func:`ident.frf_files.read_frf_csv`).

Format in :mod:`ident.frf_files`: the ``# key = value`` lines, the header line
(``freq_hz``, the ``re_P``/``im_P`` pairs, ``force``, ``coherence``, ``force_psd``) and the numeric
table under it, each checked here. Errors are :class:`ident.errors.InputError`
``FILE:LINE:COLUMN: message`` (1-based line, column name).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ident.errors import InputError, text_file
from ident.frf_header import (HEADER_KEYS, parse_control, parse_excitation, parse_run_order,
                              parse_test)
from ident.poles import QUANTITIES

#: The optional per-line columns beside the FRF (:mod:`ident.frf_files`).
EXTRA_COLUMNS = ("force", "coherence", "force_psd")


def _fail(source: str, line: int, column, message: str) -> None:
    """Raise the one-line input error ``SOURCE:LINE:COLUMN: message``."""
    raise InputError(f"{source}:{line}:{column}: {message}")


@dataclass
class FRFText:
    """The lines of an FRF CSV file: ``# key = value`` keys as (line, text), the header
    names and their line, and (line number, fields) of every data row."""

    src: str
    meta: dict[str, tuple[int, str]] = field(default_factory=dict)
    header: list[str] | None = None
    header_line: int = 0
    rows: list[tuple[int, list[str]]] = field(default_factory=list)


@dataclass
class FRFColumns:
    """Column indices of the header: the points in order, their ``re_``/``im_``
    columns, and the ``force``/``coherence`` columns present."""

    points: list[str] = field(default_factory=list)
    re_col: dict[str, int] = field(default_factory=dict)
    im_col: dict[str, int] = field(default_factory=dict)
    extra_col: dict[str, int] = field(default_factory=dict)


def read_text(path: Path, src: str) -> FRFText:
    """The keys, header and data rows of the file (non-blank lines; a header exists)."""
    text = FRFText(src)
    with text_file(path, src) as fh:
        for lineno, line in enumerate(fh, start=1):
            s = line.strip()
            if not s:
                continue
            if text.header is None and s.startswith("#"):
                if "=" not in s:
                    _fail(src, lineno, 1, "comment line must read '# key = value'")
                key, value = (t.strip() for t in s[1:].split("=", 1))
                if key not in HEADER_KEYS:
                    _fail(src, lineno, key, "unknown key (known: " + ", ".join(HEADER_KEYS) + ")")
                text.meta[key] = (lineno, value)
                continue
            fields = [t.strip() for t in s.split(",")]
            if text.header is None:
                text.header, text.header_line = fields, lineno
            else:
                text.rows.append((lineno, fields))
    if text.header is None:
        _fail(src, 1, 1, "empty file: expected a header line")
    return text


def header_columns(text: FRFText) -> FRFColumns:
    """The header's columns, checked: ``freq_hz`` first, then ``re_P``/``im_P`` pairs
    (at least one), ``force``, ``coherence`` and ``force_psd``, no name twice."""
    src, header, header_line = text.src, text.header, text.header_line
    if header[0] != "freq_hz":
        _fail(src, header_line, header[0] or 1, "first column must be 'freq_hz'")
    cols = FRFColumns()
    for j, name in enumerate(header[1:], start=1):
        if name in EXTRA_COLUMNS:
            if name in cols.extra_col:
                _fail(src, header_line, name, "duplicate column name")
            cols.extra_col[name] = j
            continue
        part, _, label = name.partition("_")
        if part not in ("re", "im") or not label:
            _fail(src, header_line, name,
                  "unknown column: expected re_<point>, im_<point>, force, coherence or "
                  "force_psd")
        target = cols.re_col if part == "re" else cols.im_col
        if label in target:
            _fail(src, header_line, name, "duplicate column name")
        target[label] = j
        if part == "re":
            cols.points.append(label)
    for label in cols.points:
        if label not in cols.im_col:
            _fail(src, header_line, f"re_{label}", f"no matching column im_{label}")
    for label in cols.im_col:
        if label not in cols.re_col:
            _fail(src, header_line, f"im_{label}", f"no matching column re_{label}")
    if not cols.points:
        _fail(src, header_line, "freq_hz", "no FRF columns (re_<point>, im_<point>)")
    return cols


def numeric_table(text: FRFText) -> tuple[np.ndarray, np.ndarray]:
    """The data rows as finite floats (rows, columns) and their line numbers; at least
    2 rows, frequencies > 0 and strictly increasing."""
    src, header, rows = text.src, text.header, text.rows
    if len(rows) < 2:
        _fail(src, text.header_line + 1, "freq_hz", "fewer than 2 frequency lines")
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
    return values, lines


def force_and_coherence(src: str, cols: FRFColumns, values: np.ndarray, lines: np.ndarray
                        ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The ``force`` (> 0 N) and ``coherence`` (in [0, 1]) columns, None where absent."""
    force = coherence = None
    if "coherence" in cols.extra_col:
        coherence = values[:, cols.extra_col["coherence"]]
        bad = np.flatnonzero((coherence < 0) | (coherence > 1))
        if bad.size:
            _fail(src, lines[bad[0]], "coherence",
                  f"coherence must be in [0, 1], got {coherence[bad[0]]:g}")
    if "force" in cols.extra_col:
        force = values[:, cols.extra_col["force"]]
        bad = np.flatnonzero(force <= 0)
        if bad.size:
            _fail(src, lines[bad[0]], "force", f"force must be > 0 N, got {force[bad[0]]:g}")
    return force, coherence


def force_psd_column(src: str, cols: FRFColumns, values: np.ndarray, lines: np.ndarray
                     ) -> np.ndarray | None:
    """The ``force_psd`` column (the drive's one-sided autospectrum per line, > 0, in
    the excitation's unit^2/Hz), None where absent."""
    if "force_psd" not in cols.extra_col:
        return None
    psd = values[:, cols.extra_col["force_psd"]]
    bad = np.flatnonzero(psd <= 0)
    if bad.size:
        _fail(src, lines[bad[0]], "force_psd", f"force_psd must be > 0, got {psd[bad[0]]:g}")
    return psd


def header_keys(text: FRFText) -> dict:
    """The values of the ``# key = value`` lines by the rules of :mod:`ident.frf_header`
    (None for a key not given): quantity, excitation, reference, control, run_order,
    test."""
    src, meta = text.src, text.meta
    quantity = excitation = reference = None
    if "quantity" in meta:
        ln, quantity = meta["quantity"]
        if quantity not in QUANTITIES:
            _fail(src, ln, "quantity", f"must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    if "excitation" in meta:
        ln, value = meta["excitation"]
        excitation = parse_excitation(value, f"{src}:{ln}:excitation")
    if "reference" in meta:
        reference = meta["reference"][1]
    control = run_order = None
    if "control" in meta:
        ln, value = meta["control"]
        control = parse_control(value, f"{src}:{ln}:control")
    if "run_order" in meta:
        ln, value = meta["run_order"]
        run_order = parse_run_order(value, f"{src}:{ln}:run_order")
    test = parse_test(meta["test"][1], f"{src}:{meta['test'][0]}:test") if "test" in meta else None
    return dict(quantity=quantity, excitation=excitation, reference=reference,
                control=control, run_order=run_order, test=test)
