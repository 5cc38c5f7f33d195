"""Pictures of a model-form diagnosis: data, base and extended fits, standardized
residuals, and the weight of every explanation.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics. Log axes
carry at most a handful of labelled ticks (1-2-5 steps, no minor labels), so the
labels do not overlap at the saved size.
"""
from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter  # noqa: E402

__all__ = ["plot_diagnosis_fits", "plot_weights", "log_ticks"]

_BASE = dict(color="tab:blue", lw=1.3, ls="--", marker="s", ms=3.5, mfc="none")
_EXT = dict(color="tab:red", lw=1.3, ls="-", marker="^", ms=3.5, mfc="none")


def log_ticks(ax, x) -> None:
    """At most about five labelled ticks on a log x axis spanning ``x``."""
    x = np.asarray(x, float)
    decades = np.log10(x.max() / x.min()) if x.min() > 0 else 1.0
    subs = (1.0, 2.0, 5.0) if decades < 2.5 else (1.0,)
    ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=subs, numticks=6))
    ax.xaxis.set_minor_locator(LogLocator(base=10.0, subs=np.arange(2, 10), numticks=12))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.2g}"))
    ax.tick_params(axis="x", labelsize=8)


def plot_diagnosis_fits(levels: dict, *, extended_label: str = "extended",
                        abscissa_label: str = "excitation", title: str | None = None,
                        path=None) -> Figure:
    """Data against the held amplitude with both fits (top) and standardized residuals
    of both fits (bottom), one column per channel.

    Parameters
    ----------
    levels : dict
        ``abscissa`` (held amplitude per level), ``omega2`` and ``zeta`` (measured,
        rad^2/s^2 and fraction), ``base_omega2``, ``base_zeta``, ``extended_omega2``,
        ``extended_zeta`` (fitted), ``response_amplitude`` with ``base_response`` and
        ``extended_response`` (or None), ``base_residual`` and ``extended_residual``
        (n, channels) in noise units, ``channels`` (names).
    extended_label, abscissa_label, title : str
    path : str or path-like, optional
        Write the figure there (PNG, 150 dpi).
    """
    x = np.asarray(levels["abscissa"], float)
    w1 = float(np.asarray(levels["omega2"], float)[0])

    def freq_pct(v):
        return 100.0 * (np.sqrt(np.asarray(v, float) / w1) - 1.0)

    panels = [("frequency change [%]", freq_pct, "omega2"),
              ("damping ratio [%]", lambda v: 100.0 * np.asarray(v, float), "zeta")]
    if levels.get("response_amplitude") is not None and "response" in levels["channels"]:
        r0 = float(levels["response_amplitude"][0] / x[0])
        panels.append(("response / held level (rel.)",
                       lambda v: np.asarray(v, float) / x / r0, "response"))
    cols = len(panels)
    fig = Figure(figsize=(4.0 * cols + 0.6, 6.0), constrained_layout=True)
    axes = fig.subplots(2, cols, sharex="col", squeeze=False,
                        gridspec_kw=dict(height_ratios=[3, 2]))
    key = {"omega2": "omega2", "zeta": "zeta", "response": "response_amplitude"}
    fit_key = {"omega2": "omega2", "zeta": "zeta", "response": "response"}
    for j, (label, show, ch) in enumerate(panels):
        top, bottom = axes[0, j], axes[1, j]
        top.plot(x, show(levels[key[ch]]), "ko", ms=4, label="data", zorder=3)
        top.plot(x, show(levels[f"base_{fit_key[ch]}"]), label="base (micro-slip Iwan)",
                 **_BASE)
        top.plot(x, show(levels[f"extended_{fit_key[ch]}"]), label=extended_label, **_EXT)
        top.set_ylabel(label, fontsize=9)
        top.set_xscale("log")
        top.grid(True, alpha=0.3)
        top.tick_params(labelsize=8)
        i = levels["channels"].index(ch)
        bottom.axhspan(-2, 2, color="0.9", zorder=0)
        bottom.plot(x, np.asarray(levels["base_residual"])[:, i], **_BASE)
        bottom.plot(x, np.asarray(levels["extended_residual"])[:, i], **_EXT)
        bottom.axhline(0.0, color="k", lw=0.8)
        bottom.set_ylabel("residual / noise", fontsize=9)
        bottom.set_xlabel(abscissa_label, fontsize=9)
        bottom.set_xscale("log")
        bottom.grid(True, alpha=0.3)
        bottom.tick_params(labelsize=8)
        log_ticks(bottom, x)
        log_ticks(top, x)
    axes[0, 0].legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(title, fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


def plot_weights(names: Sequence[str], weights: Sequence[float], *, named: str | None = None,
                 gains: Sequence[float | None] | None = None, title: str | None = None,
                 path=None) -> Figure:
    """Horizontal bars: the weight of each explanation (named one in red), with its
    cross-validated gain written beside the bar.

    Parameters
    ----------
    names : explanation labels ("none", "a", "a+b"); weights : their weights (0..1);
    named : the label drawn in red; gains : gain per explanation (None: not shown);
    title : str; path : PNG file (150 dpi).
    """
    n = len(names)
    fig = Figure(figsize=(7.0, 1.0 + 0.32 * n), constrained_layout=True)
    ax = fig.add_subplot()
    pos = np.arange(n)[::-1]
    colors = ["tab:red" if nm == named else "0.6" for nm in names]
    ax.barh(pos, weights, color=colors)
    for p, w, g in zip(pos, weights, gains if gains is not None else [None] * n):
        txt = f"{w:.3f}" + ("" if g is None else f"  (gain {g:.2g})")
        ax.text(min(w, 1.0) + 0.01, p, txt, va="center", fontsize=7)
    ax.set_yticks(pos)
    ax.set_yticklabels([nm.replace("+", " +\n") if len(nm) > 30 else nm for nm in names],
                       fontsize=7)
    ax.set_xlim(0.0, 1.25)
    ax.set_xlabel("weight (Akaike, with the cost per cause)", fontsize=8)
    ax.tick_params(axis="x", labelsize=8)
    if title:
        ax.set_title(title, fontsize=9)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
