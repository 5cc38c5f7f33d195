"""Fig. 8-style picture: log of successive damping differences against level.

Draws the arrays it is given (matplotlib, Agg backend); computes no physics. The
estimator (:mod:`inverse.estimate`) supplies ``y = log_z Delta d`` of the differences it
used, those it did not (outside the fit levels), those it could not log (<= 0, drawn
as markers on the lower axis edge) and the fitted curve (paper eq. 35: a straight
line of slope ``chi + 1`` when the excitation ratio is constant).
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

__all__ = ["plot_logslope", "plot_estimate"]


def plot_logslope(x_used, y_used, x_fit, y_fit, *, x_held=(), y_held=(), x_nonpositive=(),
                  x_pred=(), y_pred=(), labels_used=(), base: float = 2.0,
                  title: str | None = None, annotation: str | None = None,
                  path=None) -> Figure:
    """Log-slope plot of damping growth (paper Fig. 8).

    Parameters
    ----------
    x_used, y_used : array_like
        Abscissa ``log_z(e_from / e_ref)`` (``v - 1`` for a constant ratio) and
        ``log_z Delta d`` of the differences used in the fit.
    x_fit, y_fit : array_like
        The fitted curve.
    x_held, y_held : array_like, optional
        Positive differences outside the fit levels (hollow markers).
    x_nonpositive : array_like, optional
        Abscissae of differences <= 0 (cannot be logged): drawn as "x" on the lower edge.
    x_pred, y_pred : array_like, optional
        Model values at the held-out differences (dashed extension).
    labels_used : sequence of str, optional
        Annotation of each used point (e.g. "1->2").
    base : float
        The log base z, for the axis label.
    title, annotation : str, optional
        Figure title; text box (e.g. "chi = -0.377, |kappa1|B = 29.65").
    path : str or path-like, optional
        If given, the figure is written there (PNG, 150 dpi).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(6.4, 4.6), constrained_layout=True)
    ax = fig.add_subplot()
    xu, yu = np.asarray(x_used, float), np.asarray(y_used, float)
    ax.plot(np.asarray(x_fit, float), np.asarray(y_fit, float), "-", color="k", lw=1.2,
            label="fit (eq. 35)")
    if len(x_pred):
        ax.plot(np.asarray(x_pred, float), np.asarray(y_pred, float), "--", color="k", lw=1.0,
                label="prediction")
    ax.plot(xu, yu, "o", color="C0", ms=7, label="used in fit")
    for x, y, lab in zip(xu, yu, labels_used):
        ax.annotate(lab, (x, y), textcoords="offset points", xytext=(5, -11), fontsize=8,
                    color="C0")
    if len(x_held):
        ax.plot(np.asarray(x_held, float), np.asarray(y_held, float), "o", mfc="none",
                color="C1", ms=7, label="not in fit")
    ys = np.concatenate([yu, np.asarray(y_held, float), np.asarray(y_fit, float)])
    ys = ys[np.isfinite(ys)]
    if len(x_nonpositive):
        lo = ys.min() - 0.08 * max(np.ptp(ys), 1.0) if ys.size else 0.0
        ax.plot(np.asarray(x_nonpositive, float), np.full(len(x_nonpositive), lo), "x",
                color="C3", ms=8, mew=2, label="difference <= 0 (excluded)")
    ax.set_xlabel(f"log_{base:g}(excitation / reference)   (= v - 1 for ratio {base:g})")
    ax.set_ylabel(f"y = log_{base:g} Delta d   (Delta d in rad^2/s^2)")
    if title:
        ax.set_title(title)
    if annotation:
        ax.text(0.03, 0.97, annotation, transform=ax.transAxes, va="top", ha="left",
                fontsize=9, bbox={"boxstyle": "round", "fc": "white", "ec": "0.7"})
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


def plot_estimate(est, path: str, title: str | None = None) -> None:
    """Draw the Fig. 8-style log-slope plot of an :class:`~inverse.estimate.Estimate`
    (:func:`plot_logslope` of its used, held-out and excluded differences, the fitted
    curve and its prediction) to ``path``."""
    used = sorted(est.points_used, key=lambda p: p["x"])
    held = [d for d in est.differences if not d["in_fit"]]
    nonpos = [p["x"] for p in est.points_excluded]
    nonpos += [d["x"] for d in held if d["y"] is None]
    held_pos = [d for d in held if d["y"] is not None]
    fit_curve = sorted(est.points_used + est.points_excluded, key=lambda p: p["x"])
    pred = sorted([d for d in held if d["x"] > fit_curve[-1]["x"]], key=lambda p: p["x"])
    if pred:
        pred = [fit_curve[-1]] + pred
    ci = est.chi_interval
    note = (f"chi = {est.chi:.4f}  [{ci[0]:.2f}, {ci[1]:.2f}]\n"
            f"|kappa1|B = {est.kappa1_B:.4g} 1/s^2\nmethod {est.method}")
    if est.R is not None:
        note += f"\nR~ = {est.R:.4g} N/m^(chi+2)"
    plot_logslope(
        [p["x"] for p in used], [p["y"] for p in used],
        [p["x"] for p in fit_curve], [p["model_y"] for p in fit_curve],
        x_held=[d["x"] for d in held_pos], y_held=[d["y"] for d in held_pos],
        x_nonpositive=nonpos,
        x_pred=[p["x"] for p in pred], y_pred=[p["model_y"] for p in pred],
        labels_used=[f"{p['from_level']}->{p['to_level']}" for p in used],
        base=est.log_base, title=title, annotation=note, path=path)
