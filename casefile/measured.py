"""The measured-data table of a case file's ``[measured] file``.

A table (``docs/formats/measured-data.md``) is used as it is. FRF files of a series (one
per level) and a free-decay record are identified first, as ``iwanfe identify`` does
(:func:`ident.series.load_series`: LSCF per level, or the free-decay Hilbert track), and
the identified table is written once to the cache (``$XDG_CACHE_HOME/iwanfe/measured``,
default ``~/.cache``), under a hash of the files' names and contents: a rerun reads it, a
changed file is identified again.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["measured_table", "cache_dir"]


def cache_dir() -> Path:
    """Where identified tables are kept."""
    root = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(root) / "iwanfe" / "measured"


def measured_table(files) -> Path:
    """Path of the measured-data table the case file's ``files`` give (module doc)."""
    from ident.measured import write_measured
    from ident.series import is_frf_file, load_series
    from ident.time_records import is_time_record

    files = [Path(f) for f in files]
    if len(files) == 1 and not is_frf_file(files[0]) and not is_time_record(files[0]):
        return files[0]
    digest = hashlib.sha256()
    for f in files:
        digest.update(f.name.encode() + b"\0" + f.read_bytes())
    path = cache_dir() / f"{files[0].stem}-{digest.hexdigest()[:16]}.csv"
    if not path.exists():
        table = load_series(files)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".part")
        write_measured(tmp, table)
        tmp.replace(path)
    return path
