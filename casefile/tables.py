"""Reading one TOML table of a case file: typed keys, one-line errors naming file, table, key.

Every error is a :class:`CaseFileError` (an :class:`ident.errors.InputError`, so the
command line prints it as one line and exits with status 2) worded
``FILE: [TABLE] KEY: reason``. Keys starting with ``x_`` are kept (``extra``) and ignored;
any other key the reader did not ask for is an error (:meth:`Table.finish`).
"""
from __future__ import annotations

import math

from ident.errors import InputError


class CaseFileError(InputError):
    """A bad case file: the message names file, table and key."""


class Table:
    """One table (``[drive]``) or one entry of an array of tables (``[[beam]]`` number i)."""

    def __init__(self, path, name: str, data, index: int | None = None):
        self.path, self.name, self.index = str(path), name, index
        self.label = name if index is None else f"{name}.{index}"
        if not isinstance(data, dict):
            self.fail(None, f"must be a table, got {type(data).__name__}")
        self.data = data
        self.used: set[str] = set()
        self.extra = {k: v for k, v in data.items() if k.startswith("x_")}

    def fail(self, key, reason: str):
        where = f"[{self.label}]" + (f" {key}" if key else "")
        raise CaseFileError(f"{self.path}: {where}: {reason}")

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, required: bool):
        self.used.add(key)
        if key not in self.data:
            if required:
                self.fail(key, "missing (required)")
            return None
        return self.data[key]

    def number(self, key: str, required: bool = True, default=None, lo=None, hi=None,
               lo_open: bool = False, hi_open: bool = False) -> float | None:
        v = self.raw(key, required)
        if v is None:
            return default
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            self.fail(key, f"must be a finite number, got {v!r}")
        v = float(v)
        self._check_range(key, v, lo, hi, lo_open, hi_open)
        return v

    def _check_range(self, key, v, lo, hi, lo_open, hi_open):
        if lo is not None and (v < lo or (lo_open and v == lo)):
            self.fail(key, f"must be {'>' if lo_open else '>='} {lo:g}, got {v:g}")
        if hi is not None and (v > hi or (hi_open and v == hi)):
            self.fail(key, f"must be {'<' if hi_open else '<='} {hi:g}, got {v:g}")

    def integer(self, key: str, required: bool = True, lo: int | None = None) -> int | None:
        v = self.raw(key, required)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(key, f"must be an integer, got {v!r}")
        if lo is not None and v < lo:
            self.fail(key, f"must be >= {lo}, got {v}")
        return int(v)

    def text(self, key: str, required: bool = True, choices=None, default=None) -> str | None:
        v = self.raw(key, required)
        if v is None:
            return default
        if not isinstance(v, str):
            self.fail(key, f"must be a string, got {v!r}")
        if choices is not None and v not in choices:
            self.fail(key, f"must be one of {', '.join(choices)}, got {v!r}")
        return v

    def numbers(self, key: str, required: bool = True, length: int | None = None,
                lo=None) -> list[float] | None:
        v = self.raw(key, required)
        if v is None:
            return None
        if not isinstance(v, list) or not v:
            self.fail(key, f"must be a non-empty list of numbers, got {v!r}")
        out = []
        for item in v:
            if (isinstance(item, bool) or not isinstance(item, (int, float))
                    or not math.isfinite(item)):
                self.fail(key, f"must hold finite numbers, got {item!r}")
            out.append(float(item))
        if length is not None and len(out) != length:
            self.fail(key, f"must hold {length} numbers, got {len(out)}")
        if lo is not None and min(out) < lo:
            self.fail(key, f"must hold numbers >= {lo:g}, got {min(out):g}")
        return out

    def span(self, key: str = "x", required: bool = True, point_ok: bool = True):
        """``x = [x0, x1]`` (x0 <= x1; x0 < x1 unless ``point_ok``) or ``x = x0`` (a point)."""
        v = self.raw(key, required)
        if v is None:
            return None
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            v = [v, v]
        self.used.discard(key)
        x = self.numbers(key, length=2)
        if x[1] < x[0] or (not point_ok and x[1] == x[0]):
            self.fail(key, f"must be [start, end] with start {'<=' if point_ok else '<'} end, "
                           f"got {x}")
        return (x[0], x[1])

    def strings(self, key: str, required: bool = True, length: int | None = None):
        v = self.raw(key, required)
        if v is None:
            return None
        if not isinstance(v, list) or not all(isinstance(s, str) for s in v):
            self.fail(key, f"must be a list of strings, got {v!r}")
        if length is not None and len(v) != length:
            self.fail(key, f"must name {length} items, got {len(v)}")
        return list(v)

    def finish(self) -> None:
        """Refuse the keys nobody asked for (``x_`` keys are kept and ignored)."""
        for key in self.data:
            if key not in self.used and not key.startswith("x_"):
                self.fail(key, "unknown key (keys starting with x_ are ignored)")
