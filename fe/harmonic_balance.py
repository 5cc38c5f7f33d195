"""Periodic steady state by harmonic balance with alternating frequency-time (AFT).

Same model as :mod:`fe.newmark` (reduced basis, paper eq. 23-25)::

    M q'' + C q' + K_J q + G^T g(s) = Re(p e^{i w t}),   s = G q,   g = F(s) - K_T s.

Every signal is a truncated Fourier series ``x(t) = Re sum_h X_h e^{i h w t}`` over the
harmonics ``h`` kept (``X_0`` real). Because the nonlinearity acts only on the joint
slips, the harmonic equations are condensed exactly onto the slip harmonics::

    S_h = S_h^lin - R_h N_h(S),   R_h = G D_h^{-1} G^T,   S_h^lin = G D_h^{-1} p delta_{h1},
    D_h = K_J - (h w)^2 M + i h w C,

where ``N_h`` are the harmonics of ``g(s(t))``, obtained by the AFT march of the
Jenkins banks over one period (:mod:`fe.aft`, which also gives the exact Jacobian
Newton's method uses). Physical response harmonics follow as
``Q_h = D_h^{-1} (p delta_{h1} - G^T N_h)``. This module holds the settings, the
solution type, the condensed operator (:class:`HBOperator`, shared with the
first-harmonic balance on exact Iwan joints of :mod:`fe.hb_exact`), :func:`solve_hb`
and the continuation over frequency lines. The Newton iteration is globalized
(:mod:`fe.newton_path`): a line search on the residual norm, a fresh start by
continuation in the load from the all-stuck solution, and the frequency step between
lines halved when a line's corrector fails; a line that still fails raises
:class:`fe.newton_path.SteadyStateError` (one line: where and why).

SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from fe.aft import aft_joint_force
from fe.newton_path import (SteadyStateError, damped_newton, follow, natural_continuation,
                            stall_words)
from fe.reduction import JointBank, ReducedModel

__all__ = ["HBSettings", "HBSolution", "HBOperator", "check_joint_stiffness", "solve_hb",
           "natural_continuation", "continuation", "SteadyStateError"]


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
    fallback : how the solution was reached when Newton from the first guess failed
        (e.g. ``"load raised gradually from the stuck-joint solution"``) or ended on a
        step stalled at round-off (:func:`fe.newton_path.stall_words`); several joined
        by ``"; "``, empty for an ordinary convergence.
    """

    omega: float
    harmonics: np.ndarray
    slip: np.ndarray
    joint_force: np.ndarray
    q: np.ndarray
    slip_amplitude: np.ndarray
    iterations: int
    residual: float
    fallback: str = ""

    def first_harmonic(self, model: ReducedModel) -> np.ndarray:
        """Physical first-harmonic displacement ``Phi Q_1`` (n,), complex (m)."""
        i1 = int(np.flatnonzero(self.harmonics == 1)[0])
        return model.expand(self.q[i1])


def harmonic_synthesis(harmonics, n_time):
    """Real synthesis ``E`` (n_time, n_c) and analysis ``P`` (n_c, n_time) matrices for
    the real unknowns ``[Re X_h, Im X_h]`` (``Im X_0`` dropped); ``P E = I``.
    Cached (read-only arrays)."""
    return _synthesis_cached(tuple(int(h) for h in harmonics), int(n_time))


@lru_cache(maxsize=32)
def _synthesis_cached(harmonics, n_time):
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
    E, P = np.ascontiguousarray(np.array(cols).T), np.array(rows)
    E.flags.writeable = False
    P.flags.writeable = False
    return E, P


def _to_real(X, harmonics):
    """Complex (n_h, m) -> real (n_c, m)."""
    re, im, nc = _layout(tuple(int(h) for h in harmonics))
    X = np.asarray(X)
    out = np.empty((nc,) + X.shape[1:])
    out[re] = X.real
    nz = im >= 0
    out[im[nz]] = X[nz].imag
    return out


def _to_complex(y, harmonics):
    """Real (n_c, m) -> complex (n_h, m)."""
    re, im, _ = _layout(tuple(int(h) for h in harmonics))
    out = y[re].astype(complex)
    nz = im >= 0
    out[nz] += 1j * y[im[nz]]
    return out


