"""Effects a simulated mode can carry besides its Iwan joint, as first-harmonic
(describing-function) stiffnesses.

Each effect adds ``(dk_in, dk_q)`` to the in-phase and quadrature stiffness of a unit-
mass mode at modal amplitude ``X`` (m), line ``W`` (rad/s) and run order ``run``
(1-based), so the steady first-harmonic balance is
``(omega2_lin + k_in_joint + dk_in - W^2 + i (c0 W + k_q_joint + dk_q)) X = F``.

Families (drawn by :mod:`cases.synthetic_series.draw`; deliberately wider than the
diagnosis's own extensions):

* :class:`PowerSpring` ``f = k |x|^a sgn x``: ``dk_in = k g_a X^(a-1)`` with
  ``g_a = (2/sqrt(pi)) Gamma(a/2 + 1) / Gamma(a/2 + 3/2)`` (3/4 for the cubic
  spring); ``k < 0`` is a softening spring.
* :class:`GapSpring` contact stiffening past a gap ``g``: ``f = k (|x| - g)_+ sgn x``,
  ``dk_in = k [1 - (2/pi)(asin(g/X) + (g/X) sqrt(1 - (g/X)^2))]`` for ``X > g``.
* :class:`PowerDamper` ``f = c |v|^a sgn v``: equivalent viscous ``c g_a (W X)^(a-1)``,
  ``dk_q = W`` times that (8/(3 pi) for the quadratic damper).
* :class:`ShapedDamper` an amplitude-dependent viscous coefficient ``c(X)``: rising
  with an onset and saturation ``c (X/Xs)^m / (1 + (X/Xs)^m)``, or falling
  ``c / (1 + (X/Xs)^m)`` (a damping treatment whose loss falls with strain).
* :class:`Drift` ``dk_in = d f(run)``: linear in the run order or an exponential
  warm-up ``(1 - exp(-(run-1)/tau)) / (1 - exp(-(n-1)/tau))``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import gammaln

__all__ = ["power_coefficient", "PowerSpring", "GapSpring", "PowerDamper", "ShapedDamper",
           "Drift", "run_shape"]


def power_coefficient(a: float) -> float:
    """First-harmonic coefficient of ``|x|^a sgn x`` for ``x = X sin t``:
    ``(1/(pi X^a)) int |sin t|^a sgn(sin t) sin t dt = (2/sqrt(pi)) G(a/2+1)/G(a/2+3/2)``."""
    return 2.0 / math.sqrt(math.pi) * math.exp(gammaln(a / 2 + 1) - gammaln(a / 2 + 1.5))


def run_shape(run, n_runs: int, tau: float | None):
    """Run-order shape in [0, 1]: linear (``tau`` None) or exponential warm-up."""
    t = (np.asarray(run, float) - 1.0) / max(n_runs - 1, 1)
    if tau is None:
        return t
    return -np.expm1(-t / tau) / -math.expm1(-1.0 / tau)


@dataclass
class PowerSpring:
    k: float
    a: float

    def __call__(self, X, W, run):
        return self.k * power_coefficient(self.a) * X ** (self.a - 1.0), 0.0 * X


@dataclass
class GapSpring:
    k: float
    gap: float

    def __call__(self, X, W, run):
        r = np.clip(self.gap / X, 0.0, 1.0)
        dk = self.k * (1.0 - 2.0 / np.pi * (np.arcsin(r) + r * np.sqrt(1.0 - r**2)))
        return dk, 0.0 * X


@dataclass
class PowerDamper:
    c: float
    a: float

    def __call__(self, X, W, run):
        return 0.0 * X, W * self.c * power_coefficient(self.a) * (W * X) ** (self.a - 1.0)


@dataclass
class ShapedDamper:
    c: float
    x_s: float
    m: float
    falling: bool = False

    def __call__(self, X, W, run):
        u = (X / self.x_s) ** self.m
        shape = 1.0 / (1.0 + u) if self.falling else u / (1.0 + u)
        return 0.0 * X, W * self.c * shape


@dataclass
class Drift:
    d: float
    n_runs: int
    tau: float | None = None

    def __call__(self, X, W, run):
        return self.d * run_shape(run, self.n_runs, self.tau) + 0.0 * X, 0.0 * X
