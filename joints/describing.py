"""First-harmonic (describing-function) stiffnesses of the four-parameter Iwan joint.

Exact in-phase and quadrature stiffnesses for a sinusoidal slip at any amplitude
(micro- and macro-slip), and the paper's micro-slip coefficients kappa1, kappa2 (exact
and as printed, paper eqs. 14, A12, A15). The joint model itself (parameters, density,
backbone, dissipation per cycle) is :mod:`joints.iwan`.

Sign convention (paper eqs. 5, 14): for slip ``u = A sin(wt)`` the force is
``F = K_T u - dF_s`` with first harmonic
``F1 = A (k_in_phase sin wt + k_quadrature cos wt)``; in micro-slip
``k_in_phase = K_T - kappa2 A**(chi+1)`` and ``k_quadrature = -kappa1 A**(chi+1)``.
SI units: m, N, N/m.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

from joints.iwan import IWAN_VIRGIN, IwanParameters, masing_step
from joints.law import JointLaw

__all__ = ["describing_function", "IwanJoints", "as_joint_law", "iwan_describing",
           "slider_in_phase", "kappa1",
           "kappa2_exact", "kappa2_paper"]


def slider_in_phase(r):
    """In-phase describing function of one unit Jenkins element, ``r = phi/A``.

    ``g = (psi - sin(psi) cos(psi))/pi`` with ``cos(psi) = 1 - 2r`` for ``r < 1`` and
    ``g = 1`` otherwise (elastic-perfectly-plastic element). Since
    ``dg/dr = (8/pi) sqrt(r (1-r))``, ``g`` is the regularized incomplete Beta function
    ``I_r(3/2, 3/2)``, evaluated that way to keep full precision as ``r -> 0``.
    """
    r = np.clip(np.asarray(r, dtype=float), 0.0, 1.0)
    return special.betainc(1.5, 1.5, r)


def describing_function(p: IwanParameters, amplitude):
    """Exact first-harmonic stiffnesses for slip ``u = A sin(wt)``, any ``A > 0``.

    ``k_in_phase = (1/(pi A)) int F sin`` and ``k_quadrature = (1/(pi A)) int F cos``
    over one steady cycle, so the dissipation per cycle is ``pi A^2 k_quadrature``.
    The closed form (:func:`iwan_describing`, derived there) agrees with quadrature of
    the Fourier integrals of the Masing loop to 1e-10 relative (tests). Limits:
    ``k_in_phase -> K_T`` as ``A -> 0``; ``k_quadrature -> 4 F_S / (pi A)`` and
    ``k_in_phase -> (8/pi) (phi_max/A)**1.5 (2 K_T/3 - (K_T - S)/(chi + 5/2))``
    as ``A -> inf``.

    Parameters
    ----------
    p : IwanParameters
    amplitude : float or array_like
        Slip amplitude ``A`` (m), > 0.

    Returns
    -------
    k_in_phase, k_quadrature : float or ndarray (N/m)
    """
    A = np.asarray(amplitude, dtype=float)
    if np.any(~(A > 0.0)) or np.any(~np.isfinite(A)):
        raise ValueError("slip amplitude must be finite and > 0")
    k_in, k_quad, _, _ = iwan_describing(IwanJoints(p, 1), A[..., None], False)
    k_in, k_quad = k_in[..., 0], k_quad[..., 0]
    if k_in.ndim == 0:
        return float(k_in), float(k_quad)
    return k_in, k_quad


class IwanJoints(JointLaw):
    """Four-parameter Iwan joints (Segalman 2005), exact, as a :class:`joints.law.JointLaw`.

    ``joints``: one :class:`IwanParameters` shared by ``n_joints`` joints, or one per
    joint. Describing function: :func:`iwan_describing` (closed form). Time step: the
    exact continuous model by Masing's rules with loop closure
    (:func:`joints.iwan.masing_step`, a plain Python loop over joints: for tests and
    small models; the compiled step is the Jenkins bank's, :mod:`joints.bank`).
    """

    name = "iwan"

    def __init__(self, joints, n_joints: int | None = None):
        if isinstance(joints, IwanParameters):
            if n_joints is None:
                raise ValueError("n_joints is required with a single IwanParameters")
            joints = [joints] * n_joints
        joints = list(joints)
        if n_joints is not None and len(joints) != n_joints:
            raise ValueError(f"need one IwanParameters per joint ({n_joints}), got "
                             f"{len(joints)}")
        self.params = tuple(joints)
        self.chi = np.array([p.chi for p in joints])
        self.K_T = np.array([p.K_T for p in joints])
        self.R = np.array([p.R for p in joints])
        self.S = np.array([p.S for p in joints])
        self.phi_max = np.array([p.phi_max for p in joints])
        self.a = self.chi + 2.5
        self.beta_ab = special.beta(self.a, 1.5)
        self.c_in = 8.0 * self.R / (np.pi * (self.chi + 1.0))
        # micro-slip k_q = D/(pi A^2) = 4 R A^(chi+1)/(pi (chi+2)(chi+3))
        self.q_micro = 4.0 * self.R / (np.pi * (self.chi + 2.0) * (self.chi + 3.0))

    @property
    def slip_scale(self) -> np.ndarray:
        return self.phi_max

    def describing_derivative(self, amplitude):
        return iwan_describing(self, amplitude)

    def initial_state(self):
        return tuple(IWAN_VIRGIN for _ in self.params)

    def step(self, slip, state):
        out = [masing_step(p, float(s), st) for p, s, st in zip(self.params, np.ravel(slip),
                                                                  state)]
        return (np.array([o[0] for o in out]), np.array([o[1] for o in out]),
                tuple(o[2] for o in out))


#: Former name of :class:`IwanJoints` (``fe.hb_exact``, ``fe.hb_resonance``).
ExactIwanJoints = IwanJoints


def as_joint_law(joints, n_joints: int) -> JointLaw:
    """``joints`` itself if it is a :class:`joints.law.JointLaw` (checked against
    ``n_joints``), else :class:`IwanJoints` of the Iwan parameters given."""
    if isinstance(joints, JointLaw):
        if joints.n_joints != int(n_joints):
            raise ValueError(f"the joint law has {joints.n_joints} joints, the model "
                             f"{n_joints}")
        return joints
    return IwanJoints(joints, int(n_joints))


def iwan_describing(J: IwanJoints, A, micro_shortcut: bool = True):
    """Exact describing function of each joint at slip amplitudes ``A`` (broadcast
    against ``(n_joints,)``) and its derivative in ``A``:
    ``(k_in, k_q, dk_in/dA, dk_q/dA)`` (N/m, N/m^2).

    Summing the describing function ``g(phi/A)`` of each slider over the density and
    integrating by parts (``dg/dr = (8/pi) sqrt(r (1-r))``, so ``g = I_r(3/2, 3/2)``,
    :func:`slider_in_phase`) gives, with ``rho = min(1, phi_max/A)`` and
    ``B(x; a, b)`` the incomplete Beta function (derived here; not in the paper),

        k_in = K_T I_rho(3/2, 3/2) - c A**(chi+1) B(rho; chi+5/2, 3/2),
        c = 8 R / (pi (chi+1)),

    which in micro-slip (``rho = 1``) is ``K_T - kappa2_exact A**(chi+1)`` (paper
    eq. 14, A15 with the exact kappa2), and ``k_q = D/(pi A^2)`` with ``D`` the
    dissipation per cycle (:func:`joints.iwan.dissipation_per_cycle`; ``= -kappa1
    A**(chi+1)`` in micro-slip). Derivatives: ``dD/dA = 4 R a^(chi+2)/(chi+2) + 4 S
    phi_max [A > phi_max]`` (``a = min(A, phi_max)``), ``d rho/dA = -rho/A`` in
    macro-slip, ``d I_rho(3/2,3/2)/d rho = (8/pi) sqrt(rho (1-rho))``,
    ``d B(rho; a, 3/2)/d rho = rho^(a-1) sqrt(1-rho)``. With ``micro_shortcut`` (the
    solvers' default) a call whose amplitudes are all in micro-slip uses the closed
    forms at ``rho = 1`` (no incomplete Beta functions; equal to rounding);
    :func:`describing_function` evaluates the general form everywhere.
    """
    chi, pm = J.chi, J.phi_max
    A = np.maximum(np.asarray(A, dtype=float), 1e-300)
    macro = A > pm
    if micro_shortcut and not macro.any():   # micro-slip everywhere: rho = 1
        Apow = A ** (chi + 1.0)
        k_in = J.K_T - J.c_in * J.beta_ab * Apow
        k_q = J.q_micro * Apow
        return k_in, k_q, (chi + 1.0) * (k_in - J.K_T) / A, (chi + 1.0) * k_q / A
    rho = np.where(macro, pm / A, 1.0)
    inc = special.betainc(J.a, 1.5, rho) * J.beta_ab
    g = slider_in_phase(rho)
    Apow = A ** (chi + 1.0)
    k_in = J.K_T * g - J.c_in * Apow * inc
    a = np.minimum(A, pm)
    D = 4.0 * J.R * (A * a ** (chi + 2.0) / (chi + 2.0) - a ** (chi + 3.0) / (chi + 3.0))
    D = D + np.where(macro, 4.0 * J.S * pm * (A - pm), 0.0)
    with np.errstate(over="ignore"):  # A*A overflows above 1.3e154 m: divide twice there
        k_q = np.where(A < 1e150, D / (np.pi * A * A), D / (np.pi * A) / A)
        dD = 4.0 * J.R * a ** (chi + 2.0) / (chi + 2.0) + np.where(macro, 4.0 * J.S * pm, 0.0)
        dk_q = np.where(A < 1e150, (dD - 2.0 * D / A) / (np.pi * A * A),
                        (dD - 2.0 * D / A) / (np.pi * A) / A)
    one_m = np.maximum(1.0 - rho, 0.0)
    drho = -rho / A
    dg = (8.0 / np.pi) * np.sqrt(rho * one_m)
    dinc = rho ** (J.a - 1.0) * np.sqrt(one_m)
    dk_in = (J.K_T * dg * drho
             - J.c_in * ((chi + 1.0) * Apow / A * inc + Apow * dinc * drho))
    return k_in, k_q, dk_in, dk_q


def kappa1(R: float, chi: float) -> float:
    """Paper eq. (A15): ``kappa1 = -4 R / (pi (chi+2)(chi+3))`` (exact, N m^-(chi+2))."""
    return -4.0 * R / (np.pi * (chi + 2.0) * (chi + 3.0))


def kappa2_exact(R: float, chi: float) -> float:
    """Exact micro-slip coefficient of the in-phase force, paper eq. (14).

    ``kappa2 = 4 R B(chi+5/2, 1/2) / (pi (chi+1)(chi+3))`` with ``B`` the Euler Beta
    function: from paper eq. (11), ``b1 = (2 gamma1/pi) I(n)``, ``n = chi+2``,
    ``I(n) = int_{-pi/2}^{pi/2} (1+sin t)^n sin t dt = 2^n B(n+1/2, 1/2) n/(n+1)``.
    ``kappa2 -> R/2`` as ``chi -> 0``.
    """
    return 4.0 * R * special.beta(chi + 2.5, 0.5) / (np.pi * (chi + 1.0) * (chi + 3.0))


def _Q_b(chi: float) -> float:
    """Paper eq. (A12), constants 1.7071 and 0.2929 as printed."""
    n = chi + 2.0
    hi, lo = 1.7071, 0.2929
    s2 = math.sqrt(2.0)
    c3 = n * np.pi ** 3 / 384.0
    return ((hi ** n - lo ** n) * (1.0 / (2.0 * s2) - np.pi ** 2 / (192.0 * s2)) * np.pi
            + c3 * (hi ** (n - 1.0) - lo ** (n - 1.0))
            + c3 * (chi + 1.0) * (hi ** chi - lo ** chi))


def kappa2_paper(R: float, chi: float) -> float:
    """The paper's kappa2, eq. (A15) with ``Q_b`` exactly as printed in (A12).

    ``kappa2 = R 2**(-chi) Q_b(chi) / (pi (chi+1)(chi+2))``. Kept to reproduce the
    paper; use :func:`kappa2_exact` otherwise. It is 7.55 % below the exact value at
    chi = -0.5 (3.0 % at chi -> 0, 9.9 % at chi = -0.9). Of that, about 0.9 % is the
    three-term Taylor series itself; the rest are two slips in the printed ``Q_b``:
    its second term should read ``(1.7071**(chi+1) + 0.2929**(chi+1))`` and its third
    term lacks a factor ``1/sqrt(2)`` (checked against a numerical re-derivation in
    ``tests/test_iwan.py``).
    """
    return R * 2.0 ** (-chi) * _Q_b(chi) / (np.pi * (chi + 1.0) * (chi + 2.0))
