"""Any assembly of straight Euler-Bernoulli strips stacked in one plane, with interface rows.

Each strip is a chain of 2-D frame elements (:mod:`fe.beam`) on its own *reference line*
at height ``z_ref``; an element whose section centroid lies at ``z_c != z_ref`` (a notched
lap end) is an eccentric element: its centroid moves axially by ``u - e theta`` with
``e = z_c - z_ref`` (:mod:`fe.interface` eq. 1), so its matrices are ``T^T K_e T`` with
``T`` replacing ``u`` by ``u - e theta`` at both nodes (e.g. Cook et al., *Concepts and
Applications of FEA*, 4th ed., sec. 7.4, offset beams). With ``e = 0`` the element matrices
are the plain ones, bit for bit.

Couplings between strips are rows ``G`` on the DOF vector with one stiffness each
(``K += G^T diag(k) G``, :func:`fe.assembly.coupling_stiffness`): the normal gap and the
tangential slip at an interface height ``z_i`` (:func:`interface_rows`). The joint rows are
kept apart so that the nonlinear solvers put their joint law there
(``K = K_without_joints + slip^T diag(k_joint) slip``). SI units.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from fe.assembly import (assemble, coupling_rows, coupling_stiffness, expand, free_dofs,
                         point_masses, restrict, restrict_columns)
from fe.beam import THETA, U, W, frame_mass, frame_stiffness
from fe.interface import StripGeometry, stacked_energy_split
from fe.mesh import DofMap
from fe.modal import normal_modes

__all__ = ["StripMesh", "StackedModel", "strip_matrices", "interface_rows", "assemble_stack"]


@dataclass(frozen=True)
class StripMesh:
    """One strip: nodes ``x`` (m) on its reference line at ``z_ref`` (m) and, per element,
    ``EA`` (N), ``EI`` (N m^2), ``rhoA`` (kg/m), centroid offset ``offset = z_c - z_ref``
    (m), ``thickness`` and ``width`` (m)."""

    name: str
    x: np.ndarray
    z_ref: float
    EA: np.ndarray
    EI: np.ndarray
    rhoA: np.ndarray
    offset: np.ndarray
    thickness: np.ndarray
    width: np.ndarray

    @property
    def n_nodes(self) -> int:
        return int(self.x.size)


def _offset_transform(e: np.ndarray) -> np.ndarray:
    """(n, 6, 6) ``T``: nodal (u, w, theta) of the reference line -> of the centroid."""
    T = np.broadcast_to(np.eye(6), (e.size, 6, 6)).copy()
    T[:, 0, 2] = -e
    T[:, 3, 5] = -e
    return T


def strip_matrices(strip: StripMesh) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Stiffness (N/m) and consistent mass (kg) of one strip on its own node-major DOFs."""
    le = np.diff(strip.x)
    Ke = frame_stiffness(le, strip.EA, strip.EI)
    Me = frame_mass(le, strip.rhoA)
    ecc = np.flatnonzero(strip.offset != 0.0)
    if ecc.size:
        T = _offset_transform(strip.offset[ecc])
        Ke[ecc] = np.transpose(T, (0, 2, 1)) @ Ke[ecc] @ T
        Me[ecc] = np.transpose(T, (0, 2, 1)) @ Me[ecc] @ T
    dm = DofMap(strip.n_nodes, 3, 0)
    elements = np.column_stack([np.arange(le.size), np.arange(1, le.size + 1)])
    return (assemble(Ke, dm.element_dofs(elements), dm.n_dofs),
            assemble(Me, dm.element_dofs(elements), dm.n_dofs))


def interface_rows(upper: DofMap, lower: DofMap, nodes_up, nodes_lo, n_dofs: int,
                   lever_up: float | None = None, lever_lo: float | None = None) -> sp.csr_matrix:
    """Rows at paired nodes of the normal gap ``w_up - w_lo`` (m; no levers given) or of the
    tangential slip ``s = (u_up + lever_up theta_up) - (u_lo - lever_lo theta_lo)`` (m):
    :mod:`fe.interface` eq. 2, ``lever`` the distance (m) from a strip's reference line to
    the interface, ``h/2`` for strips on their centroid lines."""
    nodes_up, nodes_lo = np.asarray(nodes_up), np.asarray(nodes_lo)
    if lever_up is None:
        return coupling_rows(np.column_stack([upper.dof(nodes_up, W), lower.dof(nodes_lo, W)]),
                             [1.0, -1.0], n_dofs)
    dofs = np.column_stack([upper.dof(nodes_up, U), upper.dof(nodes_up, THETA),
                            lower.dof(nodes_lo, U), lower.dof(nodes_lo, THETA)])
    return coupling_rows(dofs, [1.0, float(lever_up), -1.0, float(lever_lo)], n_dofs)


