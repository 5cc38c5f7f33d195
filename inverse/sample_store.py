"""Resumable store of Monte Carlo samples (:mod:`inverse.uncertainty`).

One ``sample_XXXXX.npz`` (and ``nominal.npz``) per finished sample, written atomically
as it finishes, in a directory whose ``manifest.json`` (:func:`runs.store.open_manifest`)
names the sweep's hash (:func:`inverse.uncertainty.sweep_hash`); a directory of another
sweep is refused.
"""
from __future__ import annotations

import dataclasses
import math
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from runs.store import open_manifest

__all__ = ["FORMAT", "SampleResult", "SampleStore", "describe"]

FORMAT = "iwanfe-uncertainty/2"


@dataclass
class SampleResult:
    """One sample: ``index`` (-1: nominal), the drawn ``p``, ``ln_kt`` and ``n_draws``,
    the per-sample model's ``values`` (float arrays), ``status`` ("ok" or "failed: ..."),
    ``elapsed`` (s, not part of the result's bits) and ``loaded`` (from the store)."""

    index: int
    p: float
    ln_kt: float
    n_draws: int
    values: dict
    status: str
    elapsed: float = 0.0
    loaded: bool = False

    def __post_init__(self):
        self.values = {k: np.asarray(v, dtype=float) for k, v in self.values.items()}

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def chi(self) -> float:
        return self.p - 1.0

    @property
    def kappa1_B(self) -> float:
        """``|kappa1| B`` at level 1 (rad^2/s^2)."""
        return math.exp(self.ln_kt) / self.p

    def same_bits(self, other: "SampleResult") -> bool:
        """Bitwise equality of everything computed (not ``elapsed``/``loaded``)."""
        def bits(x):
            return np.asarray(x, dtype=float).tobytes()
        return (self.index == other.index and bits(self.p) == bits(other.p)
                and bits(self.ln_kt) == bits(other.ln_kt) and self.n_draws == other.n_draws
                and self.status == other.status and self.values.keys() == other.values.keys()
                and all(bits(v) == bits(other.values[k]) for k, v in self.values.items()))

    def to_npz(self, path: Path) -> None:
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, index=self.index, p=self.p, ln_kt=self.ln_kt, n_draws=self.n_draws,
                 status=self.status, elapsed=self.elapsed,
                 **{f"value_{k}": v for k, v in self.values.items()})
        os.replace(tmp, path)

    @classmethod
    def from_npz(cls, path: Path) -> "SampleResult":
        with np.load(path) as d:
            values = {k[6:]: d[k] for k in d.files if k.startswith("value_")}
            return cls(int(d["index"]), float(d["p"]), float(d["ln_kt"]), int(d["n_draws"]),
                       values, str(d["status"]), float(d["elapsed"]), loaded=True)


def describe(obj):
    """Plain (JSON-able) nested form of a dataclass: type name and fields."""
    if dataclasses.is_dataclass(obj):
        return {"type": type(obj).__name__,
                **{f.name: describe(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if isinstance(obj, (tuple, list)):
        return [describe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


class SampleStore:
    """Directory of finished samples (``nominal.npz``, ``sample_XXXXX.npz``) and a
    ``manifest.json`` naming the sweep's hash; another sweep's directory raises
    ``ValueError``."""

    def __init__(self, directory, digest: str, description: dict | None = None):
        self.path = Path(directory)
        open_manifest(self.path, digest, {"format": FORMAT, **(description or {})},
                      "Monte Carlo sweep")

    def file(self, index: int) -> Path:
        return self.path / ("nominal.npz" if index < 0 else f"sample_{index:05d}.npz")

    def load(self, indices) -> dict[int, SampleResult]:
        """The stored samples among ``indices`` (unreadable files are recomputed)."""
        out = {}
        for i in indices:
            f = self.file(i)
            if f.exists():
                try:
                    out[i] = SampleResult.from_npz(f)
                except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
                    continue
        return out

    def save(self, result: SampleResult) -> None:
        result.to_npz(self.file(result.index))
