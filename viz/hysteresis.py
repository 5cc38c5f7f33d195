"""Joint force-slip pictures: backbone curve and hysteresis loops.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics.
"""
from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_hysteresis"]


def plot_hysteresis(
    backbone_slip,
    backbone_force,
    loops: Sequence[tuple] = (),
    labels: Sequence[str] | None = None,
    *,
    slip_limit: float | None = None,
    title: str | None = None,
    path=None,
) -> Figure:
    """Draw a joint backbone and hysteresis loops.

    Parameters
    ----------
    backbone_slip, backbone_force : array_like, shape (n,)
        Virgin loading curve: slip (m) and force (N).
    loops : sequence of (slip, force) pairs of arrays
        One closed loop per amplitude (m, N).
    labels : sequence of str, optional
        Legend text of each loop.
    slip_limit : float, optional
        If given, dotted vertical lines at +/- this slip (e.g. ``phi_max``, m).
    title : str, optional
    path : str or path-like, optional
        If given, the figure is written there (PNG at 150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(6.4, 4.8), constrained_layout=True)
    ax = fig.add_subplot()
    ub = np.asarray(backbone_slip, dtype=float)
    fb = np.asarray(backbone_force, dtype=float)
    ax.plot(ub * 1e3, fb, color="k", lw=1.2, ls="--", zorder=3, label="backbone")
    if labels is None:
        labels = [None] * len(loops)
    if len(labels) != len(loops):
        raise ValueError(f"got {len(labels)} labels for {len(loops)} loops")
    colors = matplotlib.colormaps["viridis"](np.linspace(0.1, 0.85, max(len(loops), 1)))
    for (u, f), label, color in zip(loops, labels, colors):
        ax.plot(np.asarray(u, dtype=float) * 1e3, np.asarray(f, dtype=float),
                color=color, lw=1.1, label=label)
    if slip_limit is not None:
        for x in (-slip_limit, slip_limit):
            ax.axvline(x * 1e3, color="0.5", ls=":", lw=0.9)
    ax.axhline(0.0, color="0.8", lw=0.6, zorder=0)
    ax.axvline(0.0, color="0.8", lw=0.6, zorder=0)
    ax.set_xlabel("slip u [mm]")
    ax.set_ylabel("joint force F [N]")
    if title:
        ax.set_title(title)
    ax.legend(fontsize="small", loc="upper left")
    ax.grid(True, alpha=0.3)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
