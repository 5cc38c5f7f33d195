"""The generator's hidden mechanisms, one class per family (table in the package doc).

Every mechanism acts on a unit-mass mode at modal (= joint slip = drive point)
amplitude ``X`` (m), line ``W`` (rad/s) and run ``run`` (:class:`Run`). Amplitude
mechanisms return ``(dRe, dIm)`` added to the complex dynamic stiffness
(rad^2/s^2, :mod:`.first_harmonic` convention); time mechanisms return factors on the
stuck frequency squared (``omega2``), on the viscous damping (``damping``) and on the
joint's slip limits (``slip``: the preload). ``strength`` scales each mechanism's size
(the draw sizes it to a visibility); every other parameter sets its shape.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synthetic.first_harmonic import SliderBank, first_harmonic

__all__ = ["Run", "SlipRing", "TaperedEdge", "SnubberFilm", "LazanKnee", "PowerSpring",
           "HertzStop", "CappedDashpot", "TemperatureStep", "RoomCycle", "BoltLoosening",
           "DampingDrift", "ShakerImpedance", "AmplifierClipping"]


@dataclass
class Run:
    """One run (chronological index ``k`` >= 1, start time ``t`` in [0, 1] of the
    test's duration) with its own repeatability offsets: the stuck frequency is
    ``(1 + eps_f)`` times nominal, the whole damping ``(1 + eps_z)``."""

    k: int
    t: float = 0.0
    eps_f: float = 0.0
    eps_z: float = 0.0


@dataclass
class _Amplitude:
    strength: float = 1.0
    kind = "amplitude"

    def run_factors(self, run):
        return {}


@dataclass
class _Time:
    strength: float = 1.0
    kind = "time"

    def stiffness(self, X, W, run):
        return 0.0, 0.0


# ----------------------------------------------------------------- macro-slip


@dataclass
class SlipRing(_Amplitude):
    """A second contact patch: sliders of uniform stiffness density ``strength / width``
    whose slip limits lie in ``[lo, hi]`` (m): stuck below ``lo``, in gross slip
    (the whole ring released) above ``hi``."""

    lo: float = 1.0
    hi: float = 2.0
    family = "slip-ring"
    cause = "macro-slip"

    def stiffness(self, X, W, run):
        bank = SliderBank(uniform=self.strength / (self.hi - self.lo), lo=self.lo, hi=self.hi)
        X = np.asarray(X, float)
        dk, kq = bank.loss(X.ravel())
        return -dk.reshape(X.shape), kq.reshape(X.shape)


@dataclass
class TaperedEdge(_Amplitude):
    """The main joint's slip-limit density ends in a taper: ``R phi^chi`` up to
    ``phi_t``, then ``R phi_t^chi (1 - u)^taper`` for ``u = (phi - phi_t)/(phi_m -
    phi_t)`` up to ``phi_m``, no slider beyond (no Dirac share): gross slip past
    ``phi_m``. Acts through :meth:`joint` (``strength`` unused); without it the power
    law goes on."""

    phi_t: float = 1.0
    phi_m: float = 2.0
    taper: float = 1.0
    family = "tapered-edge"
    cause = "macro-slip"

    def stiffness(self, X, W, run):
        return 0.0, 0.0

    def joint(self, bank: SliderBank) -> SliderBank:
        e = self.taper
        return SliderBank(bank.R, bank.chi, self.phi_t, self.phi_m,
                          shape=lambda u: np.clip(1.0 - u, 0.0, 1.0) ** e)


# ----------------------------------------------------------------- added damping


@dataclass
class SnubberFilm(_Amplitude):
    """A squeeze-film snubber: a viscous force ``strength v`` (rad/s) once the
    displacement passes the clearance ``gap`` (m) on either side (no stiffness)."""

    gap: float = 1.0
    family = "snubber-squeeze-film"
    cause = "quadratic-damping"

    def stiffness(self, X, W, run):
        c, g = self.strength, self.gap
        return first_harmonic(lambda x, v: np.where(np.abs(x) > g, c * v, 0.0), X, W)


@dataclass
class LazanKnee(_Amplitude):
    """Material damping after Lazan: energy lost per cycle ``D = strength X^2
    (X/X_k)^(n1-2) (1 + (X/X_k)^(n2-n1))`` (rate independent, a knee at the cyclic
    stress sensitivity limit ``X_k``), so ``dIm = D / (pi X^2)``."""

    x_knee: float = 1.0
    n1: float = 2.4
    n2: float = 7.0
    family = "lazan-knee"
    cause = "quadratic-damping"

    def stiffness(self, X, W, run):
        r = np.asarray(X, float) / self.x_knee
        loss = r ** (self.n1 - 2.0) * (1.0 + r ** (self.n2 - self.n1))
        return 0.0 * r, self.strength / np.pi * loss


# ----------------------------------------------------------------- hardening / softening


@dataclass
class PowerSpring(_Amplitude):
    """A spring ``f = strength x_ref (|x|/x_ref)^a sgn x`` (strength in rad^2/s^2 at
    ``|x| = x_ref``; negative: softening, a post-buckled strip)."""

    a: float = 3.0
    x_ref: float = 1.0
    family = "power-spring"
    cause = "geometric-hardening"

    def stiffness(self, X, W, run):
        s, a, xr = self.strength, self.a, self.x_ref
        return first_harmonic(lambda x, v: s * xr * np.abs(x / xr) ** a * np.sign(x), X, W)


@dataclass
class HertzStop(_Amplitude):
    """A one-sided Hertzian stop past a clearance ``gap`` (m):
    ``f = strength gap ((x - gap)_+ / gap)^1.5`` (the mean offset it causes is left out)."""

    gap: float = 1.0
    family = "hertz-stop"
    cause = "geometric-hardening"

    def stiffness(self, X, W, run):
        s, g = self.strength, self.gap
        return first_harmonic(lambda x, v: s * g * (np.maximum(x - g, 0.0) / g) ** 1.5, X, W)


@dataclass
class CappedDashpot(_Amplitude):
    """A dashpot ``strength`` (rad/s) in series with a Coulomb slider that slips at the
    force the dashpot reaches at amplitude ``x_cap`` (m) and line ``w_cap`` (rad/s):
    the viscous force capped at ``strength w_cap x_cap`` (per unit modal mass). Its
    damping falls with amplitude past ``x_cap``; no stiffness."""

    x_cap: float = 1.0
    w_cap: float = 1.0
    family = "capped-dashpot"
    cause = "unexplained"

    def stiffness(self, X, W, run):
        c = self.strength
        cap = abs(c) * self.w_cap * self.x_cap
        return first_harmonic(lambda x, v: np.clip(c * v, -cap, cap), X, W)


# ----------------------------------------------------------------- time


@dataclass
class TemperatureStep(_Time):
    """A step of the room temperature at test time ``t_step``: the stuck frequency
    squared changes by the factor ``1 + strength`` from then on."""

    t_step: float = 0.5
    family = "temperature-step"
    cause = "thermal-drift"

    def run_factors(self, run):
        return {"omega2": 1.0 + self.strength * float(run.t >= self.t_step)}


@dataclass
class RoomCycle(_Time):
    """A room-temperature ramp plus a daily cycle over the test's time ``t``:
    ``T = ramp t + sin(2 pi t / period + phase)``, normalized to its range over the
    test; frequency squared factor ``1 + strength T`` (thermal expansion, modulus)."""

    ramp: float = 0.0
    period: float = 1.0
    phase: float = 0.0
    on_damping: bool = False
    family = "room-cycle"
    cause = "thermal-drift"

    def shape(self, t):
        tt = np.linspace(0.0, 1.0, 201)
        full = self.ramp * tt + np.sin(2 * np.pi * tt / self.period + self.phase)
        T = self.ramp * t + np.sin(2 * np.pi * t / self.period + self.phase)
        return float((T - full.min()) / (full.max() - full.min()))

    def run_factors(self, run):
        return {"omega2": 1.0 + self.strength * self.shape(run.t)}


@dataclass
class DampingDrift(RoomCycle):
    """The viscous damping follows the room temperature (grease, a glue layer):
    factor ``1 + strength T(t)``, the frequency unaffected."""

    family = "damping-drift"
    cause = "unexplained"

    def run_factors(self, run):
        return {"damping": 1.0 + self.strength * self.shape(run.t)}


@dataclass
class BoltLoosening(_Time):
    """A bolt loses preload at test time ``t_step``: slip limits scale by
    ``lam = 1 - strength`` (the joint slips more at a given amplitude) and the stuck
    contact stiffness by ``lam^(1/3)`` (Hertz-Mindlin), a share ``kt_share`` of
    omega^2."""

    t_step: float = 0.5
    kt_share: float = 0.3
    family = "bolt-loosening-step"
    cause = "unexplained"

    def run_factors(self, run):
        if run.t < self.t_step:
            return {}
        lam = 1.0 - self.strength
        return {"slip": lam, "omega2": 1.0 - self.kt_share * (1.0 - lam ** (1.0 / 3.0))}


# ----------------------------------------------------------------- exciters


@dataclass
class ShakerImpedance:
    """A voltage-driven electrodynamic shaker on a rigid stinger (held level: the
    voltage ``V``): coil ``R_c`` (Ohm) and ``L`` (H), force factor ``Bl`` (N/A),
    armature mass ``m_a`` and suspension ``k_a``, ``c_a`` (per unit modal mass).
    ``F = G(W) V - Z(W) i W q`` with ``G = Bl / (R_c + i W L)`` and
    ``Z = Bl^2 / (R_c + i W L) + i W m_a + c_a + k_a / (i W)``; the transducer reads F."""

    Bl: float = 1.0
    R_c: float = 1.0
    L: float = 0.0
    m_a: float = 0.0
    k_a: float = 0.0
    c_a: float = 0.0
    family = "shaker-impedance"
    cause = "nonproportional-amplitude"

    def gain(self, V, W):
        return self.Bl / (self.R_c + 1j * W * self.L) * V

    def nominal_gain(self, W):
        """Force per volt without back-EMF and armature (the counterfactual), N/V."""
        return float(abs(self.Bl / (self.R_c + 1j * W * self.L)))

    def load(self, W):
        """Extra dynamic stiffness the shaker puts on the mode, ``i W Z``."""
        Z = (self.Bl**2 / (self.R_c + 1j * W * self.L) + 1j * W * self.m_a + self.c_a
             + self.k_a / (1j * W))
        return 1j * W * Z


@dataclass
class AmplifierClipping:
    """An open-loop drive whose power amplifier clips softly: force
    ``g V_s tanh(V / V_s)`` for the held voltage ``V`` (an ideal force generator
    otherwise)."""

    g: float = 1.0
    v_s: float = 1.0
    family = "amplifier-clipping"
    cause = "nonproportional-amplitude"

    def gain(self, V, W):
        return self.g * self.v_s * np.tanh(V / self.v_s) + 0.0 * W

    def nominal_gain(self, W):
        return self.g

    def load(self, W):
        return 0.0 * W


@dataclass
class Ideal:
    """An exciter that delivers the held force ``g V`` (the counterfactual of both)."""

    g: float = 1.0
    family = "ideal"
    cause = None

    def gain(self, V, W):
        return self.g * V + 0.0 * W

    def nominal_gain(self, W):
        return self.g

    def load(self, W):
        return 0.0 * W
