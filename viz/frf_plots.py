"""Stepped-sine FRFs at many force levels (paper Fig. 4 style) and damping-growth fits.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib import cm  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_frf_levels", "plot_damping_growth"]


def plot_frf_levels(freq_hz, frf, force, zooms=(), title: str | None = None,
                    ylabel: str = "|receptance| (m/N)", path=None) -> Figure:
    """FRF magnitude at every force level, with zoomed panels (paper Fig. 4).

    Parameters
    ----------
    freq_hz : (n_lines,) line frequencies (Hz).
    frf : (n_levels, n_lines) complex (or magnitude) FRFs, one row per level.
    force : (n_levels,) force amplitudes (N), for the legend.
    zooms : sequence of (lo_hz, hi_hz, label)
        One zoomed panel per entry, drawn under the full-band panel.
    title, ylabel : str
    path : str or path-like, optional
        Write a PNG there (150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    f = np.asarray(freq_hz, dtype=float)
    H = np.abs(np.asarray(frf))
    force = np.asarray(force, dtype=float)
    n_z = len(zooms)
    fig = Figure(figsize=(11.0, 7.5 if n_z else 4.8), constrained_layout=True)
    if n_z:
        gs = fig.add_gridspec(2, n_z, height_ratios=[1.3, 1.0])
        ax = fig.add_subplot(gs[0, :])
    else:
        ax = fig.add_subplot()
    colors = cm.viridis(np.linspace(0.0, 0.92, H.shape[0]))
    for lv in range(H.shape[0]):
        ax.semilogy(f, H[lv], color=colors[lv], lw=0.9, label=f"{force[lv]:g} N")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(ncol=6, fontsize=7, loc="lower left", title="force amplitude", title_fontsize=7)
    if title:
        ax.set_title(title)
    for i, (lo, hi, label) in enumerate(zooms):
        axz = fig.add_subplot(gs[1, i])
        sel = (f >= lo) & (f <= hi)
        for lv in range(H.shape[0]):
            axz.plot(f[sel], H[lv, sel], ".-", color=colors[lv], lw=0.8, ms=2.5)
        ax.axvspan(lo, hi, color="0.85", zorder=0)
        axz.set_title(label, fontsize=9)
        axz.set_xlabel("frequency (Hz)")
        axz.grid(True, alpha=0.25)
        axz.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


def plot_damping_growth(panels, path=None, title: str | None = None) -> Figure:
    """Joint damping of each mode against joint slip amplitude, measured vs fitted.

    Parameters
    ----------
    panels : sequence of dict
        One panel per mode with keys ``amplitude`` (n,) (m), ``delta_c`` (n,) measured
        joint damping (rad^2/s^2), ``delta_c_model`` (n,) fitted model, ``used`` (n,)
        bool (levels in the fit), ``label`` (str, panel title) and optionally ``text``
        (str, annotation). Non-positive values are not drawn (log axes).
    path : str or path-like, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = len(panels)
    fig = Figure(figsize=(4.2 * max(n, 1), 4.0), constrained_layout=True)
    for i, pnl in enumerate(panels):
        ax = fig.add_subplot(1, n, i + 1)
        a = np.asarray(pnl["amplitude"], float)
        d = np.asarray(pnl["delta_c"], float)
        dm = np.asarray(pnl["delta_c_model"], float)
        used = np.asarray(pnl["used"], bool)
        pos = (a > 0) & (d > 0)
        ax.loglog(a[pos & used], d[pos & used], "o", color="C0", label="measured, in fit")
        ax.loglog(a[pos & ~used], d[pos & ~used], "o", mfc="none", color="C1",
                  label="measured, not in fit")
        order = np.argsort(a)
        ok = (dm[order] > 0) & (a[order] > 0)
        ax.loglog(a[order][ok], dm[order][ok], "-", color="k", lw=1.1, label="fitted model")
        ax.set_xlabel("joint slip amplitude at the peak line (m)")
        ax.set_ylabel("joint damping Delta c (rad^2/s^2)")
        ax.set_title(pnl.get("label", ""), fontsize=10)
        ax.grid(True, which="both", alpha=0.25)
        if pnl.get("text"):
            ax.text(0.03, 0.97, pnl["text"], transform=ax.transAxes, va="top", ha="left",
                    fontsize=8, bbox={"boxstyle": "round", "fc": "white", "ec": "0.7"})
        if i == 0:
            ax.legend(fontsize=7, loc="lower right")
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
