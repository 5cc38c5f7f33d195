"""The Iwan tie of a series: over the fit levels, the loss of omega^2 against the damping
growth ``2 omega^2 dzeta``; a micro-slip Iwan joint gives at least ``kappa2/|kappa1| =
3 pi/4`` (docs/formats/diagnosis.md; :func:`inverse.iwan_modal.kappa_ratio` as chi -> 0).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["TIE_MINIMUM", "tie_statement"]

#: kappa2/|kappa1| of a micro-slip Iwan joint is at least this (its limit as chi -> 0).
TIE_MINIMUM = 3.0 * math.pi / 4.0


def tie_statement(data, mask) -> dict:
    """The Iwan tie against the data over the fit levels (docs/formats/diagnosis.md)."""
    i = np.flatnonzero(mask)
    a, b = i[0], i[-1]
    d_om2 = float(data.omega2[a] - data.omega2[b])
    d_c = float(2.0 * data.omega2[b] * (data.zeta[b] - data.zeta[a]))
    ratio = d_om2 / d_c if d_c > 0 else math.nan
    return {"from_level": int(data.level[a]), "to_level": int(data.level[b]),
            "loss_omega2": d_om2, "damping_growth_2omega2dzeta": d_c, "ratio": ratio,
            "iwan_minimum": TIE_MINIMUM,
            "text": (f"levels {data.level[a]}->{data.level[b]}: the loss of omega^2 "
                     f"({d_om2:.1f} rad^2/s^2) is {ratio:.2f} times the damping growth "
                     f"2 omega^2 dzeta ({d_c:.1f} rad^2/s^2); every micro-slip Iwan joint "
                     f"needs at least kappa2/|kappa1| = 3 pi/4 = {TIE_MINIMUM:.3f} "
                     + (f"(the measured frequency drops {TIE_MINIMUM / ratio:.1f}x too little)"
                        if ratio < TIE_MINIMUM else "(the data respect the tie)")
                     if ratio > 0 else "the measured omega^2 does not fall over the fit levels")}
