"""Which poles of an identification are modes: candidates from the stabilization
chains, and the tests that keep or drop a refined pole.

* :func:`candidates`: one chain per physical mode (shorter chains within 0.5 % or a
  half-power width of a longer one are the same mode, present at the union of their
  orders); a chain present at >= max(3, 20 %) of the orders (half that near a peak of
  the mode indicator) is a candidate; ``n_modes`` given: the n longest chains in the band and every other long
  chain.
* :func:`roles` (``n_modes`` given): after the refinement the n poles in the band with
  the largest fitted peaks are the modes; another pole farther than a half-power width
  from every mode, sharper than it or with a peak of the mode indicator of its own (a
  second resonance such as a rattle) is a *nuisance* pole, fitted beside the modes and
  not returned; the rest are dropped (a second pole on a resonance a joint distorts is
  wider than the mode and has no peak of its own).
* :func:`physical`: a refined pole stays when its damping is in (1e-7, ZETA_MAX) and
  it lies in the band, or just outside it while a peak of the mode indicator inside
  the band lies within its half-power half-width (a resonance the band cuts), or
  within :data:`NEAR_BAND_REACH` decay rates of an edge: a mode outside the band whose
  skirt the band holds, refined with the modes (its LSCF chain gives a well-posed
  start) but not returned (*near-band*).
* :func:`runaway`: a pole the refinement moved by more than :data:`RUNAWAY` of its
  half-power half-widths is dropped (its start was not near an optimum).
* :func:`significant`: dropping the pole (others fixed, residues refitted) raises the
  weighted misfit significantly (an F-test with a look-elsewhere quantile) and its
  fitted peak is above 1 % of the local FRF level.
* :func:`one_resonance_pair`: two poles closer than a half-power width (and, several
  points, residue MAC > 0.9) are one resonance unless the F-test says both are needed.

Each test's statistic is returned beside its decision, so a decision within
:data:`NEAR_MARGIN` of its threshold is stated as such (:func:`near_threshold`).
"""
from __future__ import annotations

import numpy as np

from ident.lscf import LINK_MAC, NEAR_BAND_REACH, STABLE_FREQ, ZETA_MAX
from ident.lsfd import lsfd
from ident.poles import mac, pole_to_modal

__all__ = ["candidates", "roles", "runaway", "physical", "significant", "one_resonance_pair", "near_threshold",
           "NEAR_BAND_REACH", "NEAR_MARGIN", "F_LEVEL"]

#: Largest move of a pole in one refinement, in half-power half-widths of its start.
RUNAWAY = 5.0
#: A statistic within this relative distance of its threshold is reported as near it.
NEAR_MARGIN = 0.1
#: Level of the F-tests that keep a pole, divided by the number of lines K
#: (look-elsewhere: a noise pole is the best of ~K candidates).
F_LEVEL = 1e-3


def near_threshold(what: str, value: float, threshold: float) -> str | None:
    """A note when ``value`` lies within :data:`NEAR_MARGIN` (relative) of
    ``threshold``: the decision it made could go the other way on a machine whose
    round-off differs, or with a little more noise."""
    if not (np.isfinite(value) and np.isfinite(threshold)) or threshold == 0:
        return None
    if abs(value - threshold) <= NEAR_MARGIN * abs(threshold):
        side = "above" if value > threshold else "below"
        return (f"{what}: {value:.4g} is {side} its threshold {threshold:.4g} by less than "
                f"{NEAR_MARGIN:.0%}: a near decision")
    return None


