"""Plausibility of a fitted joint against the case file's interfaces.

After ``update`` on a case file, each fitted physical joint parameter is set against a
range and its source; outside it the report says ``implausible`` with both numbers
(the fit is still reported: the data may hold a mechanism the model lacks, which the
diagnosis names). The checks (every one computed from the file, no constant tuned to
data):

* the slip scale (m: ``phi_max`` of an Iwan joint, ``fs/kt`` of a Jenkins slider, ``z_u``
  of a Bouc-Wen element; ``phi_max_m`` or ``slip_scale_m``) at least :data:`PHI_MAX_FLOOR` (1 nm: below the
  roughness of any machined contact, Ra >= 0.1 um, a joint cannot stick and slip) and at
  most :data:`PHI_MAX_SHARE` of the shortest joint interface's length (a joint that
  slips by a tenth of its overlap before it slides is no longer a lap);
* ``K_T`` (stuck stiffness, N/m) at most the interfaces' shear stiffness ``G A /
  ((h_bottom + h_top) / 2)`` (the two half-layers between the strips' reference lines
  and the contact, ``G = E / (2 (1 + nu))`` with nu = 0.3 assumed): a stuck contact in
  series with those layers cannot be stiffer than they are;
* ``F_S`` (N, slip force) at most ``mu p_max A``: friction coefficient ``mu <= 1``,
  contact pressure at most 3 yield stresses (the indentation hardness) and the yield
  stress at most ``E / 100`` (metals yield below 1 % strain): ``0.03 E A`` of the joint
  interfaces (assumed bounds: the case file gives no preload, which would bound it
  closer as friction x preload);
* ``beta`` (the Dirac share of the four-parameter Iwan density) at most
  :data:`BETA_MAX` (assumed: a share 100 times the power-law part is a Coulomb joint
  with a negligible micro-slip tail);
* ``C_D`` (the air drag coefficient of ``quadratic-damping``) in :data:`DRAG_CD_RANGE`:
  about 2 for a flat plate in steady flow, up to ``8 KC^-1/3`` in oscillating flow at
  small Keulegan-Carpenter numbers ``KC = 2 pi A / b`` (Graham 1980; 40 at KC = 0.01);
  it rests on the assumed force scale (``C_D ~ 1/s``).
"""
from __future__ import annotations

__all__ = ["PHI_MAX_FLOOR", "PHI_MAX_SHARE", "POISSON", "SLIP_FORCE_SHARE", "BETA_MAX",
           "DRAG_CD_RANGE", "joint_plausibility"]

PHI_MAX_FLOOR = 1e-9
PHI_MAX_SHARE = 0.1
POISSON = 0.3
#: F_S <= mu (<= 1) x 3 yield stresses (<= E/100) x area (assumed bounds)
SLIP_FORCE_SHARE = 0.03
BETA_MAX = 100.0
#: 1 (below any plate in steady flow) .. 40 (8 KC^-1/3 at KC = 0.01, Graham 1980)
DRAG_CD_RANGE = (1.0, 40.0)


def _shear_stiffness(cf, itf) -> float:
    """``G A / ((h_b + h_t) / 2)`` of one interface (N/m), at its midpoint's sections."""
    x = 0.5 * (itf.x[0] + itf.x[1])
    (hb, _, wb), (ht, _, wt) = (cf.beam(n).section_at(x) for n in itf.beams)
    E = min(cf.material(cf.beam(n).material).E for n in itf.beams)
    area = (itf.x[1] - itf.x[0]) * min(wb, wt)
    return E / (2.0 * (1.0 + POISSON)) * area / (0.5 * (hb + ht))


def joint_plausibility(cf, joint: dict, drag_cd: float | None = None) -> list[dict]:
    """Checks of ``joint`` (``slip_scale`` or ``phi_max`` m, ``K_T`` N/m, ``F_S`` N,
    ``beta``, ``law``: the joint of
    the update's prediction, :class:`feloop.levels.LevelPrediction`) and of a fitted air
    drag coefficient ``drag_cd`` (module docstring) against the file
    ``cf``: one dict per check with ``parameter``, ``value``, ``kind`` (fitted, assumed),
    ``low``, ``high`` (None: unbounded), ``source``, ``verdict`` (``plausible``,
    ``implausible`` or ``not checked``)."""
    itfs = [i for i in cf.interfaces if i.tangential == "joint"]
    if not itfs:
        return []
    shortest = min(i.x[1] - i.x[0] for i in itfs)
    k_shear = sum(_shear_stiffness(cf, i) for i in itfs)
    out = []

    def check(name, value, kind, low, high, source):
        inside = (low is None or value >= low) and (high is None or value <= high)
        out.append({"parameter": name, "value": value, "kind": kind, "low": low,
                    "high": high, "source": source,
                    "verdict": "plausible" if inside else "implausible"})

    law = joint.get("law", "iwan4")
    check("phi_max_m" if law == "iwan4" else "slip_scale_m",
          float(joint.get("slip_scale", joint.get("phi_max"))), "fitted", PHI_MAX_FLOOR,
          PHI_MAX_SHARE * shortest,
          f"1 nm (below any machined roughness) to {PHI_MAX_SHARE:g} x the shortest joint "
          f"interface ({shortest:g} m)")
    check("K_T_N_per_m", float(joint["K_T"]), "assumed unless profiled",
          None, k_shear,
          f"at most the interfaces' shear stiffness G A / mean half-thickness = "
          f"{k_shear:.3g} N/m (nu = {POISSON} assumed)")
    area = sum((i.x[1] - i.x[0]) * min(cf.beam(n).section_at(0.5 * (i.x[0] + i.x[1]))[2]
                                       for n in i.beams) for i in itfs)
    e_min = min(cf.material(cf.beam(n).material).E for i in itfs for n in i.beams)
    check("F_S_N", float(joint["F_S"]), "fitted", None, SLIP_FORCE_SHARE * e_min * area,
          f"at most friction (mu <= 1) x 3 yield stresses (<= E/100) x the joint area "
          f"{area:.3g} m^2 = {SLIP_FORCE_SHARE:g} E A (assumed bounds; the file gives no "
          f"preload)")
    if float(joint.get("beta", 0.0)) > 0:
        check("beta", float(joint["beta"]), "fitted", 0.0, BETA_MAX,
              f"at most {BETA_MAX:g} (assumed: beyond it a Coulomb joint with a negligible "
              f"micro-slip tail)")
    if drag_cd is not None:
        check("C_D", float(drag_cd), "fitted", *DRAG_CD_RANGE,
              "a flat plate: about 2 in steady flow, 8 KC^-1/3 in oscillating flow at small "
              "Keulegan-Carpenter numbers (Graham 1980; 40 at KC = 0.01); rests on the "
              "assumed force scale (C_D ~ 1/s)")
    return out

