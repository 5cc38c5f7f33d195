"""Properties of one four-parameter Iwan joint as plain numbers (the ``iwanfe joint``
report): density parameters, kappa1 and kappa2 (exact and as printed in the paper), and
per slip amplitude the exact first-harmonic stiffnesses, the dissipation per cycle and
the in-phase stiffness the paper's kappa2 would give (micro-slip only).

Representable amplitudes. Deep in macro-slip the in-phase stiffness falls as
``k_in ~ (8/pi) (phi_max/A)^1.5 (2 K_T/3 - (K_T - S)/(chi + 5/2))``
(:func:`joints.describing.describing_function`), the difference of two terms of which
the second holds the incomplete Beta ``B(rho; chi+5/2, 3/2) ~ rho^(chi+5/2)/(chi+5/2)``,
``rho = phi_max/A``; at ``A = 1e300`` m they underflow and the stiffnesses would print as
0 (or, with only the Beta term lost, 18 % too high at ``A = 1e200`` m) although the true
values are positive. :func:`largest_amplitude` is the amplitude up to which both stay
normal doubles with a margin of 1e4: ``A_max = phi_max min((K_T/(1e4 tiny))^(2/3),
(1e4 tiny)^(-1/(chi+5/2)))`` (2.8e149 m for the joint of the README); larger
amplitudes, and any result that is not a finite number, are refused with the numbers
instead of being printed wrong. At the small end the
micro-slip dissipation ``4 R A^(chi+3)/((chi+2)(chi+3))`` underflows first:
:func:`smallest_amplitude` (about 1e-120 m for the joint of the README).
"""
from __future__ import annotations

import numpy as np

from joints.describing import describing_function, kappa1, kappa2_exact, kappa2_paper
from joints.iwan import IwanParameters, dissipation_per_cycle

_TINY = np.finfo(float).tiny


def largest_amplitude(p: IwanParameters) -> float:
    """Largest slip amplitude (m) whose stiffnesses are normal doubles (module doc)."""
    log_margin = np.log(1e4 * _TINY)
    log_ratio = min((2.0 / 3.0) * (np.log(p.K_T) - log_margin),   # k_in itself
                    -log_margin / (p.chi + 2.5))                  # its incomplete Beta
    return float(p.phi_max * np.exp(min(log_ratio, 700.0)))


def smallest_amplitude(p: IwanParameters) -> float:
    """Smallest slip amplitude (m) whose dissipation per cycle,
    ``4 R A^(chi+3)/((chi+2)(chi+3))`` (Segalman 2005), is a normal double with a
    margin of 1e4."""
    chi = p.chi
    log_a = (np.log(1e4 * _TINY) + np.log((chi + 2.0) * (chi + 3.0) / 4.0)
             - np.log(p.R)) / (chi + 3.0)
    return float(np.exp(max(log_a, -745.0)))


def _check(name: str, value: float, where: str, positive: bool = True) -> None:
    ok = np.isfinite(value) and (abs(value) >= _TINY if positive else True)
    if not ok:
        raise ValueError(f"{where}: {name} = {value:g} is outside double precision")


def joint_summary(p: IwanParameters, amplitudes) -> dict:
    """Everything ``iwanfe joint`` reports, as plain numbers (SI units).

    Raises
    ------
    ValueError
        An amplitude that is not finite and > 0, above :func:`largest_amplitude`, or a
        derived number (kappas, stiffnesses, dissipation) outside double precision.
    """
    amplitudes = np.asarray(amplitudes, dtype=float)
    bad = ~(np.isfinite(amplitudes) & (amplitudes > 0.0))
    if bad.any():
        raise ValueError(f"amplitude must be finite and > 0, got {amplitudes[bad][0]:g}")
    a_min, a_max = smallest_amplitude(p), largest_amplitude(p)
    if np.any(amplitudes < a_min):
        raise ValueError(f"amplitude {amplitudes.min():g} m is below {a_min:.3g} m, under "
                         f"which the dissipation per cycle ~ R A^(chi+3) underflows double "
                         f"precision")
    if np.any(amplitudes > a_max):
        raise ValueError(f"amplitude {amplitudes.max():g} m exceeds {a_max:.3g} m "
                         f"(= {a_max / p.phi_max:.3g} phi_max), above which the in-phase "
                         f"stiffness ~ K_T (phi_max/A)^1.5 underflows double precision")
    where = f"chi = {p.chi:g}, K_T = {p.K_T:g} N/m, F_S = {p.F_S:g} N, beta = {p.beta:g}"
    with np.errstate(all="ignore"):
        kappas = {"kappa1": kappa1(p.R, p.chi), "kappa2_exact": kappa2_exact(p.R, p.chi),
                  "kappa2_paper": kappa2_paper(p.R, p.chi)}
        for name, value in kappas.items():
            _check(name, value, where)
        k_in, k_q = describing_function(p, amplitudes)
        k_in, k_q = np.atleast_1d(k_in), np.atleast_1d(k_q)
        dissipation = np.atleast_1d(dissipation_per_cycle(p, amplitudes))
        k2p = kappas["kappa2_paper"]
        rows = []
        for A, ki, kq, d in zip(amplitudes, k_in, k_q, dissipation):
            at = f"{where}, A = {A:g} m"
            _check("k_quadrature", kq, at)
            _check("dissipation per cycle", d, at)
            _check("k_in_phase", ki, at, positive=False)
            micro = A < p.phi_max
            paper = float(p.K_T - k2p * A ** (p.chi + 1.0)) if micro else None
            if paper is not None:
                _check("k_in (paper)", paper, at, positive=False)
            rows.append({
                "amplitude": float(A),
                "regime": "micro" if micro else "macro",
                "stiffness_in_phase": float(ki),
                "stiffness_quadrature": float(kq),
                "dissipation_per_cycle": float(d),
                "stiffness_in_phase_paper_kappa2": paper,
            })
    return {
        "chi": p.chi, "K_T": p.K_T, "F_S": p.F_S, "beta": p.beta,
        "R": p.R, "phi_max": p.phi_max, "S": p.S,
        **{k: float(v) for k, v in kappas.items()},
        "amplitudes": rows,
    }
