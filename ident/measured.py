"""Measured amplitude-dependent modal data: the CSV reader and writer.

Format: ``docs/formats/measured-data.md`` (one header line, one row per level and mode,
no comment lines). Required columns ``level`` (1-based), ``excitation`` (> 0, any unit
proportional to force), ``omega2`` (rad^2/s^2, > 0), ``zeta`` (fraction in (0, 1));
optional ``mode`` (default 1), ``response_amplitude`` (> 0), ``run_order`` (default
``level``), ``omega2_std``/``zeta_std`` (> 0), ``control`` (``force``/``response``),
``test`` (``stepped-sine`` default, ``random``, ``free-decay``) and free ``x_*``
annotations (kept, otherwise ignored).

Test types (spec "Other test types"): a mode's rows share one ``test``. ``random`` and
``free-decay`` rows need ``response_amplitude`` (the response RMS in the mode's band,
the envelope along the decay), which must increase with ``level``: it is their
abscissa, as under response control. ``free-decay`` rows need no ``excitation``
(the column may be absent when every row is a free decay, or the field empty; kept as
NaN and written empty).

Every violated rule raises :class:`ident.errors.InputError` with one line
``FILE:LINE:COLUMN: message`` (LINE 1-based, the header is line 1; COLUMN the column
name, for a rule about a whole row the column the rule is about: ``level`` for a
duplicate (mode, level), ``excitation`` for a non-increasing excitation, ``mode`` for
too few levels). Repeats (rows sharing (mode, level), other ``run_order``) are legal: the
same level measured again; they count once toward the level count, and every row of a
level must exceed (in the held amplitude) every row of the level below. Blank lines are
skipped. Beyond the spec the reader also rejects an empty file, duplicated or empty header
names, rows whose field count differs from the header, a non-integer or < 1 ``level``,
non-integer ``mode``/``run_order``, and a mode whose rows mix both controls.

Response control (``control = response``): each level held a constant response
amplitude, so ``response_amplitude`` is required and must increase with ``level``; the
``excitation`` (force needed at resonance) need not increase. Under force control the
excitation must increase with ``level``.

A ``zeta`` median above 0.2 is percent: one line, exit 2, unless ``iwanfe
--units-confirmed`` (:mod:`ident.units`; then a warning). Warnings (kept in
:attr:`MeasuredData.warnings`): per mode, ratios of the held amplitude between
successive levels that differ from their median by more than 5 %, and every non-empty
``x_warning`` annotation (:func:`ident.modal_data.annotation_warnings`).

``python -m ident.measured FILE``: a summary and the warnings, or one error line, exit 2.
"""
from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

import numpy as np

from ident.errors import InputError, text_file
from ident.modal_data import TESTS, MeasuredData, annotation_warnings
from ident.units import FLAG, LIMITS, refuse

REQUIRED_COLUMNS = ("level", "excitation", "omega2", "zeta")
OPTIONAL_COLUMNS = ("mode", "response_amplitude", "run_order", "omega2_std", "zeta_std",
                    "control", "test")
CONTROLS = ("force", "response")
KNOWN_COLUMNS = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
MIN_LEVELS = 4
PERCENT_ZETA_MEDIAN = LIMITS["zeta"][1][0]
RATIO_TOLERANCE = 0.05


def _fail(source: str, line: int, column: str, message: str) -> None:
    raise InputError(f"{source}:{line}:{column}: {message}")


