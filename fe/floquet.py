"""Floquet multipliers of a periodic orbit from the period map of the Newmark scheme.

The second route to the stability of a harmonic-balance solution (the first is
:mod:`fe.hill`): the monodromy ``Phi`` of ``[q, v]`` over one period ``T = 2 pi / w`` of
the average-acceleration rule (Newmark 1959, ``beta = 1/4``, ``gamma = 1/2``, ``n_steps``
steps of ``dt = T / n_steps``), two ways:

* :func:`tangent_monodromy`: the scheme linearized on the orbit ``q(t)`` of the balance,
  ``M a + C v + K_t(t) q = 0`` with ``K_t = K_J + G^T diag(k_t - K_T) G`` and ``k_t`` the
  law's step tangent along the periodic march of the orbit's slips
  (:func:`fe.law_aft.periodic_law_force`): the product of the one-step maps

      S_{n+1} a_{n+1} = -(C v~ + K_{n+1} q~),  q~ = q_n + dt v_n + dt^2/4 a_n,
      v~ = v_n + dt/2 a_n,  q_{n+1} = q~ + dt^2/4 a_{n+1},  v_{n+1} = v~ + dt/2 a_{n+1},

  ``S_{n+1} = M + dt/2 C + dt^2/4 K_{n+1}``. Exact variational equation for a law
  without memory (its multipliers converge as ``dt^2``); for a hysteretic law it omits
  the dependence of the force on past reversals.
* :func:`period_map_monodromy`: central differences of the nonlinear period map
  (:class:`fe.newmark.NewmarkIntegrator` with the law's own step) started on the orbit
  at the sample of largest slip speed (mid-stroke, where the law is smooth in the
  start), the joint state from the orbit's periodic march; the memory is in the
  marched force. Linearized about the balance's orbit (not the scheme's own), so its
  error is that of the orbit as well as ``O(dt^2)``.

Multipliers are the eigenvalues of ``Phi``, sorted by decreasing modulus. SI units: s.
"""
from __future__ import annotations

import numpy as np

from fe.hb_forced import ForcedBalance
from fe.law_aft import periodic_law_force
from fe.newmark import NewmarkIntegrator, NewmarkSettings, NewmarkState

__all__ = ["tangent_monodromy", "period_map_monodromy", "floquet_multipliers"]


def floquet_multipliers(monodromy: np.ndarray) -> np.ndarray:
    """Eigenvalues of the monodromy, by decreasing modulus."""
    mu = np.linalg.eigvals(np.asarray(monodromy, dtype=float))
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _orbit(balance: ForcedBalance, x, omega, n_steps):
    """``q``, ``v`` (n_steps, r) at ``t_n = n T / n_steps`` (exact derivative of the
    series) and the slips (nj, n_steps)."""
    X = np.asarray(x).reshape(balance.nc, balance.r)
    q = balance.time_samples(x, n_steps)
    v = balance.time_samples((balance.derivative(omega) @ X).reshape(-1), n_steps)
    return q, v, np.ascontiguousarray((balance.model.G @ q.T))


def tangent_monodromy(balance: ForcedBalance, x: np.ndarray, omega: float,
                      n_steps: int = 2048) -> np.ndarray:
    """Monodromy (2r, 2r) of the scheme linearized on the orbit (module docstring)."""
    m = balance.model
    M, C, G, K_T = m.M, m.C, m.G, m.K_T
    r = m.n_reduced
    dt = 2.0 * np.pi / omega / n_steps
    _, _, s_t = _orbit(balance, x, omega, n_steps)
    _, kt, _ = periodic_law_force(balance.law, s_t)
    I, Z = np.eye(r), np.zeros((r, r))
    Pq = np.hstack([I, dt * I, 0.25 * dt * dt * I])
    Pv = np.hstack([Z, I, 0.5 * dt * I])

    def K_at(n):
        return m.K + G.T @ ((kt[:, n % n_steps] - K_T)[:, None] * G)

    E = np.vstack([np.hstack([I, Z]), np.hstack([Z, I]),
                   -np.linalg.solve(M, np.hstack([K_at(0), C]))])       # (3r, 2r)
    state = E
    for n in range(1, n_steps + 1):
        K = K_at(n)
        A1 = -np.linalg.solve(M + 0.5 * dt * C + 0.25 * dt * dt * K, C @ Pv + K @ Pq)
        state = np.vstack([Pq + 0.25 * dt * dt * A1, Pv + 0.5 * dt * A1, A1]) @ state
    return state[:2 * r]


def _law_state_before(law, s_t, n0):
    """The law's committed state after the periodic march (two periods from the slip
    maximum of the first joint, :func:`fe.law_aft.periodic_law_force`) has reached the
    sample before ``n0``."""
    nj, N = s_t.shape
    start = int(np.argmax(s_t[0]))
    state = law.initial_state()
    stop = (n0 - 1) % N
    for k in range(2 * N + ((stop - start) % N) + 1):
        n = (start + k) % N
        _, _, state = law.step(s_t[:, n], state)
    return state


def period_map_monodromy(balance: ForcedBalance, x: np.ndarray, omega: float,
                         n_steps: int = 1024, fd_step: float = 1e-6) -> np.ndarray:
    """Monodromy (2r, 2r) by central differences of the Newmark period map (module
    docstring); ``fd_step`` relative to the orbit's largest ``|q|`` and ``|v|``. The
    load must be real (``Re(p) cos w t``)."""
    m, law = balance.model, balance.law
    if np.any(balance.load.imag != 0.0):
        raise ValueError("period_map_monodromy needs a real load amplitude")
    r = m.n_reduced
    T = 2.0 * np.pi / omega
    dt = T / n_steps
    q, v, s_t = _orbit(balance, x, omega, n_steps)
    n0 = int(np.argmax(np.abs(np.gradient(s_t[0]))))
    before = _law_state_before(law, s_t, n0)
    integ = NewmarkIntegrator(m, law, NewmarkSettings(dt=dt))
    t0 = n0 * dt
    e = np.cos(omega * (t0 + dt * np.arange(n_steps + 1)))
    p = balance.load.real

    def period(xs):
        qs, vs = xs[:r], xs[r:]
        s = m.G @ qs
        F, _, state = law.step(s, before)
        g = np.asarray(F, dtype=float) - m.K_T * s
        a = np.linalg.solve(m.M, p * e[0] - m.C @ vs - m.K @ qs - m.G.T @ g)
        st = NewmarkState(t=t0, q=qs, v=vs, a=a, anchor=state, g=g, e=float(e[0]))
        run = integ.run(p, e, st, energy=False)
        return np.concatenate([run.state.q, run.state.v])

    x0 = np.concatenate([q[n0], v[n0]])
    h = fd_step * np.concatenate([np.full(r, max(np.abs(q).max(), 1e-300)),
                                  np.full(r, max(np.abs(v).max(), 1e-300))])
    Phi = np.empty((2 * r, 2 * r))
    for k in range(2 * r):
        dx = np.zeros(2 * r)
        dx[k] = h[k]
        Phi[:, k] = (period(x0 + dx) - period(x0 - dx)) / (2.0 * h[k])
    return Phi
