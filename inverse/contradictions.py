"""What a series shows that no Iwan joint can do, stated with its numbers.

Three facts of the four-parameter Iwan model (Segalman 2005) hold for any number of
joint elements on a mode, to first order in the joint terms (paper eq. 30-32: the
modal changes are sums of the elements' changes with weights ``(g_m . phi)^2 >= 0``):

1. *Frequency.* The in-phase stiffness ``k_in(A)`` of every Iwan element falls
   monotonically with its slip amplitude (each Jenkins slider only loses stiffness once
   it slides), in micro- and in macro-slip. A mode's ``omega^2`` therefore cannot rise
   with amplitude while a joint adds damping.
2. *The micro-slip tie.* Below ``phi_max``, ``K_T - k_in = kappa2 A^(chi+1)`` and
   ``k_q = |kappa1| A^(chi+1)`` (paper eq. 14, 18; exact kappa2), so between two levels
   ``Delta omega^2 = (kappa2/|kappa1|) Delta c`` with ``kappa2/|kappa1| =
   B(chi+5/2, 1/2) (chi+2)/(chi+1)``, which decreases from infinity at chi = -1 to its
   least value 3 pi / 4 at chi = 0 (:data:`MIN_TIE`). The loss of ``omega^2`` must be
   at least ``3 pi / 4`` times the growth of the joint's modal damping ``Delta c``. A
   joint entering macro-slip (slip past ``phi_max``, the Dirac part of the density) can
   lose less stiffness per damping gained; no micro-slip joint can.
3. *Range.* ``-1 < chi < 0`` (a finite stuck stiffness needs ``chi > -1``; ``chi >= 0``
   gives no power-law softening).

``Delta c`` follows from the damping ratio through eq. 2 of :mod:`inverse.iwan_modal`
(paper eq. 45 with its factor 2): ``Delta c_v = 2 Omega_v^2 zeta_v - c_n Omega_v``.
Between two levels with a frequency drop, taking ``c_n = 0`` gives the smallest
``Delta c`` any ``c_n >= 0`` allows, so the tie check never overstates.

Each check is judged against the noise of the data: the identification's standard
uncertainties where the table has ``omega2_std``/``zeta_std``, else the level-to-level
scatter (median absolute second difference; a smooth trend adds to it, so this errs
toward fewer contradictions). A contradiction is stated only when it exceeds
:data:`Z_STATE` noise standard deviations, or, when the noise was estimated on ``nu``
degrees of freedom (a repeatability from a few repeats or a smooth curve), the
Student-t quantile of the same tail probability (:func:`threshold`; 3 sd with known
noise is ``t_2 = 19``, ``t_5 = 6.9``, ``t_20 = 3.6`` sd).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

#: Least micro-slip ratio kappa2/|kappa1| (chi -> 0): 3 pi / 4.
MIN_TIE = 3.0 * math.pi / 4.0
#: Noise standard deviations a contradiction must exceed to be stated.
Z_STATE = 3.0

__all__ = ["Contradiction", "NoiseLevels", "noise_levels", "threshold", "iwan_contradictions",
           "MIN_TIE"]


@dataclass
class NoiseLevels:
    """Standard uncertainty of ``omega2`` (rad^2/s^2) and ``zeta`` per level.

    ``source`` says where they came from: ``"identification"`` (the table's std
    columns) or ``"scatter"`` (estimated from the level-to-level scatter)."""

    omega2: np.ndarray
    zeta: np.ndarray
    source: str
    dof_omega2: float = math.inf
    dof_zeta: float = math.inf


def threshold(dof: float) -> float:
    """Standardized size a contradiction must exceed (module doc): :data:`Z_STATE` with
    known noise, the Student-t quantile of the same one-sided tail with ``dof``."""
    if math.isinf(dof):
        return Z_STATE
    return float(stats.t.isf(stats.norm.sf(Z_STATE), max(dof, 1.0)))


def _beyond(z: float, dof: float) -> str:
    """Words for how far a contradiction lies beyond the noise and the size it had to
    exceed (:func:`threshold`)."""
    how = "known noise" if math.isinf(dof) else f"noise estimated on {dof:.3g} dof"
    return f" ({z:.3g} noise sd; stated beyond {threshold(dof):.3g} sd, {how})"


@dataclass
class Contradiction:
    """One plain statement with the numbers behind it."""

    kind: str          # "frequency-rises", "tie-violated", "chi-out-of-range"
    statement: str
    numbers: dict = field(default_factory=dict)


def _scatter_sigma(y: np.ndarray) -> float:
    """Noise of a smooth sequence from its second differences (robust: MAD).

    For white noise of std s, a second difference has std ``sqrt(6) s``."""
    if y.size < 4:
        return 0.0
    d2 = np.diff(y, 2)
    mad = np.median(np.abs(d2 - np.median(d2)))
    return float(1.4826 * mad / math.sqrt(6.0))


def noise_levels(d) -> NoiseLevels:
    """Noise of one mode's series (a :class:`ident.modal_data.MeasuredData`)."""
    n = len(d)
    if d.omega2_std is not None and d.zeta_std is not None:
        return NoiseLevels(np.asarray(d.omega2_std, float), np.asarray(d.zeta_std, float),
                           "identification")
    s_w = _scatter_sigma(np.asarray(d.omega2, float))
    s_z = _scatter_sigma(np.asarray(d.zeta, float))
    # floor: the last printed digit is at least ~1e-9 relative of omega2, 1e-7 of zeta
    s_w = max(s_w, 1e-9 * float(np.median(d.omega2)))
    s_z = max(s_z, 1e-7 * float(np.median(d.zeta)))
    return NoiseLevels(np.full(n, s_w), np.full(n, s_z), "scatter")


