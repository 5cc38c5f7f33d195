"""The FE model of a case file: strips, supports, interfaces with their joint rows, masses.

Nodes sit at every x the file names (beam and section ends, supports, interfaces, joints,
masses, drive, sensors), elements in between no longer than ``[mesh] element_size``
(:func:`fe.mesh.mesh_with_element_size`); a point (joint, mass, drive, sensor) within
:data:`SNAP_FRACTION` of the element size of another named x shares its node (no sliver
elements), two range ends that close are refused; every beam takes the nodes of its own
range, so two stacked beams share their nodes over an interface. Each beam's reference line is its
``z``; a section with another centroid height is an eccentric element
(:mod:`fe.stacked`). At an interface at height ``z_i`` (the lower beam's top face):

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

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from casefile.tables import CaseFileError
from fe.assembly import coupling_rows
from fe.beam import THETA, U, W
from fe.mesh import DofMap, line_mesh, segmented_line_mesh
from fe.stacked import StackedModel, StripMesh, assemble_stack, interface_rows

NODE_TOLERANCE = 1e-9  # m: x values closer than this are one node
#: named points (joints, masses, drive, sensors) closer than this fraction of the element
#: size to another named x share its node: an element of 1e-5 m between a bolt mass and a
#: joint element has a bending stiffness ~1e18 N/m, 1e15 times a 5 mm element's, and the
#: free-free stiffness matrix's rigid-body modes drown in round-off (a Cholesky failure)
SNAP_FRACTION = 0.1
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


def joint_positions(itf) -> np.ndarray:
    """Joint element positions of an interface (m)."""
    if itf.joints_at is not None:
        return np.asarray(itf.joints_at, dtype=float)
    return np.linspace(itf.x[0], itf.x[1], int(itf.joint_elements))


def joint_shares(itf) -> np.ndarray:
    """Each joint element's share of ``kt`` (sums to 1): equal at bolts, trapezoidal for
    distributed elements (module docstring)."""
    x = joint_positions(itf)
    if itf.joints_at is not None:
        return np.full(x.size, 1.0 / x.size)
    w = line_mesh(x).tributary_length()
    return w / w.sum()


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
    points += [(cf.drive.x, "drive.x")] if cf.drive else []
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


def _strip(cf, beam, x_all: np.ndarray) -> StripMesh:
    x = x_all[(x_all >= beam.x[0] - NODE_TOLERANCE) & (x_all <= beam.x[1] + NODE_TOLERANCE)]
    mid = 0.5 * (x[1:] + x[:-1])
    props = np.array([beam.section_at(m) for m in mid])         # thickness, z, width
    h, zc, b = props[:, 0], props[:, 1], props[:, 2]
    mat = cf.material(beam.material)
    area = b * h
    return StripMesh(beam.name, x, float(beam.z), EA=mat.E * area, EI=mat.E * (b * h**3 / 12.0),
                     rhoA=mat.rho * area, offset=zc - beam.z, thickness=h, width=b)


class _Nodes:
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


def _interface_springs(cf, itf, nodes: _Nodes):
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


def _tie_stiffness(nodes: _Nodes, lo: str, up: str, n_lo, n_up, key: str) -> np.ndarray:
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


def build_model(cf) -> BuiltCase:
    """Assemble the case file's linear model (module docstring)."""
    x_all = node_positions(cf)
    strips = [_strip(cf, b, x_all) for b in cf.beams]
    nodes = _Nodes(strips, snap_distance(cf.element_size))
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
    fixed = np.unique(np.asarray(fixed, dtype=int))
    is_free = np.ones(nodes.n, dtype=bool)
    is_free[fixed] = False

    normal_rows, normal_k, joint_rows, joint_k, joint_x, joint_itf, table = (
        [], [], [], [], [], [], [])
    for i, itf in enumerate(cf.interfaces):
        lo_b, up_b = (cf.beam(n) for n in itf.beams)
        xm = 0.5 * (itf.x[0] + itf.x[1])
        h_lo, z_lo, _ = lo_b.section_at(xm)
        z_i = z_lo + 0.5 * h_lo
        lever_lo, lever_up = z_i - lo_b.z, up_b.z - z_i
        m_lo, m_up = nodes.maps[lo_b.name], nodes.maps[up_b.name]
        n_lo, n_up, k = _interface_springs(cf, itf, nodes)
        if itf.normal == "tied":
            G = interface_rows(m_up, m_lo, n_up, n_lo, nodes.n)
            normal_rows.append(G)
            normal_k.append(k)
        if itf.tangential == "tied":
            k_slip = _tie_stiffness(nodes, lo_b.name, up_b.name, n_lo, n_up, "EA")
            couplings.append((interface_rows(m_up, m_lo, n_up, n_lo, nodes.n, lever_up, lever_lo),
                              TIED_PENALTY * k_slip))
        if "tied" in (itf.normal, itf.tangential):
            # the gap w_top - w_bot is zero along the contact, so is its slope
            rot = coupling_rows(np.column_stack([m_up.dof(n_up, THETA), m_lo.dof(n_lo, THETA)]),
                                [1.0, -1.0], nodes.n)
            k_rot = _tie_stiffness(nodes, lo_b.name, up_b.name, n_lo, n_up, "EI")
            couplings.append((rot, TIED_PENALTY * k_rot))
        if itf.tangential == "joint":
            xj = joint_positions(itf)
            kj = itf.kt * joint_shares(itf)
            _check_joint_stiffness(cf, i, float(np.max(kj)), nodes.strips[lo_b.name],
                                   nodes.strips[up_b.name])
            jn_lo = [nodes.node(lo_b.name, v) for v in xj]
            jn_up = [nodes.node(up_b.name, v) for v in xj]
            xj = nodes.strips[lo_b.name].x[jn_lo]      # a snapped joint sits at its node
            joint_rows.append(interface_rows(m_up, m_lo, jn_up, jn_lo, nodes.n, lever_up, lever_lo))
            joint_k.append(kj)
            joint_x.append(xj)
            joint_itf.append(np.full(xj.size, i))
            table += [{"interface": i, "x_m": float(a), "share": float(c / itf.kt),
                       "k_N_per_m": float(c)} for a, c in zip(xj, kj)]
    normal = None
    if normal_rows:
        G_n = sp.vstack(normal_rows, format="csr")
        k_n = np.concatenate(normal_k)
        touches_free = np.asarray(abs(G_n) @ is_free.astype(float)).ravel() > 0
        normal = (G_n[np.flatnonzero(touches_free)], k_n[touches_free])
        couplings.insert(0, normal)
    G_t = sp.vstack(joint_rows, format="csr") if joint_rows else None

    mass_dofs, masses = [], []
    for p in (*cf.masses, *cf.sensors):
        if p.mass > 0:
            mass_dofs += [nodes.dof(p.beam, p.x, W), nodes.dof(p.beam, p.x, U)]
            masses += [p.mass, p.mass]
    drive = cf.drive or (cf.sensors[0] if cf.sensors else None)
    drive_dof = nodes.dof(drive.beam, drive.x, W) if drive else _last_free_w(is_free)
    response = cf.sensors[0] if cf.sensors else drive
    response_dof = nodes.dof(response.beam, response.x, W) if response else drive_dof
    model = assemble_stack(
        strips, couplings, G_t, np.concatenate(joint_k) if joint_k else np.zeros(0),
        np.concatenate(joint_x) if joint_x else np.zeros(0),
        np.concatenate(joint_itf) if joint_itf else np.zeros(0, int), mass_dofs, masses,
        fixed, drive_dof, response_dof, normal=normal,
        point_mass=sum(p.mass for p in (*cf.masses, *cf.sensors)))
    return BuiltCase(model=model, joint_table=table, n_nodes=int(sum(s.n_nodes for s in strips)))


def _last_free_w(is_free: np.ndarray) -> int:
    """A transverse DOF off the supports (a model without drive or sensor needs one)."""
    return int(np.flatnonzero(is_free[W::3])[-1] * 3 + W)
