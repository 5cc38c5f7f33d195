"""The ``[drive]`` table of a case file: a point force (``kind = "point"``, the default:
``beam``, ``x``) or the base (``kind = "base"``: ``acceleration``, m/s^2, the amplitude
of the transverse acceleration of all supports moving together as one base).

A base drive needs a support that holds the transverse displacement ``w`` (a clamp, a
pin, or a spring with ``k_w > 0``): on a free-free structure the base moves nothing.
Errors are one line naming file, table and key (:class:`casefile.tables.CaseFileError`,
a ``ValueError``; the command line exits with status 2). SI units.
"""
from __future__ import annotations

from casefile.spec import BaseDrive, PointMass, Support
from casefile.tables import Table

DRIVE_KINDS = ("point", "base")


def holds_w(support: Support) -> bool:
    """True when ``support`` grounds the transverse displacement ``w`` (clamp, pin, or a
    spring with ``k_w > 0``): the supports a base drive moves."""
    return support.kind in ("clamp", "pin") or (support.kind == "spring" and support.k_w > 0)


def read_drive(reader, t: Table, by_name: dict, supports: tuple) -> PointMass | BaseDrive:
    """The drive of table ``t`` (module docstring); ``reader``: the case-file reader
    (:class:`casefile.schema._Reader`, for a point drive and the parameter kinds)."""
    kind = t.text("kind", required=False, choices=DRIVE_KINDS, default="point")
    if kind == "point":
        if t.has("acceleration"):
            t.fail("acceleration", 'only a base drive (kind = "base") has an acceleration; '
                                   "a point drive is a force at beam, x")
        reader.given(t, "kind")
        return reader.point(t, by_name, "drive")
    for key in ("beam", "x"):
        if t.has(key):
            t.fail(key, 'a base drive (kind = "base") moves the supports, not a point: '
                        "give acceleration only, no beam or x")
    if not t.has("acceleration"):
        t.fail("acceleration", 'missing: a base drive (kind = "base") needs the amplitude '
                               "of the base acceleration (m/s^2)")
    a = t.number("acceleration", lo=0, lo_open=True)
    if not any(holds_w(s) for s in supports):
        t.fail("kind", 'a base drive needs a support holding w (kind = "clamp", "pin", or '
                       '"spring" with k_w > 0) to move the structure; this one is '
                       "free-free")
    reader.given(t, "kind", "acceleration")
    reader.close(t)
    return BaseDrive(acceleration=a)
