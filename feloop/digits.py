"""Printed numbers that carry the digits their uncertainty supports.

A fitted value with a standard error ``sd`` is printed to the decimal of the second
significant digit of ``sd`` (:data:`SD_DIGITS`), its interval's ends to the same decimal:
``chi = -0.637464`` with a 95 % interval ``-0.679426 .. -0.595502`` (``sd`` 0.021) reads
``-0.637  -0.679 .. -0.596``. The digits beyond it are the optimizer's stopping point,
which moves with the BLAS kernel (-0.6374633 on one, -0.637464 on another); JSON keeps the
full value. Without a usable ``sd`` (an open or missing interval) the value keeps its
caller's format.
"""
from __future__ import annotations

import math

#: significant digits of the standard error that a printed value keeps
SD_DIGITS = 2
#: the normal quantile of a two-sided 95 % interval (half-width = Z95 sd)
Z95 = 1.959963984540054


def decimals(sd: float, digits: int = SD_DIGITS) -> int | None:
    """The decimal position (digits after the point, negative left of it) of the
    ``digits``-th significant digit of ``sd``; None without a finite, positive ``sd``."""
    if sd is None or not math.isfinite(sd) or sd <= 0.0:
        return None
    return digits - 1 - math.floor(math.log10(sd))


def interval_sd(value, lo, hi, z: float = Z95) -> float | None:
    """The standard error a ``z``-sided interval ``[lo, hi]`` of ``value`` stands for
    (its half-width over ``z``; one finite end alone: its distance from the value); None
    when neither end is finite."""
    ends = [e for e in (lo, hi) if e is not None and math.isfinite(e)]
    if len(ends) == 2:
        return (ends[1] - ends[0]) / (2.0 * z)
    if len(ends) == 1 and value is not None and math.isfinite(value):
        return abs(ends[0] - value) / z
    return None


def fmt(value, sd, fallback: str = ".6g", digits: int = SD_DIGITS) -> str:
    """``value`` to the decimal that :func:`decimals` gives for ``sd``: fixed point
    (``0.0000`` for a value below that decimal), with an exponent where that would take
    more than 8 decimals or |value| >= 1e6; ``format(value, fallback)`` without a usable
    ``sd``; ``"open"`` for None."""
    if value is None:
        return "open"
    d = decimals(sd, digits)
    if d is None or not math.isfinite(value):
        return format(value, fallback)
    mag = abs(value)
    if mag >= 1e6 or (d > 8 and mag > 0.0):
        significant = max(1, math.floor(math.log10(mag)) + d + 1)
        return f"{value:.{significant - 1}e}"
    text = f"{round(value, d):.0f}" if d <= 0 else f"{value:.{d}f}"
    return text.lstrip("-") if float(text) == 0.0 else text     # no "-0.00"


def fmt_interval(value, lo, hi, fallback: str = ".6g", z: float = Z95) -> tuple[str, str, str]:
    """(value, lo, hi) as text, all three to the decimal their interval's ``sd`` supports
    (:func:`interval_sd`); ``"open"`` for a missing end."""
    sd = interval_sd(value, lo, hi, z)
    return fmt(value, sd, fallback), fmt(lo, sd, fallback), fmt(hi, sd, fallback)
