"""First-harmonic stiffnesses of the generator's elements, by its own quadratures.

Convention: displacement ``x = X cos(tau)``, velocity ``v = -W X sin(tau)``; an element
of force ``f(x, v)`` has the first harmonic ``f1 = X (k_in cos(tau) - k_q sin(tau))``, so
it adds ``k_in + i k_q`` to the complex dynamic stiffness of a unit-mass mode
(rad^2/s^2; ``k_q`` > 0 dissipates ``pi X^2 k_q`` per cycle).

* :func:`first_harmonic`: any memoryless ``f(x, v)`` by the midpoint rule over one
  period (spectrally accurate for smooth forces, second order at kinks);
* :func:`jenkins_loss`: a unit Jenkins element (spring in series with a Coulomb
  slider, slip displacement ``phi``) at ``u = phi / X <= 1``, from its hysteresis
  loop: in-phase loss ``1 - (b - sin(b) cos(b)) / pi`` with ``cos b = 1 - 2u`` and
  quadrature ``(4/pi) u (1 - u)`` (derived in the module of the tests by integrating
  the loop; 0, 0 when stuck, ``u >= 1``);
* :class:`SliderBank`: a continuous bank of Jenkins elements of stiffness density
  ``rho(phi)`` (rad^2/s^2 per m of slip displacement) on ``[lo, hi]``, summed by
  Gauss-Legendre quadrature over the sliders that slip at ``X``; a power-law part
  ``R phi^chi`` near 0 is integrated after ``t = (phi / b)^(chi + 1)`` (no
  singularity). No closed form of the Iwan model is used.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["first_harmonic", "jenkins_loss", "SliderBank"]

_N_TAU = 160
_TAU = (np.arange(_N_TAU) + 0.5) * 2.0 * np.pi / _N_TAU
_GX, _GW = np.polynomial.legendre.leggauss(96)


def first_harmonic(force, X, W):
    """``(k_in, k_q)`` of a memoryless force law ``force(x, v)`` at amplitudes ``X``
    (m) and line ``W`` (rad/s); broadcasts ``X`` against ``W``."""
    X, W = np.broadcast_arrays(np.asarray(X, float), np.asarray(W, float))
    x = X[..., None] * np.cos(_TAU)
    v = -(W * X)[..., None] * np.sin(_TAU)
    f = force(x, v)
    Xs = np.maximum(X, 1e-300)
    k_in = 2.0 * np.mean(f * np.cos(_TAU), axis=-1) / Xs
    k_q = -2.0 * np.mean(f * np.sin(_TAU), axis=-1) / Xs
    return k_in, k_q


def jenkins_loss(u):
    """In-phase stiffness loss and quadrature stiffness of a unit Jenkins element at
    ``u = phi / X`` (module doc); stuck (0, 0) for ``u >= 1``."""
    u = np.clip(np.asarray(u, float), 0.0, 1.0)
    b = np.arccos(1.0 - 2.0 * u)
    return 1.0 - (b - np.sin(b) * np.cos(b)) / np.pi, 4.0 / np.pi * u * (1.0 - u)


@dataclass
class SliderBank:
    """Jenkins sliders of stiffness density ``R phi^chi`` on ``(0, lo]`` (the power-law
    core; ``R = 0``: none) and ``R lo^chi shape((phi - lo)/(hi - lo))`` on ``[lo, hi]``
    (``shape`` from 1 to 0: a tapered edge; None: no sliders there), or, with
    ``uniform`` > 0, a uniform density ``uniform`` on ``[lo, hi]`` (a ring of sliders
    that all release within it). Units: phi in m, densities in rad^2/s^2 per m."""

    R: float = 0.0
    chi: float = -0.5
    lo: float = 1.0
    hi: float = 1.0
    shape: object = None
    uniform: float = 0.0

    def loss(self, X):
        """(in-phase loss, quadrature) stiffness at slip amplitudes ``X`` (m)."""
        X = np.atleast_1d(np.asarray(X, float))
        dk, kq = np.zeros_like(X), np.zeros_like(X)
        if self.R > 0:
            p = self.chi + 1.0
            t = 0.5 * (_GX + 1.0)
            micro = X <= self.lo     # self-similar: the quadrature of one amplitude scales
            l_in, l_q = jenkins_loss(t ** (1.0 / p))
            scale = self.R * X[micro] ** p / p
            dk[micro] = scale * (0.5 * l_in @ _GW)
            kq[micro] = scale * (0.5 * l_q @ _GW)
            if np.any(~micro):      # sliders up to lo, all slipping
                Xm = X[~micro]
                l_in, l_q = jenkins_loss(self.lo * t[None, :] ** (1.0 / p) / Xm[:, None])
                scale = self.R * self.lo**p / p
                dk[~micro] = scale * (0.5 * l_in @ _GW)
                kq[~micro] = scale * (0.5 * l_q @ _GW)
        if self.uniform > 0:
            def dens(phi):
                return self.uniform + 0.0 * phi
        elif self.shape is not None and self.R > 0:
            def dens(phi):
                return self.R * self.lo**self.chi * self.shape(
                    (phi - self.lo) / (self.hi - self.lo))
        else:
            dens = None
        if dens is not None:
            top = np.minimum(X, self.hi)
            on = top > self.lo
            if np.any(on):
                a, c = self.lo, top[on]
                phi = a + (c[:, None] - a) * 0.5 * (_GX + 1.0)[None, :]
                l_in, l_q = jenkins_loss(phi / X[on, None])
                w = 0.5 * (c - a)[:, None] * _GW[None, :] * dens(phi)
                dk[on] += np.sum(w * l_in, axis=1)
                kq[on] += np.sum(w * l_q, axis=1)
        return dk, kq

    @property
    def stuck_stiffness(self) -> float:
        """Sum of the slider stiffnesses (rad^2/s^2): the bank's stiffness when stuck."""
        total = 0.0
        if self.R > 0:
            total += self.R * self.lo ** (self.chi + 1.0) / (self.chi + 1.0)
        if self.uniform > 0:
            total += self.uniform * (self.hi - self.lo)
        elif self.shape is not None and self.R > 0:
            phi = self.lo + (self.hi - self.lo) * 0.5 * (_GX + 1.0)
            total += 0.5 * (self.hi - self.lo) * np.sum(
                _GW * self.R * self.lo**self.chi
                * self.shape((phi - self.lo) / (self.hi - self.lo)))
        return float(total)
