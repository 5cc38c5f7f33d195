"""The FE model of a case file: strips, supports, interfaces with their joint rows, masses.

Nodes (:mod:`casefile.nodes`) sit at every x the file names (beam and section ends,
supports, interfaces, joints, masses, drive, sensors), elements in between no longer than
``[mesh] element_size`` (:func:`fe.mesh.mesh_with_element_size`); a point (joint, mass,
drive, sensor) within :data:`SNAP_FRACTION` of the element size of another named x shares
its node (no sliver elements), two range ends that close are refused; every beam takes the
nodes of its own range, so two stacked beams share their nodes over an interface. Each
beam's reference line is its ``z``; a section with another centroid height is an
eccentric element (:mod:`fe.stacked`). At an interface at height ``z_i`` (the lower
beam's top face):

* ``normal = "tied"``: at every node a spring on ``w_top - w_bot`` of stiffness
  ``b l / (h_bot/(2 E_bot) + h_top/(2 E_top))`` (the two half-thicknesses in series
  through the interface, ``l`` the node's tributary length in the interface, ``b`` the
  narrower width): stiff, bilateral contact; and, as a gap that stays zero along the
  contact has zero slope, a penalty on ``theta_top - theta_bot`` of :data:`TIED_PENALTY`
  times the layers' rotational stiffness at the node, ``sum (EI_bot + EI_top) / l_e`` over
  its interface elements (springs on ``w`` at the nodes alone leave the two Hermite layers
  free to turn against each other at a node: a section change at a lap end then acts as
  a hinge, 2.4 % low on a lap whose stuck joints are 1e3 times stiffer than the layers,
  at every mesh size; tests/test_case_file_interfaces.py);
* ``tangential = "tied"``: bonded, one plane section: a penalty on the slip of
  :data:`TIED_PENALTY` times the layers' axial stiffness at the node, ``sum (EA_bot +
  EA_top) / l_e``, and the rotation tie above; ``"free"``: nothing (frictionless);
* ``tangential = "joint"``: joint elements on the slip
  ``s = (u_top + lever_top theta_top) - (u_bot - lever_bot theta_bot)`` at ``joints_at``
  (equal shares of ``kt``) or at ``joint_elements`` evenly spaced positions (trapezoidal
  shares ``k_j = kt w_j / sum w``, ``w`` the trapezoidal weights of the positions), so
  ``sum k_j = kt``; a joint element over :data:`MAX_JOINT_STIFFNESS_RATIO` times the
  stiffest strip element of its interface is refused (one line naming ``kt``).

Both tie penalties are relative to the elements they tie, so they are as strong on every
mesh. A penalty fixed per unit length weakens against the elements as ``l_e^2``: its
boundary layer at the lap ends (70 um for the rotation tie of two 8 mm strips) was resolved
more and more, and a lap's first mode drifted by 3e-5 from 4 to 0.25 mm elements with
growing steps (tests/test_case_file_interfaces.py).

Supports: ``clamp`` fixes every DOF of the nodes in ``[x0, x1]``, ``pin`` fixes ``u, w``,
``spring`` adds grounded springs ``k_u, k_w, k_theta``. Point masses (and sensor masses)
act on ``u`` and ``w``. SI units.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from casefile.nodes import (  # node placement; its names stay importable from here too
    NODE_TOLERANCE, SNAP_FRACTION, StripNodes, breakpoints, joint_positions, node_positions,
    snap_distance)
from casefile.spec import is_base_drive
from casefile.tables import CaseFileError
from fe.assembly import coupling_rows
from fe.beam import THETA, U, W
from fe.mesh import DofMap, line_mesh
from fe.stacked import StackedModel, StripMesh, assemble_stack, interface_rows

#: a tied contact: this many times the layers' own stiffness at a node (a penalty for "no
#: slip" and "no relative rotation"; 1e3 keeps K well conditioned, the tied lap then
#: equals the monolithic beam to the mesh error, tests/test_case_file.py)
TIED_PENALTY = 1.0e3
#: a joint element at most this many times stiffer than the stiffest strip element of its
#: interface (axial ``EA/l``): a glued stack (0.4 m steel strips, 5 mm elements, 5 joint
#: elements) gives the same modes from kt = 1e12 to 1e17 N/m (ratio 7e6; glue slip
#: falling as 1/kt), at 1e18 (7e7) the Cholesky factor of ``K + M`` fails, at 1e20 a
#: rigid-body mode comes out at 51 Hz
MAX_JOINT_STIFFNESS_RATIO = 1.0e7


@dataclass
class BuiltCase:
    """A case file's model and what the summary reports about it."""
    model: StackedModel
    joint_table: list        # dicts: interface, x_m, share, k_N_per_m
    n_nodes: int