@lru_cache(maxsize=32)
def _layout(harmonics: tuple):
    """Rows of ``Re X_h`` and ``Im X_h`` in the real coefficient vector (``Im X_0``
    dropped): ``re`` (n_h,), ``im`` (n_h,) with -1 for ``h = 0``, and ``n_c``."""
    re, im, c = [], [], 0
    for h in harmonics:
        re.append(c)
        if h == 0:
            im.append(-1)
            c += 1
        else:
            im.append(c + 1)
            c += 2
    return np.array(re), np.array(im), c


class HBOperator:
    """Frequency-dependent linear part of the condensed HB equations (module docstring):
    ``R_h`` (``R``, and its real form ``Rr``), ``D_h^{-1} G^T`` (``XG``), ``D_h^{-1} p``
    (``Xp``) and the linear slips ``S_h^lin`` (``s_lin``, real form ``y_lin``)."""

    def __init__(self, model: ReducedModel, load, omega: float, settings: HBSettings | None,
                 harmonics=None):
        self.h = settings.harmonics if harmonics is None else np.asarray(harmonics)
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
        re, im, nc = _layout(tuple(int(x) for x in self.h))
        Rr = np.zeros((nc, nj, nc, nj))
        Rr[re, :, re, :] = self.R.real
        nz = im >= 0
        Rr[re[nz], :, im[nz], :] = -self.R[nz].imag
        Rr[im[nz], :, re[nz], :] = self.R[nz].imag
        Rr[im[nz], :, im[nz], :] = self.R[nz].real
        self.nc, self.nj = nc, nj
        self.Rr4 = Rr
        self.Rr = Rr.reshape(nc * nj, nc * nj)
        self.y_lin = _to_real(self.s_lin, self.h).reshape(-1)


def check_joint_stiffness(bank_K_T, model: ReducedModel) -> None:
    """ValueError unless the joints' stuck stiffness ``bank_K_T`` is the model's ``K_T``."""
    K_T = np.asarray(bank_K_T, dtype=float)
    if K_T.shape != model.K_T.shape or np.any(
            np.abs(K_T - model.K_T) > 1e-9 * np.abs(model.K_T) + 1e-300):
        raise ValueError("joint bank stiffness does not match the model's K_T")


class _Balance:
    """Residual ``r(y) = y - lam y_lin + R N(y)`` of the condensed equations (module
    docstring) in the real slip coefficients ``y`` (index ``(c, j)``) and its exact
    Jacobian ``I + R dN/dy``; ``lam`` scales the load (1: the given one)."""

    def __init__(self, model: ReducedModel, bank: JointBank, op: HBOperator, n_time: int):
        self.op, self.bank, self.K_T = op, bank, model.K_T
        self.E, self.P = harmonic_synthesis(op.h, n_time)
        self.eye_c = np.eye(op.nc)
        self.eye_y = np.eye(op.nc * op.nj)
        self.lam = 1.0

    def __call__(self, y):
        op, K_T = self.op, self.K_T
        s_t = np.ascontiguousarray((self.E @ y.reshape(op.nc, op.nj)).T)      # (nj, N)
        F, JF = aft_joint_force(s_t, self.bank, self.P, self.E)
        yg = (self.P @ (F - K_T[:, None] * s_t).T).reshape(-1)               # (nc*nj,)
        res = y - self.lam * op.y_lin + op.Rr @ yg
        # d yg / d y : per joint P (dF - K_T I) E, arranged in the (c, j) index:
        # Jac[(c,j),(d,l)] = delta + sum_e Rr[(c,j),(e,l)] Jg[l,e,d]
        Jg = JF - K_T[:, None, None] * self.eye_c
        n = op.nc * op.nj
        return res, self.eye_y + np.einsum("cjel,led->cjdl", op.Rr4, Jg).reshape(n, n)