_PAIR_KINDS = {"in_phase_bending": "in-phase bending",
               "out_of_phase_bending": "out-of-phase bending",
               "in_phase_axial": "axial", "out_of_phase_axial": "out-of-phase axial"}


class JointedStrips:
    """What every assembled model of jointed strips offers, from its fields ``K``, ``M``
    (free DOFs), ``free``, ``dofmaps``, ``slip_matrix`` and ``joint_stiffness``: modes,
    free-to-full vectors, per-strip displacements, joint slips. Shared by
    :class:`StackedModel` and the double beam's Python model."""

    @property
    def n_free(self) -> int:
        return int(self.free.size)

    @property
    def n_dofs(self) -> int:
        return int(self.dofmaps[-1].stop)

    def modes(self, n_modes: int):
        """Lowest ``n_modes`` modes: (omega rad/s (n,), mass-normalized shapes (n_free, n))."""
        return normal_modes(self.K, self.M, min(int(n_modes), self.n_free - 2))

    def modes_below(self, f_max_hz: float, start: int = 12):
        """All modes with frequency <= ``f_max_hz`` (plus one above, to bracket)."""
        n = start
        while True:
            omega, shapes = self.modes(n)
            if omega[-1] > 2 * np.pi * f_max_hz or n >= self.n_free - 2:
                return omega, shapes
            n *= 2

    def full_vector(self, shape: np.ndarray) -> np.ndarray:
        """Free-DOF vector(s) to all DOFs (zeros at the supports)."""
        return expand(shape, self.free, self.n_dofs)

    def strip_displacements(self, shape: np.ndarray) -> list[dict]:
        """Per strip ``dict(u=, w=, theta=)`` at all its nodes (supported ones included),
        m, rad."""
        full = self.full_vector(np.asarray(shape))
        return [{"u": dm.component(full, U), "w": dm.component(full, W),
                 "theta": dm.component(full, THETA)} for dm in self.dofmaps]

    def glue_slip_participation(self, shape: np.ndarray) -> float:
        """``sum_j k_j s_j^2 / (phi^T K phi)``: the share of the mode's strain energy in the
        joints' stuck springs, ``d ln(omega^2) / d ln(K_T)`` for a mode (Rayleigh)."""
        shape = np.asarray(shape, dtype=float)
        s = self.slip_matrix @ shape
        return float(np.sum(self.joint_stiffness * s**2) / (shape @ (self.K @ shape)))

    def joint_slips(self, shape: np.ndarray) -> np.ndarray:
        """Tangential slip at each joint for a free-DOF vector, m."""
        return self.slip_matrix @ np.asarray(shape)


@dataclass
class StackedModel(JointedStrips):
    """Assembled linear model of stacked strips over the free DOFs (joints stuck).

    ``K = K_without_joints + slip_matrix^T diag(joint_stiffness) slip_matrix`` (N/m);
    ``M`` (kg) holds the strips and the point masses. ``slip_matrix`` (n_joints, n_free)
    gives each joint element's tangential slip (m), ``normal_matrix`` the normal gaps of
    the tied contacts; ``joint_x`` (m) the joint positions, ``joint_interface`` the index
    of each joint's interface; ``drive_dof``, ``response_dof`` free-DOF indices of the
    driven and the measured transverse displacement. The methods are those of the
    double-beam model (:mod:`cases.double_beam.model`), so every consumer takes either.
    """

    strip_meshes: list
    dofmaps: list
    free: np.ndarray
    M: sp.csr_matrix
    K: sp.csr_matrix
    K_without_joints: sp.csr_matrix
    slip_matrix: sp.csr_matrix
    normal_matrix: sp.csr_matrix
    normal_stiffness: np.ndarray
    joint_stiffness: np.ndarray
    joint_x: np.ndarray
    joint_interface: np.ndarray
    drive_dof: int
    response_dof: int
    strip_mass_matrix: sp.csr_matrix = field(repr=False)
    point_mass: float = 0.0

    @property
    def strips(self) -> list[StripGeometry]:
        """Drawing geometry (:mod:`viz`): each strip at its reference line with its
        thickest section (a notched end is drawn full)."""
        return [StripGeometry(s.x.copy(), float(s.z_ref), float(s.thickness.max()),
                              float(s.width.max())) for s in self.strip_meshes]

    @property
    def mass(self) -> float:
        """Total mass (kg): strips (free and supported parts) plus point masses."""
        return float(sum(np.sum(s.rhoA * np.diff(s.x)) for s in self.strip_meshes)
                     + self.point_mass)

    def _identical_pair(self) -> bool:
        if len(self.strip_meshes) != 2:
            return False
        a, b = self.strip_meshes
        return all(np.array_equal(getattr(a, k), getattr(b, k))
                   for k in ("x", "EA", "EI", "rhoA", "offset"))

    def classify_mode(self, shape: np.ndarray) -> str:
        """The kind whose share of the strips' kinetic energy is largest: for two identical
        strips 'in-phase bending', 'out-of-phase bending', 'axial', 'out-of-phase axial'
        (:func:`fe.interface.stacked_energy_split`); otherwise 'bending' or 'axial'."""
        full = self.full_vector(np.asarray(shape, dtype=float))
        if self._identical_pair():
            lo, up = (full[dm.offset:dm.stop] for dm in self.dofmaps)
            n = self.dofmaps[0].n_dofs
            split = stacked_energy_split(lo, up, self.strip_mass_matrix[:n, :n])
            return _PAIR_KINDS[max(split, key=split.get)]
        axial = np.zeros(full.size, dtype=bool)
        axial[U::3] = True
        va, vt = np.where(axial, full, 0.0), np.where(axial, 0.0, full)
        Ms = self.strip_mass_matrix
        return "axial" if va @ (Ms @ va) > vt @ (Ms @ vt) else "bending"

    def bending_order(self, omega: np.ndarray, shapes: np.ndarray) -> np.ndarray:
        """1-based order of each mode among the (in-phase) bending elastic modes, 0 for
        others and for rigid-body modes (below 1e-3 of the highest frequency computed)."""
        kinds = [self.classify_mode(shapes[:, i]) for i in range(shapes.shape[1])]
        elastic = omega > 1e-3 * max(float(np.max(omega)), 1e-300)
        order = np.zeros(len(kinds), dtype=int)
        idx = [i for i in np.argsort(omega)
               if kinds[i] in ("in-phase bending", "bending") and elastic[i]]
        order[idx] = np.arange(1, len(idx) + 1)
        return order

    def bending_mode_frequency(self, order: int) -> float:
        """Frequency (Hz) of the ``order``-th bending mode."""
        omega, shapes = self.modes(order + 8)
        i = np.flatnonzero(self.bending_order(omega, shapes) == order)
        if i.size == 0:
            raise ValueError(f"bending mode {order} not found among the lowest {order + 8} modes")
        return float(omega[i[0]] / (2 * np.pi))


