"""Fitted parameters on their bounds: :class:`Bounded` and :func:`at_bound`."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Bounded", "at_bound"]


@dataclass
class Bounded:
    """A fitted parameter with its bounds: ``at_bound`` and which bound, and its
    interval with the kind of interval (``profile``, ``covariance``, ...). In JSON an
    infinite bound is null."""

    name: str
    value: float
    lower: float
    upper: float
    at_bound: bool
    which: str | None = None
    interval: tuple | None = None
    interval_kind: str | None = None

    def to_json(self) -> dict:
        def fin(v):
            return float(v) if np.isfinite(v) else None

        return {"value": self.value, "lower_bound": fin(self.lower),
                "upper_bound": fin(self.upper),
                "at_bound": self.at_bound, "which_bound": self.which,
                "interval": None if self.interval is None else list(self.interval),
                "interval_kind": self.interval_kind}


def at_bound(value: float, lower: float, upper: float, rtol: float = 1e-3):
    """``(on a bound?, "lower"/"upper"/None)``: within ``rtol`` of the range (of
    ``|value|`` for an infinite range) of a bound."""
    span = upper - lower
    tol = rtol * (span if np.isfinite(span) and span > 0 else max(abs(value), 1.0))
    if np.isfinite(lower) and value <= lower + tol:
        return True, "lower"
    if np.isfinite(upper) and value >= upper - tol:
        return True, "upper"
    return False, None
