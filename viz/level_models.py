"""Pictures of FE models against measured levels, and of profile likelihoods.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_level_models", "plot_profiles"]

_STYLES = [dict(color="tab:blue", ls="--", marker="s"), dict(color="tab:red", ls="-", marker="^"),
           dict(color="tab:green", ls=":", marker="o"),
           dict(color="tab:purple", ls="-.", marker="v")]


def plot_level_models(level, frequency_hz, zeta, sigma_hz, sigma_zeta, models: dict,
                      held_out, title: str | None = None, path=None) -> Figure:
    """Measured natural frequency (Hz) and damping ratio (%) per level with error bars
    (+/- 1 sigma) and each model's values (``models``: label -> (frequency_hz, zeta));
    held-out levels shaded. Bottom row: model minus measured, in Hz and % of zeta."""
    level = np.asarray(level)
    fig = Figure(figsize=(10, 6.4), constrained_layout=True)
    ax = fig.subplots(2, 2, sharex=True)
    meas = (np.asarray(frequency_hz), 100 * np.asarray(zeta))
    sig = (np.asarray(sigma_hz), 100 * np.asarray(sigma_zeta))
    held = np.asarray(held_out, dtype=bool)
    for col, (ylab, y, s) in enumerate(zip(("natural frequency [Hz]", "damping ratio [%]"),
                                           meas, sig)):
        top, bot = ax[0, col], ax[1, col]
        for a in (top, bot):
            for lv in level[held]:
                a.axvspan(lv - 0.5, lv + 0.5, color="0.9", lw=0)
        top.errorbar(level, y, yerr=s, fmt="ko", ms=4, capsize=2, label="measured", zorder=5)
        bot.axhline(0.0, color="k", lw=0.8)
        bot.fill_between(level, -2 * s, 2 * s, color="0.75", alpha=0.5, lw=0,
                         label="+/- 2 sigma")
        for (label, (f, z)), st in zip(models.items(), _STYLES):
            m = np.asarray(f) if col == 0 else 100 * np.asarray(z)
            top.plot(level, m, lw=1.3, ms=3.5, mfc="none", label=label, **st)
            bot.plot(level, m - y, lw=1.3, ms=3.5, mfc="none", **st)
        top.set_ylabel(ylab)
        bot.set_ylabel("model - measured" + (" [Hz]" if col == 0 else " [% abs.]"))
        bot.set_xlabel("level (grey: held out of the fit)")
        top.grid(alpha=0.3)
        bot.grid(alpha=0.3)
    ax[0, 0].legend(fontsize=8, loc="lower left")
    if title:
        fig.suptitle(title, fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


def plot_profiles(profiles: dict, title: str | None = None, path=None) -> Figure:
    """One panel per parameter: ``profiles`` maps a label to ``(values, delta_chi2,
    threshold, best)``; the threshold as a dashed line, the optimum as a dot."""
    n = max(len(profiles), 1)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig = Figure(figsize=(3.4 * cols, 2.6 * rows), constrained_layout=True)
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    for a, (label, (x, d, thr, best)) in zip(axes, profiles.items()):
        x, d = np.asarray(x, float), np.asarray(d, float)
        o = np.argsort(x)
        a.plot(x[o], np.minimum(d[o], 3 * thr), "o-", ms=3, color="tab:blue")
        a.axhline(thr, color="tab:red", ls="--", lw=1)
        a.plot([best], [0.0], "ko", ms=5)
        a.set_xlabel(label)
        a.set_ylabel("delta chi2 (clipped)")
        a.grid(alpha=0.3)
    for a in axes[len(profiles):]:
        a.set_visible(False)
    if title:
        fig.suptitle(title, fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
