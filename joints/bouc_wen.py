"""Bouc-Wen joints (Bouc 1967, Wen 1976) as a :class:`joints.law.JointLaw`.

Force and hysteretic displacement ``z`` (m) of a joint of slip ``s`` (m), in the form
of Wen (1976) with ``A = 1`` and exponent ``n = 1`` (as written in the survey of
Ismail, Ikhouane & Rodellar, Arch. Comput. Methods Eng. 16 (2009) 161, Sec. 2)::

    F = K_T (alpha s + (1 - alpha) z),                                          (1)
    dz = ds (1 - beta sgn(ds) z - gamma |z|)   (i.e. z' = s' - beta |s'| z - gamma s' |z|). (2)

``K_T`` is the stuck (virgin) stiffness, ``alpha`` the ratio of the stiffness left when
the joint slips through. Parameterized here by the force ``F_S`` (N) at which the
hysteretic part saturates, ``(1 - alpha) K_T z_u`` with ``z_u = 1/(beta + gamma)``, and
the shape ``gamma/beta`` in (-1, 1] (``beta - gamma >= 0``: dissipative loops)::

    beta = (1 - alpha) K_T / (F_S (1 + shape)),   gamma = shape beta.

Eq. (2) is rate independent: along a monotone slip increment ``u = |ds|`` it is an
autonomous linear ODE in ``w = sgn(ds) z`` on either side of ``w = 0``,
``dw/du = 1 - b w`` (``w >= 0``, ``b = beta + gamma``) and ``dw/du = 1 - c w``
(``w < 0``, ``c = beta - gamma``), so a step is exact in closed form (exponentials;
:func:`_advance`) and its tangent is ``dz/ds = 1 - beta w - gamma |w|`` at the end.
Unloading starts with the stiffness ``K_T (alpha + (1 - alpha)(1 + c |z|))``, above
``K_T`` unless ``shape = 1``.

Describing function: the steady loop of ``s = A sin(theta)`` has its loading branch
(``theta`` from ``-pi/2`` to ``pi/2``) start at ``z = -z_m`` with ``z_m`` the fixed point
``z_m = w(-z_m, 2A)`` (bisection), the unloading branch is its mirror image, and

    k_in = alpha K_T + (1 - alpha) K_T (2/(pi A)) int z sin(theta) dtheta,
    k_q  =             (1 - alpha) K_T (2/(pi A)) int z cos(theta) dtheta

over the loading branch, by Gauss-Legendre quadrature on the two pieces either side
of the zero of ``z`` (the integrand is smooth on each: exponentially convergent);
the derivatives in ``A`` by central differences (relative step 1e-5: error ~1e-10).
Checked against ``scipy.integrate.solve_ivp`` of eq. (2) in time to 1e-6
(``tests/test_bouc_wen.py``). SI units: m, N, N/m.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from joints.law import JointLaw

__all__ = ["BoucWenParameters", "BoucWenJoints"]

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(40)


@dataclass(frozen=True)
class BoucWenParameters:
    """One Bouc-Wen joint: stuck stiffness ``K_T`` (N/m) > 0, saturation force of the
    hysteretic part ``F_S`` (N) > 0, stiffness ratio ``alpha`` in [0, 1), ``shape`` =
    ``gamma/beta`` in (-1, 1] (module docstring)."""

    K_T: float
    F_S: float
    alpha: float = 0.0
    shape: float = 0.5

    def __post_init__(self):
        if not (np.isfinite(self.K_T) and self.K_T > 0 and np.isfinite(self.F_S)
                and self.F_S > 0):
            raise ValueError(f"Bouc-Wen joint needs finite K_T > 0 and F_S > 0, got "
                             f"K_T={self.K_T!r}, F_S={self.F_S!r}")
        if not 0.0 <= self.alpha < 1.0:
            raise ValueError(f"Bouc-Wen alpha must lie in [0, 1), got {self.alpha!r}")
        if not -1.0 < self.shape <= 1.0:
            raise ValueError(f"Bouc-Wen shape gamma/beta must lie in (-1, 1], got "
                             f"{self.shape!r}")

    @property
    def beta(self) -> float:
        """``beta`` of eq. (2) (1/m)."""
        return (1.0 - self.alpha) * self.K_T / (self.F_S * (1.0 + self.shape))

    @property
    def gamma(self) -> float:
        """``gamma`` of eq. (2) (1/m)."""
        return self.shape * self.beta


def _relax(w0, u, k):
    """``w(u)`` of ``dw/du = 1 - k w`` from ``w0`` (``k >= 0``, ``u >= 0``)."""
    safe = np.where(k > 0.0, k, 1.0)
    e = np.exp(-safe * u)
    return np.where(k > 0.0, w0 * e - np.expm1(-safe * u) / safe, w0 + u)


def _to_zero(w0, c):
    """Increment ``u`` that carries ``w0 < 0`` to 0 on ``dw/du = 1 - c w``."""
    safe = np.where(c > 0.0, c, 1.0)
    return np.where(c > 0.0, np.log1p(-safe * w0) / safe, -w0)


def _advance(w0, u, b, c):
    """Eq. (2) along a monotone increment ``u >= 0`` in ``w = sgn(ds) z`` (module
    docstring), exact."""
    neg = w0 < 0.0
    u0 = np.where(neg, _to_zero(np.minimum(w0, 0.0), c), 0.0)
    first = np.minimum(u, u0)
    w = np.where(neg, np.where(u >= u0, 0.0, _relax(w0, first, c)), w0)
    return np.where(w >= 0.0, _relax(w, u - first, b), w)


class BoucWenJoints(JointLaw):
    """Bouc-Wen joints, one :class:`BoucWenParameters` shared by ``n_joints`` or one per
    joint. State: ``(n_joints, 2)`` rows ``[s, z]`` (m) of the committed step."""

    name = "bouc-wen"

    def __init__(self, joints, n_joints: int | None = None):
        if isinstance(joints, BoucWenParameters):
            if n_joints is None:
                raise ValueError("n_joints is required with a single BoucWenParameters")
            joints = [joints] * int(n_joints)
        joints = list(joints)
        if n_joints is not None and len(joints) != n_joints:
            raise ValueError(f"need one BoucWenParameters per joint ({n_joints}), got "
                             f"{len(joints)}")
        self.params = tuple(joints)
        self.K_T = np.array([p.K_T for p in joints], dtype=float)
        self.alpha = np.array([p.alpha for p in joints], dtype=float)
        self.beta = np.array([p.beta for p in joints], dtype=float)
        self.gamma = np.array([p.gamma for p in joints], dtype=float)

    @property
    def slip_scale(self) -> np.ndarray:
        """``z_u = 1/(beta + gamma)`` (m): the slip over which the joint saturates."""
        return 1.0 / (self.beta + self.gamma)

    def initial_state(self) -> np.ndarray:
        return np.zeros((self.n_joints, 2))

    def _force(self, s, z):
        return self.K_T * (self.alpha * s + (1.0 - self.alpha) * z)

    def step(self, slip, state):
        """Exact step of eq. (2) from ``state`` to ``slip`` (module docstring)."""
        s = np.asarray(slip, dtype=float)
        s0, z0 = state[:, 0], state[:, 1]
        ds = s - s0
        sign = np.where(ds > 0.0, 1.0, np.where(ds < 0.0, -1.0, -np.sign(z0) + (z0 == 0.0)))
        w = _advance(sign * z0, np.abs(ds), self.beta + self.gamma, self.beta - self.gamma)
        z = sign * w
        dz = 1.0 - self.beta * w - self.gamma * np.abs(w)
        tangent = self.K_T * (self.alpha + (1.0 - self.alpha) * dz)
        return self._force(s, z), tangent, np.stack([s, z], axis=-1)

    def loop_amplitude(self, amplitude):
        """``z_m`` (m) of the steady loop of slip amplitude ``A``: the fixed point
        ``z_m = w(-z_m, 2A)`` by bisection on ``[0, 1/(beta+gamma)]``."""
        A = np.asarray(amplitude, dtype=float)
        b, c = self.beta + self.gamma, self.beta - self.gamma
        lo = np.zeros(np.broadcast(A, b).shape)
        hi = lo + 1.0 / b
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            up = _advance(-mid, 2.0 * A, b, c) > mid
            lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
        return 0.5 * (lo + hi)

    def _describing(self, A):
        b, c = self.beta + self.gamma, self.beta - self.gamma
        zm = self.loop_amplitude(A)
        u0 = np.minimum(_to_zero(-zm, c), 2.0 * A)
        t0 = np.arcsin(np.clip(u0 / A - 1.0, -1.0, 1.0))
        I_s = I_c = 0.0
        for lo, hi in ((-0.5 * np.pi, t0), (t0, 0.5 * np.pi)):
            half = 0.5 * (hi - lo)
            theta = (0.5 * (hi + lo))[..., None] + half[..., None] * _NODES
            z = _advance(-zm[..., None], A[..., None] * (1.0 + np.sin(theta)),
                         b[..., None], c[..., None])
            I_s = I_s + half * np.sum(_WEIGHTS * z * np.sin(theta), axis=-1)
            I_c = I_c + half * np.sum(_WEIGHTS * z * np.cos(theta), axis=-1)
        hyst = (1.0 - self.alpha) * self.K_T * 2.0 / (np.pi * A)
        return self.alpha * self.K_T + hyst * I_s, hyst * I_c

    def describing_derivative(self, amplitude):
        """``(k_in, k_q, dk_in/dA, dk_q/dA)`` by quadrature of the steady loop (module
        docstring); ``amplitude`` (m) broadcasts against ``(n_joints,)``."""
        A = np.maximum(np.asarray(amplitude, dtype=float), 1e-300)
        A = np.broadcast_to(A, np.broadcast(A, self.K_T).shape)
        k_in, k_q = self._describing(A)
        h = 1e-5 * A
        (ip, qp), (im, qm) = self._describing(A + h), self._describing(A - h)
        return k_in, k_q, (ip - im) / (2.0 * h), (qp - qm) / (2.0 * h)
