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
harmonics follow as ``Q_h = D_h^{-1} (p delta_{h1} - G^T N_h)``. The compiled march
runs the Jenkins return mapping through :func:`joints.jenkins.bank_update_kernel`
(the kernel of :func:`joints.jenkins.jenkins_update`, one joint row per call) and sums the Jacobian
rows by groups of sliders that last slipped at the same sample.

:func:`solve_hb_exact` is the first-harmonic balance with the *continuous* Iwan
joints: with one harmonic the slips are sinusoids and the joint force harmonic is
exactly the describing function of :func:`joints.iwan.describing_function`
(``F_1 = (k_in(A) + i k_q(A)) S_1``), so there is neither a slider discretization nor
time sampling; Newton uses the analytic derivative of the describing function.

SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from numba import njit
from scipy import special

from fe.reduction import JointBank, ReducedModel
from joints.iwan import IwanParameters
from joints.jenkins import bank_update_kernel, jenkins_update

__all__ = ["HBSettings", "HBSolution", "solve_hb", "continuation", "aft_joint_force",
           "solve_hb_exact", "continuation_exact"]


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
def _aft_march(slip_t, k, phi, P, E, want_jac):
    """Compiled periodic march of the Jenkins banks (same start as :func:`_aft_start`,
    same return mapping as :func:`joints.jenkins.jenkins_update`). With ``want_jac``
    also returns the harmonic Jacobian ``P (dF/ds) E`` per joint, where
    ``dF(t_n)/ds(t_m) = sum_stuck k_i (delta_nm - delta_{m, src_i(n)})``.

    The row ``sum_stuck k_i (E_n - E_{src_i})`` of sample ``n`` is not summed slider by
    slider: sliders are grouped by the sample ``m`` at which they last slipped, whose
    summed stiffness ``W_m`` is updated when a slider slips, so that the row is
    ``k_t E_n - sum_m W_m E_m`` over the few distinct ``m`` (the slip extrema) plus a
    correction for the sliders slipping at ``n`` itself. Cost per sample:
    ``n_sliders + n_c (n_active + n_c)`` instead of ``n_sliders n_c``.
    """
    nj, N = slip_t.shape
    ns = k.shape[1]
    nc = E.shape[1]
    force = np.empty((nj, N))
    Jg = np.zeros((nj, nc, nc))
    row = np.empty(nc)
    x = np.empty((1, ns))
    trial = np.empty((1, ns))
    kj = np.empty((1, ns))
    pj = np.empty((1, ns))
    s1 = np.empty(1)
    F1 = np.empty(1)
    T1 = np.empty(1)
    src = np.empty(ns, dtype=np.int64)
    count = np.zeros(N, dtype=np.int64)
    W = np.zeros(N)
    active = np.empty(N, dtype=np.int64)
    for j in range(nj):
        # periodic start at the slip maximum (see _aft_start)
        i_max = 0
        i_min = 0
        for n in range(1, N):
            if slip_t[j, n] > slip_t[j, i_max]:
                i_max = n
            if slip_t[j, n] < slip_t[j, i_min]:
                i_min = n
        s_max = slip_t[j, i_max]
        s_min = slip_t[j, i_min]
        half = 0.5 * (s_max - s_min)
        n_active = 0
        for i in range(ns):
            p = phi[j, i]
            lo = s_max - p
            hi = s_min + p
            if p < half:
                a = lo
                m = i_max
            else:
                a = 0.0 if 0.0 > lo else lo
                hb = hi if hi > lo else lo
                a = a if a < hb else hb
                if a == lo:
                    m = i_max
                elif a == hi:
                    m = i_min
                else:
                    m = -1
            x[0, i] = a
            src[i] = m
            if want_jac and m >= 0:
                if count[m] == 0:
                    active[n_active] = m
                    n_active += 1
                count[m] += 1
                W[m] += k[j, i]
        for i in range(ns):
            kj[0, i] = k[j, i]
            pj[0, i] = phi[j, i]
        for step in range(N):
            n = (i_max + step) % N
            s1[0] = slip_t[j, n]
            bank_update_kernel(s1, x, kj, pj, trial, F1, T1)
            F = F1[0]
            kt = T1[0]
            kslip = 0.0
            if want_jac:
                # sliders that slipped now: move their stiffness from the group of
                # their last slip sample to group n (most come from the previous
                # sample, which is batched)
                prev = (n - 1) % N
                w_prev = 0.0
                c_prev = 0
                w_new = 0.0
                c_new = 0
                for i in range(ns):
                    if trial[0, i] != x[0, i]:
                        ki = kj[0, i]
                        kslip += ki
                        m = src[i]
                        if m == prev:
                            w_prev += ki
                            c_prev += 1
                        elif m >= 0:
                            count[m] -= 1
                            W[m] -= ki
                        w_new += ki
                        c_new += 1
                        src[i] = n
                if c_new > 0:
                    count[prev] -= c_prev
                    W[prev] -= w_prev
                    if count[n] == 0:
                        active[n_active] = n
                        n_active += 1
                    count[n] += c_new
                    W[n] += w_new
            x, trial = trial, x
            force[j, n] = F
            if want_jac:
                for d in range(nc):
                    row[d] = kt * E[n, d]
                keep = 0
                for a_i in range(n_active):
                    m = active[a_i]
                    if count[m] == 0:
                        W[m] = 0.0
                        continue
                    active[keep] = m
                    keep += 1
                    w = W[m] - kslip if m == n else W[m]
                    for d in range(nc):
                        row[d] -= w * E[m, d]
                n_active = keep
                for c in range(nc):
                    pc = P[c, n]
                    for d in range(nc):
                        Jg[j, c, d] += pc * row[d]
        for a_i in range(n_active):        # reset for the next joint
            count[active[a_i]] = 0
            W[active[a_i]] = 0.0
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


