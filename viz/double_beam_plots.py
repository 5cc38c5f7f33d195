"""Double-beam reproduction pictures: measured vs simulated per level, joint amplitudes.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics. The study
(:mod:`cases.double_beam.study`) supplies the identified frequencies and damping
ratios, the estimator's predictions, the simulated joint slips and the modal-filter
joint damping.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_level_comparison", "plot_joint_levels"]


def _held_span(ax, level, fit_levels):
    level = np.asarray(level)
    held = level[~np.isin(level, list(fit_levels))] if len(fit_levels) else level[:0]
    if held.size:
        ax.axvspan(held.min() - 0.5, held.max() + 0.5, color="0.92", zorder=0,
                   label="held out")


def _positive(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(y) & (y > 0)
    return x[ok], y[ok]


def plot_level_comparison(level, measured: dict, simulated: dict, predictions: dict | None = None,
                          fit_levels=(), title: str | None = None, path=None) -> Figure:
    """Natural frequency and damping against level: measured, simulated, predicted.

    Four panels: ``omega2`` (rad^2/s^2), ``zeta`` (%), the loss of ``omega2`` from level
    1 and the growth of ``zeta`` from level 1 (log axes; values <= 0 are not drawn).

    Parameters
    ----------
    level : (n,) level numbers.
    measured, simulated : dict with ``omega2`` (n,) and ``zeta`` (n,) (fraction).
    predictions : dict label -> dict(``omega2``, ``zeta``), optional
        Estimator curves (e.g. one per method).
    fit_levels : levels used in the fit (the others are shaded as held out).
    title : str, optional
    path : str or path-like, optional
        Write a PNG there (150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    lv = np.asarray(level, dtype=float)
    fig = Figure(figsize=(11.0, 7.6), constrained_layout=True)
    axs = fig.subplots(2, 2)
    series = [("measured", measured, dict(marker="o", color="k", ls="-", lw=1.0, ms=6)),
              ("simulated", simulated, dict(marker="s", color="C3", ls="-", lw=1.0, ms=5))]
    for i, (lab, d) in enumerate((predictions or {}).items()):
        series.append((f"{lab}", d, dict(marker=None, color=f"C{i}", ls="--", lw=1.2)))
    for name, d, style in series:
        om2 = np.asarray(d["omega2"], float)
        ze = np.asarray(d["zeta"], float)
        axs[0, 0].plot(lv, om2, label=name, **style)
        axs[0, 1].plot(lv, 100 * ze, label=name, **style)
        axs[1, 0].semilogy(*_positive(lv[1:], om2[0] - om2[1:]), label=name, **style)
        axs[1, 1].semilogy(*_positive(lv[1:], 100 * (ze[1:] - ze[0])), label=name, **style)
    labels = [("omega^2 (rad^2/s^2)", "natural frequency"), ("zeta (%)", "damping ratio"),
              ("omega^2(1) - omega^2 (rad^2/s^2)", "loss of omega^2 from level 1"),
              ("zeta - zeta(1) (%)", "growth of zeta from level 1")]
    for ax, (yl, tl) in zip(axs.ravel(), labels):
        _held_span(ax, lv, fit_levels)
        ax.set_xlabel("level")
        ax.set_ylabel(yl)
        ax.set_title(tl, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xticks(lv)
    axs[0, 0].ticklabel_format(axis="y", style="plain", useOffset=False)
    axs[0, 0].legend(fontsize=8, loc="lower left")
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


def plot_joint_levels(level, slip_over_phi_max, proportional, delta_c, delta_c_decoupled,
                      title: str | None = None, path=None) -> Figure:
    """Joint slips at resonance and the joint's modal damping against level.

    Parameters
    ----------
    level : (n,) level numbers.
    slip_over_phi_max : (n, n_joints) slip amplitude at resonance / phi_max, per joint.
    proportional : (n,) the largest joint's level-1 value scaled with the drive (the
        estimator's assumption, paper eq. 33).
    delta_c, delta_c_decoupled : (n,) joint modal damping (rad^2/s^2) through the modal
        filter and from the decoupled eq. 30-32.
    title : str, optional
    path : str or path-like, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    lv = np.asarray(level, dtype=float)
    a = np.asarray(slip_over_phi_max, dtype=float)
    fig = Figure(figsize=(11.0, 4.4), constrained_layout=True)
    ax1, ax2 = fig.subplots(1, 2)
    for j in range(a.shape[1]):
        ax1.semilogy(lv, a[:, j], "o-", ms=3, lw=0.9, label=f"joint {j + 1}")
    ax1.semilogy(lv, np.asarray(proportional, float), "k--", lw=1.0,
                 label="largest, proportional to drive")
    ax1.axhline(1.0, color="C3", lw=1.0, label="phi_max (macro-slip above)")
    ax1.set_xlabel("level")
    ax1.set_ylabel("slip amplitude at resonance / phi_max")
    ax1.set_title("glue joints", fontsize=10)
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=7, loc="upper left")
    ax1.set_xticks(lv)
    ax2.semilogy(*_positive(lv, delta_c), "o-", color="C3", label="modal filter (simulated)")
    ax2.semilogy(*_positive(lv, delta_c_decoupled), "k--",
                 label="decoupled eq. 30-32, simulated slips")
    ax2.set_xlabel("level")
    ax2.set_ylabel("joint modal damping Delta c (rad^2/s^2)")
    ax2.set_title("joint damping as the mode sees it", fontsize=10)
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8, loc="upper left")
    ax2.set_xticks(lv)
    if title:
        fig.suptitle(title)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
