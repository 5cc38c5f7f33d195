"""Engagement: can the model's joints move the measured mode as much as the data do?

Checked before any FE fit (``update``, ``diagnose --case``, ``loop``): a mode that barely
works the joints cannot soften much however the joints are tuned, and a fit made to
follow such data anyway returns absurd joints (phi_max of 1e-13 m, F_S of micronewtons).

The bound (computed, from the case's reduced model at its joint stiffness K_T): the
first-harmonic in-phase stiffness of a slipping joint element lies between its stuck
stiffness and 0 (every slider of an Iwan joint, a Jenkins and a Bouc-Wen element; 0 in
full macro-slip), so the mode's omega^2 lies between its stuck value and its value with
every joint fully slipped; the loss over any series is at most
``loss_model = 1 - omega2_slipped / omega2_stuck``
(:func:`slipped_omega2_ratio`: the mode followed by its
shape, the slipped eigenvector with the largest share of the stuck one).

The data's loss ``(max omega2 - min omega2) / max omega2`` over all levels (measured)
contradicts the model when it exceeds ``loss_model`` by more than :data:`SIGMAS`
standard deviations of the noise model. At the case's K_T first; where the data exceed
it, the bound at the stiffest K_T of the update's grid says whether a stiffer joint
could do it (a stiffer joint takes a larger share of the mode).

First (:func:`check_frequency`): data whose frequency is more than a factor 2 from the
FE mode's are another unit (omega2 written in Hz or rad/s) or another mode, not a joint.

Damping growth is not bounded here: the damping a slipping joint adds depends on how the
mode shape changes as it slips (a friction damper between parts that separate), which a
stuck -> slipped pair of linear models does not give.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from ident.errors import InputError
from ident.units import HINT, confirmed

__all__ = ["KT_GRID", "Engagement", "engagement", "slipped_omega2_ratio", "check_engagement",
           "check_frequency", "SIGMAS",
           "FREQUENCY_FACTOR", "UNIT_MATCH"]

#: log10 K_T (N/m) values the update's K_T profile tries (``--profiles all``); the
#: stiffest bounds what any joint can do to a mode.
KT_GRID = tuple(np.round(np.arange(6.0, 11.01, 1.0), 6))
#: Standard deviations by which the data must exceed the bound to contradict it.
SIGMAS = 3.0
#: Factor between the data's and the model's frequency beyond which the data are taken
#: for another unit or another mode (the update's f0 would scale every stiffness by
#: its square).
FREQUENCY_FACTOR = 2.0


#: Relative distance within which omega2 read in another unit matches an FE mode.
UNIT_MATCH = 0.05


def check_frequency(omega2, f_model_hz: float, fe_mode: int, modes_hz=()) -> None:
    """One line (exit 2) when the data's frequency ``sqrt(max omega2) / 2 pi`` is more
    than :data:`FREQUENCY_FACTOR` away from the followed FE mode's ``f_model_hz``; it
    names the unit that would match one of the FE modes ``modes_hz`` within
    :data:`UNIT_MATCH` (omega2 written in Hz or in rad/s). Not with ``--units-confirmed``."""
    top = float(np.max(omega2))
    f_data = math.sqrt(top) / (2.0 * math.pi)
    if confirmed() or 1.0 / FREQUENCY_FACTOR <= f_data / f_model_hz <= FREQUENCY_FACTOR:
        return
    modes = np.asarray(modes_hz, float)
    best = None
    for unit, f in (("Hz", top), ("rad/s", top / (2.0 * math.pi))):
        if modes.size:
            j = int(np.argmin(np.abs(np.log(f / modes))))
            miss = abs(f / modes[j] - 1.0)
            if miss < UNIT_MATCH and (best is None or miss < best[2]):
                best = (unit, j + 1, miss, modes[j])
    why = (f"omega2 in {best[0]}? (read so, {top:.6g} matches FE mode {best[1]} at "
           f"{best[3]:.6g} Hz; omega2 must be (2 pi f)^2 in rad^2/s^2)" if best else
           "another unit, or a model far from the structure?")
    raise InputError(f"the data's omega2 = {top:.6g} rad^2/s^2 is {f_data:.4g} Hz, FE mode "
                     f"{fe_mode} (the nearest) is at {f_model_hz:.4g} Hz: {why} {HINT}")


@dataclass(frozen=True)
class Engagement:
    """What the joints can do to the measured mode and what the data show.

    ``loss_model``: the largest loss of omega^2 (fraction) at ``K_T`` (N/m, the case's;
    assumed unless the file's kt is measured), computed; ``loss_data`` and
    ``loss_data_std``: the measured loss over the series and its standard deviation
    (noise model); ``fe_mode``: the FE mode followed; ``loss_stiffest`` at
    ``K_T_stiffest`` (NaN when not needed)."""

    K_T: float
    fe_mode: int
    loss_model: float
    loss_data: float
    loss_data_std: float
    loss_stiffest: float = math.nan
    K_T_stiffest: float = math.nan

    def exceeds(self, loss: float) -> bool:
        """The data's loss exceeds ``loss`` by more than :data:`SIGMAS` sd."""
        return self.loss_data - SIGMAS * self.loss_data_std > loss

    @property
    def verdict(self) -> str:
        return "contradiction" if self.exceeds(self.loss_model) else "engaged"

    def line(self) -> str:
        """One line for reports, both numbers."""
        return (f"engagement (FE mode {self.fe_mode}, K_T = {self.K_T:.3g} N/m, the case's, "
                f"assumed): fully slipped "
                f"joints lower omega^2 by at most {100 * self.loss_model:.3g} % (computed); the "
                f"data by {100 * self.loss_data:.3g} +- {100 * self.loss_data_std:.2g} % "
                f"(measured)")

    def to_json(self) -> dict:
        return {**asdict(self), "verdict": self.verdict, "sigmas": SIGMAS}


def slipped_omega2_ratio(lin) -> float:
    """omega^2 of the measured mode of :class:`feloop.levels.LinearPart` ``lin``
    with every joint fully slipped (no joint stiffness left) over its stuck omega^2: the
    eigenvalue of the reduced ``K - G^T diag(K_T) G`` whose eigenvector has the largest
    component on the mode's basis vector ``lin.k``."""
    red = lin.red
    K0 = red.K - red.G.T @ (red.K_T[:, None] * red.G)
    w2, V = np.linalg.eigh(0.5 * (K0 + K0.T))
    return float(w2[int(np.argmax(np.abs(V[lin.k])))] / lin.omega_k ** 2)


def engagement(data, fe, noise, kt_stiffest: float | None = None) -> Engagement:
    """The :class:`Engagement` of the FE-levels model ``fe`` (at its case's K_T) with the
    measured levels ``data`` (``noise.sigma_omega2``: per level, rad^2/s^2);
    ``kt_stiffest`` (N/m): where the data exceed the bound, the bound there too."""
    lin = fe.linear(fe.default_kt)
    omega2 = np.asarray(data.omega2, float)
    check_frequency(omega2, lin.omega_k / (2.0 * math.pi), lin.fe_mode,
                    np.sort(lin.red.omega[:lin.red.n_modes]) / (2.0 * math.pi))
    sigma = np.broadcast_to(np.asarray(noise.sigma_omega2, float), omega2.shape)
    hi, lo = int(np.argmax(omega2)), int(np.argmin(omega2))
    e = Engagement(K_T=lin.K_T, fe_mode=lin.fe_mode,
                   loss_model=1.0 - slipped_omega2_ratio(lin),
                   loss_data=float((omega2[hi] - omega2[lo]) / omega2[hi]),
                   loss_data_std=float(math.hypot(sigma[hi], sigma[lo]) / omega2[hi]))
    if e.verdict == "contradiction" and kt_stiffest and kt_stiffest > lin.K_T:
        stiff = fe.linear(kt_stiffest)
        e = replace(e, loss_stiffest=1.0 - slipped_omega2_ratio(stiff), K_T_stiffest=stiff.K_T)
    return e


def check_engagement(e: Engagement) -> Engagement:
    """``e`` when the joints can move the mode as far as the data do; otherwise one line
    (exit 2) with both numbers, and whether a stiffer joint could."""
    if e.verdict == "engaged":
        return e
    if math.isnan(e.K_T_stiffest):
        stiffer = ""
    elif e.exceeds(e.loss_stiffest):
        stiffer = (f"; even at K_T = {e.K_T_stiffest:.3g} N/m by at most "
                   f"{100 * e.loss_stiffest:.3g} %")
    else:
        stiffer = (f"; a stiffer joint could (K_T = {e.K_T_stiffest:.3g} N/m: "
                   f"{100 * e.loss_stiffest:.3g} %): is the case's kt too soft?")
    raise InputError(
        f"contradiction: the joints cannot move FE mode {e.fe_mode} as far as the data do: "
        f"the data lower omega^2 by {100 * e.loss_data:.3g} +- {100 * e.loss_data_std:.2g} % "
        f"(measured), fully slipped joints at K_T = {e.K_T:.3g} N/m by at most "
        f"{100 * e.loss_model:.3g} % (computed){stiffer}; otherwise another mechanism (a "
        f"second joint, the supports), another mode or wrong units, not a joint fit "
        f"(docs/fe-loop.md#engagement)")