def candidates(rep, orders, n_orders, n_modes, peak_w, dw, band_w):
    """Candidate poles from the chains' representatives ``rep`` (rad/s) and the model
    orders each chain is present at (``orders``, a list of int arrays; module doc).
    ``peak_w``: the mode indicator's peaks (rad/s); ``dw`` the largest line spacing
    (rad/s). Returns (poles, stability = count / n_orders) or raises ValueError when
    ``n_modes`` chains are not there; with ``n_modes`` the other long chains come too
    (their roles are set after the refinement, :func:`roles`).

    Chains of one mode (within 0.5 % or a half-power width of a longer one) are one
    candidate present at the union of their orders: the linking of a heavily damped
    mode's poles across orders breaks at places that round-off decides, and so would
    the length of each piece."""
    count = np.array([o.size for o in orders])
    wn, z = pole_to_modal(rep)
    keep = np.ones(rep.size, bool)
    for i in np.argsort(-count, kind="stable"):
        if not keep[i]:
            continue
        close = (np.abs(wn - wn[i]) < np.maximum(0.5 * STABLE_FREQ * wn[i], z[i] * wn[i])) & keep
        close[i] = False
        merged = close & (count <= count[i])
        keep[merged] = False
        orders[i] = np.unique(np.concatenate([orders[i]] + [orders[j] for j in
                                                            np.flatnonzero(merged)]))
    rep = rep[keep]
    count = np.array([o.size for o, k in zip(orders, keep) if k])
    wn, z = pole_to_modal(rep)
    need = max(3, int(np.ceil(0.2 * n_orders)))
    inside = (rep.imag >= band_w[0]) & (rep.imag <= band_w[1])
    if n_modes is None:
        near_peak = np.zeros(rep.size, bool)
        if peak_w.size:
            dist = np.abs(peak_w[None, :] - wn[:, None])
            near_peak = np.any(dist < np.maximum(2 * z * wn, 2 * dw)[:, None], axis=1)
        chosen = np.flatnonzero((count >= need) | (near_peak & (count >= max(2, need // 2))))
    else:
        idx = np.flatnonzero(inside)
        chosen = idx[np.argsort(-count[idx], kind="stable")[: int(n_modes)]]
        if chosen.size < int(n_modes):
            raise ValueError(f"only {chosen.size} stable mode(s) found in "
                             f"{band_w[0] / (2 * np.pi):g}-{band_w[1] / (2 * np.pi):g} Hz, "
                             f"{n_modes} requested")
        others = np.flatnonzero((count >= need) & ~np.isin(np.arange(rep.size), chosen))
        chosen = np.concatenate([chosen, others])
    chosen = chosen[np.argsort(wn[chosen], kind="stable")]       # a canonical order
    return rep[chosen], count[chosen] / n_orders


def _peaks(f, Hn, p, ps, Wt):
    """Fitted peak ``|A_r| / sigma_r`` (norm over the points) of each pole of ``p``."""
    res = lsfd(f, Hn, np.concatenate([p, ps]), Wt)[0][:, :p.size]
    return np.sqrt(np.sum(np.abs(res) ** 2, axis=0)) / (-p.real)


def roles(f, Hn, p, ps, Wt, n_modes, band_w, peak_w):
    """(keep, nuisance) of refined poles ``p`` with ``n_modes`` asked for (module doc):
    a nuisance pole is farther than the larger half-power half-width from every mode
    and either narrower than the nearest mode or has a peak of the mode indicator
    (``peak_w``, rad/s) of its own, nearer to it than to any mode and within its
    half-power half-width: a resonance of its own (a rattle on a mode's skirt shows no
    peak but is sharper than the mode), not a wider second pole on a resonance that a
    joint distorts."""
    peak = _peaks(f, Hn, p, ps, Wt)
    inside = (p.imag >= band_w[0]) & (p.imag <= band_w[1])
    order = np.argsort(-np.where(inside, peak, -np.inf), kind="stable")
    modes = order[:min(int(n_modes), int(inside.sum()))]
    if modes.size == 0:                     # no pole in the band: no mode, no nuisance
        none = np.zeros(p.size, bool)
        return none, none.copy()
    half = -p.real
    apart = np.all(np.abs(p.imag[:, None] - p.imag[None, modes])
                   >= np.maximum(half[:, None], half[None, modes]), axis=1)
    own = np.zeros(p.size, bool)
    if peak_w.size:
        d = np.abs(peak_w[None, :] - p.imag[:, None])                         # (m, n)
        d_mode = np.min(np.abs(peak_w[None, :] - p.imag[modes][:, None]), axis=0)
        own = np.any((d <= half[:, None]) & (d < d_mode[None, :]), axis=1)
    nearest = modes[np.argmin(np.abs(p.imag[:, None] - p.imag[None, modes]), axis=1)]
    narrower = half < half[nearest]
    is_mode = np.isin(np.arange(p.size), modes)
    nuisance = apart & (own | narrower) & ~is_mode
    return nuisance | is_mode, nuisance


def runaway(start, p) -> np.ndarray:
    """Poles that the refinement moved by more than :data:`RUNAWAY` half-power
    half-widths of their start (``|p - start| > RUNAWAY |Re start|``): a start outside
    the basin of an optimum near it (a noise pole of LSCF that the fit drags across
    the band onto another resonance, where round-off decides which side it lands)."""
    start, p = np.asarray(start, complex), np.asarray(p, complex)
    return np.abs(p - start) > RUNAWAY * np.abs(start.real)


def physical(p, band_w, peak_w, dw):
    """(keep, near_band) of refined poles ``p`` (module doc)."""
    wn_p, z_p = pole_to_modal(p)
    inside = (p.imag >= band_w[0]) & (p.imag <= band_w[1])
    cut = np.zeros(p.size, bool)
    if peak_w.size:
        reach = -p.real + 2 * dw
        cut = ~inside & np.any(np.abs(peak_w[None, :] - p.imag[:, None]) < reach[:, None],
                               axis=1)
    gap = np.maximum(band_w[0] - p.imag, p.imag - band_w[1])
    near = ~inside & ~cut & (gap <= NEAR_BAND_REACH * -p.real)
    ok = (z_p > 1e-7) & (z_p < ZETA_MAX)
    return (inside | cut | near) & ok, near & ok


def _misfit(f, Hn, poles, Wt):
    return float(np.sum(np.abs(lsfd(f, Hn, poles, Wt)[2]) ** 2))


def significant(f, Hn, p, ps, Wt):
    """(keep, F, critical value) per pole of ``p`` (module doc): F = ((chi_-r - chi)/q)
    / (chi/dof) against the ``1 - F_LEVEL/K`` quantile of F(q, dof), q = 2 + 2P,
    ``ps`` the held out-of-band poles; the peak above 1 % of the local FRF level."""
    from scipy.stats import f as fisher_f

    allp = np.concatenate([p, ps])
    res, _, r = lsfd(f, Hn, allp, Wt)
    chi = float(np.sum(np.abs(r) ** 2))
    K, P = Hn.shape
    q = 2 + 2 * P
    dof = 2 * K * P - (2 * p.size + P * (2 * allp.size + 4))
    F = np.full(p.size, np.inf)
    if dof <= 0 or chi <= 0:
        return np.ones(p.size, bool), F, float("nan")
    crit = float(fisher_f.isf(F_LEVEL / K, q, dof))
    F = np.array([((_misfit(f, Hn, np.delete(allp, k), Wt) - chi) / q) / (chi / dof)
                  for k in range(p.size)])
    w = 2 * np.pi * f
    lev2 = np.sum(np.abs(Hn) ** 2, axis=1)
    wn_p, z_p = pole_to_modal(p)
    peak = np.sqrt(np.sum(np.abs(res[:, :p.size]) ** 2, axis=0)) / (-p.real)
    win = np.abs(w[None, :] - wn_p[:, None]) <= np.maximum(
        3 * z_p * wn_p, 2 * np.diff(w).max())[:, None]                    # (m, K)
    level = np.sqrt((win * lev2).sum(axis=1) / np.maximum(win.sum(axis=1), 1))
    return (F > crit) & (peak > 0.01 * level), F, crit


def one_resonance_pair(f, Hn, p, ps, Wt, refit):
    """(keep, tests) for the pairs of poles of ``p`` that look like one resonance
    (module doc): the weaker of the first such pair is dropped unless the F-test of the
    nested fits (the pair against the rest refitted by ``refit``, which returns the
    refined (poles, held poles) of a set) says both are needed. ``tests``: (pair, F,
    critical value) of every pair tested."""
    from scipy.stats import f as fisher_f

    keep = np.ones(p.size, bool)
    tests = []
    wn_p, z_p = pole_to_modal(p)
    res = lsfd(f, Hn, np.concatenate([p, ps]), Wt)[0][:, :p.size]
    peak = _peaks(f, Hn, p, ps, Wt)
    K, P = Hn.shape
    for i, j in zip(*np.triu_indices(p.size, 1)):
        close = abs(wn_p[i] - wn_p[j]) < max(z_p[i] * wn_p[i], z_p[j] * wn_p[j])
        if not close or (P > 1 and mac(res[:, i], res[:, j])[0, 0] < LINK_MAC):
            continue
        weak = i if peak[i] < peak[j] else j
        chi = _misfit(f, Hn, np.concatenate([p, ps]), Wt)
        p1, ps1 = refit(np.delete(p, weak))
        chi1 = _misfit(f, Hn, np.concatenate([p1, ps1]), Wt)
        n_par = 2 * p.size + P * (2 * (p.size + ps.size) + 4)
        dof, q = 2 * K * P - n_par, 2 + 2 * P
        if dof <= 0 or not chi > 0:
            continue
        F = ((chi1 - chi) / q) / (chi / dof)
        crit = float(fisher_f.isf(F_LEVEL / K, q, dof))
        tests.append(((int(i), int(j)), float(F), crit))
        if F < crit:
            keep[weak] = False
            break
    return keep, tests
