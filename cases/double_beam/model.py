"""The partially connected double beam of the paper's Section 4, as a linear FE model.

Two identical aluminium strips, 350 x 50 x 1 mm, are clamped together at one end and
glued to each other over the last 20 mm of the free end. Each strip is a chain of 2-D
Euler-Bernoulli frame elements (:mod:`fe.beam`, DOFs ``u, w, theta = dw/dx``) along its
own centroid line: the lower strip at ``z = -h/2``, the upper strip at ``z = +h/2``,
the interface at ``z = 0``.

Interface kinematics (:mod:`fe.interface`): the tangential slip of the upper strip over
the lower one is ``s = (u_up + (h/2) theta_up) - (u_lo - (h/2) theta_lo)`` (m), the
normal gap ``w_up - w_lo``.

Joint elements sit at the ``n_joints`` nodes of the glued zone. Each carries a linear
tangential spring ``k_j`` on ``s`` (trapezoidal share of the stuck glue stiffness
``K_T``, so ``sum k_j = K_T``) -- this is where a four-parameter Iwan element is placed in
the nonlinear model -- and a stiff normal spring on ``w_up - w_lo``.

Assumed properties (the paper gives only the dimensions, "aluminum", the 20 mm glue
length, the clamp and exciter positions in words):

=========================  ==================  =============================================
property                   default             source / reason
=========================  ==================  =============================================
E, rho                     70 GPa, 2700 kg/m3  handbook values of wrought aluminium alloys
                                               (68-73 GPa, 2660-2800 kg/m3)
strip length, width, h     350, 50, 1 mm       paper Sec. 4
glue zone                  last 20 mm          paper Sec. 4 ("evenly distributed ... 20 mm")
K_T (stuck tangential      1.0e8 N/m           not measured; chosen so that the measured
stiffness of the glue)                         frequency drop needs micro-slip only
                                               (:mod:`cases.double_beam.calibration`)
contact along free length  tied (bilateral)    the strips lie flat on each other: equal
                                               transverse displacement, frictionless
                                               tangential sliding (``contact="tied"``);
                                               ``"glue-only"`` couples them only in the
                                               glued zone (strips free to open)
normal stiffness per node  E b l / h           two aluminium half-thicknesses in series
                                               (l = the node's tributary length): stiff
clamp                      rigid, grip length  all DOFs of both strips fixed at the clamp
                           *calibrated*        face; free length = ``length - grip``
exciter + force gauge      2.0 g, 50 mm from   "on the clamped side": drives the lower
                           the clamp face      strip's w; 2 g = gauge top + stud (assumed)
Acc. 1                     1.0 g, same x       miniature accelerometer on the upper strip,
                                               its w is the response DOF
Acc. 2, Acc. 3             1.0 g each, tip     the paper's glue-zone accelerometers (used
                                               in the tests), one on each strip at the end
=========================  ==================  =============================================

Which model mode was measured (the 4th in-phase bending mode,
:data:`MEASURED_BENDING_ORDER`) and the one calibrated parameter (the clamp grip,
:data:`CALIBRATED_CLAMP_LENGTH`): :mod:`cases.double_beam.calibration`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from fe.assembly import (
    assemble,
    coupling_stiffness,
    free_dofs,
    free_index,
    point_masses,
    restrict,
    restrict_columns,
)
from fe.beam import U, W, Section, frame_mass, frame_stiffness
from fe.interface import (normal_gap_rows, stacked_energy_split, stacked_strips,
                          tangential_slip_rows)
from fe.mesh import DofMap, LineMesh, line_mesh, mesh_with_element_size
from fe.stacked import JointedStrips

MEASURED_FREQUENCY_HZ = 252.0  # sqrt(2.50677e6) / (2 pi), paper Table 4, experiment 1
MATCH_TOLERANCE = 0.005  # relative, for "matches_measured"
DEFAULT_BAND_HZ = (50.0, 450.0)  # paper Sec. 4: stepped sine 50-450 Hz
#: Clamp grip length (m) calibrated so that the 4th in-phase bending mode of the default
#: model is at 252.0 Hz; reproduced by
#: :func:`cases.double_beam.calibration.calibrate_clamp_length`.
CALIBRATED_CLAMP_LENGTH = 0.0186168
UNCALIBRATED_CLAMP_LENGTH = 0.0


@dataclass(frozen=True)
class DoubleBeamConfig:
    """Parameters of the double-beam model (SI units). Defaults: the shipped case.

    See the module docstring for the source of every default.
    """

    length: float = 0.35
    width: float = 0.05
    thickness: float = 1.0e-3
    E: float = 70.0e9
    rho: float = 2700.0
    clamp_length: float | None = None  # None: CALIBRATED_CLAMP_LENGTH
    glue_length: float = 0.02
    glue_tangential_stiffness: float = 1.0e8  # K_T, N/m (stuck, whole glued zone)
    contact: str = "tied"  # "tied" or "glue-only"
    element_size: float = 5.0e-3  # free-length elements, m
    n_joints: int = 5  # joint elements (nodes) in the glued zone
    drive_x: float = 0.05  # from the clamp face, m
    exciter_mass: float = 2.0e-3  # kg, force gauge top + stud on the lower strip
    sensor_mass: float = 1.0e-3  # kg, each accelerometer (Acc. 1, 2, 3)
    glue_sensors: bool = True  # Acc. 2 and Acc. 3 at the free end

    def __post_init__(self) -> None:
        positive = ("length", "width", "thickness", "E", "rho", "glue_length",
                    "element_size", "drive_x")
        for name in positive:
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be positive, got {v!r}")
        for name in ("exciter_mass", "sensor_mass"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be >= 0, got {v!r}")
        if self.clamp_length is not None and not (0 <= self.clamp_length < self.length):
            raise ValueError(f"clamp_length must be in [0, length), got {self.clamp_length!r}")
        if not (np.isfinite(self.glue_tangential_stiffness)
                and self.glue_tangential_stiffness >= 0):
            raise ValueError("glue_tangential_stiffness must be >= 0")
        if self.contact not in ("tied", "glue-only"):
            raise ValueError(f"contact must be 'tied' or 'glue-only', got {self.contact!r}")
        if int(self.n_joints) != self.n_joints or self.n_joints < 2:
            raise ValueError(f"n_joints must be an integer >= 2, got {self.n_joints!r}")
        if not self.drive_x < self.free_length - self.glue_length:
            raise ValueError("drive_x must lie between the clamp and the glued zone")

    @property
    def grip(self) -> float:
        """Clamp grip length actually used, m."""
        return CALIBRATED_CLAMP_LENGTH if self.clamp_length is None else self.clamp_length

    @property
    def free_length(self) -> float:
        """Length of strip between the clamp face and the free end, m."""
        return self.length - self.grip

    @property
    def K_T(self) -> float:
        """Stuck tangential stiffness of the whole glued zone, N/m."""
        return float(self.glue_tangential_stiffness)

    @property
    def section(self) -> Section:
        return Section(E=self.E, rho=self.rho, width=self.width, thickness=self.thickness)


@dataclass
class DoubleBeamModel(JointedStrips):
    """Assembled linear model over the free DOFs (the clamp removed).

    Attributes
    ----------
    M, K : scipy.sparse.csr_matrix, (n_free, n_free)
        Mass (kg) and stiffness (N/m); ``K = K_without_joints + slip_matrix.T
        diag(joint_stiffness) slip_matrix``.
    K_without_joints : scipy.sparse.csr_matrix
        Strips + normal couplings, no tangential glue springs.
    slip_matrix : scipy.sparse.csr_matrix, (n_joints, n_free)
        Tangential slip ``s`` (m) of each joint element from the free DOFs.
    normal_matrix : scipy.sparse.csr_matrix, (n_normal, n_free)
        Normal gaps ``w_up - w_lo`` (m) of the normal couplings.
    joint_stiffness : ndarray, (n_joints,)
        Each joint's share of K_T, N/m.
    joint_x : ndarray, (n_joints,)
        Joint positions from the clamp face, m.
    drive_dof, response_dof : int
        Free-DOF indices of the driven w (lower strip) and the measured w (upper strip).
    strips : list of fe.interface.StripGeometry
        ``[lower, upper]``.
    """

    config: DoubleBeamConfig
    mesh: LineMesh
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
    drive_dof: int
    response_dof: int
    strips: list
    _strip_mass: sp.csr_matrix = field(repr=False)

    def energy_split(self, shape: np.ndarray) -> dict:
        """Kinetic-energy fractions of a shape in the strips' own mass (point masses
        excluded): :func:`fe.interface.stacked_energy_split` of the two strips."""
        full = self.full_vector(np.asarray(shape, dtype=float))
        lo, up = (full[dm.offset:dm.stop] for dm in self.dofmaps)
        return stacked_energy_split(lo, up, self._strip_mass)

    def classify_mode(self, shape: np.ndarray) -> str:
        """'in-phase bending', 'out-of-phase bending', 'axial' or 'out-of-phase axial'.

        The kind whose kinetic energy share (:meth:`energy_split`) is largest.
        """
        split = self.energy_split(shape)
        names = {"in_phase_bending": "in-phase bending",
                 "out_of_phase_bending": "out-of-phase bending",
                 "in_phase_axial": "axial",
                 "out_of_phase_axial": "out-of-phase axial"}
        return names[max(split, key=split.get)]

    def bending_order(self, omega: np.ndarray, shapes: np.ndarray) -> np.ndarray:
        """1-based order of each mode among the in-phase bending modes (0 for others)."""
        kinds = [self.classify_mode(shapes[:, i]) for i in range(shapes.shape[1])]
        order = np.zeros(len(kinds), dtype=int)
        idx = [i for i in np.argsort(omega) if kinds[i] == "in-phase bending"]
        order[idx] = np.arange(1, len(idx) + 1)
        return order

    def band_modes(self, band_hz=DEFAULT_BAND_HZ, measured_hz: float | None = MEASURED_FREQUENCY_HZ,
                   tolerance: float = MATCH_TOLERANCE) -> list[dict]:
        """Modes with lo <= f <= hi as records (index = 1-based order in the whole model).

        Keys: index, frequency_hz, omega2, kind, bending_order, glue_slip,
        matches_measured (within ``tolerance`` of ``measured_hz``).
        """
        lo, hi = band_hz
        if not (0 <= lo < hi):
            raise ValueError(f"band must satisfy 0 <= LO < HI, got {lo!r} {hi!r}")
        omega, shapes = self.modes_below(hi)
        order = self.bending_order(omega, shapes)
        f = omega / (2 * np.pi)
        rows = []
        for i in np.flatnonzero((f >= lo) & (f <= hi)):
            rows.append({
                "index": int(i + 1),
                "frequency_hz": float(f[i]),
                "omega2": float(omega[i] ** 2),
                "kind": self.classify_mode(shapes[:, i]),
                "bending_order": int(order[i]),
                "glue_slip": self.glue_slip_participation(shapes[:, i]),
                "matches_measured": bool(measured_hz is not None
                                         and abs(f[i] / measured_hz - 1) <= tolerance),
            })
        return rows


def _glue_zone_x(config: DoubleBeamConfig) -> np.ndarray:
    L = config.free_length
    return np.linspace(L - config.glue_length, L, int(config.n_joints))


def build_mesh(config: DoubleBeamConfig) -> LineMesh:
    """Strip mesh: clamp face, drive point and glued-zone start are nodes.

    Free length: elements no longer than ``element_size``; glued zone: ``n_joints - 1``
    equal elements (their nodes carry the joints).
    """
    L = config.free_length
    x_g = L - config.glue_length
    free_part = mesh_with_element_size([0.0, config.drive_x, x_g], config.element_size)
    return line_mesh(np.concatenate([free_part.x, _glue_zone_x(config)[1:]]))


def build_double_beam(config: DoubleBeamConfig | None = None) -> DoubleBeamModel:
    """Assemble the double-beam model (see module docstring). Default: the shipped case."""
    config = DoubleBeamConfig() if config is None else config
    sec = config.section
    h, b = config.thickness, config.width
    mesh = build_mesh(config)
    n_nodes = mesh.n_nodes
    lower = DofMap(n_nodes, 3, 0)
    upper = DofMap(n_nodes, 3, lower.stop)
    n = upper.stop

    # strips (identical element matrices, one per strip block)
    le = mesh.element_length
    Ke = frame_stiffness(le, sec.EA, sec.EI)
    Me = frame_mass(le, sec.mass_per_length)
    K_strip = assemble(Ke, lower.element_dofs(mesh.elements), lower.n_dofs)
    M_strip = assemble(Me, lower.element_dofs(mesh.elements), lower.n_dofs)
    K_pair = sp.block_diag([K_strip, K_strip], format="csr")
    M_pair = sp.block_diag([M_strip, M_strip], format="csr")

    # normal couplings w_up - w_lo
    glue_nodes = mesh.nodes_in(config.free_length - config.glue_length, config.free_length)
    normal_nodes = np.arange(1, n_nodes) if config.contact == "tied" else glue_nodes
    trib = mesh.tributary_length()[normal_nodes]
    k_normal = config.E * b * trib / h  # two half-thicknesses h/2 in series
    G_n = normal_gap_rows(upper, lower, normal_nodes, n)

    # tangential joints: s = (u_up + h/2 theta_up) - (u_lo - h/2 theta_lo)
    G_t = tangential_slip_rows(upper, lower, glue_nodes, h, h, n)
    w = mesh.tributary_length(glue_nodes)
    k_joint = config.K_T * w / w.sum()

    # attachments: exciter on the lower strip, Acc. 1 on the upper strip, Acc. 2/3 at the tip
    i_drive = mesh.node_at(config.drive_x)
    mass_dofs = [lower.dof(i_drive, W), lower.dof(i_drive, U),
                 upper.dof(i_drive, W), upper.dof(i_drive, U)]
    mass_vals = [config.exciter_mass] * 2 + [config.sensor_mass] * 2
    if config.glue_sensors:
        tip = n_nodes - 1
        mass_dofs += [lower.dof(tip, W), lower.dof(tip, U), upper.dof(tip, W), upper.dof(tip, U)]
        mass_vals += [config.sensor_mass] * 4
    M_att = point_masses(np.array(mass_dofs), np.array(mass_vals), n)

    K0 = K_pair + coupling_stiffness(G_n, k_normal)
    K_full = K0 + coupling_stiffness(G_t, k_joint)
    M_full = M_pair + M_att

    fixed = np.concatenate([lower.node_dofs([0]).ravel(), upper.node_dofs([0]).ravel()])
    free = free_dofs(n, fixed)
    return DoubleBeamModel(
        config=config,
        mesh=mesh,
        dofmaps=[lower, upper],
        free=free,
        M=restrict(M_full, free),
        K=restrict(K_full, free),
        K_without_joints=restrict(K0, free),
        slip_matrix=restrict_columns(G_t, free),
        normal_matrix=restrict_columns(G_n, free),
        normal_stiffness=k_normal,
        joint_stiffness=k_joint,
        joint_x=mesh.x[glue_nodes].copy(),
        drive_dof=free_index(free, int(lower.dof(i_drive, W))),
        response_dof=free_index(free, int(upper.dof(i_drive, W))),
        strips=stacked_strips(mesh.x, h, b),
        _strip_mass=M_strip,
    )


def bending_mode_frequency(model: DoubleBeamModel, order: int) -> float:
    """Frequency (Hz) of the ``order``-th in-phase bending mode."""
    omega, shapes = model.modes(order + 8)
    orders = model.bending_order(omega, shapes)
    i = np.flatnonzero(orders == order)
    if i.size == 0:
        raise ValueError(f"in-phase bending mode {order} not found")
    return float(omega[i[0]] / (2 * np.pi))


MEASURED_BENDING_ORDER = 4  # the measured mode is the 4th in-phase bending mode
