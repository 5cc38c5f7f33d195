"""Pictures of a model-form diagnosis: data, base and extended fits, residuals, evidence.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_diagnosis_fits", "plot_evidence"]

_BASE = dict(color="tab:blue", lw=1.3, ls="--", marker="s", ms=3.5, mfc="none")
_EXT = dict(color="tab:red", lw=1.3, ls="-", marker="^", ms=3.5, mfc="none")


def plot_diagnosis_fits(
    excitation,
    omega2,
    zeta,
    base_omega2,
    base_zeta,
    extended_omega2,
    extended_zeta,
    sigma_omega2: float,
    sigma_zeta: float,
    *,
    response=None,
    base_response=None,
    extended_response=None,
    sigma_response: float | None = None,
    extended_label: str = "extended",
    title: str | None = None,
    path=None,
) -> Figure:
    """Data against excitation with both fits (top) and standardized residuals (bottom).

    Parameters
    ----------
    excitation : array_like (n,)
        Excitation amplitude per level (any unit proportional to force).
    omega2, zeta : array_like (n,)
        Measured natural frequency squared (rad^2/s^2) and damping ratio (fraction).
    base_omega2, base_zeta, extended_omega2, extended_zeta : array_like (n,)
        Fitted values of the base and the extended model.
    sigma_omega2, sigma_zeta : float
        Noise levels used to standardize the residuals.
    response, base_response, extended_response : array_like (n,), optional
        Measured response amplitude and the two models' fitted values (same unit);
        adds a third column.
    sigma_response : float, optional
        Noise level of log(response) (relative), for its residuals.
    extended_label : str
        Legend text of the extended model (the cause).
    title : str, optional
    path : str or path-like, optional
        Write the figure there (PNG, 150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    x = np.asarray(excitation, float)
    cols = 3 if response is not None else 2
    fig = Figure(figsize=(4.4 * cols, 6.4), constrained_layout=True)
    axes = fig.subplots(2, cols, sharex=True, gridspec_kw=dict(height_ratios=[3, 2]))
    panels = [
        ("omega2 - omega2[1]  [rad$^2$/s$^2$]", omega2, base_omega2, extended_omega2,
         sigma_omega2, float(np.asarray(omega2, float)[0]), 1.0, False),
        ("zeta  [%]", zeta, base_zeta, extended_zeta, sigma_zeta, 0.0, 100.0, False),
    ]
    if response is not None:
        panels.append(("response / excitation (relative)", response, base_response,
                       extended_response, sigma_response, 0.0, 1.0, True))
    for j, (label, y, yb, ye, sig, offset, scale, ratio) in enumerate(panels):
        y, yb, ye = (np.asarray(v, float) for v in (y, yb, ye))
        top, bottom = axes[0, j], axes[1, j]
        if ratio:
            norm = y[0] / x[0]
            show = lambda v: v / x / norm  # noqa: E731
            res_b, res_e = np.log(y / yb) / sig, np.log(y / ye) / sig
        else:
            show = lambda v: (v - offset) * scale  # noqa: E731
            res_b, res_e = (y - yb) / sig, (y - ye) / sig
        top.plot(x, show(y), "ko", ms=4, label="data", zorder=3)
        top.plot(x, show(yb), label="base (micro-slip Iwan)", **_BASE)
        top.plot(x, show(ye), label=extended_label, **_EXT)
        top.set_ylabel(label)
        top.grid(True, alpha=0.3)
        bottom.axhspan(-2, 2, color="0.9", zorder=0)
        bottom.plot(x, res_b, **_BASE)
        bottom.plot(x, res_e, **_EXT)
        bottom.axhline(0.0, color="k", lw=0.8)
        bottom.set_ylabel("residual / sigma")
        bottom.set_xlabel("excitation")
        bottom.set_xscale("log")
        bottom.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


def plot_evidence(
    names: Sequence[str],
    delta_aicc: Sequence[float],
    threshold: float,
    *,
    chosen: str | None = None,
    cv_gain: Mapping[str, float] | None = None,
    title: str | None = None,
    path=None,
) -> Figure:
    """Bar chart of the AICc drop of every candidate against the base model.

    Parameters
    ----------
    names : sequence of str
        Candidate causes.
    delta_aicc : sequence of float
        AICc(base) - AICc(candidate); NaN for an unavailable candidate.
    threshold : float
        Drop a candidate must exceed to be named (dashed line).
    chosen : str, optional
        The named cause (drawn in red).
    cv_gain : mapping name -> float, optional
        Cross-validation gains written above the bars.
    title : str, optional
    path : str or path-like, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(6.4, 3.6), constrained_layout=True)
    ax = fig.add_subplot()
    d = np.asarray(delta_aicc, float)
    pos = np.arange(len(names))
    colors = ["tab:red" if n == chosen else "0.6" for n in names]
    shown = np.where(np.isfinite(d), d, 0.0)
    ax.bar(pos, shown, color=colors)
    ax.axhline(threshold, color="k", ls="--", lw=1, label=f"threshold {threshold:g}")
    ax.axhline(0.0, color="k", lw=0.8)
    for i, n in enumerate(names):
        if not np.isfinite(d[i]):
            ax.text(i, 0.0, "n/a", ha="center", va="bottom", fontsize=8)
        elif cv_gain and n in cv_gain:
            ax.text(i, shown[i], f"gain {cv_gain[n]:.2f}", ha="center",
                    va="bottom" if shown[i] >= 0 else "top", fontsize=8)
    ax.set_xticks(pos)
    ax.set_xticklabels(names, rotation=20, ha="right", fontsize=8)
    ax.set_ylabel("AICc(base) - AICc(candidate)")
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
