"""The step loops of the HHT/Newmark integrator (:mod:`fe.newmark`), compiled and plain.

:func:`march` is the compiled loop: the joints' return mapping is
:func:`joints.kernel.bank_update_kernel`, so its joint forces and slider states are
bitwise those of :func:`joints.jenkins.jenkins_update` on the same bank for the same
slips; it allocates nothing per step (measured with ``benchmarks/bench_sdof.py``: about
0.2 us per step for one joint of 100 sliders, 10x the previous inlined loop and 100x a
plain numpy step). :func:`reference_loop` is the same algebra as a Python loop over
:func:`joints.jenkins.jenkins_update` (for tests, and for recording the joint forces).
The algebra of a step is in :mod:`fe.newmark`'s docstring. SI units: s, m, N.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from joints import kernel
from joints.kernel_reference import KERNEL_STAMP

__all__ = ["march", "reference_loop"]


def reference_loop(st, e, B, sl, GP, GB, Gsl, P, Vp, Y, Z, cz, bdt2, al, ga_dt, G, K_T,
                   step, tol, max_iter, slip_scale, record_force, dissipated=None):
    """Python step loop over a joint law's ``step(slip, state) -> (F, dF/ds, state)``
    (:mod:`joints.law`; for a Jenkins bank :func:`joints.jenkins.jenkins_update`: the
    reference of :func:`march`). The other arguments are
    :meth:`fe.newmark.NewmarkIntegrator.run`'s operators; ``dissipated(old, new)`` the
    friction work of a committed step (J), or None (then 0 is summed)."""
    n_steps = e.size - 1
    r = sl.size
    nj = K_T.size
    I_nj = np.eye(nj)
    qh = np.empty((n_steps + 1, r))
    vh = np.empty((n_steps + 1, r))
    sh = np.empty((n_steps + 1, nj))
    fh = np.empty((n_steps + 1, nj)) if record_force else None
    qh[0], vh[0] = st.q, st.v
    sh[0] = G @ st.q
    if record_force:
        fh[0] = st.g + K_T * sh[0]
    x = np.concatenate([st.q, st.v, st.a])
    g0 = np.asarray(st.g, dtype=float)
    anchor = st.anchor
    dissip = 0.0
    iters = 0
    for k in range(n_steps):
        ee = (1.0 + al) * e[k + 1] - al * e[k]
        a_lin = B @ x + sl * ee
        s_lin = GP @ x + bdt2 * (GB @ x + Gsl * ee)
        if al != 0.0:
            a_lin = a_lin + al * (Y @ g0)
            s_lin = s_lin + al * bdt2 * (Z @ g0)
        s = s_lin - cz * (Z @ g0)             # start from the last joint force
        for _ in range(max_iter):
            F, kt, anc = step(s, anchor)
            g = F - K_T * s
            h = s - s_lin + cz * (Z @ g)
            iters += 1
            if np.max(np.abs(h)) <= tol * (np.max(np.abs(s)) + slip_scale):
                break
            J = I_nj + cz * Z * (kt - K_T)[None, :]
            s = s - np.linalg.solve(J, h)
        else:
            raise RuntimeError(f"Newton did not converge at step {k} (|h| = {np.abs(h).max():.3e})")
        if dissipated is not None:
            dissip += dissipated(anchor, anc)
        anchor = anc
        a1 = a_lin - (1.0 + al) * (Y @ g)
        q1 = P @ x + bdt2 * a1
        v1 = Vp @ x + ga_dt * a1
        x = np.concatenate([q1, v1, a1])
        g0 = g
        qh[k + 1], vh[k + 1], sh[k + 1] = q1, v1, s
        if record_force:
            fh[k + 1] = F
    return qh, vh, sh, fh, x, g0, anchor, dissip, iters


@njit(cache=True, inline="always")
def _solve_in_place(J, h):
    """Solve ``J d = h`` for a small dense ``J`` (n, n) by Gaussian elimination with
    partial pivoting; ``J`` is destroyed and ``h`` overwritten by ``d``. Returns False
    for a singular matrix."""
    n = h.size
    if n == 1:
        if J[0, 0] == 0.0:
            return False
        h[0] = h[0] / J[0, 0]
        return True
    for c in range(n):
        p = c
        big = abs(J[c, c])
        for r in range(c + 1, n):
            if abs(J[r, c]) > big:
                big = abs(J[r, c])
                p = r
        if big == 0.0:
            return False
        if p != c:
            for cc in range(n):
                tmp = J[c, cc]
                J[c, cc] = J[p, cc]
                J[p, cc] = tmp
            tmp = h[c]
            h[c] = h[p]
            h[p] = tmp
        for r in range(c + 1, n):
            f = J[r, c] / J[c, c]
            if f != 0.0:
                for cc in range(c + 1, n):
                    J[r, cc] -= f * J[c, cc]
                h[r] -= f * h[c]
    for c in range(n - 1, -1, -1):
        acc = h[c]
        for cc in range(c + 1, n):
            acc -= J[c, cc] * h[cc]
        h[c] = acc / J[c, c]
    return True


def _compile(kernel_stamp):
    """The compiled step loop, its numba cache keyed by the kernel it compiles in
    (:mod:`joints.kernel`)."""

    @njit(cache=True)
    def march(BT, sl, G, YT, Z, cz, bdt2, al, dt, c_qa, c_va, ga_dt, e, x0, g0, anchor0,
               k, phi, fric, K_T, tol, max_iter, slip_scale):
        """Compiled step loop of :func:`integrate` (same algebra as :func:`reference_loop`).

        The joints' return mapping is :func:`joints.kernel.bank_update_kernel`, so each
        Newton iterate gives bitwise the forces of :func:`joints.jenkins.jenkins_update`.
        No heap allocation inside the loop: the matrix-vector products are written as
        loops over contiguous rows (``BT = B^T``, ``YT = Y^T``), which LLVM vectorizes, and
        the ``n_joints`` x ``n_joints`` Newton system is solved by
        :func:`_solve_in_place`. ``c_qa = dt^2 (1/2 - beta)``, ``c_va = dt (1 - gamma)``:
        the predictors ``q~ = q + dt v + c_qa a``, ``v~ = v + c_va a``.
        """
        kernel_stamp  # noqa: B018 - in the closure: the cache key (joints.kernel)
        n_steps = e.size - 1
        r = sl.size
        nj, ns = k.shape
        qh = np.empty((n_steps + 1, r))
        vh = np.empty((n_steps + 1, r))
        sh = np.empty((n_steps + 1, nj))
        x = x0.copy()                    # [q, v, a]
        g_old = g0.copy()
        anchor = anchor0.copy()
        trial = np.empty((nj, ns))
        a_lin = np.empty(r)
        u = np.empty(r)
        s = np.empty(nj)
        s_lin = np.empty(nj)
        g = np.empty(nj)
        F = np.empty(nj)
        kt = np.empty(nj)
        h = np.empty(nj)
        J = np.empty((nj, nj))
        for i in range(r):
            qh[0, i] = x[i]
            vh[0, i] = x[r + i]
        for j in range(nj):
            sh[0, j] = 0.0               # filled by the caller
        dissip = 0.0
        iters = 0
        status = -1
        for step in range(n_steps):
            ee = (1.0 + al) * e[step + 1] - al * e[step]
            # a_lin = B x + Sinv p ee (+ alpha Y g_old)
            for i in range(r):
                a_lin[i] = sl[i] * ee
            for c in range(3 * r):
                xc = x[c]
                for i in range(r):
                    a_lin[i] += BT[c, i] * xc
            if al != 0.0:
                for j in range(nj):
                    w = al * g_old[j]
                    for i in range(r):
                        a_lin[i] += YT[j, i] * w
            # displacement if the joints kept their force: u = q~ + beta dt^2 a_lin
            for i in range(r):
                u[i] = x[i] + dt * x[r + i] + c_qa * x[2 * r + i] + bdt2 * a_lin[i]
            for j in range(nj):
                acc = 0.0
                for i in range(r):
                    acc += G[j, i] * u[i]
                s_lin[j] = acc
            # predictor: the last joint force
            for j in range(nj):
                acc = 0.0
                for other in range(nj):
                    acc += Z[j, other] * g_old[other]
                s[j] = s_lin[j] - cz * acc
            converged = False
            for _ in range(max_iter):
                iters += 1
                kernel.bank_update_kernel(s, anchor, k, phi, trial, F, kt)
                for j in range(nj):
                    g[j] = F[j] - K_T[j] * s[j]
                smax = 0.0
                hmax = 0.0
                for j in range(nj):
                    acc = 0.0
                    for other in range(nj):
                        acc += Z[j, other] * g[other]
                    h[j] = s[j] - s_lin[j] + cz * acc
                    smax = max(smax, abs(s[j]))
                    hmax = max(hmax, abs(h[j]))
                if hmax <= tol * (smax + slip_scale):
                    converged = True
                    break
                for j in range(nj):
                    for other in range(nj):
                        J[j, other] = cz * Z[j, other] * (kt[other] - K_T[other])
                    J[j, j] += 1.0
                if not _solve_in_place(J, h):
                    break
                for j in range(nj):
                    s[j] -= h[j]
            if not converged:
                status = step
                break
            for j in range(nj):
                dj = 0.0
                for i in range(ns):
                    dj += fric[j, i] * abs(trial[j, i] - anchor[j, i])
                dissip += dj
            anchor, trial = trial, anchor          # commit the sliders
            # a1 = a_lin - (1 + alpha) Y g; q1 = q~ + beta dt^2 a1; v1 = v~ + gamma dt a1
            for i in range(r):
                u[i] = a_lin[i]
            for j in range(nj):
                w = (1.0 + al) * g[j]
                for i in range(r):
                    u[i] -= YT[j, i] * w
            for i in range(r):
                a1 = u[i]
                q1 = x[i] + dt * x[r + i] + c_qa * x[2 * r + i] + bdt2 * a1
                v1 = x[r + i] + c_va * x[2 * r + i] + ga_dt * a1
                x[i] = q1
                x[r + i] = v1
                x[2 * r + i] = a1
                qh[step + 1, i] = q1
                vh[step + 1, i] = v1
            for j in range(nj):
                g_old[j] = g[j]
                sh[step + 1, j] = s[j]
        return qh, vh, sh, x, g_old, anchor, dissip, iters, status

    return march


march = _compile(KERNEL_STAMP)
