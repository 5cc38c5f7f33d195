"""Periodic steady state by harmonic balance with alternating frequency-time (AFT).

Same model as :mod:`fe.newmark` (reduced basis, paper eq. 23-25)::

    M q'' + C q' + K_J q + G^T g(s) = Re(p e^{i w t}),   s = G q,   g = F(s) - K_T s.

Every signal is a truncated Fourier series ``x(t) = Re sum_h X_h e^{i h w t}`` over the
harmonics ``h`` kept (``X_0`` real). Because the nonlinearity acts only on the joint
slips, the harmonic equations are condensed exactly onto the slip harmonics::

    S_h = S_h^lin - R_h N_h(S),   R_h = G D_h^{-1} G^T,   S_h^lin = G D_h^{-1} p delta_{h1},
    D_h = K_J - (h w)^2 M + i h w C,

where ``N_h`` are the harmonics of ``g(s(t))``. AFT: the slips are synthesized at
``n_time`` instants of a period, the Jenkins banks (:mod:`joints.jenkins`) are
marched once around the periodic loop starting at the slip maximum (sliders that slip
in the loop start at ``s_max - phi``: the exact periodic state; the others at the
virgin position clipped to stay stuck), and ``N_h`` is the discrete Fourier transform of
``g``. Newton's method uses the exact Jacobian of the sampled Jenkins force: a stuck
slider's force ``k_i (s_n - x_i)`` depends on the current sample and on the sample at
which the slider last slipped (its anchor is ``s_m -+ phi_i``), so
``dF_n/ds_m = sum_stuck k_i (delta_nm - delta_{m, m_i(n)})`` — the tangent
``k_t = sum_stuck k_i`` on the diagonal plus the anchor terms. Physical response
harmonics follow as ``Q_h = D_h^{-1} (p delta_{h1} - G^T N_h)``.

SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fe.reduction import JointBank, ReducedModel
from joints.jenkins import jenkins_update
from numba import njit

__all__ = ["HBSettings", "HBSolution", "solve_hb", "continuation", "aft_joint_force"]


@dataclass(frozen=True)
class HBSettings:
    """Harmonics ``1..n_harmonics`` (odd ones only if ``odd_only``; add ``0`` with
    ``include_static``), ``n_time`` AFT samples per period, Newton tolerance on the
    relative slip update and iteration cap."""

    n_harmonics: int = 7
    n_time: int = 256
    odd_only: bool = True
    include_static: bool = False
    tol: float = 1e-10
    max_iter: int = 60

    def __post_init__(self):
        if self.n_harmonics < 1:
            raise ValueError("n_harmonics must be >= 1")
        if self.n_time < 2 * self.n_harmonics + 2:
            raise ValueError(f"n_time must be >= 2 n_harmonics + 2 = {2 * self.n_harmonics + 2}")

    @property
    def harmonics(self) -> np.ndarray:
        h = np.arange(1, self.n_harmonics + 1, 2 if self.odd_only else 1)
        return np.concatenate([[0], h]) if self.include_static else h


@dataclass
class HBSolution:
    """Converged periodic state at ``omega`` (rad/s).

    Attributes
    ----------
    harmonics : (n_h,) harmonic numbers.
    slip : (n_h, n_joints) complex slip harmonics ``S_h`` (m).
    joint_force : (n_h, n_joints) complex harmonics of ``g = F - K_T s`` (N).
    q : (n_h, r) complex reduced displacement harmonics.
    slip_amplitude : (n_joints,) half peak-to-peak slip over the period (m).
    iterations : Newton iterations; residual : final relative update.
    """

    omega: float
    harmonics: np.ndarray
    slip: np.ndarray
    joint_force: np.ndarray
    q: np.ndarray
    slip_amplitude: np.ndarray
    iterations: int
    residual: float

    def first_harmonic(self, model: ReducedModel) -> np.ndarray:
        """Physical first-harmonic displacement ``Phi Q_1`` (n,), complex (m)."""
        i1 = int(np.flatnonzero(self.harmonics == 1)[0])
        return model.expand(self.q[i1])


def _synthesis(harmonics, n_time):
    """Real synthesis ``E`` (n_time, n_c) and analysis ``P`` (n_c, n_time) matrices for
    the real unknowns ``[Re X_h, Im X_h]`` (``Im X_0`` dropped); ``P E = I``."""
    theta = 2 * np.pi * np.arange(n_time) / n_time
    cols, rows = [], []
    for h in harmonics:
        if h == 0:
            cols.append(np.ones(n_time))
            rows.append(np.ones(n_time) / n_time)
        else:
            c, s = np.cos(h * theta), np.sin(h * theta)
            cols += [c, -s]
            rows += [2 * c / n_time, -2 * s / n_time]
    return np.array(cols).T, np.array(rows)


def _to_real(X, harmonics):
    """Complex (n_h, m) -> real (n_c, m)."""
    parts = []
    for i, h in enumerate(harmonics):
        parts.append(X[i].real)
        if h != 0:
            parts.append(X[i].imag)
    return np.array(parts)


def _to_complex(y, harmonics):
    out = np.empty((len(harmonics),) + y.shape[1:], dtype=complex)
    j = 0
    for i, h in enumerate(harmonics):
        if h == 0:
            out[i] = y[j]
            j += 1
        else:
            out[i] = y[j] + 1j * y[j + 1]
            j += 2
    return out


def _aft_start(slip_t, k, phi):
    """Initial periodic slider state at the slip maximum (see module docstring)."""
    nj, N = slip_t.shape
    rows = np.arange(nj)
    i_max = np.argmax(slip_t, axis=1)
    i_min = np.argmin(slip_t, axis=1)
    s_max = slip_t[rows, i_max][:, None]
    s_min = slip_t[rows, i_min][:, None]
    in_loop = phi < 0.5 * (s_max - s_min)
    lo, hi = s_max - phi, s_min + phi
    anchor = np.where(in_loop, lo, np.clip(0.0, lo, np.maximum(lo, hi)))
    src = np.where(in_loop | (anchor == lo), i_max[:, None],
                   np.where(anchor == hi, i_min[:, None], -1))
    return anchor, src.astype(np.int64), i_max


@njit(cache=True)
def _aft_march(slip_t, k, phi, anchor, src, i_max, P, E, want_jac):
    """Compiled periodic march of the Jenkins banks (same return mapping as
    :func:`joints.jenkins.jenkins_update`). With ``want_jac`` also returns the
    harmonic Jacobian ``P (dF/ds) E`` per joint, where
    ``dF(t_n)/ds(t_m) = sum_stuck k_i (delta_nm - delta_{m, src_i(n)})``."""
    nj, N = slip_t.shape
    ns = k.shape[1]
    nc = E.shape[1]
    force = np.empty((nj, N))
    Jg = np.zeros((nj, nc, nc))
    row = np.empty(nc)
    x = anchor.copy()
    sr = src.copy()
    for j in range(nj):
        for step in range(N):
            n = (i_max[j] + step) % N
            s = slip_t[j, n]
            F = 0.0
            if want_jac:
                for d in range(nc):
                    row[d] = 0.0
            for i in range(ns):
                lo = s - phi[j, i]
                hi = s + phi[j, i]
                xi = x[j, i]
                xn = xi
                if xn < lo:
                    xn = lo
                if xn > hi:
                    xn = hi
                F += k[j, i] * (s - xn)
                if xn != xi:
                    sr[j, i] = n
                    x[j, i] = xn
                elif want_jac:
                    m = sr[j, i]
                    if m >= 0:
                        for d in range(nc):
                            row[d] += k[j, i] * (E[n, d] - E[m, d])
                    else:
                        for d in range(nc):
                            row[d] += k[j, i] * E[n, d]
            force[j, n] = F
            if want_jac:
                for c in range(nc):
                    pc = P[c, n]
                    for d in range(nc):
                        Jg[j, c, d] += pc * row[d]
    return force, Jg


def _dense_jacobian(slip_t, k, phi, anchor, src, i_max):
    """Reference (numpy) march returning the force and the dense time-domain Jacobian."""
    nj, N = slip_t.shape
    rows = np.arange(nj)
    order = (i_max[:, None] + np.arange(N)[None, :]) % N
    force = np.empty((nj, N))
    J = np.zeros((nj, N, N))
    for step in range(N):
        n = order[:, step]
        F, kt, new = jenkins_update(slip_t[rows, n], anchor, k, phi)
        force[rows, n] = F
        moved = new != anchor
        src = np.where(moved, n[:, None], src)
        w = np.where(moved, 0.0, k)
        J[rows, n, n] += w.sum(axis=1)
        for j in range(nj):
            has = (~moved[j]) & (src[j] >= 0)
            np.add.at(J[j, n[j]], src[j][has], -w[j][has])
        anchor = new
    return force, J


def aft_joint_force(slip_t: np.ndarray, bank: JointBank, P=None, E=None, compiled: bool = True):
    """Periodic Jenkins force for sampled periodic slips (one period).

    Parameters
    ----------
    slip_t : ndarray, shape (n_joints, n_time)
        Slip samples over one period (m).
    bank : JointBank
    P, E : ndarray, optional
        Analysis (n_c, n_time) and synthesis (n_time, n_c) matrices; when given, the
        harmonic Jacobian ``P dF/ds E`` (n_joints, n_c, n_c) is returned too.
    compiled : bool
        ``False`` uses the reference loop over :func:`joints.jenkins.jenkins_update` and
        returns the dense time-domain Jacobian ``dF_n/ds_m`` (n_joints, n_time,
        n_time) instead (for tests).

    Returns
    -------
    force : ndarray, shape (n_joints, n_time)
        Joint force ``F`` (N) on the periodic loop.
    jacobian : ndarray or None
    """
    slip_t = np.ascontiguousarray(slip_t, dtype=float)
    k, phi = bank.stiffness, bank.slip_limit
    anchor, src, i_max = _aft_start(slip_t, k, phi)
    if not compiled:
        return _dense_jacobian(slip_t, k, phi, anchor, src, i_max)
    want = P is not None
    if not want:
        P = np.zeros((1, slip_t.shape[1]))
        E = np.zeros((slip_t.shape[1], 1))
    force, Jg = _aft_march(slip_t, k, phi, anchor, src, i_max,
                           np.ascontiguousarray(P), np.ascontiguousarray(E), want)
    return force, (Jg if want else None)


class _HBOperator:
    """Frequency-dependent linear part of the condensed HB equations."""

    def __init__(self, model: ReducedModel, load, omega: float, settings: HBSettings):
        self.h = settings.harmonics
        w = omega * self.h
        D = (model.K[None] - (w ** 2)[:, None, None] * model.M[None]
             + 1j * w[:, None, None] * model.C[None])
        rhs = np.concatenate([model.G.T, np.asarray(load, dtype=complex)[:, None]], axis=1)
        X = np.linalg.solve(D, np.broadcast_to(rhs, (len(self.h),) + rhs.shape))
        nj = model.n_joints
        self.XG = X[:, :, :nj]                      # D_h^{-1} G^T   (n_h, r, nj)
        self.Xp = X[:, :, nj]                       # D_h^{-1} p     (n_h, r)
        self.R = model.G @ self.XG                  # (n_h, nj, nj)
        self.s_lin = np.zeros((len(self.h), nj), dtype=complex)
        one = self.h == 1
        self.s_lin[one] = (model.G @ self.Xp[one].T).T
        # real form of the multiplication by R_h: (n_c*nj, n_c*nj) with index (c, j)
        nc = sum(1 if hh == 0 else 2 for hh in self.h)
        Rr = np.zeros((nc, nj, nc, nj))
        c = 0
        for i, hh in enumerate(self.h):
            Rh = self.R[i]
            if hh == 0:
                Rr[c, :, c, :] = Rh.real
                c += 1
            else:
                Rr[c, :, c, :] = Rh.real
                Rr[c, :, c + 1, :] = -Rh.imag
                Rr[c + 1, :, c, :] = Rh.imag
                Rr[c + 1, :, c + 1, :] = Rh.real
                c += 2
        self.nc, self.nj = nc, nj
        self.Rr = Rr.reshape(nc * nj, nc * nj)
        self.y_lin = _to_real(self.s_lin, self.h).reshape(-1)


def solve_hb(model: ReducedModel, bank: JointBank, load, omega: float,
             settings: HBSettings = HBSettings(), guess: np.ndarray | None = None) -> HBSolution:
    """Harmonic-balance steady state at ``omega`` (rad/s) for ``Re(load e^{i w t})``.

    Parameters
    ----------
    model, bank : ReducedModel, JointBank
    load : ndarray, shape (r,)
        Reduced complex load amplitude ``Phi^T f`` (N).
    omega : float
    settings : HBSettings
    guess : ndarray, shape (n_h, n_joints), complex, optional
        Initial slip harmonics (default: the stuck-joint linear solution).

    Returns
    -------
    HBSolution
    """
    if not np.allclose(bank.K_T, model.K_T, rtol=1e-9):
        raise ValueError("joint bank stiffness does not match the model's K_T")
    op = _HBOperator(model, load, omega, settings)
    h = op.h
    E, P = _synthesis(h, settings.n_time)
    nc, nj = op.nc, op.nj
    y = op.y_lin.copy() if guess is None else _to_real(np.asarray(guess), h).reshape(-1)
    K_T = model.K_T
    scale = max(np.abs(op.y_lin).max(), 1e-300)
    it, upd = 0, np.inf
    for it in range(1, settings.max_iter + 1):
        Y = y.reshape(nc, nj)
        s_t = (E @ Y).T                                          # (nj, N)
        F, JF = aft_joint_force(s_t, bank, P, E)
        g_t = F - K_T[:, None] * s_t
        yg = (P @ g_t.T).reshape(-1)                              # (nc*nj,)
        res = y - op.y_lin + op.Rr @ yg
        # d yg / d y : per joint P (dF - K_T I) E, arranged in the (c, j) index
        Jg = JF - K_T[:, None, None] * np.eye(nc)[None]
        Jfull = np.zeros((nc, nj, nc, nj))
        Jfull[:, np.arange(nj), :, np.arange(nj)] = Jg           # (nj, nc, nc) on the diagonal
        Jac = np.eye(nc * nj) + op.Rr @ Jfull.reshape(nc * nj, nc * nj)
        dy = np.linalg.solve(Jac, -res)
        y = y + dy
        upd = np.abs(dy).max() / max(np.abs(y).max(), scale * 1e-12)
        if upd < settings.tol:
            break
    else:
        raise RuntimeError(f"harmonic balance did not converge at {omega / (2 * np.pi):.4g} Hz "
                           f"(relative update {upd:.2e})")
    Y = y.reshape(nc, nj)
    s_t = (E @ Y).T
    F, _ = aft_joint_force(s_t, bank)
    g_t = F - K_T[:, None] * s_t
    Gh = _to_complex(P @ g_t.T, h)                                 # (n_h, nj)
    S = _to_complex(Y, h)
    q = -np.einsum("hrj,hj->hr", op.XG, Gh)
    q[h == 1] += op.Xp[h == 1]
    amp = 0.5 * (s_t.max(axis=1) - s_t.min(axis=1))
    return HBSolution(omega=float(omega), harmonics=h, slip=S, joint_force=Gh, q=q,
                      slip_amplitude=amp, iterations=it, residual=float(upd))


def continuation(model: ReducedModel, bank: JointBank, load, omegas,
                 settings: HBSettings = HBSettings(), progress=None) -> list[HBSolution]:
    """Natural-parameter continuation over ascending (or descending) ``omegas``.

    Each line starts from a secant extrapolation of the two previous solutions (the
    previous one at the second line, the linear solution at the first), which follows
    the branch the way a stepped-sine sweep does.
    """
    sols: list[HBSolution] = []
    for i, w in enumerate(np.asarray(omegas, dtype=float)):
        guess = None
        if i == 1:
            guess = sols[-1].slip
        elif i >= 2:
            w1, w2 = sols[-2].omega, sols[-1].omega
            t = (w - w2) / (w2 - w1) if w2 != w1 else 0.0
            guess = sols[-1].slip + t * (sols[-1].slip - sols[-2].slip)
        try:
            sol = solve_hb(model, bank, load, w, settings, guess)
        except RuntimeError:
            if guess is None:
                raise
            sol = solve_hb(model, bank, load, w, settings, sols[-1].slip)
        sols.append(sol)
        if progress is not None:
            progress.update(1)
    return sols