def _parse_float(text: str, source: str, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        _fail(source, line, column, f"not a number: {text!r}")
    if not math.isfinite(value):
        _fail(source, line, column, f"not a finite number: {text!r}")
    return value


def _parse_int(text: str, source: str, line: int, column: str) -> int:
    value = _parse_float(text, source, line, column)
    if value != round(value):
        _fail(source, line, column, f"must be an integer, got {text!r}")
    if abs(value) > 2.0 ** 53:  # beyond that a float holds no exact integer (nor does C long)
        _fail(source, line, column, f"integer out of range (|value| <= 2^53), got {text!r}")
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
            _fail(source, reader.line_num, "1", f"not a CSV line ({exc})")


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
        _fail(source, 1, "1", "empty file: expected a header line")
    if header_line != 1:
        _fail(source, header_line, "1", "header must be on line 1")
    return header, rows


def _check_header(header: list[str], source: str) -> None:
    seen: set[str] = set()
    for j, name in enumerate(header, start=1):
        if not name:
            _fail(source, 1, str(j), "empty column name in header")
        if name in seen:
            _fail(source, 1, name, "duplicate column name")
        seen.add(name)
        if name not in KNOWN_COLUMNS and not name.startswith("x_"):
            sep = next((c for c in ";\t|" if c in name), None)
            if sep:
                _fail(source, 1, name, f"columns are separated by commas, not {sep!r}")
            _fail(source, 1, name, "unknown column (known: " + ", ".join(KNOWN_COLUMNS)
                  + "; free annotations must start with 'x_')")
    for name in REQUIRED_COLUMNS:
        if name == "excitation" and "test" in seen:
            continue   # free-decay rows need none: checked row by row
        if name not in seen:
            _fail(source, 1, name, "missing required column (header: "
                  + ", ".join(header) + ")")


def _check_increasing(source, m, name, level, e, lines) -> None:
    """Every row of a level must exceed every row of the level below it in ``e`` (rows
    sorted by level; repeats of one level may differ among themselves)."""
    ends = np.flatnonzero(np.diff(level) > 0)          # last row of each level but the top
    starts = np.r_[0, ends + 1]
    top = np.maximum.reduceat(e, starts)               # per level: max and min over repeats
    low = np.minimum.reduceat(e, starts)
    bad = np.flatnonzero(low[1:] <= top[:-1])
    if bad.size:
        k = bad[0]
        j = starts[k + 1] + int(np.argmin(e[starts[k + 1]:starts[k + 2]
                                            if k + 2 < starts.size else None]))
        i = starts[k] + int(np.argmax(e[starts[k]:starts[k + 1]]))
        _fail(source, lines[j], name,
              f"mode {m}: {name} of level {level[j]} ({e[j]:g}) does not "
              f"exceed that of level {level[i]} ({e[i]:g})")


def read_measured(path) -> MeasuredData:
    """Read and validate a measured-data CSV file (``docs/formats/measured-data.md``).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    MeasuredData
        Entries in file order; ``warnings`` lists non-fatal findings, each prefixed by
        the file name.

    Raises
    ------
    ident.errors.InputError
        One line ``FILE:LINE:COLUMN: message`` for the first violated rule.
    """
    path = Path(path)
    source = str(path)
    header, rows = _read_rows(path, source)
    _check_header(header, source)
    if not rows:
        _fail(source, 2, "level", "no data rows")

    col = {name: j for j, name in enumerate(header)}
    n = len(rows)
    lines = np.array([ln for ln, _ in rows], dtype=int)
    for ln, fields in rows:
        if len(fields) != len(header):
            _fail(source, ln, str(min(len(fields), len(header)) + 1),
                  f"row has {len(fields)} fields, header has {len(header)}")

    def floats(name):
        return np.array([_parse_float(f[col[name]], source, ln, name) for ln, f in rows])

    def ints(name):
        return np.array([_parse_int(f[col[name]], source, ln, name) for ln, f in rows], int)

    level = ints("level")
    if "test" in col:
        test = np.array([f[col["test"]].lower() for _, f in rows], dtype=str)
        first_bad_test = np.flatnonzero(~np.isin(test, TESTS))
        if first_bad_test.size:
            i = first_bad_test[0]
            _fail(source, lines[i], "test",
                  f"test must be one of {', '.join(TESTS)}, got {test[i]!r}")
    else:
        test = np.full(n, "stepped-sine")
    def excitation_of(i, ln, fields):
        text = fields[col["excitation"]] if "excitation" in col else ""
        if not text and test[i] == "free-decay":
            return math.nan                     # a free decay has no excitation
        if "excitation" not in col:
            _fail(source, ln, "excitation", f"a {test[i]} row needs an excitation")
        return _parse_float(text, source, ln, "excitation")

    excitation = np.array([excitation_of(i, ln, f) for i, (ln, f) in enumerate(rows)])
    omega2 = floats("omega2")
    zeta = floats("zeta")
    mode = ints("mode") if "mode" in col else np.ones(n, int)
    run_order = ints("run_order") if "run_order" in col else level.copy()
    response = floats("response_amplitude") if "response_amplitude" in col else None
    omega2_std = floats("omega2_std") if "omega2_std" in col else None
    zeta_std = floats("zeta_std") if "zeta_std" in col else None
    if "control" in col:
        control = np.array([f[col["control"]].lower() for _, f in rows], dtype=str)
    else:
        control = np.full(n, "force")

    def first_bad(mask, name, message):
        bad = np.flatnonzero(mask)
        if bad.size:
            i = bad[0]
            _fail(source, lines[i], name, message(i))

    first_bad(level < 1, "level", lambda i: f"level must be >= 1, got {level[i]}")
    first_bad(~np.isnan(excitation) & (excitation <= 0), "excitation",
              lambda i: f"excitation must be > 0, got {excitation[i]:g}")
    first_bad(omega2 <= 0, "omega2", lambda i: f"omega2 must be > 0 rad^2/s^2, got {omega2[i]:g}")
    first_bad((zeta <= 0) | (zeta >= 1), "zeta",
              lambda i: f"zeta must be a fraction in (0, 1), got {zeta[i]:g}"
              + (" (percent? write 0.01278 for 1.278 %)" if zeta[i] >= 1 else ""))
    if response is not None:
        first_bad(response <= 0, "response_amplitude",
                  lambda i: f"response_amplitude must be > 0, got {response[i]:g}")
    for name, std in (("omega2_std", omega2_std), ("zeta_std", zeta_std)):
        if std is not None:
            first_bad(std <= 0, name, lambda i: f"{name} must be > 0, got {std[i]:g}")
    first_bad(~np.isin(control, CONTROLS), "control",
              lambda i: f"control must be force or response, got '{control[i]}'")
    if response is None:
        first_bad(control == "response", "response_amplitude",
                  lambda i: "control = response needs a response_amplitude column (the "
                            "amplitude each level held)")
        first_bad(test != "stepped-sine", "response_amplitude",
                  lambda i: f"test = {test[i]} needs a response_amplitude column (its "
                            "abscissa: the response RMS, or the envelope along the decay)")

    # Duplicate (mode, level, run_order): report the second occurrence in file order.
    # Rows sharing (mode, level) with different run orders are repeats (legal).
    key = np.stack([mode, level, run_order], axis=1)
    _, first_index = np.unique(key, axis=0, return_index=True)
    dup = np.ones(n, bool)
    dup[first_index] = False
    first_bad(dup, "level", lambda i: f"duplicate (mode, level, run_order) = ({mode[i]}, "
                                      f"{level[i]}, {run_order[i]})")

    warnings: list[str] = []
    for m in np.unique(mode):
        idx = np.flatnonzero(mode == m)
        idx = idx[np.lexsort((run_order[idx], level[idx]))]
        n_levels = np.unique(level[idx]).size
        if n_levels < MIN_LEVELS:
            _fail(source, lines[idx].min(), "mode",
                  f"mode {m} has {n_levels} levels, at least {MIN_LEVELS} are needed")
        controls = np.unique(control[idx])
        if controls.size > 1:
            _fail(source, lines[idx].min(), "control",
                  f"mode {m} mixes control = force and response; one series has one control")
        tests = np.unique(test[idx])
        if tests.size > 1:
            _fail(source, lines[idx].min(), "test",
                  f"mode {m} mixes test types ({', '.join(tests)}); one series has one test")
        name = ("response_amplitude" if controls[0] == "response" or tests[0] != "stepped-sine"
                else "excitation")
        e = response[idx] if name == "response_amplitude" else excitation[idx]
        _check_increasing(source, m, name, level[idx], e, lines[idx])
        e = e[np.r_[True, np.diff(level[idx]) > 0]]     # one row per level for the ratios
        with np.errstate(over="ignore", invalid="ignore"):   # extreme but valid values
            ratio = e[1:] / e[:-1]
            median = np.median(ratio)
            uneven = np.any(np.abs(ratio / median - 1.0) > RATIO_TOLERANCE)
        if uneven:
            warnings.append(
                f"{source}: mode {m}: {name} ratios between successive levels are not "
                f"constant ({ratio.min():.3g} to {ratio.max():.3g}, median {median:.3g})")
    if np.median(zeta) > PERCENT_ZETA_MEDIAN:       # percent? (ident.units)
        refuse(f"{source}: zeta median", "zeta", float(np.median(zeta)))
        warnings.insert(0, f"{source}: zeta median {np.median(zeta):.3g} > "
                        f"{PERCENT_ZETA_MEDIAN}: is zeta in percent? ({FLAG} given)")

    extra = {}
    for name in (h for h in header if h.startswith("x_")):
        texts = [f[col[name]] for _, f in rows]
        try:                         # numbers where every entry is one (not x_warning)
            if name == "x_warning":
                raise ValueError
            extra[name] = np.array([float(t) for t in texts])
        except ValueError:
            extra[name] = np.array(texts, dtype=str)
    data = MeasuredData(level=level, excitation=excitation, omega2=omega2, zeta=zeta,
                        mode=mode, run_order=run_order, response_amplitude=response,
                        omega2_std=omega2_std, zeta_std=zeta_std, control=control,
                        test=test, extra=extra, warnings=warnings, line=lines, source=source)
    data.warnings.extend(annotation_warnings(data))
    return data


def write_measured(path, data: MeasuredData) -> None:
    """Write ``data`` as a measured-data CSV file (round-trips through read_measured).

    Columns: level, excitation, omega2, zeta, mode, [response_amplitude,] run_order,
    [omega2_std, zeta_std,] [control (only when some entry is response-controlled),]
    [test (only when some entry is not a stepped sine),] then the ``x_*`` annotations;
    floats with 17 significant digits (exact); a NaN excitation (free decay) is empty.
    """
    names = ["level", "excitation", "omega2", "zeta", "mode"]
    cols = [data.level, data.excitation, data.omega2, data.zeta, data.mode]
    if data.response_amplitude is not None:
        names.append("response_amplitude")
        cols.append(data.response_amplitude)
    names.append("run_order")
    cols.append(data.run_order)
    for name in ("omega2_std", "zeta_std"):
        if getattr(data, name) is not None:
            names.append(name)
            cols.append(getattr(data, name))
    if np.any(data.control != "force"):
        names.append("control")
        cols.append(data.control)
    if np.any(data.test != "stepped-sine"):
        names.append("test")
        cols.append(data.test)
    for k, v in data.extra.items():
        if not k.startswith("x_"):
            raise ValueError(f"extra column {k!r} must start with 'x_'")
        names.append(k)
        cols.append(v)

    def fmt(v):
        if isinstance(v, (int, np.integer)):
            return str(int(v))
        if isinstance(v, (float, np.floating)):
            return "" if math.isnan(v) else repr(float(v))
        return str(v)

    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(names)
        for row in zip(*cols):
            writer.writerow([fmt(v) for v in row])


def summary(data: MeasuredData) -> str:
    """Human-readable table: per mode, levels, excitation range, f_n and zeta ranges."""
    out = [f"{data.source or '<memory>'}: {len(data)} rows, "
           f"modes {', '.join(map(str, data.modes))}"]
    for m, d in ((m, data.for_mode(m)) for m in data.modes):
        f = d.omega_hz
        out.append(
            f"  mode {m}: {len(d)} levels, excitation {d.excitation[0]:.4g} .. "
            f"{d.excitation[-1]:.4g}, f_n {f[0]:.6g} .. {f[-1]:.6g} Hz, "
            f"zeta {d.zeta[0]:.5g} .. {d.zeta[-1]:.5g}")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """``python -m ident.measured FILE...``: validate, print summary and warnings."""
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: python -m ident.measured FILE...\n"
              "Validate measured-data CSV files (docs/formats/measured-data.md).")
        return 0 if argv else 2
    for name in argv:
        try:
            data = read_measured(name)
        except (ValueError, OSError) as exc:
            print(f"error: {exc}".splitlines()[0], file=sys.stderr)
            return 2
        print(summary(data))
        for w in data.warnings:
            print(f"warning: {w}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
