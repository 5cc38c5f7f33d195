"""How large an effect the judge can name: power bounds for an effect of known size.

An effect's size is ``lam``, the chi2 by which the nearest series the base model can
produce misses the series with the effect, in true noise units (the noncentrality of
the drop; ``benchmarks/oracle.py`` computes it from a generator's truth).
"""
from __future__ import annotations

import math

from scipy import stats

from inverse.judge.selection import T_CAUSE, drop_for_known_noise

__all__ = ["detection_bound", "naming_power"]


def detection_bound(lam: float, alpha: float = 0.1) -> float:
    """Neyman-Pearson power ``Phi(sqrt(lam) - z_{1-alpha})`` of a known signal of
    squared size ``lam`` (noise units) in known Gaussian noise at false-alarm rate
    ``alpha``: no test that keeps ``alpha`` on the nearest base-model series does
    better (the simple-vs-simple test, Neyman and Pearson 1933)."""
    return float(stats.norm.cdf(math.sqrt(max(lam, 0.0)) - stats.norm.ppf(1 - alpha)))


def naming_power(lam: float, nu: float = math.inf, q: int = 2,
                 t_cause: float = T_CAUSE) -> float:
    """Probability that the selection rule names a cause of ``q`` parameters whose form
    is right: its drop passes ``2 q + t_cause`` at its known-noise equivalent (module
    doc of :mod:`inverse.judge`, "Selection"). Noise known (``nu`` inf): the drop is
    noncentral chi-square(q, lam); estimated on ``nu`` dof: ``q`` times a noncentral
    F(q, nu, lam)."""
    need = drop_for_known_noise(2 * q + t_cause, q, nu)
    lam = max(lam, 1e-12)
    if math.isinf(nu):
        return float(stats.ncx2.sf(need, q, lam))
    return float(stats.ncf.sf(need / q, q, nu, lam))
