"""One-dimensional meshes along x and DOF maps for frame elements.

A :class:`LineMesh` holds node coordinates and two-node connectivity. A
:class:`DofMap` numbers ``dofs_per_node`` DOFs per node, node-major
(``dof = offset + dofs_per_node * node + component``), so several meshes (e.g. the two
strips of a double beam) can be stacked by giving each an ``offset``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LineMesh:
    """Nodes on the x axis and two-node elements.

    Attributes
    ----------
    x : ndarray, shape (n_nodes,)
        Node coordinates, m, strictly increasing.
    elements : ndarray, shape (n_elements, 2)
        Node indices of each element.
    """

    x: np.ndarray
    elements: np.ndarray

    @property
    def n_nodes(self) -> int:
        return int(self.x.size)

    @property
    def n_elements(self) -> int:
        return int(self.elements.shape[0])

    @property
    def element_length(self) -> np.ndarray:
        """Element lengths, m, shape (n_elements,)."""
        return self.x[self.elements[:, 1]] - self.x[self.elements[:, 0]]

    def nodes_in(self, lo: float, hi: float, tol: float = 1e-12) -> np.ndarray:
        """Indices of the nodes with ``lo - tol <= x <= hi + tol``."""
        return np.flatnonzero((self.x >= lo - tol) & (self.x <= hi + tol))

    def node_at(self, x0: float, tol: float = 1e-9) -> int:
        """Index of the node at ``x0``; ValueError if no node lies within ``tol``."""
        i = int(np.argmin(np.abs(self.x - x0)))
        if abs(self.x[i] - x0) > tol:
            raise ValueError(f"no mesh node at x = {x0:g} m (nearest {self.x[i]:g} m)")
        return i

    def tributary_length(self, nodes: np.ndarray | None = None) -> np.ndarray:
        """Trapezoidal-rule weight of each node, m (half of each adjacent element).

        Sums to the length of the mesh over all nodes. With ``nodes`` given, the weights
        of the sub-mesh made of the elements whose two nodes are both in ``nodes``.
        """
        le = self.element_length
        if nodes is None:
            mask = np.ones(self.n_elements, dtype=bool)
        else:
            inside = np.zeros(self.n_nodes, dtype=bool)
            inside[np.asarray(nodes)] = True
            mask = inside[self.elements].all(axis=1)
        w = np.zeros(self.n_nodes)
        np.add.at(w, self.elements[mask].ravel(), np.repeat(0.5 * le[mask], 2))
        return w if nodes is None else w[np.asarray(nodes)]


def line_mesh(x: np.ndarray) -> LineMesh:
    """Mesh of consecutive two-node elements through the given node coordinates (m)."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ValueError("a line mesh needs at least two node coordinates")
    if np.any(np.diff(x) <= 0):
        raise ValueError("node coordinates must be strictly increasing")
    n = x.size
    elements = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    return LineMesh(x=x, elements=elements)


def segmented_line_mesh(breakpoints, n_elements) -> LineMesh:
    """Uniform sub-meshes between consecutive breakpoints, sharing the breakpoint nodes.

    Parameters
    ----------
    breakpoints : array_like, shape (n_seg + 1,)
        Strictly increasing x coordinates (m) that must be nodes.
    n_elements : int or array_like of int, shape (n_seg,)
        Number of elements in each segment.
    """
    b = np.asarray(breakpoints, dtype=float)
    if b.ndim != 1 or b.size < 2 or np.any(np.diff(b) <= 0):
        raise ValueError("breakpoints must be strictly increasing, at least two")
    counts = np.broadcast_to(np.asarray(n_elements, dtype=int), (b.size - 1,))
    if np.any(counts < 1):
        raise ValueError("every segment needs at least one element")
    pieces = [np.linspace(b[i], b[i + 1], counts[i] + 1)[:-1] for i in range(b.size - 1)]
    return line_mesh(np.concatenate(pieces + [b[-1:]]))


def mesh_with_element_size(breakpoints, element_size: float) -> LineMesh:
    """Segmented mesh whose elements are no longer than ``element_size`` (m)."""
    b = np.asarray(breakpoints, dtype=float)
    if not element_size > 0:
        raise ValueError(f"element size must be positive, got {element_size!r}")
    counts = np.maximum(1, np.ceil(np.diff(b) / element_size - 1e-9).astype(int))
    return segmented_line_mesh(b, counts)


@dataclass(frozen=True)
class DofMap:
    """Node-major numbering of ``dofs_per_node`` DOFs per node, starting at ``offset``."""

    n_nodes: int
    dofs_per_node: int = 3
    offset: int = 0

    @property
    def n_dofs(self) -> int:
        return self.n_nodes * self.dofs_per_node

    @property
    def stop(self) -> int:
        """First DOF index after this map (offset of the next block)."""
        return self.offset + self.n_dofs

    def dof(self, node, component) -> np.ndarray:
        """Global DOF index of ``component`` at ``node`` (arrays broadcast)."""
        node = np.asarray(node)
        component = np.asarray(component)
        if np.any((node < 0) | (node >= self.n_nodes)):
            raise ValueError("node index out of range")
        return self.offset + self.dofs_per_node * node + component

    def node_dofs(self, nodes) -> np.ndarray:
        """All DOFs of the given nodes, shape (len(nodes), dofs_per_node)."""
        nodes = np.asarray(nodes)
        return self.dof(nodes[..., None], np.arange(self.dofs_per_node))

    def element_dofs(self, elements: np.ndarray) -> np.ndarray:
        """DOFs of two-node elements, shape (n_elements, 2 * dofs_per_node)."""
        d = self.node_dofs(np.asarray(elements))  # (n_el, 2, dpn)
        return d.reshape(d.shape[0], -1)

    def component(self, vector: np.ndarray, component: int) -> np.ndarray:
        """Values of one component at every node from a full DOF vector (or matrix)."""
        return np.asarray(vector)[self.dof(np.arange(self.n_nodes), component)]
