"""Four-parameter Iwan joint model (Segalman, J. Appl. Mech. 72 (2005) 752).

A parallel bank of Jenkins elements (unit-stiffness spring + Coulomb slider of slip
displacement ``phi``) with population density (paper eq. 6; Segalman 2005)

    rho(phi) = R phi**chi [H(phi) - H(phi - phi_max)] + S delta(phi - phi_max),

so that the force is ``F = int rho(phi) (u - x(phi)) dphi`` (paper eq. 1). The density
parameters ``(R, chi, phi_max, S)`` map one-to-one on the physical parameters
``(chi, K_T, F_S, beta)``:

    K_T  = R phi_max**(chi+1)/(chi+1) + S            (joint stiffness, N/m)
    F_S  = R phi_max**(chi+2)/(chi+2) + S phi_max    (macro-slip force, N)
    beta = S (chi+1) / (R phi_max**(chi+1))          (Dirac / continuous stiffness)

and back (paper eqs. 41, 42; the paper's eq. 7 for F_S is misprinted)

    phi_max = F_S (1+beta) / (K_T (beta + (chi+1)/(chi+2)))
    R       = F_S (chi+1) / (phi_max**(chi+2) (beta + (chi+1)/(chi+2)))
    S       = (F_S/phi_max) beta / (beta + (chi+1)/(chi+2)).

Everything here is the exact continuous model in the time domain (closed forms,
Masing rules): parameters, density, backbone, Masing branches, force along any slip
path, the steady loop and the dissipation per cycle. Its first-harmonic (describing
function) stiffnesses and the paper's kappa1, kappa2 are in :mod:`joints.describing`;
the discretized Jenkins bank is in :mod:`joints.jenkins`. SI units: displacements in m,
forces in N, stiffnesses in N/m, energies in J.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "IwanParameters",
    "density",
    "backbone",
    "masing_branch",
    "force_history",
    "masing_step",
    "IWAN_VIRGIN",
    "steady_loop",
    "dissipation_per_cycle",
]


def _finite(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v!r}")
    return v


def _check_chi(chi: float) -> None:
    if not -1.0 < chi < 0.0:
        raise ValueError(f"chi must lie in (-1, 0), got {chi:g}")


@dataclass(frozen=True)
class IwanParameters:
    """Physical parameters of the four-parameter Iwan joint (Segalman 2005).

    Parameters
    ----------
    chi : float
        Exponent of the density, in (-1, 0). Micro-slip dissipation grows as
        ``A**(chi+3)``.
    K_T : float
        Joint stiffness at small load (N/m), > 0.
    F_S : float
        Force at which macro-slip starts (N), > 0.
    beta : float
        Ratio of the Dirac (``S``) to the continuous part of the stiffness, >= 0.

    Raises
    ------
    ValueError
        With a one-line message naming the bad value.
    """

    chi: float
    K_T: float
    F_S: float
    beta: float

    def __post_init__(self):
        for name in ("chi", "K_T", "F_S", "beta"):
            object.__setattr__(self, name, _finite(name, getattr(self, name)))
        _check_chi(self.chi)
        if self.K_T <= 0.0:
            raise ValueError(f"K_T must be > 0, got {self.K_T:g}")
        if self.F_S <= 0.0:
            raise ValueError(f"F_S must be > 0, got {self.F_S:g}")
        if self.beta < 0.0:
            raise ValueError(f"beta must be >= 0, got {self.beta:g}")
        self._check_representable()

    def _check_representable(self) -> None:
        """phi_max and R must be positive normal doubles and S finite.

        Each input may be a fine number while a derived one is not: ``K_T = 1e300`` N/m
        with ``F_S = 400`` N gives ``phi_max ~ 4e-297`` m, whose power ``chi+2`` underflows
        and ``R = F_S (chi+1)/(phi_max^(chi+2) ...)`` would be ~1e446 N/m^1.5, beyond
        double precision. Such a joint cannot be computed with, so it is refused here,
        with the numbers, instead of failing later as a division by zero or an infinity.
        """
        tiny = np.finfo(float).tiny
        try:
            phi_max = self.phi_max
            R = self.R if phi_max >= tiny else math.nan
            S = self.S if phi_max >= tiny else math.nan
        except (ZeroDivisionError, OverflowError):
            phi_max, R, S = self.phi_max, math.nan, math.nan
        where = (f"chi = {self.chi:g}, K_T = {self.K_T:g} N/m, F_S = {self.F_S:g} N, "
                 f"beta = {self.beta:g}")
        if not (math.isfinite(phi_max) and phi_max >= tiny):
            raise ValueError(f"{where} give phi_max = F_S (1+beta)/(K_T (beta + (chi+1)/"
                             f"(chi+2))) = {phi_max:g} m, outside double precision")
        if not (math.isfinite(R) and R >= tiny and math.isfinite(S)):
            raise ValueError(f"{where} give phi_max = {phi_max:g} m and a density R = F_S "
                             f"(chi+1)/(phi_max^(chi+2) (beta + (chi+1)/(chi+2))) outside "
                             f"double precision (paper eq. 42)")

    @property
    def _c(self) -> float:
        return (self.chi + 1.0) / (self.chi + 2.0)

    @property
    def phi_max(self) -> float:
        """Slip displacement of the strongest slider (m), paper eq. (41)."""
        return self.F_S * (1.0 + self.beta) / (self.K_T * (self.beta + self._c))

    @property
    def R(self) -> float:
        """Density coefficient (N m^-(chi+2)), paper eq. (42)."""
        return (self.F_S * (self.chi + 1.0)
                / (self.phi_max ** (self.chi + 2.0) * (self.beta + self._c)))

    @property
    def S(self) -> float:
        """Weight of the Dirac term at ``phi_max`` (N/m): ``K_T beta/(1+beta)``."""
        return self.F_S / self.phi_max * self.beta / (self.beta + self._c)

    @classmethod
    def from_density(cls, R: float, chi: float, phi_max: float, S: float) -> "IwanParameters":
        """Build from the density parameters (relations in the module docstring).

        ``R > 0`` (N m^-(chi+2)), ``chi`` in (-1, 0), ``phi_max > 0`` (m), ``S >= 0`` (N/m).
        """
        R = _finite("R", R)
        chi = _finite("chi", chi)
        phi_max = _finite("phi_max", phi_max)
        S = _finite("S", S)
        _check_chi(chi)
        if R <= 0.0:
            raise ValueError(f"R must be > 0, got {R:g}")
        if phi_max <= 0.0:
            raise ValueError(f"phi_max must be > 0, got {phi_max:g}")
        if S < 0.0:
            raise ValueError(f"S must be >= 0, got {S:g}")
        tiny = np.finfo(float).tiny
        try:
            continuous = R * phi_max ** (chi + 1.0) / (chi + 1.0)
            F_S = R * phi_max ** (chi + 2.0) / (chi + 2.0) + S * phi_max
            beta = S / continuous
        except (OverflowError, ZeroDivisionError):
            continuous = F_S = beta = math.nan
        if not all(math.isfinite(v) and v >= tiny for v in (continuous, F_S)) \
                or not math.isfinite(beta):
            raise ValueError(f"R = {R:g}, chi = {chi:g}, phi_max = {phi_max:g} m, S = {S:g} N/m "
                             f"give K_T or F_S = R phi_max^(chi+2)/(chi+2) + S phi_max outside "
                             f"double precision")
        return cls(chi=chi, K_T=continuous + S, F_S=F_S, beta=beta)


# --------------------------------------------------------------------------- density


def density(p: IwanParameters, phi):
    """Continuous part of the slider density, ``R phi**chi`` on ``(0, phi_max)``.

    Paper eq. (6). The Dirac part, a slider population of total stiffness ``p.S``
    (N/m) at ``phi = phi_max``, is not included (it is ``p.S``). Units N/m^2.
    """
    phi = np.asarray(phi, dtype=float)
    inside = (phi > 0.0) & (phi < p.phi_max)
    safe = np.where(inside, phi, 1.0)
    return np.where(inside, p.R * safe ** p.chi, 0.0)


# --------------------------------------------------------------------------- backbone


def backbone(p: IwanParameters, u):
    """Virgin loading curve ``F(u)`` (N) for slip ``u`` (m), exact and odd.

    For ``|u| < phi_max``: ``F = K_T u - R |u|**(chi+2) sign(u) / ((chi+1)(chi+2))``
    (integrate paper eq. 1 with ``x = u - phi`` for ``phi < |u|``, ``x = 0`` above);
    for ``|u| >= phi_max``: ``F = F_S sign(u)`` (Segalman 2005).
    """
    u = np.asarray(u, dtype=float)
    a = np.minimum(np.abs(u), p.phi_max)
    micro = p.K_T * a - p.R * a ** (p.chi + 2.0) / ((p.chi + 1.0) * (p.chi + 2.0))
    return np.sign(u) * np.where(np.abs(u) >= p.phi_max, p.F_S, micro)


def masing_branch(p: IwanParameters, u, u_reversal, F_reversal):
    """Force on the Masing branch leaving the reversal point ``(u_r, F_r)``.

    ``F = F_r + 2 backbone((u - u_r)/2)`` (Masing's rule; exact for any Iwan density,
    Iwan 1967). Broadcasts over all arguments.
    """
    u = np.asarray(u, dtype=float)
    return F_reversal + 2.0 * backbone(p, 0.5 * (u - u_reversal))


def force_history(p: IwanParameters, u):
    """Joint force along an arbitrary slip path, exact continuous Iwan model.

    The joint starts virgin (all sliders unstressed) at ``u = 0`` and is driven along
    straight segments through ``u[0], u[1], ...``. Reversal-memory rules (Masing,
    extended; exact for the parallel Iwan model):

    * first loading follows :func:`backbone`;
    * after a reversal at ``(u_r, F_r)`` the force follows
      :func:`masing_branch` from that point;
    * a branch that reaches the reversal point it started from (the previous one
      in the stack; ``-u_1`` for the first branch, by odd symmetry) closes its loop:
      both reversal points are forgotten and the path continues on the branch that
      was interrupted (the backbone when the stack empties).

    Parameters
    ----------
    p : IwanParameters
    u : array_like, shape (n,)
        Slip (m).

    Returns
    -------
    ndarray, shape (n,)
        Force (N).
    """
    u = np.asarray(u, dtype=float).ravel()
    F = np.empty_like(u)
    if u.size == 0:
        return F
    path = np.concatenate(([0.0], u))
    du = np.diff(path)
    # direction of each step, zero steps inherit the previous direction
    direction = np.sign(du)
    nz = np.flatnonzero(direction)
    if nz.size == 0:
        F[:] = 0.0
        return F
    idx = np.maximum.accumulate(np.where(direction != 0, np.arange(direction.size), -1))
    direction = np.where(idx >= 0, direction[np.maximum(idx, 0)], direction[nz[0]])
    # a monotone run ends where the direction changes; u[k] with k = end is a reversal
    change = np.flatnonzero(direction[1:] != direction[:-1]) + 1
    starts = np.concatenate(([0], change))
    ends = np.concatenate((change, [u.size]))

    stack_u: list[float] = []  # reversal points, oldest first
    stack_F: list[float] = []

    def evaluate(vals):
        if stack_u:
            return masing_branch(p, vals, stack_u[-1], stack_F[-1])
        return backbone(p, vals)

    for s, e, d in zip(starts, ends, direction[starts]):
        seg = u[s:e]
        done = 0
        while done < seg.size:
            # bound of the current branch: where its loop closes
            if len(stack_u) >= 2:
                bound = stack_u[-2]
            elif len(stack_u) == 1:
                bound = -stack_u[-1]
            else:
                bound = math.inf * d
            rest = seg[done:]
            beyond = d * (rest - bound) > 0.0
            n_in = int(np.argmax(beyond)) if beyond.any() else rest.size
            F[s + done:s + done + n_in] = evaluate(rest[:n_in])
            done += n_in
            if done < seg.size:  # loop closes: forget two reversal points (or one)
                if len(stack_u) >= 2:
                    del stack_u[-2:], stack_F[-2:]
                else:
                    stack_u.clear(), stack_F.clear()
        # end of the run: the last point is a reversal (if the path goes on)
        if e < u.size:
            stack_u.append(float(u[e - 1]))
            stack_F.append(float(F[e - 1]))
    return F


#: State of a virgin joint for :func:`masing_step`: (slip, force, direction, reversal
#: slips, reversal forces).
IWAN_VIRGIN = (0.0, 0.0, 0.0, (), ())


def masing_step(p: IwanParameters, u: float, state=IWAN_VIRGIN):
    """One step of :func:`force_history` (same rules) from a committed ``state`` to the
    slip ``u`` (m): ``(force (N), tangent dF/du (N/m), new_state)``. The tangent is the
    slope of the branch at ``u``, ``backbone'((u - u_r)/2)`` (``K_T`` at a reversal).
    """
    u0, F, d0, su, sF = state
    d = float(np.sign(u - u0)) or d0
    if d0 and d != d0:                               # reversal at the committed point
        su, sF = su + (u0,), sF + (F,)
    while su and (len(su) == 1 and d * (u + su[-1]) > 0.0
                  or len(su) >= 2 and d * (u - su[-2]) > 0.0):
        su, sF = su[:-2], sF[:-2]                    # loop closed: forget two (or one)
    x = 0.5 * (u - su[-1]) if su else u
    F = float(masing_branch(p, u, su[-1], sF[-1]) if su else backbone(p, u))
    a = abs(x)
    tangent = p.K_T - p.R * a ** (p.chi + 1.0) / (p.chi + 1.0) if a < p.phi_max else 0.0
    return F, tangent, (float(u), F, d, su, sF)


def steady_loop(p: IwanParameters, amplitude: float, n_points: int = 401):
    """Closed steady hysteresis loop for ``u = A sin(theta)``, ``theta`` in [0, 2 pi].

    Loading branch ``F = -B(A) + 2 B((u+A)/2)``, unloading ``F = B(A) - 2 B((A-u)/2)``
    (paper eq. 10 in micro-slip, Masing in general).

    Returns
    -------
    theta, u, F : ndarray, shape (n_points,)
    """
    A = float(amplitude)
    theta = np.linspace(0.0, 2.0 * np.pi, int(n_points))
    u = A * np.sin(theta)
    loading = np.cos(theta) >= 0.0
    BA = backbone(p, A)
    F = np.where(loading,
                 -BA + 2.0 * backbone(p, 0.5 * (u + A)),
                 BA - 2.0 * backbone(p, 0.5 * (A - u)))
    return theta, u, F


# --------------------------------------------------------------------------- dissipation


def dissipation_per_cycle(p: IwanParameters, amplitude):
    """Energy dissipated per cycle of slip amplitude ``A`` (J), exact.

    Each slider of strength ``phi < A`` dissipates ``4 phi (A - phi)`` per unit
    stiffness, so ``D = int rho(phi) 4 phi (A - phi) dphi``:

    * micro-slip ``A < phi_max``: ``D = 4 R A**(chi+3) / ((chi+2)(chi+3))``
      (Segalman 2005; ``= pi A^2 |kappa1| A^(chi+1)``, paper A15);
    * macro-slip ``A >= phi_max``:
      ``D = 4 R (A phi_max**(chi+2)/(chi+2) - phi_max**(chi+3)/(chi+3))
      + 4 S phi_max (A - phi_max)``, which tends to ``4 F_S A``.
    """
    A = np.asarray(amplitude, dtype=float)
    chi, R, S, pm = p.chi, p.R, p.S, p.phi_max
    a = np.minimum(A, pm)
    cont = 4.0 * R * (A * a ** (chi + 2.0) / (chi + 2.0) - a ** (chi + 3.0) / (chi + 3.0))
    dirac = np.where(A > pm, 4.0 * S * pm * (A - pm), 0.0)
    return cont + dirac
