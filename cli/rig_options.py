"""``--rig-repeatability``: what the user states of the rig's run-to-run repeatability,
the assumed part of the judge's noise (:mod:`inverse.judge.prior`), for every command
that judges a fit (``estimate``, ``diagnose``, ``update``)::

    add_rig_argument(parser)
    data.rig_repeatability = rig_from_args(args)    # MeasuredData.rig_repeatability
"""
from __future__ import annotations

import math

from inverse.judge.prior import RIG_REPEATABILITY

__all__ = ["add_rig_argument", "rig_from_args"]


def add_rig_argument(parser) -> None:
    """Add ``--rig-repeatability FREQ_PCT DAMP_PCT [DOF] | none``."""
    f = 50 * RIG_REPEATABILITY.rel_sd["omega2"]
    z = 100 * RIG_REPEATABILITY.rel_sd["zeta"]
    parser.add_argument(
        "--rig-repeatability", nargs="+", default=None, metavar="PCT",
        help="the rig's run-to-run repeatability as a standard deviation, "
             "FREQ_PCT DAMP_PCT [DOF] (e.g. 0.05 3), pooled with the data's scatter where "
             f"the scatter does not contradict it; 'none': the data's scatter alone "
             f"(default, assumed: {f:g} %% in frequency, {z:g} %% in damping, "
             f"{RIG_REPEATABILITY.dof:g} dof)")


def rig_from_args(args) -> tuple | None:
    """``(f, z, dof)`` relative sds for :attr:`ident.modal_data.MeasuredData.rig_repeatability`,
    zeros for ``none``, None when not given; ValueError (one line) on a bad value."""
    given = getattr(args, "rig_repeatability", None)
    if given is None:
        return None
    if len(given) == 1 and given[0].lower() == "none":
        return (0.0, 0.0, 0.0)
    try:
        values = [float(v) for v in given]
    except ValueError:
        values = []
    ok = (len(values) in (2, 3) and all(math.isfinite(v) and v >= 0 for v in values)
          and (len(values) == 2 or values[2] > 0))
    if not ok:
        raise ValueError(f"--rig-repeatability {' '.join(given)}: give FREQ_PCT DAMP_PCT "
                         "[DOF] (numbers >= 0, DOF > 0) or 'none'")
    dof = values[2] if len(values) == 3 else RIG_REPEATABILITY.dof
    return (values[0] / 100, values[1] / 100, dof)