_NO_P = np.zeros((1, 1))
_NO_E = np.zeros((1, 1))


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
    if not compiled:
        anchor, src, i_max = _aft_start(slip_t, k, phi)
        return _dense_jacobian(slip_t, k, phi, anchor, src, i_max)
    want = P is not None
    if not want:
        P = _NO_P
        E = _NO_E
    force, Jg = _aft_march(slip_t, np.ascontiguousarray(k), np.ascontiguousarray(phi),
                           np.ascontiguousarray(P), np.ascontiguousarray(E), want)
    return force, (Jg if want else None)


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


class _HBOperator:
    """Frequency-dependent linear part of the condensed HB equations."""

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


def _check_stiffness(bank_K_T, model: ReducedModel) -> None:
    K_T = np.asarray(bank_K_T, dtype=float)
    if K_T.shape != model.K_T.shape or np.any(
            np.abs(K_T - model.K_T) > 1e-9 * np.abs(model.K_T) + 1e-300):
        raise ValueError("joint bank stiffness does not match the model's K_T")


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
    _check_stiffness(bank.K_T, model)
    op = _HBOperator(model, load, omega, settings)
    h = op.h
    E, P = _synthesis(h, settings.n_time)
    nc, nj = op.nc, op.nj
    y = op.y_lin.copy() if guess is None else _to_real(np.asarray(guess), h).reshape(-1)
    K_T = model.K_T
    k_sl = np.ascontiguousarray(bank.stiffness)
    phi_sl = np.ascontiguousarray(bank.slip_limit)
    eye_c = np.eye(nc)
    eye_y = np.eye(nc * nj)
    scale = max(np.abs(op.y_lin).max(), 1e-300)
    it, upd = 0, np.inf
    for it in range(1, settings.max_iter + 1):
        Y = y.reshape(nc, nj)
        s_t = np.ascontiguousarray((E @ Y).T)                    # (nj, N)
        F, JF = _aft_march(s_t, k_sl, phi_sl, P, E, True)
        g_t = F - K_T[:, None] * s_t
        yg = (P @ g_t.T).reshape(-1)                              # (nc*nj,)
        res = y - op.y_lin + op.Rr @ yg
        # d yg / d y : per joint P (dF - K_T I) E, arranged in the (c, j) index:
        # Jac[(c,j),(d,l)] = delta + sum_e Rr[(c,j),(e,l)] Jg[l,e,d]
        Jg = JF - K_T[:, None, None] * eye_c
        Jac = eye_y + np.einsum("cjel,led->cjdl", op.Rr4, Jg).reshape(nc * nj, nc * nj)
        dy = np.linalg.solve(Jac, -res)
        y = y + dy
        upd = np.abs(dy).max() / max(np.abs(y).max(), scale * 1e-12)
        if upd < settings.tol:
            break
    else:
        raise RuntimeError(f"harmonic balance did not converge at {omega / (2 * np.pi):.4g} Hz "
                           f"(relative update {upd:.2e})")
    Y = y.reshape(nc, nj)
    s_t = np.ascontiguousarray((E @ Y).T)
    F, _ = _aft_march(s_t, k_sl, phi_sl, _NO_P, _NO_E, False)
    g_t = F - K_T[:, None] * s_t
    Gh = _to_complex(P @ g_t.T, h)                                 # (n_h, nj)
    S = _to_complex(Y, h)
    q = -np.einsum("hrj,hj->hr", op.XG, Gh)
    q[h == 1] += op.Xp[h == 1]
    amp = 0.5 * (s_t.max(axis=1) - s_t.min(axis=1))
    return HBSolution(omega=float(omega), harmonics=h, slip=S, joint_force=Gh, q=q,
                      slip_amplitude=amp, iterations=it, residual=float(upd))


