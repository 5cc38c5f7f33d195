"""First-harmonic balance of many force levels at once: steady states and phase resonance.

The condensed first-harmonic equations of :mod:`fe.harmonic_balance` and
:mod:`fe.hb_exact` (any joint law through its describing function, :mod:`joints.law`;
continuous Iwan joints for Iwan parameters), solved for all force levels of a
stepped-sine campaign in one vectorized Newton iteration, on a reduced model in modal
form (``M = I``, ``K`` and ``C`` diagonal, as :func:`fe.reduction.ritz_basis` builds
it), where ``D(w) = diag(a k_r - w^2 + i w c_r)`` is inverted element by element.
Besides the joints (slips ``S = G q``) the balance carries extra first-harmonic
*elements* on reduced coordinates ``Z = H q`` (:class:`CubicSpring`,
:class:`QuadraticDamper`), and a per-level stiffness scale ``a`` (structure and joints
alike: ``K -> a K``, joint force ``-> a`` times). With ``Y = [S; Z]``, ``X = [G; H]``
and the describing-function force ``N(Y)`` (``a (k_in - K_T + i k_q) S`` for the
joints, ``(k_in + i k_q) Z`` for the elements)::

    Y = X D^-1 p - X D^-1 X^T N(Y),      q = D^-1 (p - X^T N(Y)).                (1)

:func:`resonance_levels` finds, per level, the phase resonance of one mode ``k`` of the
basis: the frequency where the modal-filter dynamic stiffness ``D_k = phi_d F / q_k``
(``phi_d = p_k``, the mode's drive-point value; ``q_k = phi^T M x`` is the mode's modal
filter, :mod:`ident.modal_filter`) is purely imaginary, i.e. ``Re q_k = 0``; there
``omega2 = w^2`` and ``zeta = Im D_k / (2 w^2)``: the mode's natural frequency and
damping ratio at that level as the stepped-sine test sees them (for a linear modally
damped structure exactly ``omega_k^2`` and its ``zeta``). The frequency is found by the
secant method on ``Re D_k``, each step a warm-started Newton solve of (1).
:func:`fe.hb_batch.resonance_batch` solves many such problems at once, by Newton's
method on (1) and the phase condition together where a guess is at hand.
:func:`frf_levels` sweeps frequency lines (natural continuation) for simulated FRFs.
SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fe.newton_path import (ARMIJO, MIN_DAMPING, ROUNDOFF, STALL_FACTOR, SteadyStateError,
                            stall_words)
from fe.reduction import ReducedModel
from joints.describing import IwanJoints, as_joint_law, iwan_describing
from joints.law import describing_force

__all__ = ["CubicSpring", "QuadraticDamper", "ResonanceLevels", "resonance_levels",
           "frf_levels"]


@dataclass(frozen=True)
class CubicSpring:
    """Cubic springs ``f = k3 z^3`` on coordinates ``z = rows q``: first harmonic
    ``k_in = 3/4 k3 A^2`` (exact for one harmonic), ``k_q = 0``.

    rows : (n_e, r); k3 : (n_e,) N/m^3 in the units of ``z``."""

    rows: np.ndarray
    k3: np.ndarray

    def df(self, A, omega):
        k_in = 0.75 * self.k3 * A * A
        z = np.zeros_like(A)
        return k_in, z, 1.5 * self.k3 * A, z


@dataclass(frozen=True)
class QuadraticDamper:
    """Quadratic dampers ``f = c2 |z'| z'`` on ``z = rows q``: first harmonic
    ``k_q = 8 c2 w^2 A / (3 pi)`` (the equivalent viscous damping ``8 c2 w A/(3 pi)``
    times ``w``), ``k_in = 0``.

    rows : (n_e, r); c2 : (n_e,) N s^2/m^2 in the units of ``z``."""

    rows: np.ndarray
    c2: np.ndarray

    def df(self, A, omega):
        c = (8.0 / (3.0 * np.pi)) * self.c2 * omega[:, None] ** 2
        z = np.zeros_like(A)
        return z, c * A, z, c + z


@dataclass
class ResonanceLevels:
    """Per level at phase resonance: ``omega`` (rad/s), ``omega2``, ``zeta``, the slip
    harmonics ``slip`` (L, n_joints) complex and amplitudes ``slip_amplitude`` (m), the
    element amplitudes ``element_amplitude`` (L, n_e) and harmonics
    ``element_harmonics``, reduced response ``q`` (L, r), secant steps and Newton
    iterations (total), and per level how its steady state was reached when not by an
    ordinary Newton convergence (``fallbacks``, empty strings otherwise; a last Newton
    step accepted at round-off, :func:`fe.newton_path.stall_words`)."""

    omega: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    slip: np.ndarray
    slip_amplitude: np.ndarray
    element_amplitude: np.ndarray
    q: np.ndarray
    secant_steps: int
    newton_iterations: int
    element_harmonics: np.ndarray | None = None
    fallbacks: list | None = None


#: The Iwan parameters :func:`joints.describing.iwan_describing` reads; each element's.
_IWAN = ("chi", "K_T", "R", "S", "phi_max", "a", "beta_ab", "c_in", "q_micro")
_COEF = {CubicSpring: "k3", QuadraticDamper: "c2"}


class _PerLevel:
    """Iwan parameters (:data:`_IWAN`) per level, (L, nj) views of one (L, 9 nj) block."""

    def __init__(self, block, nj: int):
        self.block, self.nj = block, nj
        for i, n in enumerate(_IWAN):
            setattr(self, n, block[:, i * nj:(i + 1) * nj])

    def take(self, idx) -> "_PerLevel":
        return _PerLevel(self.block[idx], self.nj)


def _per_level(e, rows):
    return replace(e, **{_COEF[type(e)]: rows})      # element e, its coefficient per level


class _Balance:
    """The condensed equations (1) of every level (vectorized over levels), every
    quantity row by row (coefficients and damping held per level). Levels may come in
    *groups* (``group``, ``starts``: the problems :func:`fe.hb_batch.resonance_batch`
    stacks), each taking the describing function's micro-slip shortcut as its own call
    would. ``like``: a balance of the same model, load and rows (its checks reused)."""

    def __init__(self, model: ReducedModel, joints, load, forces, scale, elements, like=None):
        M, K, C, r = model.M, model.K, model.C, model.n_reduced
        rows = (model.G, load) + tuple(np.atleast_2d(e.rows) for e in elements)

        def off(A):                      # largest off-diagonal term (0 for a diagonal A)
            return 0.0 if np.count_nonzero(A) == np.count_nonzero(np.diagonal(A)) else \
                np.abs(A - np.diag(np.diag(A))).max()

        same = like is not None and len(rows) == len(like.source) - 2 and \
            all(a is b for a, b in zip((M, K) + rows[:2], like.source)) and \
            all(np.array_equal(a, b) for a, b in zip(rows[2:], like.source[4:]))
        if (not same and (off(M) > 1e-12 or off(K) > 1e-9 * np.abs(np.diag(K)).max()
                          or np.abs(np.diag(M) - 1.0).max() > 1e-10)
                or off(C) > 1e-9 * max(np.abs(np.diag(C)).max(), 1e-300)):
            raise ValueError("the batched first-harmonic balance needs a reduced model in "
                             "modal form (M = I, K and C diagonal): fe.reduction.ritz_basis")
        self.source, self.c, self.joints = (M, K) + rows, np.diag(C).copy(), joints
        again = same and joints is like.joints        # the same joints: their law again
        self.J = like.J if again else as_joint_law(joints, model.n_joints)
        if np.any(np.abs(self.J.K_T - model.K_T) > 1e-9 * np.abs(model.K_T)):
            raise ValueError("joint stiffness does not match the model's K_T")
        if same:
            self.k, self.X, self.XX, self.p = like.k, like.X, like.XX, like.p
        else:
            self.k, self.X = np.diag(K).copy(), np.vstack((np.asarray(model.G, float),) + rows[2:])
            if self.X.shape[1] != r:
                raise ValueError(f"element rows must have {r} columns")
            ny = self.X.shape[0]       # R = X D^-1 X^T from XX[r, i ny + j] = X_ir X_jr
            self.XX = (self.X[:, None, :] * self.X[None, :, :]).reshape(ny * ny, r).T.copy()
            self.p = np.asarray(load, dtype=float).reshape(r)
        self.nj, self.ny = model.n_joints, self.X.shape[0]
        self.F = np.atleast_1d(np.asarray(forces, dtype=float))
        L = self.F.size
        self.a = np.ones(L) if scale is None else np.broadcast_to(
            np.asarray(scale, dtype=float), (L,)).copy()
        self.L, self.group, self.starts = L, np.zeros(L, dtype=int), np.zeros(1, dtype=int)
        self.cl = np.broadcast_to(self.c, (L, r))                    # damping per level
        self.law = like.law if again and like.L == L else _PerLevel(np.tile(np.concatenate(
            [getattr(self.J, n) for n in _IWAN]), (L, 1)), self.nj) \
            if isinstance(self.J, IwanJoints) else None
        self.elements = [_per_level(e, np.tile(getattr(e, _COEF[type(e)]), (L, 1)))
                         if type(e) in _COEF else e for e in elements]

    def whole(self, flag, every: bool = True) -> np.ndarray:
        """Per level: ``flag`` holds at every (``every``) or at some level of its group."""
        if self.starts.size == 1:
            return np.full(self.L, flag.all() if every else flag.any())
        g = (np.logical_and if every else np.logical_or).reduceat(flag, self.starts)
        return np.repeat(g, np.diff(self.starts, append=self.L))

    def operator(self, omega):
        """``R = X D^-1 X^T`` (L, ny, ny), ``Y_lin`` (L, ny), ``1/D`` (L, r)."""
        Dinv = 1.0 / (self.a[:, None] * self.k[None] - (omega ** 2)[:, None]
                      + 1j * omega[:, None] * self.cl)
        ny, Dp = self.ny, Dinv * self.p
        R, Ylin = np.empty((self.L, ny * ny), complex), np.empty((self.L, ny), complex)
        R.real, R.imag = Dinv.real @ self.XX, Dinv.imag @ self.XX
        Ylin.real, Ylin.imag = Dp.real @ self.X.T, Dp.imag @ self.X.T
        return R.reshape(self.L, ny, ny), Ylin * self.F[:, None], Dinv

    def _joint_df(self, A):
        """The joints' ``describing_derivative`` at ``A`` (L, nj), Iwan's micro-slip
        shortcut taken (or not) group by group, as each group's own call would."""
        if self.law is None:
            return self.J.describing_derivative(A)
        macro = self.whole(np.any(A > self.law.phi_max, axis=1), every=False)
        if macro.all() or not macro.any():
            return iwan_describing(self.law, A)
        out = [np.empty_like(A) for _ in range(4)]
        for rows in (macro, ~macro):
            for o, v in zip(out, iwan_describing(self.law.take(rows), A[rows])):
                o[rows] = v
        return out

    def force(self, Y, omega):
        """``N(Y)`` and its derivatives ``dN/dRe Y``, ``dN/dIm Y`` (each (L, ny))."""
        A = np.maximum(np.abs(Y), 1e-300)
        nj = self.nj
        kin, kq, dkin, dkq = (np.empty_like(A) for _ in range(4))
        ki, qj, dki, dqj = self._joint_df(A[:, :nj])
        a = self.a[:, None]
        kin[:, :nj] = a * (ki - (self.J.K_T if self.law is None else self.law.K_T))
        kq[:, :nj] = a * qj
        dkin[:, :nj] = a * dki
        dkq[:, :nj] = a * dqj
        c = nj
        for e in self.elements:
            n = np.atleast_2d(e.rows).shape[0]
            kin[:, c:c + n], kq[:, c:c + n], dkin[:, c:c + n], dkq[:, c:c + n] = \
                e.df(A[:, c:c + n], omega)
            c += n
        return describing_force(kin + 1j * kq, dkin + 1j * dkq, Y, A)

    def residual(self, Y, R, Ylin, omega):
        """Residual of (1), ``N`` and its derivatives, and the size of the residual's
        largest term per level (its round-off scale)."""
        N, dx, dy = self.force(Y, omega)
        RN = np.einsum("lij,lj->li", R, N)
        size = np.maximum(np.abs(Y).max(axis=1), np.abs(RN).max(axis=1))
        return Y - Ylin + RN, N, dx, dy, size

    def jacobian(self, R, dx, dy, extra: int = 0):
        """``d(Re, Im (1))/d(Re Y, Im Y)``, ``extra`` rows and columns left to fill."""
        ny, n = self.ny, 2 * self.ny + extra
        Ra, Rb, eye = R * dx[:, None, :], R * dy[:, None, :], np.eye(ny)
        Jac = np.empty((self.L, n, n))
        Jac[:, :ny, :ny] = eye + Ra.real
        Jac[:, :ny, ny:2 * ny] = Rb.real
        Jac[:, ny:2 * ny, :ny] = Ra.imag
        Jac[:, ny:2 * ny, ny:2 * ny] = eye + Rb.imag
        return Jac

    def solve(self, omega, Y, tol, max_iter):
        """Newton on (1) at ``omega`` (L,) from ``Y`` (L, ny), globalized level by level
        with the line search of :func:`fe.newton_path.damped_newton` (deep macro-slip
        from a linear guess); returns Y, N, Dinv, iterations and the relative update of
        each level's last Newton step (L,) (at or above ``tol`` where accepted at
        round-off, :data:`fe.newton_path.STALL_FACTOR`). Raises
        :class:`fe.newton_path.SteadyStateError` where a level's line search stalls."""
        R, Ylin, Dinv = self.operator(omega)
        ny = self.ny
        scale = np.maximum(np.abs(Ylin).max(axis=1), 1e-300)
        res, N, dx, dy, size = self.residual(Y, R, Ylin, omega)
        for it in range(1, max_iter + 1):
            d = np.linalg.solve(self.jacobian(R, dx, dy),
                                -np.concatenate([res.real, res.imag], axis=1)[..., None])
            step = d[:, :ny, 0] + 1j * d[:, ny:, 0]
            norm = np.linalg.norm(res, axis=1)
            lam = np.ones(self.L)
            # the line search of fe.newton_path.damped_newton, level by level: halve
            # where the residual norm does not fall by ARMIJO lam; a residual already at
            # round-off of its largest term takes the full step; below MIN_DAMPING the
            # level has stalled
            floor = norm <= ROUNDOFF * np.sqrt(ny) * size
            while True:
                Yt = Y + lam[:, None] * step
                rt, Nt, dxt, dyt, st = self.residual(Yt, R, Ylin, omega)
                bad = np.linalg.norm(rt, axis=1) > norm * (1.0 - ARMIJO * lam) + 1e-300
                bad &= np.abs(step).max(axis=1) > tol * np.abs(Y).max(axis=1)
                bad &= ~(floor & (lam == 1.0))
                if not bad.any():
                    break
                if np.any(bad & (0.5 * lam < MIN_DAMPING)):
                    raise SteadyStateError(
                        f"{np.asarray(omega).max() / (2 * np.pi):.6g} Hz",
                        f"line search stalled after {it} iterations at "
                        f"{int(np.count_nonzero(bad))} of {self.L} levels",
                        solver="first-harmonic balance")
                lam = np.where(bad, 0.5 * lam, lam)
            Y, res, N, dx, dy, size = Yt, rt, Nt, dxt, dyt, st
            upd = np.abs(step).max(axis=1) / np.maximum(np.abs(Y).max(axis=1), 1e-12 * scale)
            # converged: the full Newton step is negligible, or within STALL_FACTOR tol
            # and no step along it lowers the residual any more (round-off floor)
            if np.all((upd < tol) | ((upd < STALL_FACTOR * tol) & ((lam < 1.0) | floor))):
                return Y, N, Dinv, it, upd
        raise RuntimeError(f"first-harmonic balance did not converge at "
                           f"{np.asarray(omega).max() / (2 * np.pi):.4g} Hz (relative update "
                           f"{upd.max():.2e} after {max_iter} iterations)")

    def response(self, N, Dinv):
        """Reduced response ``q = D^-1 (F p - X^T N)`` (L, r)."""
        return Dinv * (self.F[:, None] * self.p[None] - N @ self.X)


