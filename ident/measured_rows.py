"""The rows of a measured-data CSV file: the header checked and the fields parsed.

The reading half of :func:`ident.measured.read_measured` (``docs/formats/measured-data.md``;
the rules on the values are there): the header line (known, unique, non-empty names, the
required columns), the data rows (blank lines skipped, as many fields as the header),
every field of a standard column as a number (finite; an integer where the column holds
one) or a word, and the ``x_*`` annotations. Every violated rule raises
:class:`ident.errors.InputError` with one line ``FILE:LINE:COLUMN: message``.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ident.errors import InputError, text_file
from ident.modal_data import TESTS

REQUIRED_COLUMNS = ("level", "excitation", "omega2", "zeta")
OPTIONAL_COLUMNS = ("mode", "response_amplitude", "run_order", "omega2_std", "zeta_std",
                    "control", "test")
KNOWN_COLUMNS = REQUIRED_COLUMNS + OPTIONAL_COLUMNS

#: The standard columns of a file as arrays, keyed by :class:`ident.modal_data.MeasuredData`
#: field name (None for an optional column the file does not have).
Columns = dict[str, "np.ndarray | None"]


def fail(source: str, line: int, column: str, message: str) -> None:
    """Raise the one-line input error ``SOURCE:LINE:COLUMN: message``."""
    raise InputError(f"{source}:{line}:{column}: {message}")


def _parse_float(text: str, source: str, line: int, column: str) -> float:
    """One field as a finite float."""
    try:
        value = float(text)
    except ValueError:
        fail(source, line, column, f"not a number: {text!r}")
    if not math.isfinite(value):
        fail(source, line, column, f"not a finite number: {text!r}")
    return value


def _parse_int(text: str, source: str, line: int, column: str) -> int:
    """One field as an integer (a float with no fraction, |value| <= 2^53)."""
    value = _parse_float(text, source, line, column)
    if value != round(value):
        fail(source, line, column, f"must be an integer, got {text!r}")
    if abs(value) > 2.0 ** 53:  # beyond that a float holds no exact integer (nor does C long)
        fail(source, line, column, f"integer out of range (|value| <= 2^53), got {text!r}")
    return int(round(value))


def _csv_rows(reader, source: str):
    """The reader's rows; its own errors (a field over the size limit, a bad quote)
    become one-line input errors."""
    while True:
        try:
            yield next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            fail(source, reader.line_num, "1", f"not a CSV line ({exc})")


def _read_rows(path: Path, source: str) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header names and (line number, fields) of the non-blank data rows."""
    with text_file(path, source, newline="") as fh:
        reader = csv.reader(fh)
        header: list[str] | None = None
        rows: list[tuple[int, list[str]]] = []
        for fields in _csv_rows(reader, source):
            lineno = reader.line_num
            if not any(f.strip() for f in fields):
                continue
            fields = [f.strip() for f in fields]
            if header is None:
                header = fields
                header_line = lineno
                continue
            rows.append((lineno, fields))
    if header is None:
        fail(source, 1, "1", "empty file: expected a header line")
    if header_line != 1:
        fail(source, header_line, "1", "header must be on line 1")
    return header, rows


def _check_header(header: list[str], source: str) -> None:
    """Header names: non-empty, unique, known (or ``x_*``), the required ones present."""
    seen: set[str] = set()
    for j, name in enumerate(header, start=1):
        if not name:
            fail(source, 1, str(j), "empty column name in header")
        if name in seen:
            fail(source, 1, name, "duplicate column name")
        seen.add(name)
        if name not in KNOWN_COLUMNS and not name.startswith("x_"):
            sep = next((c for c in ";\t|" if c in name), None)
            if sep:
                fail(source, 1, name, f"columns are separated by commas, not {sep!r}")
            fail(source, 1, name, "unknown column (known: " + ", ".join(KNOWN_COLUMNS)
                 + "; free annotations must start with 'x_')")
    for name in REQUIRED_COLUMNS:
        if name == "excitation" and "test" in seen:
            continue   # free-decay rows need none: checked row by row
        if name not in seen:
            fail(source, 1, name, "missing required column (header: "
                 + ", ".join(header) + ")")


