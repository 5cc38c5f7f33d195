"""One mode with an Iwan joint under a stepped-sine test: steady first-harmonic states
and the FRF of each level (force or response control, with or without an exciter that
falls short).

Structure: a unit-mass modal oscillator whose modal coordinate ``q`` is the joint slip
(``u = q``) and the response at the drive point. First-harmonic balance at line ``W``:

    D(X, W) X = F,   D = omega2_lin + k_in(X) - W^2 + i (c0 W + k_q(X))           (1)

``k_in, k_q`` the exact describing function of the four-parameter Iwan joint
(:func:`joints.describing.describing_function`, micro- and macro-slip) plus the effects
of :mod:`cases.synthetic_series.effects`. The measured FRF is ``q / F`` with ``F`` the
force at the transducer, so it is ``1 / D(X(W), W)`` whatever drives the structure.

Preload loss with run order (an effect on the joint itself): every slip strength
scales by ``lam(run) = 1 - rho f(run)`` (slider stiffnesses unchanged), so
``R -> R lam^-(chi+1)``, ``phi_max -> lam phi_max``, ``K_T`` unchanged; the contact's
stuck stiffness falls with the preload as ``lam^(1/3)`` (Hertz-Mindlin), taken off
``omega2_lin``.

Controls of a level:
* force control: each line at force amplitude ``F_v`` (a control loop holds it);
* a voltage-driven exciter (held level ``V``): ``F = G(V) V - i W c_e q`` (back-EMF
  damping ``c_e``, amplifier/armature gain ``G(V) = g / (1 + (V/V_s)^a)^(1/a)``), so
  the force reaching the structure falls short of proportional;
* response control: each line at modal amplitude ``X_v``; ``F = D X_v``.
SI units: rad/s, m, N (unit modal mass: N per kg).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from joints.describing import describing_function
from joints.iwan import IwanParameters

__all__ = ["JointedMode", "Exciter", "level_frf"]


@dataclass
class JointedMode:
    """Unit-mass mode: ``omega2_lin`` (rad^2/s^2, without the joint), viscous ``c0``
    (rad/s), the Iwan ``joint`` on its coordinate, ``effects`` (callables
    ``(X, W, run) -> (dk_in, dk_q)``), and an optional preload loss ``(rho, shape)``
    with ``shape(run)`` in [0, 1]."""

    omega2_lin: float
    c0: float
    joint: IwanParameters
    effects: list = field(default_factory=list)
    preload_loss: tuple | None = None

    @property
    def omega0(self) -> float:
        """Small-amplitude natural frequency ``sqrt(omega2_lin + K_T)``, rad/s."""
        return float(np.sqrt(self.omega2_lin + self.joint.K_T))

    def _joint_at(self, run):
        if self.preload_loss is None:
            return self.joint, 0.0
        rho, shape = self.preload_loss
        lam = 1.0 - rho * float(shape(run))
        j = self.joint
        p = j.chi + 1.0
        phi = j.phi_max * lam
        joint = IwanParameters.from_density(j.R * lam**-p, j.chi, phi, j.S)
        return joint, -j.K_T * (1.0 - lam ** (1.0 / 3.0))

    def stiffness(self, X, W, run=1.0):
        """Complex dynamic stiffness ``D(X, W)`` of eq. (1) at run ``run``."""
        X = np.maximum(np.asarray(X, float), 1e-30)
        joint, dk0 = self._joint_at(run)
        k_in, k_q = describing_function(joint, X)
        real = self.omega2_lin + dk0 + k_in - W**2
        imag = self.c0 * W + k_q
        for eff in self.effects:
            a, b = eff(X, W, run)
            real = real + a
            imag = imag + b
        return real + 1j * imag


@dataclass
class Exciter:
    """Voltage-driven exciter: gain ``g``, saturation ``v_s`` (inf: none) with
    exponent ``a``, back-EMF damping ``c_e`` (N s/m per kg)."""

    g: float = 1.0
    v_s: float = np.inf
    a: float = 2.0
    c_e: float = 0.0

    def force(self, volts):
        return self.g * volts / (1.0 + (volts / self.v_s) ** self.a) ** (1.0 / self.a)


def _solve_amplitude(mode, W, target, c_e, run, n_iter=70):
    """``X`` with ``X |D(X, W) + i W c_e| = target`` per line (bisection in log X);
    returns (X, fold) where fold flags a non-monotone ``X |D|`` (several states)."""
    D0 = mode.stiffness(1e-12, W, run) + 1j * W * c_e
    x_lin = target / np.abs(D0)
    lo, hi = np.log(x_lin * 1e-3), np.log(x_lin * 1.5)
    for _ in range(n_iter):
        mid = 0.5 * (lo + hi)
        Xm = np.exp(mid)
        big = Xm * np.abs(mode.stiffness(Xm, W, run) + 1j * W * c_e) > target
        hi, lo = np.where(big, mid, hi), np.where(big, lo, mid)
    X = np.exp(0.5 * (lo + hi))
    grid = np.geomspace(0.2, 1.5, 25)[:, None] * x_lin[None, :]
    g = grid * np.abs(mode.stiffness(grid, W[None, :], run) + 1j * W[None, :] * c_e)
    fold = bool(np.any(np.diff(g, axis=0) <= 0.0))
    return X, fold


def level_frf(mode: JointedMode, W, control: str, held: float, run: float = 1.0,
              exciter: Exciter | None = None, force_scale: float = 1.0):
    """Steady state of one level at every line ``W`` (rad/s).

    ``control``: ``"force"`` (each line at force ``held * force_scale``; with an
    ``exciter`` the held level is its voltage) or ``"response"`` (each line at
    amplitude ``held``). Returns (frf ``q/F`` (complex), force amplitude at the
    transducer per line, amplitude ``X`` per line, fold flag)."""
    W = np.asarray(W, float)
    if control == "response":
        X = np.full(W.shape, float(held))
        D = mode.stiffness(X, W, run)
        return 1.0 / D, np.abs(D) * X, X, False
    if exciter is None:
        target = np.full(W.shape, float(held) * force_scale)
        X, fold = _solve_amplitude(mode, W, target, 0.0, run)
        D = mode.stiffness(X, W, run)
        return 1.0 / D, np.abs(D) * X, X, fold
    target = np.full(W.shape, float(exciter.force(held)))
    X, fold = _solve_amplitude(mode, W, target, exciter.c_e, run)
    D = mode.stiffness(X, W, run)
    return 1.0 / D, np.abs(D) * X, X, fold