def _resonate(b: _Balance, k: int, w0, Y, tol, max_secant, max_newton) -> ResonanceLevels:
    """The phase resonances of the levels of ``b`` from ``w0``, ``Y`` (module docstring)."""
    Y, N, Dinv, its, _ = b.solve(w0, Y, tol, max_newton)

    def re_dk(N, Dinv):
        """``Re D_k`` (rad^2/s^2); ``~ omega_eff^2 - w^2`` near the resonance."""
        return (b.p[k] * b.F / b.response(N, Dinv)[:, k]).real

    g0 = re_dk(N, Dinv)
    # first step: w^2 + Re D_k (exact for a linear single mode), then secant steps
    w1 = np.sqrt(np.maximum(w0 ** 2 + g0, (0.9 * w0) ** 2))
    w1 = np.where(w1 == w0, w0 * (1.0 - 1e-7), w1)
    Y1, N, Dinv, it, upd = b.solve(w1, Y, tol, max_newton)
    its += it
    g1 = re_dk(N, Dinv)
    steps = 1
    for steps in range(2, max_secant + 1):
        dg = g1 - g0
        secant = np.where(dg == 0.0, 0.0, -g1 * (w1 - w0) / np.where(dg == 0.0, 1.0, dg))
        step = np.clip(secant, -0.05 * w1, 0.05 * w1)
        w0, g0, Y = w1, g1, Y1
        w1 = w1 + step
        Y1, N, Dinv, it, upd = b.solve(w1, Y, tol, max_newton)
        its += it
        g1 = re_dk(N, Dinv)
        if np.all(np.abs(step) <= tol * w1):
            break
    else:
        raise RuntimeError(f"phase resonance not found in {max_secant} secant steps")
    q = b.response(N, Dinv)
    Dk = b.p[k] * b.F / q[:, k]
    A = np.abs(Y1)
    return ResonanceLevels(omega=w1, omega2=w1 ** 2, zeta=Dk.imag / (2.0 * w1 ** 2),
                           slip=Y1[:, :b.nj], slip_amplitude=A[:, :b.nj],
                           element_amplitude=A[:, b.nj:], q=q, secant_steps=steps,
                           newton_iterations=its, element_harmonics=Y1[:, b.nj:],
                           fallbacks=[stall_words(u, tol) for u in upd])


