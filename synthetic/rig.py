"""The simulated test rig: one jointed mode, its mechanisms, the exciter, the lines.

Unit-mass modal coordinate ``q`` (the joint slip and the drive-point response, m). At a
line ``W`` (rad/s) of run ``run`` the first-harmonic balance is ``D(X, W) q = F`` with

    D = omega0^2 a_w (1 + eps_f)^2 - W^2 - dK_joint(X) + sum dRe
        + i (1 + eps_z) [2 zeta0 omega0 W a_z + kq_joint(X) + sum dIm]          (1)

``X = |q|``; ``omega0`` the stuck (small-amplitude) natural frequency; the joint a bank
of Jenkins sliders (:class:`.first_harmonic.SliderBank`); ``a_w``, ``a_z`` and the
joint's slip-limit scale from the time mechanisms; ``eps_f``, ``eps_z`` the run's
repeatability offsets (:class:`.mechanisms.Run`). The exciter delivers
``F = G(W, V) - L(W) q`` (``L`` its load on the mode), so the amplitude solves
``X |D + L| = |G|`` (bisection in log X); under response control ``X`` is held and
``F = D X``. The transducer reads ``F``; the measured FRF is ``q / F = 1 / D`` plus a
linear neighbour mode's residual ``r_n / (omega_n^2 - W^2)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from synthetic.first_harmonic import SliderBank
from synthetic.mechanisms import Ideal, Run

__all__ = ["Structure", "solve_level", "resonance", "noisy"]


@dataclass
class Structure:
    """The mode (module doc): ``omega0`` rad/s, ``zeta0``, the main ``joint``, the
    amplitude and time ``mechanisms``, the ``exciter`` and an optional neighbour mode
    ``(omega_n rad/s, r_n)``."""

    omega0: float
    zeta0: float
    joint: SliderBank
    mechanisms: list = field(default_factory=list)
    exciter: object = field(default_factory=Ideal)
    neighbour: tuple | None = None

    def without(self, mechanism) -> "Structure":
        """The same structure with one mechanism (or the exciter) taken out."""
        if mechanism is self.exciter:
            return replace(self, exciter=Ideal(mechanism.nominal_gain(self.omega0)))
        return replace(self, mechanisms=[m for m in self.mechanisms if m is not mechanism])

    def _factors(self, run):
        f = {"omega2": 1.0, "damping": 1.0, "slip": 1.0}
        for m in self.mechanisms:
            for k, v in m.run_factors(run).items():
                f[k] *= v
        return f

    def _joint(self, slip):
        bank = self.joint
        for m in self.mechanisms:
            if hasattr(m, "joint"):
                bank = m.joint(bank)
        if slip == 1.0:
            return bank
        p = bank.chi + 1.0        # slip limits x lam, slider stiffnesses unchanged
        return SliderBank(bank.R * slip**-p, bank.chi, bank.lo * slip, bank.hi * slip,
                          bank.shape, bank.uniform / slip)

    def stiffness(self, X, W, run: Run):
        """Complex dynamic stiffness ``D(X, W)`` of eq. (1), rad^2/s^2."""
        X, W = np.broadcast_arrays(np.maximum(np.asarray(X, float), 1e-300),
                                   np.asarray(W, float))
        f = self._factors(run)
        dk, kq = self._joint(f["slip"]).loss(X.ravel())
        re = self.omega0**2 * f["omega2"] * (1 + run.eps_f) ** 2 - W**2 - dk.reshape(X.shape)
        im = 2 * self.zeta0 * self.omega0 * W * f["damping"] + kq.reshape(X.shape)
        for m in self.mechanisms:
            a, b = m.stiffness(X, W, run)
            re, im = re + a, im + b
        return re + 1j * (1 + run.eps_z) * im

    def frf(self, D, W):
        """Measured receptance ``q / F`` at the lines (module doc)."""
        H = 1.0 / D
        if self.neighbour is not None:
            wn, rn = self.neighbour
            H = H + rn / (wn**2 - np.asarray(W, float) ** 2)
        return H

    def x_upper(self, target, W, run):
        """An amplitude above every solution of ``X |D + L| = target``: the viscous
        part alone bounds ``Im`` from below (every other term dissipates)."""
        f = self._factors(run)
        c = (1 + run.eps_z) * 2 * self.zeta0 * self.omega0 * W * f["damping"]
        return 1.001 * target / c


def _bracket(excess, lo, hi, rounds=4, n=16):
    """Root of an increasing ``excess(log X)`` in [lo, hi] (arrays, one per line), by
    ``rounds`` grids of ``n`` points (vectorized; resolution (hi-lo)/(n-1)^rounds)."""
    for _ in range(rounds):
        grid = lo[None, :] + (hi - lo)[None, :] * np.linspace(0.0, 1.0, n)[:, None]
        big = excess(grid) > 0
        i = np.where(big.any(axis=0), big.argmax(axis=0), n - 1)
        cols = np.arange(lo.size)
        lo, hi = grid[np.maximum(i - 1, 0), cols], grid[i, cols]
    return 0.5 * (lo + hi)


def _solve(st, W, target, run, n_iter=46):
    """``X`` with ``X |D(X, W) + L(W)| = target`` per line (bisection in log X,
    vectorized over the lines), and a fold flag (the left side not increasing on a
    grid: several steady states)."""
    L = st.exciter.load(W)
    hi = np.log(st.x_upper(target, W, run))
    lo = hi - math.log(1e7)
    for _ in range(n_iter):
        mid = 0.5 * (lo + hi)
        Xm = np.exp(mid)
        big = Xm * np.abs(st.stiffness(Xm, W, run) + L) > target
        hi, lo = np.where(big, mid, hi), np.where(big, lo, mid)
    X = np.exp(0.5 * (lo + hi))
    grid = X[None, :] * np.geomspace(0.25, 4.0, 17)[:, None]
    g = grid * np.abs(st.stiffness(grid, W[None, :], run) + L[None, :])
    fold = bool(np.any(np.diff(g, axis=0) <= 0.0))
    return X, fold


def solve_level(st: Structure, W, control: str, held: float, run: Run):
    """Steady state of one level at the lines ``W``: (FRF ``q/F``, force amplitude at
    the transducer, amplitude ``X``, fold flag). ``held``: the force-drive level
    (exciter input) or, under response control, the amplitude ``X``."""
    W = np.asarray(W, float)
    if control == "response":
        X = np.full(W.shape, float(held))
        D = st.stiffness(X, W, run)
        return st.frf(D, W), np.abs(D) * X, X, False
    target = np.abs(st.exciter.gain(float(held), W))
    X, fold = _solve(st, W, target, run)
    D = st.stiffness(X, W, run)
    return st.frf(D, W), np.abs(D) * X, X, fold


def resonance(st: Structure, control: str, held: float, run: Run):
    """Amplitude, natural frequency squared and damping ratio at the resonance of a
    level (the backbone at the peak amplitude, rad^2/s^2): the quick predictor of what
    an identification returns, used to size the mechanisms and place the lines.
    Returns (X, omega2, zeta, zeta with the exciter's load)."""
    def at(X):
        w2 = st.stiffness(X, 1.0, run).real + 1.0
        w = np.sqrt(np.maximum(w2, 1e-12))
        return w2, w, st.stiffness(X, w, run)
    if control == "response":
        X = float(held)
    else:
        w = at(np.array(1e-12))[1]
        hi = math.log(float(st.x_upper(abs(st.exciter.gain(float(held), w)), w, run)))

        def excess(logx):
            X = np.exp(logx)
            w2, w, D = at(X)
            return X * np.abs(D + st.exciter.load(w)) - np.abs(st.exciter.gain(float(held), w))
        X = float(np.exp(_bracket(excess, np.array([hi - math.log(1e7)]), np.array([hi]))[0]))
    w2, w, D = at(np.array(X))
    w2, w = float(w2), float(w)
    zeta = float(D.imag) / (2 * w2)
    zeta_loaded = float((D + st.exciter.load(w)).imag) / (2 * w2)
    return X, w2, zeta, zeta_loaded


def noisy(rng, H, eps_m, eps_a):
    """``H`` with complex Gaussian noise: relative ``eps_m`` per line plus ``eps_a``
    of the peak magnitude (E|n|^2 = eps^2 |.|^2)."""
    def cn(shape):
        return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / math.sqrt(2)
    return H * (1 + eps_m * cn(H.shape)) + eps_a * np.abs(H).max() * cn(H.shape)
