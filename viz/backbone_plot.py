"""Backbones: frequency and damping ratio against amplitude, one curve or marker set each.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics. The
curves come from :mod:`fe.epmc` (nonlinear modes) and from identified virtual tests
(:mod:`cases.backbones`).
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_backbones"]


def plot_backbones(curves, *, xlabel: str = "amplitude", title: str | None = None,
                   marks=(), path=None) -> Figure:
    """Two panels sharing a log amplitude axis: frequency (Hz) and damping ratio (%).

    Parameters
    ----------
    curves : sequence of dict
        Each with ``amplitude``, ``frequency_hz``, ``zeta`` (fraction) arrays, a
        ``label`` and optionally ``style`` (a matplotlib format, e.g. ``"-"`` for a
        line, ``"o"`` for markers).
    xlabel : str
        Label of the amplitude axis (what the amplitude is, with its unit).
    marks : sequence of (float, str)
        Vertical reference lines at these amplitudes with their labels (e.g. the
        amplitude at which the joint reaches phi_max).
    path : str or path-like, optional
        If given, the figure is written there (PNG, 150 dpi).
    """
    fig = Figure(figsize=(6.4, 6.4), constrained_layout=True)
    ax_f, ax_z = fig.subplots(2, 1, sharex=True)
    for i, c in enumerate(curves):
        style = c.get("style", "-")
        kw = {"ms": 6, "mfc": "none"} if style.strip("-") else {"lw": 1.4}
        a = np.asarray(c["amplitude"], float)
        ax_f.plot(a, np.asarray(c["frequency_hz"], float), style, color=f"C{i}",
                  label=c["label"], **kw)
        ax_z.plot(a, 100 * np.asarray(c["zeta"], float), style, color=f"C{i}", **kw)
    for x, text in marks:
        for ax in (ax_f, ax_z):
            ax.axvline(x, color="0.5", lw=0.8, ls=":")
        ax_f.annotate(text, (x, 1.0), xycoords=("data", "axes fraction"), rotation=90,
                      va="top", ha="right", fontsize=8, color="0.35")
    ax_z.set_xscale("log")
    ax_f.set_ylabel("frequency (Hz)")
    ax_z.set_ylabel("damping ratio (%)")
    ax_z.set_xlabel(xlabel)
    ax_f.legend(fontsize=8, loc="lower left")
    for ax in (ax_f, ax_z):
        ax.grid(True, which="both", alpha=0.3)
    if title:
        ax_f.set_title(title, fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