def joint_shares(itf) -> np.ndarray:
    """Each joint element's share of ``kt`` (sums to 1): equal at bolts, trapezoidal for
    distributed elements (module docstring)."""
    x = joint_positions(itf)
    if itf.joints_at is not None:
        return np.full(x.size, 1.0 / x.size)
    w = line_mesh(x).tributary_length()
    return w / w.sum()


def _strip(cf, beam, x_all: np.ndarray) -> StripMesh:
    x = x_all[(x_all >= beam.x[0] - NODE_TOLERANCE) & (x_all <= beam.x[1] + NODE_TOLERANCE)]
    mid = 0.5 * (x[1:] + x[:-1])
    props = np.array([beam.section_at(m) for m in mid])         # thickness, z, width
    h, zc, b = props[:, 0], props[:, 1], props[:, 2]
    mat = cf.material(beam.material)
    area = b * h
    return StripMesh(beam.name, x, float(beam.z), EA=mat.E * area, EI=mat.E * (b * h**3 / 12.0),
                     rhoA=mat.rho * area, offset=zc - beam.z, thickness=h, width=b)


def _interface_springs(cf, itf, nodes: StripNodes):
    """Node pairs of an interface and the through-thickness stiffness per node (N/m)."""
    lo_b, up_b = (cf.beam(n) for n in itf.beams)
    n_lo = nodes.nodes_in(lo_b.name, *itf.x)
    n_up = nodes.nodes_in(up_b.name, *itf.x)
    x = nodes.strips[lo_b.name].x[n_lo]
    trib = line_mesh(x).tributary_length()
    centre = 0.5 * (itf.x[0] + itf.x[1])
    inward = x + np.sign(centre - x) * 1e-7
    E_lo, E_up = cf.material(lo_b.material).E, cf.material(up_b.material).E
    k = np.empty(x.size)
    for i, xi in enumerate(inward):
        h_lo, _, b_lo = lo_b.section_at(xi)
        h_up, _, b_up = up_b.section_at(xi)
        k[i] = min(b_lo, b_up) * trib[i] / (0.5 * h_lo / E_lo + 0.5 * h_up / E_up)
    return n_lo, n_up, k


def _tie_stiffness(nodes: StripNodes, lo: str, up: str, n_lo, n_up, key: str) -> np.ndarray:
    """Per interface node, ``sum (S_lo + S_up) / l_e`` over its interface elements, ``S``
    the strips' ``EI`` (N m^2: a rotational stiffness, N m/rad) or ``EA`` (N: N/m)."""
    s_lo, s_up = nodes.strips[lo], nodes.strips[up]
    e_lo, e_up = np.asarray(n_lo)[:-1], np.asarray(n_up)[:-1]     # element = its left node
    per = ((getattr(s_lo, key)[e_lo] + getattr(s_up, key)[e_up])
           / (s_lo.x[e_lo + 1] - s_lo.x[e_lo]))
    return np.concatenate([per, [0.0]]) + np.concatenate([[0.0], per])


def _check_joint_stiffness(cf, i: int, k_max: float, *strips) -> None:
    """Refuse a joint element stiffer than :data:`MAX_JOINT_STIFFNESS_RATIO` times the
    stiffest strip element of its interface (one line naming ``[interface.i] kt``)."""
    ea_l = max(float(np.max(s.EA / np.diff(s.x))) for s in strips)
    if k_max > MAX_JOINT_STIFFNESS_RATIO * ea_l:
        kt = cf.interfaces[i].kt
        raise CaseFileError(
            f"{cf.path}: [interface.{i}] kt: {kt:g} N/m puts {k_max:.3g} N/m on one joint "
            f"element, {k_max / ea_l:.2g} times the stiffest strip element (EA/l = "
            f"{ea_l:.3g} N/m); above {MAX_JOINT_STIFFNESS_RATIO:g} times the modes drown in "
            f"round-off: give kt <= {kt * MAX_JOINT_STIFFNESS_RATIO * ea_l / k_max:.3g} N/m "
            f"(stuck joints that stiff act as a bond: tangential = \"tied\")")


