"""The joint laws a case file names (``law = "iwan4" | "jenkins" | "bouc-wen"``): each
law's keys with their ranges and units, and its joints on the joint elements.

Every law takes ``kt`` (N/m, the stuck tangential stiffness of the whole interface),
shared by the joint elements by their stiffness shares ``w_j``
(:func:`casefile.build.joint_shares`); a force parameter (``fs``) is shared alike, so
each law's slip scale is the interface's at every element. Its own keys:

* ``iwan4`` (four-parameter Iwan, Segalman 2005; :class:`joints.describing.IwanJoints`,
  time domain by Jenkins banks): ``chi`` (1, in (-1, 0)), ``fs`` (N, > 0), ``beta``
  (1, >= 0); slip scale ``phi_max``.
* ``jenkins`` (one elastic-perfectly-plastic slider per joint element, a
  :class:`joints.bank.JointBank` of one slider: stiffness ``kt w_j``, slip force ``fs
  w_j``): ``fs`` (N, > 0); slip scale ``fs / kt`` (the slip at which it slides).
* ``bouc-wen`` (Bouc 1967, Wen 1976, ``n = 1``; :class:`joints.bouc_wen.BoucWenJoints`
  with ``K_T = kt w_j``, ``F_S = fs w_j``): ``fs`` (N, > 0, the force at which the
  hysteretic part saturates), ``alpha`` (1, in [0, 1): the stiffness left in gross slip
  as a fraction of ``kt``), ``shape`` (1, ``gamma/beta`` in (-1, 1]); slip scale
  ``z_u = fs / ((1 - alpha) kt)``.

A key of another law is refused (one line naming file, table and key). SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Key", "LAWS", "LAW_KEYS", "DESCRIPTION", "SLIP_SCALE", "law_keys", "joint_law"]


@dataclass(frozen=True)
class Key:
    """One parameter of a law: ``name``, ``unit``, its range (``Table.number``'s
    arguments) and what it is."""

    name: str
    unit: str
    meaning: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False

    def read(self, table):
        """The value in ``table`` (a :class:`casefile.tables.Table`) or None (range
        checked, one line otherwise)."""
        return table.number(self.name, required=False, lo=self.lo, hi=self.hi,
                            lo_open=self.lo_open, hi_open=self.hi_open)


_FS = "N, of the whole interface, shared like kt"
LAWS = {
    "iwan4": (Key("chi", "1", "Iwan density exponent", -1, 0, True, True),
              Key("fs", "N", f"macro-slip force ({_FS})", 0, None, True),
              Key("beta", "1", "Dirac share of the Iwan density", 0)),
    "jenkins": (Key("fs", "N", f"slip force of the slider ({_FS})", 0, None, True),),
    "bouc-wen": (Key("fs", "N", f"saturation force of the hysteretic part ({_FS})", 0, None,
                     True),
                 Key("alpha", "1", "stiffness left in gross slip, a fraction of kt", 0, 1,
                     False, True),
                 Key("shape", "1", "gamma/beta of the evolution equation", -1, 1, True)),
}
#: every law-specific key (``kt`` is every law's)
LAW_KEYS = tuple(dict.fromkeys(k.name for keys in LAWS.values() for k in keys))
DESCRIPTION = {"iwan4": "four-parameter Iwan joint (Segalman 2005)",
               "jenkins": "one elastic-perfectly-plastic slider",
               "bouc-wen": "Bouc-Wen hysteresis (Wen 1976, n = 1)"}
#: the slip each law's backbone amplitude is measured in
SLIP_SCALE = {"iwan4": "phi_max", "jenkins": "fs/kt", "bouc-wen": "z_u"}


def law_keys(law: str) -> tuple[str, ...]:
    """The names of ``law``'s own keys (besides ``kt``), in the file's order."""
    return tuple(k.name for k in LAWS[law])


def joint_law(itfs, shares):
    """The joints of interfaces ``itfs`` (one law, every key given) with stiffness shares
    ``shares`` (one array per interface): Iwan parameters (``iwan4``, one per joint
    element) or a :class:`joints.law.JointLaw` (``jenkins``, ``bouc-wen``)."""
    import numpy as np

    law = itfs[0].law
    rows = [(itf, float(w)) for itf, ws in zip(itfs, shares) for w in ws]
    if law == "iwan4":
        from joints.iwan import IwanParameters

        return [IwanParameters(chi=i.chi, K_T=i.kt * w, F_S=i.fs * w, beta=i.beta)
                for i, w in rows]
    if law == "jenkins":
        from joints.bank import JointBank

        return JointBank(np.array([[i.kt * w] for i, w in rows]),
                         np.array([[i.fs / i.kt] for i, _ in rows]))
    from joints.bouc_wen import BoucWenJoints, BoucWenParameters

    return BoucWenJoints([BoucWenParameters(K_T=i.kt * w, F_S=i.fs * w, alpha=i.alpha,
                                            shape=i.shape) for i, w in rows])
