"""Forced-response curves through folds, with stability: the way the field computes them.

:func:`forced_response` follows the multi-harmonic balance of
:class:`fe.hb_forced.ForcedBalance` (any joint law by AFT) over a frequency range by
pseudo-arclength continuation (:func:`fe.continuation.continue_branch`; folds located),
and judges every point by Hill's method (:func:`fe.hill.hill_stability`): the curve of
Krack & Gross 2019 (NLvib), Detroux et al. 2015. Amplitudes are those of one observed
coordinate ``y = c . q`` (``c``: ``observe``): the first-harmonic amplitude ``|c . Q_1|``
and the half peak-to-peak of ``y(t)``. SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fe.continuation import ContinuationSettings, continue_branch
from fe.floquet import floquet_multipliers, period_map_monodromy, tangent_monodromy
from fe.hb_forced import ForcedBalance
from fe.hill import hill_stability
from fe.reduction import ReducedModel

__all__ = ["FRCSettings", "ForcedResponse", "forced_response"]


@dataclass(frozen=True)
class FRCSettings:
    """Harmonics, AFT samples per period, joint Jacobian (:class:`fe.law_aft.LawHarmonics`),
    continuation settings, whether to judge stability (Hill), and the Floquet multipliers
    of the Newmark period map as well (``floquet``: None, ``"period_map"`` or
    ``"tangent"``, :mod:`fe.floquet`, ``floquet_steps`` per period; the tangent route
    omits a hysteretic law's memory)."""

    harmonics: tuple = (1, 3, 5)
    n_time: int = 128
    jacobian: str = "auto"
    continuation: ContinuationSettings = field(default_factory=ContinuationSettings)
    stability: bool = True
    floquet: str | None = None
    floquet_steps: int = 1024

    def __post_init__(self):
        if self.floquet not in (None, "period_map", "tangent"):
            raise ValueError(f"floquet must be None, 'period_map' or 'tangent', got "
                             f"{self.floquet!r}")


@dataclass
class ForcedResponse:
    """A forced-response curve in order of arclength.

    Attributes
    ----------
    omega : (n,) drive frequency (rad/s).
    x : (n, n_c r) real harmonic coefficients (:mod:`fe.hb_forced`).
    amplitude : (n,) first-harmonic amplitude of the observed coordinate (m).
    peak : (n,) its half peak-to-peak over the period (m).
    max_multiplier : (n,) largest Floquet multiplier modulus (Hill; NaN without stability).
    stable : (n,) bool (Hill).
    floquet_multiplier : (n,) the same from the Newmark period map (NaN unless asked).
    folds : list of dict (``omega``, ``amplitude``, ``peak``, ``after``, and ``fold``:
        the :class:`fe.continuation.Fold` itself).
    harmonics : harmonics kept.
    """

    omega: np.ndarray
    x: np.ndarray
    amplitude: np.ndarray
    peak: np.ndarray
    max_multiplier: np.ndarray
    stable: np.ndarray
    folds: list
    harmonics: np.ndarray
    floquet_multiplier: np.ndarray = None

    @property
    def frequency_hz(self) -> np.ndarray:
        return self.omega / (2.0 * np.pi)

    def to_points(self) -> list[dict]:
        """One dict per point: ``frequency_hz``, ``amplitude``, ``peak``,
        ``max_multiplier``, ``stable`` (JSON-ready)."""
        fl = (np.full(self.omega.size, np.nan) if self.floquet_multiplier is None
              else self.floquet_multiplier)
        out = []
        for f, a, p, m, s, q in zip(self.frequency_hz, self.amplitude, self.peak,
                                    self.max_multiplier, self.stable, fl):
            d = {"frequency_hz": float(f), "amplitude": float(a), "peak": float(p),
                 "max_multiplier": float(m), "stable": bool(s)}
            if np.isfinite(q):
                d["floquet_multiplier"] = float(q)
            out.append(d)
        return out


def _observed(balance: ForcedBalance, X: np.ndarray, c: np.ndarray):
    """First-harmonic amplitude and half peak-to-peak of ``c . q`` per point."""
    k1 = int(np.flatnonzero(balance.harmonics == 1)[0])
    re, im = balance.re[k1], balance.im[k1]
    Xr = X.reshape(X.shape[0], balance.nc, balance.r)
    amp = np.hypot(Xr[:, re] @ c, Xr[:, im] @ c)
    from fe.harmonic_balance import harmonic_synthesis

    E, _ = harmonic_synthesis(balance.harmonics, max(balance.n_time, 64))
    y = np.einsum("nc,pcr,r->pn", E, Xr, c)
    return amp, 0.5 * (y.max(axis=1) - y.min(axis=1))


def forced_response(model: ReducedModel, law, load, omega_range, observe=None,
                    settings: FRCSettings = FRCSettings(), x_scale=None,
                    p_scale: float | None = None) -> ForcedResponse:
    """Forced-response curve from ``omega_range[0]`` to ``omega_range[1]`` (module
    docstring).

    Parameters
    ----------
    model : ReducedModel
    law : joints.law.JointLaw
    load : ndarray, shape (r,)
        Reduced complex load amplitude (N) of ``Re(p e^{i w t})``.
    omega_range : (w_start, w_end)
        Rad/s; the continuation starts at the stuck-joint solution at ``w_start``.
    observe : ndarray, shape (r,), optional
        Observed coordinate ``y = observe . q`` (default: the only one of a one-DOF model).
    settings : FRCSettings
    x_scale, p_scale : optional
        Arclength scales (default: the largest stuck-joint coefficient over the range;
        a tenth of the range).

    Returns
    -------
    ForcedResponse

    Raises
    ------
    fe.newton_path.SteadyStateError
        When the continuation cannot proceed (one line).
    """
    w0, w1 = (float(w) for w in omega_range)
    if not (np.isfinite(w0) and np.isfinite(w1) and w0 > 0 and w1 > 0 and w0 != w1):
        raise ValueError(f"the frequency range must be two distinct positive numbers, got "
                         f"{w0:g}, {w1:g}")
    if observe is None:
        if model.n_reduced != 1:
            raise ValueError("observe (the observed coordinate) is needed for a model "
                             "with more than one coordinate")
        observe = np.ones(1)
    c = np.asarray(observe, dtype=float).reshape(model.n_reduced)
    bal = ForcedBalance(model, law, load, settings.harmonics, settings.n_time,
                        settings.jacobian)
    if x_scale is None:
        x_scale = max(float(np.abs(np.array([bal.stuck(w) for w in np.linspace(
            w0, w1, 41)])).max()), 1e-300)
    if p_scale is None:
        p_scale = 0.1 * abs(w1 - w0)
    b = continue_branch(bal, bal.stuck(w0), w0, (w0, w1), settings.continuation,
                        x_scale=x_scale, p_scale=p_scale, direction=1 if w1 > w0 else -1)
    amp, peak = _observed(bal, b.x, c)
    mods = np.full(b.p.size, np.nan)
    if settings.stability:
        mods = np.array([hill_stability(bal, x, w).max_modulus for x, w in zip(b.x, b.p)])
    floq = np.full(b.p.size, np.nan)
    if settings.floquet is not None:
        route = period_map_monodromy if settings.floquet == "period_map" else tangent_monodromy
        floq = np.array([np.abs(floquet_multipliers(route(bal, x, w, settings.floquet_steps))
                                ).max() for x, w in zip(b.x, b.p)])
    folds = []
    for f in b.folds:
        fa, fp = _observed(bal, f.x[None, :], c)
        folds.append({"omega": f.p, "frequency_hz": f.p / (2 * np.pi),
                      "amplitude": float(fa[0]), "peak": float(fp[0]), "after": f.after,
                      "fold": f})
    return ForcedResponse(omega=b.p, x=b.x, amplitude=amp, peak=peak, max_multiplier=mods,
                          stable=mods < 1.0, folds=folds, harmonics=bal.harmonics,
                          floquet_multiplier=floq)
