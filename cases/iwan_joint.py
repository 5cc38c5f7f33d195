"""Properties of one four-parameter Iwan joint as plain numbers (the ``iwanfe joint``
report): density parameters, kappa1 and kappa2 (exact and as printed in the paper), and
per slip amplitude the exact first-harmonic stiffnesses, the dissipation per cycle and
the in-phase stiffness the paper's kappa2 would give (micro-slip only)."""
from __future__ import annotations

import numpy as np

from joints.describing import describing_function, kappa1, kappa2_exact, kappa2_paper
from joints.iwan import IwanParameters, dissipation_per_cycle


def joint_summary(p: IwanParameters, amplitudes) -> dict:
    """Everything ``iwanfe joint`` reports, as plain numbers (SI units)."""
    amplitudes = np.asarray(amplitudes, dtype=float)
    bad = ~(np.isfinite(amplitudes) & (amplitudes > 0.0))
    if bad.any():
        raise ValueError(f"amplitude must be finite and > 0, got {amplitudes[bad][0]:g}")
    k_in, k_q = describing_function(p, amplitudes)
    k_in, k_q = np.atleast_1d(k_in), np.atleast_1d(k_q)
    dissipation = np.atleast_1d(dissipation_per_cycle(p, amplitudes))
    k2p = kappa2_paper(p.R, p.chi)
    rows = []
    for A, ki, kq, d in zip(amplitudes, k_in, k_q, dissipation):
        micro = A < p.phi_max
        rows.append({
            "amplitude": float(A),
            "regime": "micro" if micro else "macro",
            "stiffness_in_phase": float(ki),
            "stiffness_quadrature": float(kq),
            "dissipation_per_cycle": float(d),
            "stiffness_in_phase_paper_kappa2": (
                float(p.K_T - k2p * A ** (p.chi + 1.0)) if micro else None),
        })
    return {
        "chi": p.chi, "K_T": p.K_T, "F_S": p.F_S, "beta": p.beta,
        "R": p.R, "phi_max": p.phi_max, "S": p.S,
        "kappa1": kappa1(p.R, p.chi),
        "kappa2_exact": kappa2_exact(p.R, p.chi),
        "kappa2_paper": k2p,
        "amplitudes": rows,
    }
