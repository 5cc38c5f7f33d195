"""Model families of the diagnosis: the base Iwan modal model, one extension per cause,
and every combination of two.

Abscissa (the joint amplitude, relative). Under response control the held response
amplitude ``R_v`` is the measure of the joint amplitude (linear mode shape), so
``s_v = R_v / max R``. Under force control the paper takes ``s_v`` proportional to the
excitation, which holds only while the damping ratio stays put: at resonance a mode
of damping ratio ``zeta`` under force ``E`` reaches ``X = E / (2 zeta omega^2)`` (unit
modal mass), so the base model takes

    s_v = (E_v / (zeta_v omega2_v)) / max(...)                                    (1)

from the identified ``zeta_v`` and ``omega2_v``: proportional to the excitation at fixed
damping (the paper's assumption), and the resonant amplitude of a mode whose damping
grows. A shortfall beyond (1) (exciter force drop-out, a held level that is not the
force reaching the structure) is the ``nonproportional-amplitude`` cause. With the
``response_amplitude`` column the response channel ``y_v = log R_v - log s_v`` is fitted
too: a constant (the offset ``alpha``) in every model but that cause, plus the
identification's distortion of a force-controlled level, ``kappa_id d ln zeta / d ln s``
(slopes over the measured level means; ``kappa_id`` fitted, about 0.17 in size,
:mod:`inverse.diagnosis.noise`): the equivalent linear fit of a stepped sine at
constant force averages the damping over the half-power band, so the resonant amplitude
read from it departs from (1) in proportion to the damping's log-slope. Without it that
departure, a property of identification, would be read as a force shortfall.

Base model (paper Sec. 2.2 and 4, eq. 43 and 45 with its factor 2), micro-slip, one
equivalent joint, ``p = chi + 1``:

    omega2_v = W - K2 s_v**p,                  K2 = kappa_ratio(chi) K1           (2)
    zeta_v   = c / (2 sqrt(omega2_v)) + K1 s_v**p / (2 omega2_v)                  (3)

with ``kappa_ratio = kappa2_exact / |kappa1| = B(chi+5/2, 1/2) (chi+2)/(chi+1)``
(:func:`inverse.iwan_modal.kappa_ratio`), a function of chi alone: the tie between the
frequency drop and the damping growth. ``K1 >= 0`` is the hysteretic modal stiffness at
the top level (rad^2/s^2), ``c`` the viscous modal damping (rad/s); the measured
``omega2_v`` stands in the factors of (3), as in the paper.

What identification returns is not the backbone's ``W - K2 s**p`` but the squared
modulus of the pole of the equivalent linear mode ``lambda^2 + c lambda + W_v + i k_q
= 0`` (``W_v`` the in-phase and ``k_q`` the quadrature stiffness of the level, here
``K1 s_v**p``): to second order in the damping

    |lambda|^2 = W_v + k_q zeta_v                                                  (4)

(zeta_v the level's whole damping ratio; exact for a viscous mode, ``k_q = 0``). So a
joint's hysteretic damping *raises* the identified omega2 by ``k_q zeta_v`` (1e-3 of
omega2 at 2 % damping), which a model of ``W_v`` alone would read as hardening. The
models apply (4) to the joint's quadrature columns with the measured ``zeta_v``
(checked against the LSCF of :func:`ident.identify.identify` on the FRF of a known
hysteretic SDOF, ``tests/test_diagnosis_identified_omega2.py``).

Extensions: one per cause of the catalogue, each defined in its own file of
:mod:`inverse.diagnosis.causes` (its nonlinear parameters with bounds and grid, its
linear columns, its amplitude transform). ``s`` is the effective amplitude: ``s_v`` of
(1), transformed by a cause that changes it (a force shortfall).

A pair of causes applies both extensions. :func:`design` builds the weighted linear
columns of a model for a batch of nonlinear parameter points.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from inverse.diagnosis.causes import CATALOGUE, CAUSES
from inverse.diagnosis.noise import log_slope
from inverse.iwan_modal import kappa_ratio

__all__ = ["CAUSES", "Model", "Observations", "MODELS", "design"]

# the base model's nonlinear parameter: p = chi + 1, bounds and grid of the global search
_BASE = ("p", 0.01, 0.99, np.linspace(0.04, 0.96, 13))
_BASE_P_FINE = np.linspace(0.02, 0.98, 33)   # the base model alone: a finer chi grid


@dataclass(frozen=True)
class Model:
    """The base model with a set of causes (empty: the base model, cause ``none``)."""

    causes: tuple = ()

    @property
    def name(self) -> str:
        return "+".join(self.causes) if self.causes else "none"

    def has(self, cause: str) -> bool:
        return cause in self.causes

    @property
    def nonlinear(self) -> list:
        """``[(name, lower, upper, grid)]``: chi's ``p`` first, then each cause's."""
        out = [_BASE if self.causes else ("p", 0.01, 0.99, _BASE_P_FINE)]
        for c in self.causes:
            out += CATALOGUE[c].NONLINEAR
        return out

    def _joint(self):
        return next((c for c in self.causes
                     if getattr(CATALOGUE[c], "REPLACES_JOINT", False)), None)

    def linear_names(self, response: bool) -> list:
        joint = self._joint()
        names = ["W", "c"] + (list(CATALOGUE[joint].LINEAR) if joint else ["K1"])
        names += [n for c in self.causes if c != joint for n in CATALOGUE[c].LINEAR]
        return names + (["alpha", "kappa_id"] if response else [])

    def nonneg(self, response: bool) -> list:
        keep = {"K1"}.union(*(CATALOGUE[c].NONNEG for c in self.causes))
        return [i for i, n in enumerate(self.linear_names(response)) if n in keep]

    def n_params(self, response: bool) -> int:
        return len(self.linear_names(response)) + len(self.nonlinear)


#: Every candidate: the base, each cause alone, every pair (catalogue order).
MODELS = [Model()] + [Model((c,)) for c in CAUSES] + [Model(p) for p in combinations(CAUSES, 2)]


@dataclass
class Observations:
    """One mode's data as the fits use them, sorted by level.

    ``s`` is the base abscissa of eq. (1), ``log_r`` the response channel
    ``log R_v - log s_v`` (None without one), ``t_run`` the run order scaled to [0, 1]
    (``run_monotone``: the levels were run in order of amplitude; ``run_span`` max - min
    run order), ``sigma`` the noise level per channel and row (set by the diagnosis),
    ``level_ids`` the level of each row (repeats share one; default ``level``)."""

    level: np.ndarray
    s: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    t_run: np.ndarray
    log_r: np.ndarray | None
    response_controlled: bool
    sigma: dict
    run_monotone: bool = False
    run_span: float = 0.0
    level_ids: np.ndarray | None = None

    @property
    def n(self) -> int:
        return int(self.level.size)

    @property
    def levels(self) -> np.ndarray:
        """Level of each row (rows of one level are repeats)."""
        return self.level if self.level_ids is None else self.level_ids

    @property
    def channels(self) -> list:
        return ["omega2", "zeta"] + (["response"] if self.log_r is not None else [])

    def channel_rows(self, mask) -> np.ndarray:
        """The rows of a level mask ``(n,)`` in the channel-stacked residual
        ``(channels * n,)``."""
        return np.tile(mask, len(self.channels))


# --------------------------------------------------------------------------- design


def design(model: Model, obs: Observations, theta):
    """Weighted design of ``model`` for every parameter point of ``theta`` (G, d).

    Rows: the omega2 channel (target ``omega2 - omega2[0]``), the zeta channel, the
    response channel (when present), each divided by its noise level. Returns
    ``(A (G, N, k), b (G, N), log_s_eff (G, n))``; columns in the order of
    :meth:`Model.linear_names`.
    """
    theta = np.atleast_2d(theta)
    G, n = theta.shape[0], obs.n
    names = [a[0] for a in model.nonlinear]
    col = {name: theta[:, i:i + 1] for i, name in enumerate(names)}
    p = col["p"]
    log_s = np.broadcast_to(np.log(obs.s)[None, :], (G, n))
    for c in model.causes:
        if hasattr(CATALOGUE[c], "transform_log_s"):
            log_s = CATALOGUE[c].transform_log_s(log_s, col)
    w2 = obs.omega2[None, :]
    one, zero = np.ones((G, n)), np.zeros((G, n))
    inv_w = np.broadcast_to(0.5 / np.sqrt(w2), (G, n))
    om, ze = [one, zero], [zero, inv_w]
    joint = model._joint()
    if joint:
        o, z = CATALOGUE[joint].columns(obs, col, log_s, p, w2)
    else:
        sp = np.exp(p * log_s)
        o, z = [-kappa_ratio(p - 1.0, "exact") * sp], [0.5 * sp / w2]
    # the identified omega2 is |pole|^2: the joint's quadrature stiffness k_q = 2 w2 z
    # adds k_q zeta to it (eq. 4)
    o = [oi + 2.0 * w2 * zi * obs.zeta[None, :] for oi, zi in zip(o, z)]
    om, ze = om + o, ze + z
    for c in model.causes:
        if c != joint:
            o, z = CATALOGUE[c].columns(obs, col, log_s, p, w2)
            om, ze = om + list(o), ze + list(z)
    sw, sz = obs.sigma["omega2"][None, :, None], obs.sigma["zeta"][None, :, None]
    blocks = [np.stack(om, -1) / sw, np.stack(ze, -1) / sz]
    targets = [np.broadcast_to((obs.omega2 - obs.omega2[0]) / obs.sigma["omega2"], (G, n)),
               np.broadcast_to(obs.zeta / obs.sigma["zeta"], (G, n))]
    if obs.log_r is not None:
        k = blocks[0].shape[-1]
        blocks = [np.concatenate([b, np.zeros((G, n, 2))], -1) for b in blocks]
        sr = obs.sigma["response"][None, :]
        resp = np.zeros((G, n, k + 2))
        resp[..., k] = 1.0 / sr
        resp[..., k + 1] = log_slope(obs.levels, np.log(obs.s), np.log(obs.zeta))[None] / sr
        blocks.append(resp)
        shift = log_s - np.log(obs.s)[None, :]
        targets.append((obs.log_r[None, :] - shift) / sr)
    return np.concatenate(blocks, axis=1), np.concatenate(targets, axis=1), log_s