def _support_dofs(cf, nodes: StripNodes) -> tuple[np.ndarray, list]:
    """The supports' fixed DOFs (sorted, unique) and grounded springs ``[(G, k), ...]``."""
    fixed, couplings = [], []
    for s in cf.supports:
        for beam in s.beams:
            dm = nodes.maps[beam]
            if s.kind == "clamp":
                fixed += list(dm.node_dofs(nodes.nodes_in(beam, *s.x)).ravel())
            elif s.kind == "pin":
                n0 = nodes.node(beam, s.x[0])
                fixed += [int(dm.dof(n0, U)), int(dm.dof(n0, W))]
            elif s.kind == "spring":
                for comp, k in ((U, s.k_u), (W, s.k_w), (THETA, s.k_theta)):
                    if k > 0:
                        dof = nodes.dof(beam, s.x[0], comp)
                        couplings.append((coupling_rows([[dof]], [1.0], nodes.n), np.array([k])))
    return np.unique(np.asarray(fixed, dtype=int)), couplings


@dataclass(frozen=True)
class _Contact:
    """An interface's two strips on the mesh: beam names, DOF maps, interface nodes and
    levers (m) from each beam's reference line to the interface (lower, upper)."""
    lo: str
    up: str
    m_lo: DofMap
    m_up: DofMap
    n_lo: np.ndarray
    n_up: np.ndarray
    lever_lo: float
    lever_up: float

    def slip_rows(self, n_dofs: int, n_lo, n_up) -> sp.csr_matrix:
        """Slip rows ``upper - lower`` (with the levers) at the node pairs."""
        return interface_rows(self.m_up, self.m_lo, n_up, n_lo, n_dofs, self.lever_up,
                              self.lever_lo)


def _contact(cf, itf, nodes: StripNodes) -> tuple[_Contact, np.ndarray]:
    """The interface's :class:`_Contact` and its through-thickness stiffness per node (N/m)."""
    lo_b, up_b = (cf.beam(n) for n in itf.beams)
    xm = 0.5 * (itf.x[0] + itf.x[1])
    h_lo, z_lo, _ = lo_b.section_at(xm)
    z_i = z_lo + 0.5 * h_lo
    lever_lo, lever_up = z_i - lo_b.z, up_b.z - z_i
    m_lo, m_up = nodes.maps[lo_b.name], nodes.maps[up_b.name]
    n_lo, n_up, k = _interface_springs(cf, itf, nodes)
    return _Contact(lo_b.name, up_b.name, m_lo, m_up, n_lo, n_up, lever_lo, lever_up), k


def _ties(itf, c: _Contact, nodes: StripNodes) -> list:
    """Penalty couplings of a tied interface: on the slip (tangential tied), then on the
    relative rotation (normal or tangential tied)."""
    couplings = []
    if itf.tangential == "tied":
        k_slip = _tie_stiffness(nodes, c.lo, c.up, c.n_lo, c.n_up, "EA")
        couplings.append((c.slip_rows(nodes.n, c.n_lo, c.n_up), TIED_PENALTY * k_slip))
    if "tied" in (itf.normal, itf.tangential):
        # the gap w_top - w_bot is zero along the contact, so is its slope
        rot = coupling_rows(np.column_stack([c.m_up.dof(c.n_up, THETA), c.m_lo.dof(c.n_lo, THETA)]),
                            [1.0, -1.0], nodes.n)
        k_rot = _tie_stiffness(nodes, c.lo, c.up, c.n_lo, c.n_up, "EI")
        couplings.append((rot, TIED_PENALTY * k_rot))
    return couplings


def _joint_elements(cf, i: int, c: _Contact,
                    nodes: StripNodes) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """Interface ``i``'s joint elements: slip rows, stiffnesses (N/m), positions (m)."""
    itf = cf.interfaces[i]
    xj = joint_positions(itf)
    kj = itf.kt * joint_shares(itf)
    _check_joint_stiffness(cf, i, float(np.max(kj)), nodes.strips[c.lo], nodes.strips[c.up])
    jn_lo = [nodes.node(c.lo, v) for v in xj]
    jn_up = [nodes.node(c.up, v) for v in xj]
    xj = nodes.strips[c.lo].x[jn_lo]      # a snapped joint sits at its node
    return c.slip_rows(nodes.n, jn_lo, jn_up), kj, xj


