"""One mode followed across excitation levels: levels agreeing on the number of modes,
matching identified modes of successive levels (frequency and MAC), and the
measured-data table built from them."""
from __future__ import annotations

import numpy as np

from ident.identify import IdentifiedMode
from ident.lscf import LINK_MAC
from ident.measured import MeasuredData
from ident.poles import mac

MATCH_FREQ = 0.05
MATCH_MAC = 0.8


def one_resonance(modes) -> bool:
    """True when two modes lie closer than the larger half-power half-width
    ``zeta f_n`` and (several points) their shapes agree (MAC >= 0.9): two poles
    fitted to one resonance, which no level-to-level tracking can separate."""
    for a in range(len(modes)):
        for b in range(a + 1, len(modes)):
            ma, mb = modes[a], modes[b]
            half = max(ma.zeta * ma.frequency_hz, mb.zeta * mb.frequency_hz)
            if abs(ma.frequency_hz - mb.frequency_hz) >= half:
                continue
            if np.size(ma.shape) < 2 or mac(ma.shape, mb.shape)[0, 0] >= LINK_MAC:
                return True
    return False


def agree_on_modes(results, refit):
    """Make the levels of a series agree on the number of modes in the band.

    A level whose automatic selection put two poles on one resonance
    (:func:`one_resonance`) is identified again with one mode fewer; then every level
    with more modes than the most common count (the smaller on a tie; typically a level
    with little signal, or a force-controlled FRF that a nonlinear joint distorts) is
    identified again with that count. Levels with fewer modes are kept (a mode may
    leave the band), and so is a level whose identification with the new count fails
    (its note says why).

    Parameters
    ----------
    results : list of :class:`ident.identify.Identification`, one per level.
    refit : callable ``(k, n_modes) -> Identification`` identifying level k again.

    Returns
    -------
    (results, notes): the new list and, per level, what was done (list of str).
    """
    results = list(results)
    notes = [[] for _ in results]

    def found(res):
        return ", ".join(f"{m.frequency_hz:.6g}" for m in res.modes)

    def again(k, n):
        """Level k identified with n modes, or None (with a note) when that fails."""
        try:
            return refit(k, n)
        except ValueError as exc:
            notes[k].append(f"identified again with {n} mode(s): failed ({exc}); the "
                            f"automatic selection is kept")
            return None

    for k in range(len(results)):
        while len(results[k].modes) > 1 and one_resonance(results[k].modes):
            was = found(results[k])
            res = again(k, len(results[k].modes) - 1)
            if res is None:
                break
            results[k] = res
            notes[k].append(f"two poles within one half-power width ({was} Hz) are one "
                            f"resonance: identified with {len(results[k].modes)}")
    counts = np.array([len(r.modes) for r in results])
    if np.any(counts > 0):
        values, freq = np.unique(counts[counts > 0], return_counts=True)
        common = int(values[np.argmax(freq)])
        agree = int(np.sum(counts == common))
        for k in np.flatnonzero(counts > common):
            was = found(results[k])
            res = again(int(k), common)
            if res is None:
                continue
            results[k] = res
            notes[k].append(f"automatic selection found {counts[k]} modes ({was} Hz); "
                            f"identified with {common}, as at {agree} of {len(results)} levels")
    return results, notes


def match_modes(previous: list, current: list) -> list:
    """Match modes of successive levels by frequency and (several points) MAC.

    Cost ``|f_a - f_b| / f_a + (1 - MAC)`` minimized by the Hungarian assignment; a pair
    is accepted when frequencies differ by < 5 % and (several points) MAC >= 0.8.

    Returns
    -------
    list, for each mode of ``current``, the index into ``previous`` or -1.
    """
    from scipy.optimize import linear_sum_assignment

    out = [-1] * len(current)
    if not previous or not current:
        return out
    fa = np.array([m.frequency_hz for m in previous])
    fb = np.array([m.frequency_hz for m in current])
    df = np.abs(fb[None, :] - fa[:, None]) / fa[:, None]
    several = np.size(previous[0].shape) > 1 and all(
        np.size(m.shape) == np.size(previous[0].shape) for m in current)
    macs = (mac(np.stack([m.shape for m in previous], 1), np.stack([m.shape for m in current], 1))
            if several else np.ones_like(df))
    cost = df + (1.0 - macs)
    rows, cols = linear_sum_assignment(cost)
    for i, j in zip(rows, cols):
        if df[i, j] < MATCH_FREQ and macs[i, j] >= MATCH_MAC:
            out[j] = int(i)
    return out


