"""Stability of a harmonic-balance solution by Hill's method.

A perturbation ``y(t) = e^{lam t} p(t)`` of the periodic solution of
:class:`fe.hb_forced.ForcedBalance`, with ``p`` a Fourier series in the layout of that
module (real coefficients ``z``), satisfies, to first order (Hill 1886; in harmonic
balance von Groll & Ewins 2001, Detroux et al. 2015 eq. 12-14, the formulation of NLvib,
Krack & Gross 2019 Sec. 3.6),

    (lam^2 Delta_2 + lam Delta_1 + J) z = 0,
    Delta_2 = I (x) M,   Delta_1 = I (x) C + 2 D (x) M,                             (1)

where ``J = dR/dx`` is the Jacobian of the balance at the solution and ``D`` the
derivative on the coefficients (``y' = e^{lam t}(lam p + p')``, ``y'' = e^{lam t}(lam^2 p
+ 2 lam p' + p'')``). The quadratic eigenproblem (1) is solved as the generalized one of
size ``2 n_c r``; each Floquet exponent appears repeated at ``lam + i k w``, and the ``2 r``
exponents of smallest ``|Im lam|`` are kept (Detroux et al. 2015, Sec. 3.2; the
truncation is most accurate there). Floquet multipliers ``mu = exp(lam T)``, ``T = 2 pi /
w``; the solution is asymptotically stable when every ``|mu| < 1``.

The perturbation harmonics default to every integer ``0..H`` (``H`` the highest harmonic
of the solution) whatever the solution keeps: with odd harmonics only, a real multiplier
(the saddle-node of a fold) sits at ``Im lam = w``, tied with its shifted copies, and the
selection by ``|Im lam|`` would be ambiguous; with all harmonics it is at ``Im lam = 0``.
SI units: rad/s, 1/s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la

from fe.hb_forced import ForcedBalance

__all__ = ["HillResult", "hill_matrices", "hill_stability"]


@dataclass
class HillResult:
    """Floquet exponents (2r,) (1/s, complex, sorted by ``|Im|``), multipliers
    ``exp(lam T)`` (2r,), their largest modulus and ``stable`` (``max |mu| < 1``)."""

    exponents: np.ndarray
    multipliers: np.ndarray
    max_modulus: float
    stable: bool


def hill_matrices(balance: ForcedBalance, omega: float):
    """``Delta_2``, ``Delta_1`` of eq. (1) (n, n) for ``balance``'s harmonics."""
    m, nc = balance.model, balance.nc
    eye = np.eye(nc)
    return np.kron(eye, m.M), np.kron(eye, m.C) + 2.0 * np.kron(balance.derivative(omega), m.M)


def hill_stability(balance: ForcedBalance, x: np.ndarray, omega: float,
                   hill_harmonics=None) -> HillResult:
    """Floquet exponents and multipliers of the solution ``x`` of ``balance`` at ``omega``
    (rad/s) by Hill's method (module docstring).

    Parameters
    ----------
    balance : ForcedBalance
    x : ndarray, shape (balance.n,)
        Converged real coefficients.
    omega : float
    hill_harmonics : sequence of int, optional
        Harmonics of the perturbation (default ``0..max(balance.harmonics)``).

    Returns
    -------
    HillResult
    """
    if hill_harmonics is None:
        hill_harmonics = np.arange(int(np.max(balance.harmonics)) + 1)
    hb = balance
    if not np.array_equal(np.asarray(hill_harmonics), balance.harmonics):
        hb = balance.with_harmonics(hill_harmonics)
        x = hb.embed(x, balance)
    J = hb(x, omega)[1]
    D2, D1 = hill_matrices(hb, omega)
    n = hb.n
    Z, I = np.zeros((n, n)), np.eye(n)
    A = np.block([[Z, I], [-J, -D1]])
    B = np.block([[I, Z], [Z, D2]])
    lam = la.eig(A, B, right=False)
    lam = lam[np.isfinite(lam)]
    keep = np.argsort(np.abs(lam.imag), kind="stable")[:2 * hb.r]
    lam = lam[keep]
    mu = np.exp(lam * 2.0 * np.pi / omega)
    top = float(np.abs(mu).max())
    return HillResult(exponents=lam, multipliers=mu, max_modulus=top, stable=top < 1.0)