def assemble_stack(strips, couplings, joint_rows, joint_stiffness, joint_x, joint_interface,
                   mass_dofs, masses, fixed, drive_dof: int, response_dof: int,
                   normal=None, point_mass: float = 0.0) -> StackedModel:
    """Assemble strips (:class:`StripMesh`, DOFs numbered strip after strip) with
    couplings ``[(G, k), ...]`` (rows on all DOFs, N/m; grounded springs are rows with
    one entry), joint rows (n_joints, n_dofs) with their stuck stiffnesses (N/m), point
    masses (kg) on DOFs, ``fixed`` DOFs, and all-DOF indices of the drive and the response.
    ``normal``: ``(G, k)`` of the normal contacts, kept on the model (also in ``couplings``);
    ``point_mass``: the point masses' total (kg), for the model's mass.
    """
    dofmaps, offset = [], 0
    for s in strips:
        dofmaps.append(DofMap(s.n_nodes, 3, offset))
        offset = dofmaps[-1].stop
    n = offset
    pairs = [strip_matrices(s) for s in strips]
    K_strips = sp.block_diag([k for k, _ in pairs], format="csr")
    M_strips = sp.block_diag([m for _, m in pairs], format="csr")
    K0 = K_strips
    for G, k in couplings:
        K0 = K0 + coupling_stiffness(G, k)
    G_t = joint_rows if joint_rows is not None else sp.csr_matrix((0, n))
    k_t = np.asarray(joint_stiffness, dtype=float)
    K_full = K0 + coupling_stiffness(G_t, k_t) if k_t.size else K0
    M_full = M_strips + point_masses(np.asarray(mass_dofs, dtype=int),
                                     np.asarray(masses, dtype=float), n)
    free = free_dofs(n, np.asarray(fixed, dtype=int))
    G_n, k_n = normal if normal is not None else (sp.csr_matrix((0, n)), np.zeros(0))
    index = np.full(n, -1)
    index[free] = np.arange(free.size)
    for dof in (drive_dof, response_dof):
        if index[dof] < 0:
            raise ValueError("the drive or the response point lies on a support")
    return StackedModel(
        strip_meshes=list(strips), dofmaps=dofmaps, free=free,
        M=restrict(M_full, free), K=restrict(K_full, free), K_without_joints=restrict(K0, free),
        slip_matrix=restrict_columns(sp.csr_matrix(G_t), free),
        normal_matrix=restrict_columns(sp.csr_matrix(G_n), free),
        normal_stiffness=np.asarray(k_n, dtype=float), joint_stiffness=k_t,
        joint_x=np.asarray(joint_x, dtype=float), joint_interface=np.asarray(joint_interface, int),
        drive_dof=int(index[drive_dof]), response_dof=int(index[response_dof]),
        strip_mass_matrix=M_strips, point_mass=float(point_mass),
    )
