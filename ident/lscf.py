"""LSCF poles over model orders, their stabilization status and chains across orders.

1. **LSCF** (least-squares complex-frequency, Guillaume et al. 2003; Verboven 2002,
   eq. 5.26) with *complex* coefficients on the band only, in the Laplace domain: the
   band [lo, hi] is shifted to its centre omega_c and scaled,
   ``x_k = (omega_k - omega_c) / h``, ``h = (omega_hi - omega_lo) / 2``, and the
   polynomials are Chebyshev series in ``x`` (well conditioned on [-1, 1] for any, even
   non-uniform, frequency grid such as stepped sine). Common-denominator model
   ``H_o = N_o(x) / D(x)``; the numerators are eliminated (reduced normal equations
   ``M = sum_o T_o - S_o^H R^-1 S_o``) and ``D`` (leading coefficient 1) is solved for
   each order 1..max_order from leading sub-blocks of the same matrices. Root ``x_r``
   of ``D`` gives the pole ``lambda_r = i (omega_c + h x_r)``. A mode
   ``A / (i omega - lambda)`` is exactly one root in ``x`` at every order, however its
   damping compares with the band; on the unit-circle map
   ``xi = exp(i (omega - omega_c) T)`` used before it is not rational, and a mode whose
   half-power width exceeds the band (41 lines of 0.05 Hz around an 80 Hz mode of 2 %
   damping) gave no stable pole in 4 % of noise realizations (none now).
2. **Stabilization**: a pole of order n is *stable* when a pole of order n-1 lies
   within 1 % in frequency, 5 % in damping and (several points) has residue MAC > 0.98
   (residues by LSFD with the poles of that order); this status is what the diagram
   shows. Poles within 1 % in frequency, 25 % in damping and MAC > 0.9 are linked
   into chains. Poles in the band take part, and those within
   :data:`NEAR_BAND_REACH` of their decay rates outside it (a mode whose skirt the
   band holds). Which chains are modes is decided by :func:`ident.identify.identify`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from numpy.polynomial.chebyshev import chebroots, chebvander

from ident.lsfd import lsfd
from ident.poles import pole_to_modal

# Stabilization criteria (relative frequency, relative damping, MAC).
STABLE_FREQ = 0.01
STABLE_DAMP = 0.05
STABLE_MAC = 0.98
# Looser criteria that link poles of successive orders into chains (candidate modes):
# LSCF damping of weak modes flutters by more than 5 % under additive noise.
LINK_DAMP = 0.25
LINK_MAC = 0.9
ZETA_MAX = 0.3
#: Poles outside the band within this many of their decay rates of an edge take part
#: (near-band poles: a mode outside the band whose skirt the band holds).
NEAR_BAND_REACH = 3.0


@dataclass
class StabilizationDiagram:
    """Poles of every LSCF order with their stability status (for plotting).

    ``status``: 0 new, 1 stable in frequency, 2 frequency and damping, 3 frequency,
    damping and residue vector (MAC). ``selected_hz`` are the chosen modes.
    """

    order: np.ndarray
    frequency_hz: np.ndarray
    zeta: np.ndarray
    status: np.ndarray
    indicator_hz: np.ndarray
    indicator: np.ndarray
    selected_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))


def lscf_poles(freq_hz, frf, max_order: int) -> list[np.ndarray]:
    """Poles (rad/s) of the complex-coefficient LSCF model for orders 1..max_order.

    Guillaume et al. (2003) / Verboven (2002, eq. 5.26) reduced normal equations with
    unit weights on a Chebyshev basis of the band-shifted frequency
    ``x = (w - w_c) / h``; see module doc.

    Parameters
    ----------
    freq_hz : (K,) frequencies of the band, Hz (any spacing).
    frf : (K, P) complex FRFs (any consistent unit; each column is scaled to unit rms).
    max_order : highest denominator order.

    Returns
    -------
    list of complex arrays; entry n-1 holds the n poles of order n.
    """
    w = 2 * np.pi * np.asarray(freq_hz, float)
    H = np.asarray(frf)
    H = H / np.sqrt(np.mean(np.abs(H) ** 2, axis=0))
    wc, hw = 0.5 * (w[0] + w[-1]), 0.5 * (w[-1] - w[0])
    n = int(max_order)
    X = chebvander((w - wc) / hw, n).astype(complex)                     # (K, n+1)
    XH = X.conj().T
    R = XH @ X                                                            # (n+1, n+1)
    S = -np.einsum("jk,kp,kl->pjl", XH, H, X)                             # (P, n+1, n+1)
    Tm = (XH * np.sum(np.abs(H) ** 2, axis=1)) @ X                        # (n+1, n+1)
    poles = []
    for order in range(1, n + 1):
        m = order + 1
        Sm = S[:, :m, :m]
        RinvS = np.linalg.solve(R[:m, :m], Sm)
        M = Tm[:m, :m] - np.einsum("pji,pjl->il", Sm.conj(), RinvS)
        M = 0.5 * (M + M.conj().T)
        alpha = np.linalg.solve(M[:order, :order], -M[:order, order])
        x = chebroots(np.concatenate([alpha, [1.0]]))
        poles.append(1j * (wc + hw * x))
    return poles


def stabilization(freq_hz, frf, pole_sets, band_w):
    """Status of every pole and chains of stable poles across orders."""
    order, lam, status, prev_link = [], [], [], []
    start = 0
    prev = None
    for n, p in enumerate(pole_sets, start=1):
        wn, z = pole_to_modal(p)
        reach = NEAR_BAND_REACH * -p.real
        ok = np.isfinite(p) & (p.real < 0) & (z < ZETA_MAX) \
            & (p.imag >= band_w[0] - reach) & (p.imag <= band_w[1] + reach)
        p = p[ok]
        wn, z = wn[ok], z[ok]
        shapes = lsfd(freq_hz, frf, p)[0] if (p.size and frf.shape[1] > 1) else None
        st = np.zeros(p.size, int)
        link = np.full(p.size, -1)
        if prev is not None and p.size and prev["p"].size:
            df = np.abs(wn[:, None] - prev["wn"][None]) / wn[:, None]
            j = np.argmin(df, axis=1)
            dfj = df[np.arange(p.size), j]
            dz = np.abs(z - prev["z"][j]) / z
            fine_f = dfj < STABLE_FREQ
            fine_z = fine_f & (dz < STABLE_DAMP)
            linked = fine_f & (dz < LINK_DAMP)
            if shapes is not None:
                macs = np.abs(np.sum(shapes.conj() * prev["shapes"][:, j], axis=0)) ** 2 / (
                    np.sum(np.abs(shapes) ** 2, 0) * np.sum(np.abs(prev["shapes"][:, j]) ** 2, 0))
                st = fine_f.astype(int) + fine_z + (fine_z & (macs > STABLE_MAC))
                linked &= macs > LINK_MAC
            else:                          # one point: no shape criterion, status <= 2
                st = fine_f.astype(int) + fine_z
            link = np.where(linked, prev["start"] + j, -1)
        order.append(np.full(p.size, n))
        lam.append(p)
        status.append(st)
        prev_link.append(link)
        prev = dict(p=p, wn=wn, z=z, shapes=shapes, start=start)
        start += p.size
    order = np.concatenate(order)
    lam = np.concatenate(lam)
    status = np.concatenate(status)
    link = np.concatenate(prev_link)
    # chains: union of stable links (each pole links to at most one predecessor)
    label = np.arange(lam.size)
    for i in np.flatnonzero(link >= 0):   # links point backwards: one pass suffices
        label[i] = label[link[i]]
    return order, lam, status, link, label


def chain_representatives(lam, link, label, order):
    """Chains of >= 2 linked poles: (representative pole, the orders present).

    The representative is the median (real and imaginary parts) of the members in
    the upper half of the chain's orders."""
    chains = []
    for lab in np.unique(label[link >= 0]):
        members = np.flatnonzero(label == lab)
        top = members[order[members] >= np.median(order[members])]
        rep = np.median(lam[top].real) + 1j * np.median(lam[top].imag)
        chains.append((rep, np.unique(order[members])))
    return chains
