"""The data sets of a universal file, read whole or refused.

pyuff finds data sets between pairs of ``    -1`` delimiter lines and reads each set's
values up to its closing delimiter, whatever its header announced: a file cut inside a
data set (no closing delimiter) loses that set and every later one without a word, and a
set missing lines gives a shorter axis. Here both are refused with the file, the data
set and what is missing (``ident.errors.InputError``, one line), and pyuff's prints and
warnings (non-finite values) are kept off the terminal.
"""
from __future__ import annotations

import contextlib
import io
import warnings
from pathlib import Path

import numpy as np

from ident.errors import InputError

__all__ = ["read_uff_sets"]


def _uff_delimiters(data: bytes) -> list[int]:
    """Byte offsets of the ``    -1`` lines that open and close data sets (pyuff's rule:
    the token followed by a line end, the end of the file, or blanks to column 80)."""
    found, at = [], data.find(b"    -1")
    while at != -1:
        after = data[at + 6:at + 80]
        if not after or after[:1] in (b"\n", b"\r") or (len(after) == 74 and not after.strip()):
            found.append(at)
        at = data.find(b"    -1", at + 1)
    return found


def _check_uff_structure(src: str, data: bytes) -> list[tuple[int, str]]:
    """(first line, type) of every data set; a data set without its closing delimiter
    (a file cut inside it) is refused with its number, type and first line."""
    marks = _uff_delimiters(data)
    sets = []
    for k in range(0, len(marks), 2):
        line = data.count(b"\n", 0, marks[k]) + 1
        head = data[marks[k]:marks[k] + 200].splitlines()
        kind = head[1][:6].decode("ascii", "replace").strip() if len(head) > 1 else "?"
        if k + 1 == len(marks):
            raise InputError(f"{src}:{line}: data set {k // 2 + 1} (type {kind or '?'}) is cut "
                             "off: no closing '    -1' line (truncated file?)")
        sets.append((line, kind))
    return sets


def read_uff_sets(path, set_type: int) -> list[dict]:
    """Every data set of type ``set_type`` in the universal file ``path`` (pyuff dicts),
    each checked whole: closed by its delimiter and holding the ``num_pts`` values its
    record 7 announces (data sets 58)."""
    import pyuff

    src = str(path)
    if not Path(path).is_file():
        raise InputError(f"{src}: no such file")
    layout = _check_uff_structure(src, Path(path).read_bytes())
    try:   # pyuff prints, and warns on non-finite values (refused by the callers)
        with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings(), \
                np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            uff = pyuff.UFF(src)
            types = np.asarray(uff.get_set_types())
            idx = [int(i) for i in np.flatnonzero(types == set_type)]
            sets = uff.read_sets(idx) if idx else []
    except Exception as exc:  # pyuff raises bare Exception
        raise InputError(f"{src}: not a readable universal file ({exc})") from None
    if isinstance(sets, dict):
        sets = [sets]
    for i, s in zip(idx, sets):
        n = int(s.get("num_pts", -1))
        got = np.size(s.get("data"))
        if got != n or np.size(s.get("x")) != n:
            line = layout[i][0] if i < len(layout) else "?"
            raise InputError(f"{src}:{line}: data set {i + 1} ({set_type}, response node "
                             f"{s.get('rsp_node', '?')} direction {s.get('rsp_dir', '?')}) "
                             f"holds {got} of the {n} values its record 7 announces")
    return sets
