"""The parts of a checked case file as dataclasses (SI units: m, kg, N, Pa); read by
:mod:`casefile.schema`."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class Material:
    name: str
    E: float
    rho: float


@dataclass(frozen=True)
class Section:
    """A piece of a beam with its own thickness, centroid height and width, m."""
    x: tuple
    thickness: float
    z: float
    width: float


@dataclass(frozen=True)
class Beam:
    name: str
    material: str
    x: tuple
    width: float
    thickness: float
    z: float
    sections: tuple = ()

    def section_at(self, x: float) -> tuple[float, float, float]:
        """(thickness, centroid z, width) at ``x`` (m): the last section holding it, else
        the beam's own."""
        for s in reversed(self.sections):
            if s.x[0] <= x <= s.x[1]:
                return s.thickness, s.z, s.width
        return self.thickness, self.z, self.width


@dataclass(frozen=True)
class Support:
    beams: tuple                 # one beam, or several held by one clamp
    kind: str
    x: tuple
    k_u: float = 0.0
    k_w: float = 0.0
    k_theta: float = 0.0


@dataclass(frozen=True)
class Interface:
    beams: tuple                 # (bottom, top)
    x: tuple
    normal: str
    tangential: str
    joints_at: tuple | None = None
    joint_elements: int | None = None
    law: str | None = None
    kt: float | None = None
    chi: float | None = None      # iwan4
    fs: float | None = None       # iwan4, jenkins, bouc-wen (N)
    beta: float | None = None     # iwan4
    alpha: float | None = None    # bouc-wen
    shape: float | None = None    # bouc-wen


@dataclass(frozen=True)
class PointMass:
    beam: str
    x: float
    mass: float
    label: str


@dataclass(frozen=True)
class BaseDrive:
    """``[drive] kind = "base"``: every support moves as one base in transverse
    translation ``w_b(t)``, with acceleration ``a_b(t) = Re(acceleration e^{i w t})``
    (``acceleration``: amplitude, m/s^2). In coordinates relative to the base the load
    is ``f = -M r a_b`` (``r``: 1 on every node's ``w``, 0 on ``u`` and ``theta``;
    :mod:`fe.base_excitation`)."""

    acceleration: float
    kind: str = "base"


def is_base_drive(drive) -> bool:
    """True for a ``[drive] kind = "base"`` (a :class:`BaseDrive`)."""
    return isinstance(drive, BaseDrive)


@dataclass(frozen=True)
class Measured:
    """``[measured]``: ``files`` (a measured-data table, the FRF files of a series or a
    free-decay record; () when only the linear frequency is given), ``mode``,
    ``frequency_hz``. ``file``: the measured-data table (FRF files and records are
    identified first, :func:`casefile.measured.measured_table`)."""

    files: tuple
    mode: int | None
    frequency_hz: float | None

    @property
    def file(self) -> Path | None:
        if not self.files:
            return None
        from casefile.measured import measured_table

        return measured_table(self.files)


@dataclass(frozen=True)
class Calibrate:
    parameters: tuple
    frequencies_hz: tuple


@dataclass(frozen=True)
class CaseFile:
    """A checked case file. ``kinds`` maps ``table.i.key`` to ``(kind, source)``."""
    path: Path
    name: str
    description: str
    materials: tuple
    beams: tuple
    supports: tuple
    interfaces: tuple
    masses: tuple
    sensors: tuple
    drive: PointMass | BaseDrive | None      # a point drive, or the base (kind = "base")
    measured: Measured | None
    calibrate: Calibrate | None
    element_size: float
    zeta: float
    kinds: dict = field(default_factory=dict, compare=False)
    extra: dict = field(default_factory=dict, compare=False)

    def beam(self, name: str) -> Beam:
        return next(b for b in self.beams if b.name == name)

    def material(self, name: str) -> Material:
        return next(m for m in self.materials if m.name == name)