def resonance_levels(model: ReducedModel, joints, load, forces, mode_index: int,
                     scale=None, elements=(), tol: float = 1e-12,
                     max_secant: int = 40, max_newton: int = 100,
                     guess: ResonanceLevels | None = None) -> ResonanceLevels:
    """Phase resonance of basis vector ``mode_index`` at every force level (module
    docstring, eq. 1).

    Parameters
    ----------
    model : ReducedModel
        Modal form (:func:`fe.reduction.ritz_basis`).
    joints : joints.law.JointLaw, or IwanParameters (one per joint or one shared);
        ``K_T`` = ``model.K_T``.
    load : (r,) reduced unit load ``Phi^T f`` (real).
    forces : (L,) force amplitudes (N).
    mode_index : int
        0-based basis vector whose modal filter defines the resonance.
    scale : (L,) or float, optional
        Stiffness scale ``a`` per level (default 1).
    elements : sequence of :class:`CubicSpring` / :class:`QuadraticDamper`
    tol : float
        Bound on the relative Newton update and on the relative frequency step.
    guess : ResonanceLevels, optional
        A previous solution of a nearby problem (same levels and elements): its
        frequencies and harmonics start the search (the answer is the same to ``tol``).

    Returns
    -------
    ResonanceLevels
    """
    b = _Balance(model, joints, load, forces, scale, elements)
    k = int(mode_index)
    if abs(b.p[k]) == 0.0:
        raise ValueError(f"the load does not excite basis vector {k}")
    if guess is not None and guess.q.shape == (b.L, b.p.size) and \
            guess.element_amplitude.shape[1] == b.ny - b.nj:
        w0 = guess.omega.copy()
        Y0 = np.concatenate([guess.slip, guess.element_harmonics], axis=1)
    else:
        w0 = np.sqrt(b.a * b.k[k])
        Y0 = b.operator(w0)[1]
    return _resonate(b, k, w0, Y0, tol, max_secant, max_newton)


def frf_levels(model: ReducedModel, joints, load, forces, omegas, scale=None,
               elements=(), tol: float = 1e-12, max_newton: int = 100):
    """Steady first-harmonic states of every level over the lines ``omegas`` (rad/s,
    swept in the given order, each line starting from the previous line's solution:
    natural continuation as in a stepped-sine test).

    Returns
    -------
    q : (L, n_lines, r) complex reduced response amplitudes (m per basis unit)
    slip_amplitude : (L, n_lines, n_joints) (m)
    """
    b = _Balance(model, joints, load, forces, scale, elements)
    omegas = np.asarray(omegas, dtype=float)
    q = np.empty((b.L, omegas.size, b.p.size), dtype=complex)
    amp = np.empty((b.L, omegas.size, b.nj))
    Y = None
    for i, w in enumerate(omegas):
        wl = np.full(b.L, w)
        Y = b.operator(wl)[1] if Y is None else Y
        Y, N, Dinv = b.solve(wl, Y, tol, max_newton)[:3]
        q[:, i] = b.response(N, Dinv)
        amp[:, i] = np.abs(Y[:, :b.nj])
    return q, amp
