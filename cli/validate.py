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


def input_file(path, option: str = "") -> Path:
    """``path`` if it is an existing, readable file (``option``: its option, "" for a
    positional argument)."""
    p = Path(path)
    name = f"{option} {path}" if option else str(path)
    if not p.is_file():
        raise ValueError(f"{name}: no such file" if not p.exists() else f"{name}: not a file")
    if not os.access(p, os.R_OK):
        raise ValueError(f"{name}: not readable")
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


#: Most stepped-sine lines per level: 10,000 (with the default 32 Hz band, df = 3.2 mHz,
#: about 2,000 lines in the half-power band of the 252 Hz mode where the identification
#: needs a dozen; every line costs a harmonic-balance solve at every level).
MAX_LINES = 10_000
#: Most Jenkins sliders per octave of slip limit: 256, 16 times the default; the
#: discretization error falls as n^-2 and is 6.3e-4 at the default 16 (cases.double_beam.
#: settings), so 256 reach ~2.5e-6, below anything the identification resolves.
MAX_SLIDERS_PER_OCTAVE = 256


def stepped_sine(study, data=None, prefix: str = "") -> None:
    """Check the lines and sliders of a double-beam study (``DoubleBeamStudy``) and that
    its band holds the measured mode: every measured level's frequency with its
    half-power band ``f (1 -+ zeta)`` (the identification fits the peak from the lines
    around it; a band beside the mode runs a whole campaign for nothing). ``data``: the
    measured levels (``cases.double_beam.settings.measured_levels``)."""
    lo, hi = study.band_hz
    n_lines = (hi - lo) / study.df_hz + 1
    if n_lines > MAX_LINES:
        raise ValueError(f"{prefix}--df {study.df_hz:g}: gives {n_lines:.3g} lines in "
                         f"{lo:g}-{hi:g} Hz, more than {MAX_LINES}")
    if not 1 <= study.sliders_per_octave <= MAX_SLIDERS_PER_OCTAVE:
        raise ValueError(f"{prefix}--sliders-per-octave {study.sliders_per_octave}: must be in "
                         f"1..{MAX_SLIDERS_PER_OCTAVE}")
    if data is not None:
        import numpy as np

        f = np.sqrt(data.omega2) / (2 * np.pi)
        need_lo, need_hi = float(np.min(f * (1 - data.zeta))), float(np.max(f * (1 + data.zeta)))
        if lo > need_lo or hi < need_hi:
            raise ValueError(f"{prefix}--band {lo:g} {hi:g}: must hold the measured mode "
                             f"({f.min():.2f}-{f.max():.2f} Hz) with its half-power band, "
                             f"i.e. LO <= {need_lo:.1f} and HI >= {need_hi:.1f} Hz")
#: Most Jenkins sliders per joint of the lumped model: 10,000, 100 times the default (the
#: bank's backbone and dissipation errors fall as n^-2, so 1e4 times below the default's).
MAX_SLIDERS = 10_000
