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

import numpy as np

from ident.measured_rows import (  # noqa: F401 (the column names, re-exported)
    KNOWN_COLUMNS, OPTIONAL_COLUMNS, REQUIRED_COLUMNS, Columns, MeasuredRows, annotations, fail,
    parse_columns, read_rows)
from ident.modal_data import MeasuredData, annotation_warnings
from ident.units import FLAG, LIMITS, refuse

CONTROLS = ("force", "response")
MIN_LEVELS = 4
PERCENT_ZETA_MEDIAN = LIMITS["zeta"][1][0]
RATIO_TOLERANCE = 0.05


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
        fail(source, lines[j], name,
             f"mode {m}: {name} of level {level[j]} ({e[j]:g}) does not "
             f"exceed that of level {level[i]} ({e[i]:g})")


def _check_values(t: MeasuredRows, c: Columns) -> None:
    """Every value in its range, the control known, the columns a control or test needs."""
    level, excitation, omega2, zeta = c["level"], c["excitation"], c["omega2"], c["zeta"]
    response, control, test = c["response_amplitude"], c["control"], c["test"]
    t.first_bad(level < 1, "level", lambda i: f"level must be >= 1, got {level[i]}")
    t.first_bad(~np.isnan(excitation) & (excitation <= 0), "excitation",
                lambda i: f"excitation must be > 0, got {excitation[i]:g}")
    t.first_bad(omega2 <= 0, "omega2",
                lambda i: f"omega2 must be > 0 rad^2/s^2, got {omega2[i]:g}")
    t.first_bad((zeta <= 0) | (zeta >= 1), "zeta",
                lambda i: f"zeta must be a fraction in (0, 1), got {zeta[i]:g}"
                + (" (percent? write 0.01278 for 1.278 %)" if zeta[i] >= 1 else ""))
    if response is not None:
        t.first_bad(response <= 0, "response_amplitude",
                    lambda i: f"response_amplitude must be > 0, got {response[i]:g}")
    for name in ("omega2_std", "zeta_std"):
        std = c[name]
        if std is not None:
            t.first_bad(std <= 0, name, lambda i: f"{name} must be > 0, got {std[i]:g}")
    t.first_bad(~np.isin(control, CONTROLS), "control",
                lambda i: f"control must be force or response, got '{control[i]}'")
    if response is None:
        t.first_bad(control == "response", "response_amplitude",
                    lambda i: "control = response needs a response_amplitude column (the "
                              "amplitude each level held)")
        t.first_bad(test != "stepped-sine", "response_amplitude",
                    lambda i: f"test = {test[i]} needs a response_amplitude column (its "
                              "abscissa: the response RMS, or the envelope along the decay)")


def _check_duplicates(t: MeasuredRows, c: Columns) -> None:
    """No two rows share (mode, level, run_order): the second in file order is reported.
    Rows sharing (mode, level) with different run orders are repeats (legal)."""
    mode, level, run_order = c["mode"], c["level"], c["run_order"]
    key = np.stack([mode, level, run_order], axis=1)
    _, first_index = np.unique(key, axis=0, return_index=True)
    dup = np.ones(len(t.rows), bool)
    dup[first_index] = False
    t.first_bad(dup, "level", lambda i: f"duplicate (mode, level, run_order) = ({mode[i]}, "
                                        f"{level[i]}, {run_order[i]})")


def _ratio_warning(source: str, m, name: str, e: np.ndarray, level: np.ndarray) -> str | None:
    """The warning on uneven ratios of the held amplitude ``e`` between successive levels
    (rows sorted by level), or None."""
    e = e[np.r_[True, np.diff(level) > 0]]     # one row per level for the ratios
    with np.errstate(over="ignore", invalid="ignore"):   # extreme but valid values
        ratio = e[1:] / e[:-1]
        median = np.median(ratio)
        uneven = np.any(np.abs(ratio / median - 1.0) > RATIO_TOLERANCE)
    if uneven:
        return (f"{source}: mode {m}: {name} ratios between successive levels are not "
                f"constant ({ratio.min():.3g} to {ratio.max():.3g}, median {median:.3g})")
    return None


def _check_mode(t: MeasuredRows, c: Columns, m) -> str | None:
    """Check the series of mode ``m`` (enough levels, one control, one test, the held
    amplitude increasing with level); its ratio warning or None."""
    mode, level, run_order = c["mode"], c["level"], c["run_order"]
    idx = np.flatnonzero(mode == m)
    idx = idx[np.lexsort((run_order[idx], level[idx]))]
    first_line = t.lines[idx].min()
    n_levels = np.unique(level[idx]).size
    if n_levels < MIN_LEVELS:
        fail(t.source, first_line, "mode",
             f"mode {m} has {n_levels} levels, at least {MIN_LEVELS} are needed")
    controls = np.unique(c["control"][idx])
    if controls.size > 1:
        fail(t.source, first_line, "control",
             f"mode {m} mixes control = force and response; one series has one control")
    tests = np.unique(c["test"][idx])
    if tests.size > 1:
        fail(t.source, first_line, "test",
             f"mode {m} mixes test types ({', '.join(tests)}); one series has one test")
    name = ("response_amplitude" if controls[0] == "response" or tests[0] != "stepped-sine"
            else "excitation")
    e = c[name][idx]
    _check_increasing(t.source, m, name, level[idx], e, t.lines[idx])
    return _ratio_warning(t.source, m, name, e, level[idx])


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
    t = read_rows(path)
    source = t.source
    c = parse_columns(t)
    _check_values(t, c)
    _check_duplicates(t, c)
    warnings: list[str] = []
    for m in np.unique(c["mode"]):
        warning = _check_mode(t, c, m)
        if warning:
            warnings.append(warning)
    zeta = c["zeta"]
    if np.median(zeta) > PERCENT_ZETA_MEDIAN:       # percent? (ident.units)
        refuse(f"{source}: zeta median", "zeta", float(np.median(zeta)))
        warnings.insert(0, f"{source}: zeta median {np.median(zeta):.3g} > "
                        f"{PERCENT_ZETA_MEDIAN}: is zeta in percent? ({FLAG} given)")
    data = MeasuredData(**c, extra=annotations(t), warnings=warnings, line=t.lines,
                        source=source)
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
