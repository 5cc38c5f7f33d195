"""Values whose size says their unit is wrong, and the flag that confirms them.

Case files and measured tables are in SI units (m, kg, N, Pa; zeta a fraction, omega2
in rad^2/s^2). A value far outside what a jointed laboratory structure has is most
often another unit: millimetres for metres, MPa or GPa for Pa, g/cm^3 for kg/m^3, zeta in
percent. Such a value is one line and exit status 2 (:func:`suspect`), unless the run
is started with ``iwanfe --units-confirmed COMMAND ...`` (which sets
:data:`ENVIRONMENT` for the run and its worker processes).
"""
from __future__ import annotations

import os

from ident.errors import InputError

__all__ = ["ENVIRONMENT", "FLAG", "HINT", "confirmed", "suspect", "refuse", "LIMITS"]

ENVIRONMENT = "IWANFE_UNITS_CONFIRMED"
FLAG = "--units-confirmed"
#: how each such line ends
HINT = f"(if the value is right: iwanfe {FLAG} ...)"

#: (lowest, highest) plausible value of each quantity, SI, and the unit a value beyond
#: each end most likely is. Laboratory jointed structures: beams up to 20 m long, sections
#: up to 1 m; E from 1e8 Pa (polymers) to 1e12 Pa; rho from 100 (foams) to 25 000 kg/m^3
#: (beyond osmium); zeta (a fraction) up to 0.2.
LIMITS = {
    "length": ((None, None), (20.0, "millimetres (the case file is in metres)")),
    "section": ((None, None), (1.0, "millimetres (the case file is in metres)")),
    "E": ((1e8, "MPa or GPa (E is in Pa)"), (1e12, "a unit smaller than Pa")),
    "rho": ((100.0, "g/cm^3 or t/m^3 (rho is in kg/m^3)"), (25e3, "g/m^3 or another unit")),
    "zeta": ((None, None), (0.2, "percent (zeta is a fraction: 0.01278 for 1.278 %)")),
}


def confirmed() -> bool:
    """Whether the run was started with :data:`FLAG`."""
    return os.environ.get(ENVIRONMENT) == "1"


def suspect(quantity: str, value: float) -> str | None:
    """Why ``value`` of ``quantity`` (a key of :data:`LIMITS`) looks like another unit,
    or None when it is plausible or :func:`confirmed`."""
    (lo, lo_unit), (hi, hi_unit) = LIMITS[quantity]
    if confirmed():
        return None
    if lo is not None and value < lo:
        return f"{value:g} is below {lo:g}: {lo_unit}?"
    if hi is not None and value > hi:
        return f"{value:g} is above {hi:g}: {hi_unit}?"
    return None


def refuse(where: str, quantity: str, value: float) -> None:
    """Raise the one line of :func:`suspect` prefixed by ``where``, if any."""
    why = suspect(quantity, value)
    if why:
        raise InputError(f"{where}: {why} {HINT}")