def _load_continuation(balance: _Balance, settings: HBSettings, scale: float):
    """Steady state at the full load from the stuck-joint solution, by continuation in
    the load factor ``lam`` (:func:`fe.newton_path.follow` in ``ln lam``): at ``lam0 =
    phi_min / max|S_lin|`` every slider sticks, so ``lam0 y_lin`` is exact; the
    predictor scales the last solution (secant of ``y / lam`` in ``ln lam``).

    Returns (y, Newton iterations)."""
    y_lin = balance.op.y_lin
    lam0 = min(1.0, float(balance.bank.slip_limit.min()) / max(np.abs(y_lin).max(), 1e-300))
    iters = [0]

    def solve(p, guess):
        balance.lam = float(np.exp(p))
        y, it, _, _ = damped_newton(balance, guess, settings.tol, settings.max_iter,
                                    scale * balance.lam)
        iters[0] += it
        return y / balance.lam

    def predictor(p, hist):
        z = hist[-1][1] if len(hist) < 2 else hist[-1][1] + (p - hist[-1][0]) / (
            hist[-1][0] - hist[-2][0]) * (hist[-1][1] - hist[-2][1])
        return z * np.exp(p)

    try:
        z, _ = follow(solve, [(np.log(lam0), y_lin)], 0.0, predictor,
                      max_halvings=LOAD_HALVINGS)
    finally:
        balance.lam = 1.0
    return z, iters[0]


#: Halvings of the step of the load continuation (in ln of the load factor) before a
#: fresh start is given up.
LOAD_HALVINGS = 10


def solve_hb(model: ReducedModel, bank: JointBank, load, omega: float,
             settings: HBSettings = HBSettings(), guess: np.ndarray | None = None) -> HBSolution:
    """Harmonic-balance steady state at ``omega`` (rad/s) for ``Re(load e^{i w t})``.

    Newton's method with the exact AFT Jacobian and a line search on the residual norm
    (:func:`fe.newton_path.damped_newton`). Without ``guess`` it starts from the
    stuck-joint linear solution; if that fails (deep macro-slip), the load is raised
    from the level at which every slider sticks to the full load by continuation
    (:func:`_load_continuation`).

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

    Raises
    ------
    fe.newton_path.SteadyStateError
        One line: the frequency and the reason.
    """
    if not isinstance(bank, JointBank):
        raise ValueError(f"the multi-harmonic balance (AFT) needs Jenkins banks; solve "
                         f"{getattr(bank, 'name', 'this joint law')} joints through their "
                         f"describing function (fe.hb_exact.solve_hb_exact)")
    check_joint_stiffness(bank.K_T, model)
    op = HBOperator(model, load, omega, settings)
    h = op.h
    balance = _Balance(model, bank, op, settings.n_time)
    scale = max(np.abs(op.y_lin).max(), 1e-300)
    where = f"{omega / (2 * np.pi):.6g} Hz"
    y0 = op.y_lin.copy() if guess is None else _to_real(np.asarray(guess), h).reshape(-1)
    try:
        y, it, upd, _ = damped_newton(balance, y0, settings.tol, settings.max_iter, scale)
        fallback = stall_words(upd, settings.tol)
    except SteadyStateError as exc:
        if guess is not None:
            raise SteadyStateError(where, exc.reason) from None
        try:
            y, it = _load_continuation(balance, settings, scale)
        except SteadyStateError as exc2:
            raise SteadyStateError(where, f"{exc2.reason}, also with the load raised "
                                          f"gradually from the stuck-joint solution") from None
        upd = 0.0
        fallback = f"load raised gradually from the stuck-joint solution ({exc.reason})"
    nc, nj = op.nc, op.nj
    E, P = balance.E, balance.P
    Y = y.reshape(nc, nj)
    s_t = np.ascontiguousarray((E @ Y).T)
    F, _ = aft_joint_force(s_t, bank)
    g_t = F - model.K_T[:, None] * s_t
    Gh = _to_complex(P @ g_t.T, h)                                 # (n_h, nj)
    S = _to_complex(Y, h)
    q = -np.einsum("hrj,hj->hr", op.XG, Gh)
    q[h == 1] += op.Xp[h == 1]
    amp = 0.5 * (s_t.max(axis=1) - s_t.min(axis=1))
    return HBSolution(omega=float(omega), harmonics=h, slip=S, joint_force=Gh, q=q,
                      slip_amplitude=amp, iterations=it, residual=float(upd),
                      fallback=fallback)


def continuation(model: ReducedModel, bank: JointBank, load, omegas,
                 settings: HBSettings = HBSettings(), progress=None) -> list[HBSolution]:
    """Natural-parameter continuation over ascending (or descending) ``omegas``.

    Each line starts from a secant extrapolation of the two previous solutions (the
    previous one at the second line, the linear solution at the first), which follows
    the branch the way a stepped-sine sweep does.
    """
    return natural_continuation(
        lambda w, guess: solve_hb(model, bank, load, w, settings, guess), omegas, progress)
