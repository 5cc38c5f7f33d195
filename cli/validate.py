"""Checks of command-line values made before any work starts, each failing with one line
that names the option, its value and the reason (a ``ValueError``, exit status 2).

Output paths follow one rule for every command (stated in :mod:`cli.main`):

* an output **file** goes into an existing folder; no folder is made for a file;
* an output **folder** is created with its missing parents, unless the first folder to
  create would sit directly in the filesystem root (a typo such as ``/nonexistent/out``
  would otherwise make a top-level folder); a path that exists as a file is refused.
"""
from __future__ import annotations

import math
import os
from pathlib import Path

__all__ = ["finite", "positive", "band", "input_file", "output_file", "output_dir"]


def finite(value: float, option: str) -> float:
    """``value`` if it is a finite number."""
    if not math.isfinite(value):
        raise ValueError(f"{option} {value:g}: must be a finite number")
    return value


def positive(value: float, option: str) -> float:
    """``value`` if it is finite and > 0."""
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{option} {value:g}: must be a finite number > 0")
    return value


def band(values, option: str = "--band", lowest: float = 0.0) -> tuple[float, float]:
    """``(lo, hi)`` if both are finite and ``lowest <= lo < hi`` (Hz)."""
    lo, hi = (float(v) for v in values)
    if not (math.isfinite(lo) and math.isfinite(hi) and lowest <= lo < hi):
        raise ValueError(f"{option} {lo:g} {hi:g}: needs finite {lowest:g} <= LO < HI (Hz)")
    return lo, hi


def input_file(path, option: str) -> Path:
    """``path`` if it is an existing, readable file."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{option} {path}: no such file" if not p.exists()
                         else f"{option} {path}: not a file")
    if not os.access(p, os.R_OK):
        raise ValueError(f"{option} {path}: not readable")
    return p


def _first_existing(p: Path) -> Path:
    p = p.absolute()
    while not p.exists():
        p = p.parent
    return p


def output_file(path, option: str, suffixes: tuple[str, ...] = ()) -> Path:
    """``path`` if its folder exists and is writable (and its suffix is one of
    ``suffixes``, if given); nothing is created."""
    p = Path(path)
    if suffixes and p.suffix.lower() not in suffixes:
        raise ValueError(f"{option} {path}: must end in {' or '.join(suffixes)}")
    if p.is_dir():
        raise ValueError(f"{option} {path}: is a folder, expected a file name")
    folder = p.absolute().parent
    if not folder.is_dir():
        raise ValueError(f"{option} {path}: folder {folder} does not exist (output files "
                         "go into existing folders)")
    if not os.access(folder, os.W_OK):
        raise ValueError(f"{option} {path}: folder {folder} is not writable")
    return p


def output_dir(path, option: str) -> Path:
    """``path`` if it is a folder or can be created (module rule); nothing is created."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ValueError(f"{option} {path}: exists and is not a folder")
    base = _first_existing(p)
    if not base.is_dir():
        raise ValueError(f"{option} {path}: {base} is a file, not a folder")
    if base != p.absolute() and base.parent == base:
        raise ValueError(f"{option} {path}: would create a folder in the filesystem root "
                         f"{base} (create it first if that is what you want)")
    if not os.access(base, os.W_OK):
        raise ValueError(f"{option} {path}: {base} is not writable")
    return p