def track_modes(held, results):
    """Follow modes from level to level: levels by increasing held amplitude, labels.

    Parameters
    ----------
    held : (L,) the amplitude each FRF set held (> 0; equal values are repeats of one
        level): the excitation under force control, the response amplitude under
        response control.
    results : list of L lists of IdentifiedMode.

    Modes are labelled 1, 2, ... at the lowest level (by frequency) and followed to the
    next level by :func:`match_modes` against the latest mode of every label; a mode
    without a match gets a new label.

    Returns
    -------
    order : (L,) indices of ``results`` by increasing ``held`` (level = position + 1).
    rows : list of (k, i, label, mac) in level order, ``results[k][i]`` being the mode;
        ``mac`` with the same label's previous mode (NaN at its first level or with one
        response point).
    """
    held = np.asarray(held, float)
    L = held.size
    if len(results) != L:
        raise ValueError("one result per excitation level is needed")
    if np.any(~np.isfinite(held) | (held <= 0)):
        raise ValueError("excitation levels must be finite and > 0")
    order = np.argsort(held, kind="stable")     # equal held levels: repeats, file order
    rows = []
    last: dict[int, IdentifiedMode] = {}   # label -> latest mode
    next_label = 1
    for k in order:
        idx = sorted(range(len(results[k])), key=lambda i: results[k][i].frequency_hz)
        modes = [results[k][i] for i in idx]
        labels = list(last)
        match = match_modes([last[lab] for lab in labels], modes)
        for i, mode, j in zip(idx, modes, match):
            if j >= 0:
                lab = labels[j]
                prev = last[lab]
                m = (float(mac(prev.shape, mode.shape)[0, 0])
                     if np.size(mode.shape) > 1 and np.size(prev.shape) == np.size(mode.shape)
                     else float("nan"))
            else:
                lab, m = next_label, float("nan")
                next_label += 1
            rows.append((int(k), i, lab, m))
            last[lab] = mode
    return order, rows


def modal_data_from_levels(excitation, results, run_order=None, sources=None):
    """Measured-data table (``docs/formats/measured-data.md``) from identified levels.

    Parameters
    ----------
    excitation : (L,) excitation amplitude of each FRF set (distinct, > 0).
    results : list of L lists of IdentifiedMode.
    run_order : (L,) chronological order (default 1..L in the given order).
    sources : list of L file names for the ``x_source`` annotation.

    Levels are numbered by increasing excitation and modes followed by
    :func:`track_modes`. Annotations: ``x_frequency_hz``, ``x_stability`` and ``x_mac``
    (MAC with the same mode one level below; NaN at its first level or with one
    response point). Series with response control, uncertainties and fit warnings:
    :func:`ident.series.series_table`.

    Returns
    -------
    ident.measured.MeasuredData
    """
    excitation = np.asarray(excitation, float)
    order, rows = track_modes(excitation, results)
    L = excitation.size
    run_order = np.arange(1, L + 1) if run_order is None else np.asarray(run_order, int)
    sources = [""] * L if sources is None else list(sources)
    if not rows:
        raise ValueError("no mode identified at any level")
    level_of = {int(k): n + 1 for n, k in enumerate(order)}
    modes = [results[k][i] for k, i, _, _ in rows]
    ks = [k for k, _, _, _ in rows]
    return MeasuredData(level=[level_of[k] for k in ks], excitation=excitation[ks],
                        omega2=[m.omega2 for m in modes], zeta=[m.zeta for m in modes],
                        mode=[lab for _, _, lab, _ in rows], run_order=run_order[ks],
                        extra={"x_frequency_hz": np.array([m.frequency_hz for m in modes]),
                               "x_stability": np.array([m.stability for m in modes]),
                               "x_mac": np.array([r[3] for r in rows], float),
                               "x_source": np.array([sources[k] for k in ks], dtype=str)})