def _pct(x: float) -> str:
    return f"{100.0 * x:+.3g} %"


def _frequency_rise(d, sig: NoiseLevels) -> Contradiction | None:
    """A significant rise of omega^2 between two levels while zeta grew: from the lowest
    to the top level when that pair shows it, else the pair of largest z-score."""
    w, z = np.asarray(d.omega2, float), np.asarray(d.zeta, float)
    i, j = np.triu_indices(w.size, 1)
    s_w = np.hypot(sig.omega2[i], sig.omega2[j])
    s_z = np.hypot(sig.zeta[i], sig.zeta[j])
    z_rise = (w[j] - w[i]) / s_w
    ok = ((z[j] - z[i]) / s_z > threshold(sig.dof_zeta)) & (z_rise > threshold(sig.dof_omega2))
    if not ok.any():
        return None
    # the whole series (lowest -> top level) when it shows the rise, else the strongest pair
    whole = np.flatnonzero(ok & (i == 0) & (j == w.size - 1))
    k = whole[0] if whole.size else np.flatnonzero(ok)[np.argmax(z_rise[ok])]
    a, b = int(i[k]), int(j[k])
    f_a, f_b = math.sqrt(w[a]) / (2 * math.pi), math.sqrt(w[b]) / (2 * math.pi)
    growth = z[b] / z[a]
    text = (f"the natural frequency rises by {_pct(f_b / f_a - 1.0)} ({f_a:.6g} -> "
            f"{f_b:.6g} Hz, level {d.level[a]} -> {d.level[b]}) while the damping ratio "
            f"grows {growth:.3g}x ({100 * z[a]:.4g} % -> {100 * z[b]:.4g} %): an Iwan "
            f"joint only lowers the frequency as it adds damping"
            + _beyond(float(z_rise[k]), sig.dof_omega2))
    return Contradiction("frequency-rises", text, {
        "levels": [int(d.level[a]), int(d.level[b])],
        "frequency_hz": [f_a, f_b], "frequency_change": f_b / f_a - 1.0,
        "zeta": [float(z[a]), float(z[b])], "zeta_growth": growth,
        "z_score": float(z_rise[k])})


def _tie(d, sig: NoiseLevels) -> Contradiction | None:
    """omega^2 loss below 3 pi/4 times the joint damping growth, lowest vs top level."""
    w, z = np.asarray(d.omega2, float), np.asarray(d.zeta, float)
    a, b = 0, w.size - 1
    loss = w[a] - w[b]
    growth_c = 2.0 * (w[b] * z[b] - w[a] * z[a])      # Delta c with c_n = 0 (module doc)
    if loss < 0 or growth_c <= 0:
        return None
    s_loss = math.hypot(sig.omega2[a], sig.omega2[b])
    s_c = 2.0 * math.hypot(w[b] * sig.zeta[b], w[a] * sig.zeta[a])
    least = MIN_TIE * growth_c
    margin = (least - loss) / math.hypot(s_loss, MIN_TIE * s_c)
    if margin <= threshold(min(sig.dof_omega2, sig.dof_zeta)):
        return None
    f_a = math.sqrt(w[a]) / (2 * math.pi)

    def drop(dw):
        """The frequency drop of an omega^2 loss ``dw`` from level a, in words."""
        if dw >= w[a]:
            return "more than the whole omega^2"
        return f"a frequency drop of {100 * (1 - math.sqrt(1 - dw / w[a])):.3g} %"

    text = (f"from level {d.level[a]} to {d.level[b]} the damping ratio grows "
            f"{100 * z[a]:.4g} % -> {100 * z[b]:.4g} % (joint modal damping +{growth_c:.4g} "
            f"rad^2/s^2), so a micro-slip Iwan joint must lower omega^2 by at least 3 pi/4 x "
            f"that = {least:.4g} rad^2/s^2 ({drop(least)} at {f_a:.6g} Hz); the data "
            f"lose {loss:.4g} rad^2/s^2 ({drop(loss)[len('a frequency drop of '):]}), "
            f"{least / max(loss, 1e-300):.3g}x less; only slip past phi_max (macro-slip) or "
            f"damping from elsewhere can do that"
            + _beyond(margin, min(sig.dof_omega2, sig.dof_zeta)))
    return Contradiction("tie-violated", text, {
        "levels": [int(d.level[a]), int(d.level[b])], "omega2_loss": float(loss),
        "joint_damping_growth": float(growth_c), "least_loss_micro_slip": float(least),
        "z_score": float(margin)})


def _chi_range(chi: float) -> Contradiction | None:
    if chi is None or not math.isfinite(chi) or -1.0 < chi < 0.0:
        return None
    text = (f"the fitted chi = {chi:.3g} lies outside the Iwan range -1 < chi < 0: the "
            f"damping growth does not follow a micro-slip power law "
            + ("(it grows faster than the amplitude)" if chi >= 0 else
               "(chi <= -1 means an infinite stuck stiffness)"))
    return Contradiction("chi-out-of-range", text, {"chi": float(chi)})


def iwan_contradictions(d, chi: float | None = None,
                        noise: NoiseLevels | None = None) -> list[Contradiction]:
    """Statements of what one mode's series shows that no (micro-slip) Iwan joint can do.

    Parameters
    ----------
    d : ident.modal_data.MeasuredData
        One mode, sorted by level (``MeasuredData.for_mode``).
    chi : float, optional
        A fitted chi to check against the Iwan range.
    noise : NoiseLevels, optional
        Default :func:`noise_levels` of ``d``.

    Returns
    -------
    list of Contradiction (empty when the data agree with an Iwan joint within noise)
    """
    noise = noise_levels(d) if noise is None else noise
    found = [_frequency_rise(d, noise), _tie(d, noise), _chi_range(chi)]
    return [c for c in found if c is not None]
