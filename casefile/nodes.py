"""Where a case file's nodes are: every named x, points snapped to a neighbour within
:data:`SNAP_FRACTION` of the element size, elements no longer than the element size in
between, and the node and DOF lookup of the strips (:mod:`casefile.build` assembles the
model on them). SI units.
"""
from __future__ import annotations

import numpy as np

from casefile.spec import is_base_drive
from casefile.tables import CaseFileError
from fe.mesh import DofMap, segmented_line_mesh

NODE_TOLERANCE = 1e-9  # m: x values closer than this are one node
#: named points (joints, masses, drive, sensors) closer than this fraction of the element
#: size to another named x share its node: an element of 1e-5 m between a bolt mass and a
#: joint element has a bending stiffness ~1e18 N/m, 1e15 times a 5 mm element's, and the
#: free-free stiffness matrix's rigid-body modes drown in round-off (a Cholesky failure)
SNAP_FRACTION = 0.1


def joint_positions(itf) -> np.ndarray:
    """Joint element positions of an interface (m)."""
    if itf.joints_at is not None:
        return np.asarray(itf.joints_at, dtype=float)
    return np.linspace(itf.x[0], itf.x[1], int(itf.joint_elements))


def _named_x(cf) -> tuple[list, list]:
    """``(structural, points)``: lists of ``(x, label)`` (m, ``table.i.key``). Structural x
    (beam, section, support and interface ends) bound element properties and ranges;
    points (joints, masses, drive, sensors) load one node."""
    structural, points = [], []
    for i, b in enumerate(cf.beams):
        structural += [(v, f"beam.{i}.x") for v in b.x]
        structural += [(v, f"beam.{i}.section.{j}.x")
                       for j, s in enumerate(b.sections) for v in s.x]
    for i, s in enumerate(cf.supports):
        (structural if s.kind == "clamp" else points).extend((v, f"support.{i}.x") for v in s.x)
    for i, itf in enumerate(cf.interfaces):
        structural += [(v, f"interface.{i}.x") for v in itf.x]
        if itf.tangential == "joint":
            key = "joints_at" if itf.joints_at is not None else "joint_elements"
            points += [(v, f"interface.{i}.{key}") for v in joint_positions(itf)]
    points += [(p.x, f"mass.{i}.x") for i, p in enumerate(cf.masses)]
    points += [(p.x, f"sensor.{i}.x") for i, p in enumerate(cf.sensors)]
    points += [(cf.drive.x, "drive.x")] if cf.drive and not is_base_drive(cf.drive) else []
    return structural, points


def snap_distance(element_size: float) -> float:
    """Named points closer than this (m) share one node (module docstring)."""
    return SNAP_FRACTION * element_size


def breakpoints(cf, element_size: float) -> np.ndarray:
    """The x that must be nodes (m): every structural x, and every point not within
    :func:`snap_distance` of one already kept (structural x first, then points in order of
    x). Two structural x closer than the snap distance (but not equal) are refused."""
    structural, points = _named_x(cf)
    snap = snap_distance(element_size)
    structural.sort()
    kept = [structural[0]]
    for x, label in structural[1:]:
        if x - kept[-1][0] > NODE_TOLERANCE:
            gap = x - kept[-1][0]
            if gap < snap:
                raise CaseFileError(
                    f"{cf.path}: [{label.rsplit('.', 1)[0]}] x: {x:g} m lies {gap:.3g} m "
                    f"from {kept[-1][1]} = {kept[-1][0]:g} m; make them equal or at least "
                    f"{snap:.3g} m ({SNAP_FRACTION:g} element_size) apart")
            kept.append((x, label))
    xs = [x for x, _ in kept]
    for x, _ in sorted(points):
        if np.min(np.abs(np.asarray(xs) - x)) >= snap:
            xs.append(x)
    return np.sort(np.asarray(xs, dtype=float))


def node_positions(cf, element_size: float | None = None) -> np.ndarray:
    """All node positions (m): the breakpoints (:func:`breakpoints`), elements between
    them no longer than the element size (to 1e-6 relative, so a calibrated length rounded
    in its last digits does not add an element)."""
    h = cf.element_size if element_size is None else element_size
    b = breakpoints(cf, h)
    counts = np.maximum(1, np.ceil(np.diff(b) / h - 1e-6).astype(int))
    return segmented_line_mesh(b, counts).x


class StripNodes:
    """Node and DOF lookup of the strips."""

    def __init__(self, strips, snap: float):
        self.strips, self.snap = {s.name: s for s in strips}, snap
        self.maps, offset = {}, 0
        for s in strips:
            self.maps[s.name] = DofMap(s.n_nodes, 3, offset)
            offset = self.maps[s.name].stop
        self.n = offset

    def node(self, beam: str, x: float) -> int:
        """The node at ``x`` or, for a point snapped to a neighbour, the nearest node."""
        xs = self.strips[beam].x
        i = int(np.argmin(np.abs(xs - x)))
        if abs(xs[i] - x) >= self.snap:
            raise ValueError(f"no node of beam {beam!r} at x = {x:g} m")
        return i

    def nodes_in(self, beam: str, x0: float, x1: float) -> np.ndarray:
        xs = self.strips[beam].x
        return np.flatnonzero((xs >= x0 - NODE_TOLERANCE) & (xs <= x1 + NODE_TOLERANCE))

    def dof(self, beam: str, x: float, component: int) -> int:
        return int(self.maps[beam].dof(self.node(beam, x), component))