@dataclass
class MeasuredRows:
    """The data rows of one file, ``(line number, fields)`` each, under its header."""

    source: str
    header: list[str]
    rows: list[tuple[int, list[str]]]
    col: dict[str, int] = field(init=False)
    lines: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.col = {name: j for j, name in enumerate(self.header)}
        self.lines = np.array([ln for ln, _ in self.rows], dtype=int)

    def floats(self, name: str) -> np.ndarray:
        """Column ``name`` as finite floats."""
        return np.array([_parse_float(f[self.col[name]], self.source, ln, name)
                         for ln, f in self.rows])

    def ints(self, name: str) -> np.ndarray:
        """Column ``name`` as integers."""
        return np.array([_parse_int(f[self.col[name]], self.source, ln, name)
                         for ln, f in self.rows], int)

    def words(self, name: str) -> np.ndarray:
        """Column ``name`` as lower-case strings."""
        return np.array([f[self.col[name]].lower() for _, f in self.rows], dtype=str)

    def first_bad(self, mask: np.ndarray, name: str, message: Callable[[int], str]) -> None:
        """Fail on the first row where ``mask`` holds, in column ``name``, with
        ``message(row index)``."""
        bad = np.flatnonzero(mask)
        if bad.size:
            i = bad[0]
            fail(self.source, self.lines[i], name, message(i))


def read_rows(path) -> MeasuredRows:
    """The checked header and data rows of a measured-data CSV file."""
    path = Path(path)
    source = str(path)
    header, rows = _read_rows(path, source)
    _check_header(header, source)
    if not rows:
        fail(source, 2, "level", "no data rows")
    table = MeasuredRows(source, header, rows)
    for ln, fields in rows:
        if len(fields) != len(header):
            fail(source, ln, str(min(len(fields), len(header)) + 1),
                 f"row has {len(fields)} fields, header has {len(header)}")
    return table


def _test_column(t: MeasuredRows) -> np.ndarray:
    """The ``test`` of every row (default ``stepped-sine``), each one of :data:`TESTS`."""
    if "test" not in t.col:
        return np.full(len(t.rows), "stepped-sine")
    test = t.words("test")
    first_bad_test = np.flatnonzero(~np.isin(test, TESTS))
    if first_bad_test.size:
        i = first_bad_test[0]
        fail(t.source, t.lines[i], "test",
             f"test must be one of {', '.join(TESTS)}, got {test[i]!r}")
    return test


def _excitation_column(t: MeasuredRows, test: np.ndarray) -> np.ndarray:
    """The ``excitation`` of every row: NaN where a free decay leaves it empty."""
    def excitation_of(i: int, ln: int, fields: list[str]) -> float:
        text = fields[t.col["excitation"]] if "excitation" in t.col else ""
        if not text and test[i] == "free-decay":
            return math.nan                     # a free decay has no excitation
        if "excitation" not in t.col:
            fail(t.source, ln, "excitation", f"a {test[i]} row needs an excitation")
        return _parse_float(text, t.source, ln, "excitation")

    return np.array([excitation_of(i, ln, f) for i, (ln, f) in enumerate(t.rows)])


def parse_columns(t: MeasuredRows) -> Columns:
    """The standard columns (:data:`Columns`), defaults filled in: ``mode`` 1,
    ``run_order`` the level, ``control`` force, ``test`` stepped sine."""
    n = len(t.rows)
    level = t.ints("level")
    test = _test_column(t)
    excitation = _excitation_column(t, test)
    return dict(
        level=level, excitation=excitation, omega2=t.floats("omega2"), zeta=t.floats("zeta"),
        mode=t.ints("mode") if "mode" in t.col else np.ones(n, int),
        run_order=t.ints("run_order") if "run_order" in t.col else level.copy(),
        response_amplitude=(t.floats("response_amplitude") if "response_amplitude" in t.col
                            else None),
        omega2_std=t.floats("omega2_std") if "omega2_std" in t.col else None,
        zeta_std=t.floats("zeta_std") if "zeta_std" in t.col else None,
        control=t.words("control") if "control" in t.col else np.full(n, "force"),
        test=test)


def annotations(t: MeasuredRows) -> dict[str, np.ndarray]:
    """The ``x_*`` columns: floats where every entry is a number (never ``x_warning``),
    else strings."""
    extra = {}
    for name in (h for h in t.header if h.startswith("x_")):
        texts = [f[t.col[name]] for _, f in t.rows]
        try:                         # numbers where every entry is one (not x_warning)
            if name == "x_warning":
                raise ValueError
            extra[name] = np.array([float(x) for x in texts])
        except ValueError:
            extra[name] = np.array(texts, dtype=str)
    return extra
