"""Nonlinear modes by the extended periodic motion concept (EPMC, Krack 2015).

Krack, "Nonlinear modal analysis of nonconservative systems: extension of the periodic
motion concept", Comput. Struct. 154 (2015) 59. The autonomous system of the reduced
model (:mod:`fe.reduction`, paper eq. 25) gets an artificial negative viscous term
``-xi M q'`` that balances the dissipation, so that its damped free vibration becomes
periodic (Krack 2015, eq. 3)::

    M q'' + (C - xi M) q' + K_J q + G^T g(G q) = 0.

Harmonic balance: ``q(t) = Re sum_h a Psi_h e^{i h w t}`` over the harmonics of the
joint path (:mod:`fe.joint_harmonics`), with the amplitude ``a`` as the continuation
parameter and ``Psi`` normalized by one complex linear functional ``L`` (Krack 2015,
eq. 7-8, amplitude and phase normalization in one): ``L Psi_1 = 1``, i.e. ``Re L Psi_1
= 1`` and ``Im L Psi_1 = 0``. Three functionals (:func:`amplitude_functional`):

* ``"modal"``: ``L = phi^T M``, ``a`` is the projection of the first harmonic on the
  mass-normalized linear mode ``phi`` (kg^1/2 m);
* ``"slip"``: ``L = g_ref``, the slip row of the joint that slips most in ``phi``:
  ``a`` is that joint's first-harmonic slip amplitude (m);
* an integer DOF ``d``: ``L`` = row ``d`` of the basis, ``a`` is the first-harmonic
  displacement amplitude there (m), e.g. the drive point.

Per harmonic ``h`` the equations are ``D_h(w, xi) Psi_h + G^T G_h(a G Psi)/a = 0`` with
``D_h = K_J - (h w)^2 M + i h w (C - xi M)`` and ``G_h`` the harmonics of ``g``; with the
two normalization equations they are square in ``(Psi, w, xi)`` and solved by Newton's
method with the exact Jacobian. The damping ratio is (Krack 2015, eq. 8)

    zeta = xi / (2 w),                                                          (1)

which for a linear structure with proportional damping is the modal damping ratio of
the mode (independent of how ``Psi`` is scaled, because the artificial term is
proportional to ``M``); with joints it is ``c_n/(2 w) + Delta c/(2 w^2)`` (eq. 2 of
:mod:`inverse.iwan_modal`). SI units: rad/s, 1/s, m.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as la

from fe.backbone import Backbone
from fe.newton_path import SteadyStateError, damped_newton
from fe.reduction import ReducedModel

__all__ = ["linear_mode", "amplitude_functional", "solve_epmc", "epmc_backbone"]


def linear_mode(model: ReducedModel, mode: int):
    """Stuck-joint mode ``mode`` (1-based) of ``(K, M)``: ``(omega (rad/s), phi)`` with
    ``phi^T M phi = 1``, largest component positive."""
    lam, V = la.eigh(model.K, model.M)
    if not 1 <= int(mode) <= lam.size:
        raise ValueError(f"mode must be in 1..{lam.size}, got {mode}")
    phi = V[:, int(mode) - 1]
    phi = phi / np.sqrt(phi @ model.M @ phi)
    phi = phi * np.sign(phi[np.argmax(np.abs(phi))])
    return float(np.sqrt(max(lam[int(mode) - 1], 0.0))), phi


def amplitude_functional(model: ReducedModel, phi, at="slip") -> np.ndarray:
    """The row ``L`` (r,) of the normalization ``L Psi_1 = 1`` (module docstring), signed
    so that ``L phi > 0``."""
    if isinstance(at, str):
        if at == "modal":
            L = model.M @ phi
        elif at == "slip":
            gphi = model.G @ phi
            if np.abs(gphi).max() <= 1e-9 * np.abs(model.G).max() * np.abs(phi).max():
                raise ValueError("the mode does not slip the joints (G phi = 0): it has no "
                                 "slip amplitude and no joint nonlinearity")
            L = model.G[int(np.argmax(np.abs(gphi)))]
        else:
            raise ValueError(f"unknown amplitude {at!r} (modal, slip or a DOF index)")
    else:
        L = model.basis[int(at)]
    L = np.asarray(L, dtype=float)
    s = float(L @ phi)
    if abs(s) < 1e-12 * np.linalg.norm(L) * np.linalg.norm(phi):
        raise ValueError(f"the amplitude {at!r} does not see the mode (L phi = 0)")
    return L * np.sign(s)


class _EPMCSystem:
    """Residual and Jacobian of the EPMC equations in real form, unknowns
    ``z = [Y (n_c, r) row-major, w, xi]`` with ``Y`` the real coefficients of ``Psi``."""

    def __init__(self, model: ReducedModel, joints, L):
        self.M, self.K, self.C, self.G = model.M, model.K, model.C, model.G
        self.joints = joints
        self.h = np.asarray(joints.harmonics)
        self.r = model.n_reduced
        self.nc = joints.nc
        self.m = self.nc * self.r
        self.L = L

    def evaluate(self, z, a):
        r, nc, m = self.r, self.nc, self.m
        M, K, C, G = self.M, self.K, self.C, self.G
        Y = z[:m].reshape(nc, r)
        w, xi = z[m], z[m + 1]
        G_h, J_g, amp = self.joints(a * (Y @ G.T))
        res = np.empty(m + 2)
        Jac = np.zeros((m + 2, m + 2))
        F = (G_h @ G) / a                                   # (n_c, r): G^T g_h / a
        Cx = C - xi * M
        for k, h in enumerate(self.h):
            re, im = slice(2 * k * r, (2 * k + 1) * r), slice((2 * k + 1) * r, (2 * k + 2) * r)
            xr, xq = Y[2 * k], Y[2 * k + 1]
            A = K - (h * w) ** 2 * M
            B = h * w * Cx
            res[re] = A @ xr - B @ xq + F[2 * k]
            res[im] = B @ xr + A @ xq + F[2 * k + 1]
            Jac[re, re], Jac[re, im], Jac[im, re], Jac[im, im] = A, -B, B, A
            dA, dB = -2.0 * h * h * w * M, h * Cx               # d/dw
            Jac[re, m] = dA @ xr - dB @ xq
            Jac[im, m] = dB @ xr + dA @ xq
            Mx = h * w * M                                      # d/dxi: dB = -h w M
            Jac[re, m + 1] = Mx @ xq
            Jac[im, m + 1] = -Mx @ xr
        # joints: dF[c, i]/dY[d, k] = sum_l G[l, i] J_g[l, c, d] G[l, k]
        Jac[:m, :m] += np.einsum("li,lcd,lk->cidk", G, J_g, G, optimize=True).reshape(m, m)
        res[m] = self.L @ Y[0] - 1.0
        res[m + 1] = self.L @ Y[1]
        Jac[m, :r] = self.L
        Jac[m + 1, r:2 * r] = self.L
        return res, Jac, amp

    def newton(self, z, a, tol, max_iter):
        """:func:`fe.newton_path.damped_newton` at amplitude ``a`` from ``z``: ``(z, it,
        upd)``, or ``(None, max_iter, inf)`` when it fails (the reason in ``self.failure``)."""
        m = self.m

        def relative_update(zn, dz):
            return max(np.abs(dz[:m]).max() / max(np.abs(zn[:m]).max(), 1e-300),
                       abs(dz[m]) / abs(zn[m]), abs(dz[m + 1]) / abs(zn[m]))

        try:
            return damped_newton(lambda x: self.evaluate(x, a)[:2], z, tol, max_iter, 1.0,
                                 relative_update=relative_update,
                                 admissible=lambda x: x[m] > 0)[:3]
        except SteadyStateError as exc:
            self.failure = exc.reason
            return None, max_iter, np.inf


def _start(model, joints, omega0, phi, L):
    """Linear-mode start: ``Psi_1 = phi / (L phi)``, ``w`` the stuck-joint frequency and
    ``xi = phi^T C phi`` (exact for proportional damping)."""
    r, nc = model.n_reduced, joints.nc
    z = np.zeros(nc * r + 2)
    z[:r] = phi / (L @ phi)
    z[nc * r] = omega0
    z[nc * r + 1] = float(phi @ model.C @ phi)
    return z


def solve_epmc(model: ReducedModel, joints, mode: int, amplitude: float, at="slip",
               guess=None, tol: float = 1e-11, max_iter: int = 40):
    """One point of the nonlinear mode ``mode`` at amplitude ``a`` (module docstring).

    Returns
    -------
    Backbone
        With one point.
    """
    return epmc_backbone(model, joints, mode, [amplitude], at=at, tol=tol,
                         max_iter=max_iter, _guess=guess)


def epmc_backbone(model: ReducedModel, joints, mode: int, amplitudes, at="slip",
                  tol: float = 1e-11, max_iter: int = 40, max_halvings: int = 10,
                  progress=None, _guess=None) -> Backbone:
    """The backbone of nonlinear mode ``mode``: continuation over ``amplitudes``.

    Parameters
    ----------
    model : ReducedModel
    joints : fe.joint_harmonics.BankHarmonics or ExactHarmonics
        The joint path (its harmonics are the harmonics of the balance).
    mode : int
        1-based stuck-joint mode of ``(K, M)`` the branch starts from.
    amplitudes : array_like
        Values of ``a`` (positive, ascending), in the unit of ``at``.
    at : {"slip", "modal"} or int
        The amplitude normalization (module docstring).
    tol : float
        Bound on the relative Newton update of ``Psi``, ``w`` and ``xi``.
    max_halvings : int
        A point whose Newton iteration fails from the secant predictor is reached by
        halving the step in ``log a`` (up to this many times).
    progress : tqdm bar or None (one tick per point).

    Returns
    -------
    Backbone
    """
    a_all = np.asarray(amplitudes, dtype=float).ravel()
    if a_all.size == 0 or np.any(~(a_all > 0)) or np.any(~np.isfinite(a_all)):
        raise ValueError("amplitudes must be finite and > 0")
    if np.any(np.diff(a_all) <= 0):
        raise ValueError("amplitudes must increase")
    omega0, phi = linear_mode(model, mode)
    L = amplitude_functional(model, phi, at)
    system = _EPMCSystem(model, joints, L)
    z0 = _start(model, joints, omega0, phi, L) if _guess is None else np.asarray(_guess)
    hist: list[tuple[float, np.ndarray]] = []      # (log a, z) of converged points
    points = []

    def predict(la_t):
        if not hist:
            return z0
        if len(hist) == 1:
            return hist[-1][1]
        (l1, z1), (l2, z2) = hist[-2], hist[-1]
        return z2 + (la_t - l2) / (l2 - l1) * (z2 - z1)

    for a in a_all:
        target = np.log(a)
        todo = [target]
        fallbacks = 0
        while todo:
            lt = todo[-1]
            z, it, upd = system.newton(predict(lt), np.exp(lt), tol, max_iter)
            if z is None and hist:
                fallbacks += 1          # restart from the last converged point
                z, it, upd = system.newton(hist[-1][1], np.exp(lt), tol, max_iter)
            if z is None:
                last = hist[-1][0] if hist else None
                if last is None or len(todo) > max_halvings:
                    raise SteadyStateError(f"amplitude {np.exp(lt):.4g}",
                                           f"{system.failure} (mode {mode})", solver="EPMC")
                fallbacks += 1          # halve the step in log a
                todo.append(0.5 * (last + lt))
                continue
            hist.append((lt, z))
            todo.pop()
        Y = z[:system.m].reshape(system.nc, system.r)
        _, _, slip = joints(a * (Y @ model.G.T), jacobian=False)
        points.append((a, z, slip, it, fallbacks))
        if progress is not None:
            progress.update(1)
    return Backbone.from_solutions(model, joints, mode, at, L, phi, omega0, points)
