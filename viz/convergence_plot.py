"""Log-log mesh-convergence plots (matplotlib, Agg). Draws what it is given."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_convergence(path, element_size, relative_error, mode_labels=None, reference_rate=4.0,
                     sweeps=None, title="Mesh convergence"):
    """Write a PNG with the relative frequency error against element size.

    Parameters
    ----------
    path : str or Path
        Output PNG.
    element_size : array_like, shape (n_mesh,)
        Element size h, m.
    relative_error : array_like, shape (n_mesh, n_modes)
        Relative frequency error of each mode (NaN/0 points are skipped).
    mode_labels : list of str, optional
    reference_rate : float or None
        Slope of a dashed ``h^rate`` guide line through the first mode's coarsest point.
    sweeps : list of (label, h (n,), relative_change (n,)), optional
        Extra curves drawn on a second panel (e.g. the double-beam sweeps).
    """
    h = np.asarray(element_size, float)
    err = np.asarray(relative_error, float)
    n_modes = err.shape[1]
    labels = mode_labels or [f"mode {j + 1}" for j in range(n_modes)]
    ncols = 2 if sweeps else 1
    fig, axes = plt.subplots(1, ncols, figsize=(6.0 * ncols, 4.5), squeeze=False)
    ax = axes[0, 0]
    for j in range(n_modes):
        ok = np.isfinite(err[:, j]) & (err[:, j] > 0)
        ax.loglog(h[ok] * 1e3, err[ok, j], "o-", label=labels[j])
    if reference_rate is not None:
        ok = np.isfinite(err[:, 0]) & (err[:, 0] > 0)
        h0, e0 = h[ok][0], err[ok, 0][0]
        ax.loglog(h * 1e3, e0 * (h / h0) ** reference_rate, "k--", lw=1,
                  label=f"h^{reference_rate:g}")
    ax.set_xlabel("element size h (mm)")
    ax.set_ylabel("relative frequency error")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if sweeps:
        ax2 = axes[0, 1]
        for label, hs, change in sweeps:
            hs, change = np.asarray(hs, float), np.abs(np.asarray(change, float))
            ok = change > 0
            ax2.loglog(hs[ok] * 1e3, change[ok], "s-", label=label)
        ax2.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax2.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax2.set_xlabel("element / joint spacing (mm)")
        ax2.set_ylabel("relative change vs finest")
        ax2.set_title("double beam, measured mode")
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
