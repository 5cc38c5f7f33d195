"""Stabilization diagram: poles of every model order over the mode-indicator function.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics. The
identifier (:mod:`ident.identify`) supplies, for every pole, its model order, its
undamped natural frequency and a status code (0 new, 1 stable in frequency, 2 also in
damping, 3 also in mode shape), the mode-indicator function ``sum_o |H_o|^2`` and the
frequencies of the modes it selected.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_stabilization"]

_STYLE = {  # status -> (marker, colour, label)
    0: ("o", "0.65", "new"),
    1: ("^", "C1", "stable frequency"),
    2: ("s", "C0", "+ damping"),
    3: ("*", "C2", "+ mode shape"),
}


def plot_stabilization(order, frequency_hz, status, *, indicator_hz=(), indicator=(),
                       selected_hz=(), title: str | None = None, path=None) -> Figure:
    """Stabilization diagram.

    Parameters
    ----------
    order, frequency_hz, status : array_like (n_poles,)
        Model order, undamped natural frequency (Hz) and status code of every pole.
    indicator_hz, indicator : array_like, optional
        Mode-indicator function (drawn on a log scale on a second axis).
    selected_hz : array_like, optional
        Frequencies of the selected modes (vertical lines).
    title : str, optional
    path : str or path-like, optional
        If given, the figure is written there (PNG, 150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    order = np.asarray(order)
    freq = np.asarray(frequency_hz, float)
    status = np.asarray(status, int)
    fig = Figure(figsize=(7.2, 4.8), constrained_layout=True)
    ax = fig.add_subplot()
    for code, (marker, colour, label) in _STYLE.items():
        sel = status == code
        if sel.any():
            ax.plot(freq[sel], order[sel], marker, ls="none", color=colour, ms=5 if code else 3,
                    mfc=colour if code == 3 else "none", label=label)
    for k, f in enumerate(np.asarray(selected_hz, float)):
        ax.axvline(f, color="C3", lw=0.9, ls="--", label="selected" if k == 0 else None)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    if len(indicator):
        ax2 = ax.twinx()
        ax2.semilogy(np.asarray(indicator_hz, float), np.asarray(indicator, float), "-",
                     color="k", lw=0.8, alpha=0.6)
        ax2.set_ylabel(r"mode indicator $\sum_o |H_o|^2$ (normalized)")
        ax.set_zorder(ax2.get_zorder() + 1)
        ax.patch.set_visible(False)
        ax.set_xlim(np.min(indicator_hz), np.max(indicator_hz))
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=5, fontsize=8,
              frameon=False)
    if title:
        ax.set_title(title)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
