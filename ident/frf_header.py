"""The header keys of an FRF file of a stepped-sine series and their rules.

``docs/formats/measured-data.md``, "FRF files of a stepped-sine series": ``quantity``,
``control`` (force | response), ``run_order`` (integer >= 1), ``excitation`` (the held
level, > 0), ``reference`` (the drive point) and ``test`` (``stepped-sine``,
``random``: an H1 FRF averaged over a broadband random record, the excitation its
drive RMS; spec "Other test types"). Read from CSV ``# key = value`` lines
and UFF ID lines ``key=value`` (:mod:`ident.frf_files`); values given on the command
line override the file's (:func:`with_overrides`).
"""
from __future__ import annotations

import math
import re
from dataclasses import replace

from ident.errors import InputError

CONTROLS = ("force", "response")
FRF_TESTS = ("stepped-sine", "random")
HEADER_KEYS = ("quantity", "control", "run_order", "excitation", "reference", "test")
_ID_KEY = re.compile(r"\b(excitation|control|run_order|reference|test)\s*=\s*([^\s,;]+)")


def parse_excitation(text, where: str) -> float:
    """A held level: a finite number > 0 (InputError ``where: message`` otherwise)."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{where}: not a number: {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{where}: excitation must be a finite number > 0, got {text!r}")
    return value


def parse_control(text, where: str) -> str:
    """``force`` or ``response`` (case-insensitive)."""
    value = str(text).strip().lower()
    if value not in CONTROLS:
        raise InputError(f"{where}: control must be force or response, got {text!r}")
    return value


def parse_test(text, where: str) -> str:
    """The test type of an FRF file: ``stepped-sine`` or ``random`` (case-insensitive;
    a free decay is a time record, :mod:`ident.time_records`)."""
    value = str(text).strip().lower()
    if value not in FRF_TESTS:
        raise InputError(f"{where}: test must be one of {', '.join(FRF_TESTS)} in an FRF "
                         f"file, got {text!r}")
    return value


def parse_run_order(text, where: str) -> int:
    """A run order: an integer >= 1."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{where}: not a number: {text!r}") from None
    if not (math.isfinite(value) and value == round(value) and value >= 1):
        raise InputError(f"{where}: run_order must be an integer >= 1, got {text!r}")
    return int(round(value))


def header_values(frfset) -> list[tuple[str, str]]:
    """The set's header keys that have a value, as (key, text), in ``HEADER_KEYS``
    order (floats with 17 significant digits: exact round trip)."""
    values = {"quantity": frfset.quantity, "control": frfset.control,
              "run_order": None if frfset.run_order is None else str(int(frfset.run_order)),
              "excitation": None if frfset.excitation is None else repr(float(frfset.excitation)),
              "reference": frfset.reference or None, "test": frfset.test}
    return [(k, values[k]) for k in HEADER_KEYS if values[k] is not None]


def id_line_values(dataset: dict, source: str) -> dict:
    """``key=value`` header keys in the ID lines (``id1`` .. ``id5``) of a UFF data set 58,
    checked by the rules above (the first occurrence of a key counts)."""
    found: dict[str, tuple[str, str]] = {}
    for line in ("id1", "id2", "id3", "id4", "id5"):
        for m in _ID_KEY.finditer(str(dataset.get(line, ""))):
            found.setdefault(m.group(1), (line, m.group(2)))
    parse = {"excitation": parse_excitation, "control": parse_control,
             "run_order": parse_run_order, "reference": lambda text, where: text,
             "test": parse_test}
    return {k: parse[k](text, f"{source}: {line}") for k, (line, text) in found.items()}


def with_overrides(frfset, excitation=None, control=None, run_order=None, reference=None,
                   test=None):
    """A copy of an :class:`ident.frf_files.FRFSet` with the given header values replacing
    the file's (None keeps the file's value); values are checked by the rules above."""
    where = frfset.source or "command line"
    changes = {}
    if excitation is not None:
        changes["excitation"] = parse_excitation(excitation, f"{where}: --excitation")
    if control is not None:
        changes["control"] = parse_control(control, f"{where}: --control")
    if run_order is not None:
        changes["run_order"] = parse_run_order(run_order, f"{where}: --run-order")
    if reference is not None:
        changes["reference"] = str(reference)
    if test is not None:
        changes["test"] = parse_test(test, f"{where}: --test")
    return replace(frfset, **changes)