def _continue(solve, omegas, progress) -> list[HBSolution]:
    """Natural-parameter continuation with a secant predictor (see :func:`continuation`);
    ``solve(omega, guess)`` returns an :class:`HBSolution`."""
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
            sol = solve(w, guess)
        except RuntimeError:
            if guess is None:
                raise
            sol = solve(w, sols[-1].slip)
        sols.append(sol)
        if progress is not None:
            progress.update(1)
    return sols


def continuation(model: ReducedModel, bank: JointBank, load, omegas,
                 settings: HBSettings = HBSettings(), progress=None) -> list[HBSolution]:
    """Natural-parameter continuation over ascending (or descending) ``omegas``.

    Each line starts from a secant extrapolation of the two previous solutions (the
    previous one at the second line, the linear solution at the first), which follows
    the branch the way a stepped-sine sweep does.
    """
    return _continue(lambda w, guess: solve_hb(model, bank, load, w, settings, guess),
                     omegas, progress)


# ------------------------------------------------- first harmonic, exact Iwan joints


class _ExactIwan:
    """Per-joint arrays of four-parameter Iwan joints for :func:`_iwan_df`."""

    def __init__(self, joints, n_joints: int):
        if isinstance(joints, IwanParameters):
            joints = [joints] * n_joints
        joints = list(joints)
        if len(joints) != n_joints:
            raise ValueError(f"need one IwanParameters per joint ({n_joints}), got "
                             f"{len(joints)}")
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


def _iwan_df(J: _ExactIwan, A):
    """Exact describing function of each joint at slip amplitudes ``A`` (n_joints,) and
    its derivative in ``A``: ``(k_in, k_q, dk_in/dA, dk_q/dA)`` (N/m, N/m^2).

    Same closed form as :func:`joints.iwan.describing_function` (there derived and
    checked against quadrature): with ``rho = min(1, phi_max/A)``,
    ``k_in = K_T I_rho(3/2, 3/2) - c A^(chi+1) B(rho; chi+5/2, 3/2)``,
    ``c = 8 R/(pi (chi+1))``, ``k_q = D/(pi A^2)`` with ``D`` the dissipation per cycle
    (Segalman 2005). Derivatives: ``dD/dA = 4 R a^(chi+2)/(chi+2) + 4 S phi_max [A >
    phi_max]`` (``a = min(A, phi_max)``), ``d rho/dA = -rho/A`` in macro-slip,
    ``d I_rho(3/2,3/2)/d rho = (8/pi) sqrt(rho (1-rho))``,
    ``d B(rho; a, 3/2)/d rho = rho^(a-1) sqrt(1-rho)``.
    """
    chi, pm = J.chi, J.phi_max
    A = np.maximum(np.asarray(A, dtype=float), 1e-300)
    macro = A > pm
    if not macro.any():            # micro-slip everywhere: rho = 1, closed forms
        Apow = A ** (chi + 1.0)
        k_in = J.K_T - J.c_in * J.beta_ab * Apow
        k_q = J.q_micro * Apow
        return k_in, k_q, (chi + 1.0) * (k_in - J.K_T) / A, (chi + 1.0) * k_q / A
    rho = np.where(macro, pm / A, 1.0)
    inc = special.betainc(J.a, 1.5, rho) * J.beta_ab
    g = special.betainc(1.5, 1.5, rho)
    Apow = A ** (chi + 1.0)
    k_in = J.K_T * g - J.c_in * Apow * inc
    a = np.minimum(A, pm)
    D = 4.0 * J.R * (A * a ** (chi + 2.0) / (chi + 2.0) - a ** (chi + 3.0) / (chi + 3.0))
    D = D + np.where(macro, 4.0 * J.S * pm * (A - pm), 0.0)
    k_q = D / (np.pi * A * A)
    dD = 4.0 * J.R * a ** (chi + 2.0) / (chi + 2.0) + np.where(macro, 4.0 * J.S * pm, 0.0)
    dk_q = (dD - 2.0 * D / A) / (np.pi * A * A)
    one_m = np.maximum(1.0 - rho, 0.0)
    drho = -rho / A
    dg = (8.0 / np.pi) * np.sqrt(rho * one_m)
    dinc = rho ** (J.a - 1.0) * np.sqrt(one_m)
    dk_in = (J.K_T * dg * drho
             - J.c_in * ((chi + 1.0) * Apow / A * inc + Apow * dinc * drho))
    return k_in, k_q, dk_in, dk_q


