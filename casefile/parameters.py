"""Parameters of a case file by address ``table.i.key`` (``support.0.x``, ``mass.0.mass``):
read, replace, and the bounds a calibration keeps them in. A range key (``x = [x0, x1]``)
stands for its second value (spec: calibration moves it). SI units."""
from __future__ import annotations

import dataclasses

_FIELDS = {"material": "materials", "beam": "beams", "support": "supports",
           "interface": "interfaces", "mass": "masses", "sensor": "sensors"}
#: keys a calibration may move: lengths and masses, and the stiffnesses the file gives
CALIBRATABLE = {"material": ("E", "rho"), "beam": ("x", "width", "thickness", "z"),
                "support": ("x", "k_u", "k_w", "k_theta"), "interface": ("kt",),
                "mass": ("x", "mass"), "sensor": ("x", "mass")}


def _split(address: str):
    parts = address.split(".")
    if len(parts) != 3 or not parts[1].isdigit():
        return None
    return parts[0], int(parts[1]), parts[2]


def check_parameter(cf, address: str) -> str | None:
    """Why ``address`` cannot be calibrated in case file ``cf`` (None if it can)."""
    parts = _split(address)
    if parts is None:
        return "must read table.index.key, e.g. support.0.x"
    table, i, key = parts
    if table not in CALIBRATABLE or key not in CALIBRATABLE[table]:
        allowed = "; ".join(f"{t}: {', '.join(k)}" for t, k in CALIBRATABLE.items())
        return f"not a calibratable parameter ({allowed})"
    items = getattr(cf, _FIELDS[table])
    if i >= len(items):
        return f"there are {len(items)} [[{table}]] tables"
    if getattr(items[i], key) is None:
        return "not given in the file: a calibration starts from the file's value"
    return None


def get_parameter(cf, address: str) -> float:
    """The value of ``address`` (a range's second value)."""
    table, i, key = _split(address)
    v = getattr(getattr(cf, _FIELDS[table])[i], key)
    return float(v[1]) if isinstance(v, tuple) else float(v)


def set_parameter(cf, address: str, value: float):
    """A copy of ``cf`` with ``address`` set to ``value`` (a range keeps its first value)."""
    table, i, key = _split(address)
    items = list(getattr(cf, _FIELDS[table]))
    old = getattr(items[i], key)
    new = (old[0], float(value)) if isinstance(old, tuple) else float(value)
    items[i] = dataclasses.replace(items[i], **{key: new})
    return dataclasses.replace(cf, **{_FIELDS[table]: tuple(items)})


def bounds(cf, address: str) -> tuple[float, float]:
    """Where a calibration may move ``address``: a position inside its beam (a range's end
    between its start and the beam's end), a mass, stiffness or size above 0."""
    table, i, key = _split(address)
    item = getattr(cf, _FIELDS[table])[i]
    if key == "x" and table != "beam":
        beam = cf.beam(item.beams[0] if hasattr(item, "beams") else item.beam)
        lo = item.x[0] if isinstance(item.x, tuple) else beam.x[0]
        return lo, beam.x[1]
    if key == "x":
        return item.x[0] + 1e-9, float("inf")
    if key == "z":
        return -float("inf"), float("inf")
    return 0.0, float("inf")