@dataclass
class _Interfaces:
    """What the interfaces add to the model, in file order: tie couplings, tied normal
    contacts, joint elements (rows, stiffnesses, positions, interface index), joint table."""
    couplings: list = field(default_factory=list)
    normal_rows: list = field(default_factory=list)
    normal_k: list = field(default_factory=list)
    joint_rows: list = field(default_factory=list)
    joint_k: list = field(default_factory=list)
    joint_x: list = field(default_factory=list)
    joint_itf: list = field(default_factory=list)
    table: list = field(default_factory=list)

    def add_joints(self, i: int, kt: float, rows: sp.csr_matrix, kj: np.ndarray,
                   xj: np.ndarray) -> None:
        """Append interface ``i``'s joint elements and their table rows."""
        self.joint_rows.append(rows)
        self.joint_k.append(kj)
        self.joint_x.append(xj)
        self.joint_itf.append(np.full(xj.size, i))
        self.table += [{"interface": i, "x_m": float(a), "share": float(c / kt),
                        "k_N_per_m": float(c)} for a, c in zip(xj, kj)]

    def joint_arrays(self) -> tuple:
        """(slip rows or None, stiffnesses, positions, interface indices) of all joints."""
        G_t = sp.vstack(self.joint_rows, format="csr") if self.joint_rows else None
        return (G_t, np.concatenate(self.joint_k) if self.joint_k else np.zeros(0),
                np.concatenate(self.joint_x) if self.joint_x else np.zeros(0),
                np.concatenate(self.joint_itf) if self.joint_itf else np.zeros(0, int))

    def normal_contact(self, is_free: np.ndarray) -> tuple | None:
        """``(G, k)`` of the tied normal contacts whose rows touch a free DOF (None if none)."""
        if not self.normal_rows:
            return None
        G_n = sp.vstack(self.normal_rows, format="csr")
        k_n = np.concatenate(self.normal_k)
        touches_free = np.asarray(abs(G_n) @ is_free.astype(float)).ravel() > 0
        return G_n[np.flatnonzero(touches_free)], k_n[touches_free]


def _interfaces(cf, nodes: StripNodes) -> _Interfaces:
    """Ties, tied normal contacts and joint elements of every interface (module docstring)."""
    parts = _Interfaces()
    for i, itf in enumerate(cf.interfaces):
        c, k = _contact(cf, itf, nodes)
        if itf.normal == "tied":
            parts.normal_rows.append(interface_rows(c.m_up, c.m_lo, c.n_up, c.n_lo, nodes.n))
            parts.normal_k.append(k)
        parts.couplings += _ties(itf, c, nodes)
        if itf.tangential == "joint":
            parts.add_joints(i, itf.kt, *_joint_elements(cf, i, c, nodes))
    return parts


def _point_dofs(cf, nodes: StripNodes, is_free: np.ndarray) -> tuple[list, list, int, int]:
    """Point-mass DOFs and masses (kg), all-DOF indices of the drive and the response."""
    mass_dofs, masses = [], []
    for p in (*cf.masses, *cf.sensors):
        if p.mass > 0:
            mass_dofs += [nodes.dof(p.beam, p.x, W), nodes.dof(p.beam, p.x, U)]
            masses += [p.mass, p.mass]
    drive = cf.drive if cf.drive is not None and not is_base_drive(cf.drive) else \
        (cf.sensors[0] if cf.sensors else None)   # a base drive: its response point
    drive_dof = nodes.dof(drive.beam, drive.x, W) if drive else _last_free_w(is_free)
    response = cf.sensors[0] if cf.sensors else drive
    response_dof = nodes.dof(response.beam, response.x, W) if response else drive_dof
    return mass_dofs, masses, drive_dof, response_dof


def build_model(cf) -> BuiltCase:
    """Assemble the case file's linear model (module docstring)."""
    x_all = node_positions(cf)
    strips = [_strip(cf, b, x_all) for b in cf.beams]
    nodes = StripNodes(strips, snap_distance(cf.element_size))
    fixed, couplings = _support_dofs(cf, nodes)
    is_free = np.ones(nodes.n, dtype=bool)
    is_free[fixed] = False
    parts = _interfaces(cf, nodes)
    couplings += parts.couplings
    normal = parts.normal_contact(is_free)
    if normal is not None:
        couplings.insert(0, normal)
    mass_dofs, masses, drive_dof, response_dof = _point_dofs(cf, nodes, is_free)
    model = assemble_stack(
        strips, couplings, *parts.joint_arrays(), mass_dofs, masses, fixed, drive_dof,
        response_dof, normal=normal, point_mass=sum(p.mass for p in (*cf.masses, *cf.sensors)))
    return BuiltCase(model=model, joint_table=parts.table,
                     n_nodes=int(sum(s.n_nodes for s in strips)))


def _last_free_w(is_free: np.ndarray) -> int:
    """A transverse DOF off the supports (a model without drive or sensor needs one)."""
    return int(np.flatnonzero(is_free[W::3])[-1] * 3 + W)