def solve_hb_exact(model: ReducedModel, joints, load, omega: float, tol: float = 1e-13,
                   max_iter: int = 60, guess: np.ndarray | None = None,
                   _prepared: _ExactIwan | None = None) -> HBSolution:
    """First-harmonic balance with the exact continuous Iwan joints (describing function).

    With one harmonic every joint slip is a sinusoid ``s_j = Re(S_j e^{i w t})`` and the
    first harmonic of the joint force is exactly
    ``F_j = (k_in(|S_j|) + i k_q(|S_j|)) S_j`` (:func:`joints.iwan.describing_function`;
    paper eq. 14 in micro-slip), so ``g_j = F_j - K_T S_j`` and the condensed equations
    ``S = S_lin - R_1 N(S)`` (module docstring) are solved by Newton's method with the
    analytic derivative of the describing function (:func:`_iwan_df`). No slider
    discretization and no time sampling: the only error is the truncation to the first
    harmonic.

    Parameters
    ----------
    model : ReducedModel
    joints : IwanParameters or sequence of IwanParameters
        One per joint (or one shared by all); ``K_T`` must equal ``model.K_T``.
    load : ndarray, shape (r,)
        Reduced complex load amplitude (N).
    omega : float
        Drive frequency (rad/s).
    tol : float
        Bound on the relative Newton update.
    guess : ndarray, shape (1, n_joints), complex, optional
        Initial slip harmonics (default: the stuck-joint linear solution).

    Returns
    -------
    HBSolution
        ``harmonics = [1]``; ``slip_amplitude = |S_1|``.
    """
    nj = model.n_joints
    J = _ExactIwan(joints, nj) if _prepared is None else _prepared
    _check_stiffness(J.K_T, model)
    op = _HBOperator(model, load, omega, None, harmonics=np.array([1]))
    R1 = op.R[0]
    S_lin = op.s_lin[0]
    S = S_lin.copy() if guess is None else np.asarray(guess, dtype=complex).reshape(nj).copy()
    scale = max(np.abs(S_lin).max(), 1e-300)
    eye = np.eye(2 * nj)
    Rr = np.empty((2 * nj, 2 * nj))
    Rr[:nj, :nj] = R1.real
    Rr[:nj, nj:] = -R1.imag
    Rr[nj:, :nj] = R1.imag
    Rr[nj:, nj:] = R1.real
    Jn = np.zeros((2 * nj, 2 * nj))
    diag = np.arange(nj)
    rhs = np.empty(2 * nj)
    it, upd = 0, np.inf
    for it in range(1, max_iter + 1):
        A = np.abs(S)
        k_in, k_q, dk_in, dk_q = _iwan_df(J, A)
        kap = (k_in - J.K_T) + 1j * k_q
        N = kap * S
        res = S - S_lin + R1 @ N
        # dN/dRe S = kap + S kap' Re S/A,  dN/dIm S = i kap + S kap' Im S/A
        dkap = (dk_in + 1j * dk_q) / np.maximum(A, 1e-300)
        dx = kap + S * dkap * S.real
        dyy = 1j * kap + S * dkap * S.imag
        Jn[diag, diag] = dx.real
        Jn[diag, nj + diag] = dyy.real
        Jn[nj + diag, diag] = dx.imag
        Jn[nj + diag, nj + diag] = dyy.imag
        Jac = eye + Rr @ Jn
        rhs[:nj] = -res.real
        rhs[nj:] = -res.imag
        d = np.linalg.solve(Jac, rhs)
        S = S + (d[:nj] + 1j * d[nj:])
        upd = np.abs(d).max() / max(np.abs(S).max(), scale * 1e-12)
        if upd < tol:
            break
    else:
        raise RuntimeError(f"describing-function balance did not converge at "
                           f"{omega / (2 * np.pi):.4g} Hz (relative update {upd:.2e})")
    A = np.abs(S)
    k_in, k_q, _, _ = _iwan_df(J, A)
    N = ((k_in - J.K_T) + 1j * k_q) * S
    q = op.Xp[0] - op.XG[0] @ N
    return HBSolution(omega=float(omega), harmonics=np.array([1]), slip=S[None, :],
                      joint_force=N[None, :], q=q[None, :], slip_amplitude=A,
                      iterations=it, residual=float(upd))


def continuation_exact(model: ReducedModel, joints, load, omegas, tol: float = 1e-13,
                       progress=None) -> list[HBSolution]:
    """:func:`continuation` for :func:`solve_hb_exact` (exact Iwan joints, first
    harmonic)."""
    J = _ExactIwan(joints, model.n_joints)
    return _continue(lambda w, guess: solve_hb_exact(model, joints, load, w, tol,
                                                     guess=guess, _prepared=J),
                     omegas, progress)
