"""Monte Carlo bands of predicted frequency and damping against level.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics. The
sweep (:mod:`cases.double_beam.uncertainty`) supplies the per-level sample quantiles, the nominal
FE prediction, the estimator's closed-form prediction with its delta-method interval
and the measured values.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_uncertainty_bands"]


def plot_uncertainty_bands(level, panels, held_out=None, band_label: str = "Monte Carlo",
                           title: str | None = None, path=None) -> Figure:
    """One panel per quantity: sample band, median, nominal, closed form, measured.

    Parameters
    ----------
    level : (n,) level numbers.
    panels : list of dict
        Each with ``ylabel`` and (n,) arrays ``lo``, ``median``, ``hi`` (the sample
        band), ``nominal`` (deterministic FE prediction), ``closed_form``,
        ``closed_form_lo``, ``closed_form_hi`` (estimator and its interval),
        ``measured``; optional ``samples`` (n_samples, n) drawn as thin lines,
        ``inner_lo``, ``inner_hi`` (n,) an inner band (the quartiles), and ``scale``
        (multiplies every array, e.g. 100 for %).
    held_out : (n,) bool, optional
        Levels not used in the fit: shaded, measured points drawn open.
    band_label : str
        Legend text of the band (e.g. "Monte Carlo 5-95 %").
    title : str, optional
    path : str or path-like, optional
        Write a PNG there (150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    lv = np.asarray(level, dtype=float)
    held = np.zeros(lv.size, bool) if held_out is None else np.asarray(held_out, bool)
    fig = Figure(figsize=(6.0 * len(panels), 4.8), constrained_layout=True)
    axs = np.atleast_1d(fig.subplots(1, len(panels)))
    for ax, p in zip(axs, panels):
        k = float(p.get("scale", 1.0))

        def a(name):
            return k * np.asarray(p[name], dtype=float)

        if held.any():
            ax.axvspan(lv[held].min() - 0.5, lv[held].max() + 0.5, color="0.93", zorder=0,
                       label="held out of the fit")
        if p.get("samples") is not None:
            s = k * np.asarray(p["samples"], dtype=float)
            ax.plot(lv, s.T, color="C0", lw=0.4, alpha=0.15, zorder=1)
        ax.fill_between(lv, a("lo"), a("hi"), color="C0", alpha=0.3, lw=0, zorder=2,
                        label=band_label)
        if p.get("inner_lo") is not None:
            ax.fill_between(lv, a("inner_lo"), a("inner_hi"), color="C0", alpha=0.45, lw=0,
                            zorder=2, label="Monte Carlo 25-75 %")
        ax.plot(lv, a("median"), color="C0", lw=1.6, zorder=3, label="Monte Carlo median")
        ax.plot(lv, a("nominal"), color="C3", ls="--", lw=1.4, zorder=4,
                label="nominal FE prediction")
        cf, lo, hi = a("closed_form"), a("closed_form_lo"), a("closed_form_hi")
        ax.errorbar(lv + 0.12, cf, yerr=[cf - lo, hi - cf], fmt="d", color="C2", ms=4,
                    capsize=3, lw=1.0, zorder=5, label="closed form, delta-method interval")
        m = a("measured")
        ax.plot(lv[~held], m[~held], "o", color="k", ms=6, zorder=6, label="measured (fit)")
        ax.plot(lv[held], m[held], "o", mfc="white", mec="k", ms=6, zorder=6,
                label="measured (held out)")
        ax.set_xlabel("level")
        ax.set_ylabel(p["ylabel"])
        ax.set_xticks(lv)
        ax.grid(True, alpha=0.3)
        ax.ticklabel_format(axis="y", style="plain", useOffset=False)
    axs[0].legend(fontsize=7, loc="lower left")
    if title:
        fig.suptitle(title, fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
