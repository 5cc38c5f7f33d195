"""Alternating frequency-time (AFT) march of the Jenkins banks over one period.

For harmonic balance (:mod:`fe.harmonic_balance`) the joint slips are synthesized at
``n_time`` instants of a period, the Jenkins banks (:mod:`joints.jenkins`) are
marched once around the periodic loop starting at the slip maximum (sliders that slip
in the loop start at ``s_max - phi``: the exact periodic state; the others at the
virgin position clipped to stay stuck), and the joint force harmonics are the discrete
Fourier transform of the sampled force. Newton's method uses the exact Jacobian of the
sampled Jenkins force: a stuck slider's force ``k_i (s_n - x_i)`` depends on the
current sample and on the sample at which the slider last slipped (its anchor is
``s_m -+ phi_i``), so ``dF_n/ds_m = sum_stuck k_i (delta_nm - delta_{m, m_i(n)})`` — the
tangent ``k_t = sum_stuck k_i`` on the diagonal plus the anchor terms. The compiled
march runs the Jenkins return mapping through :func:`joints.kernel.bank_update_kernel`
(the kernel of :func:`joints.jenkins.jenkins_update`, one joint row per call) and sums
the Jacobian rows by groups of sliders that last slipped at the same sample; a
reference march over :func:`joints.jenkins.jenkins_update` returns the dense
time-domain Jacobian (for tests).

SI units: m, N.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from fe.reduction import JointBank
from joints import kernel
from joints.jenkins import jenkins_update
from joints.kernel_reference import KERNEL_STAMP

__all__ = ["aft_joint_force", "aft_slider_state"]


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


def _compile(kernel_stamp):
    """The compiled march, its numba cache keyed by the kernel it compiles in
    (:mod:`joints.kernel`)."""

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
        kernel_stamp  # noqa: B018 - in the closure: the cache key (joints.kernel)
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
                kernel.bank_update_kernel(s1, x, kj, pj, trial, F1, T1)
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

    return _aft_march


_aft_march = _compile(KERNEL_STAMP)


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


def aft_slider_state(slip_t: np.ndarray, bank: JointBank, sample: int = 0) -> np.ndarray:
    """Slider anchors (m) of the periodic loop at one sample of the period.

    The banks are marched around the loop from the slip maximum as in
    :func:`aft_joint_force` (same periodic start, :func:`joints.jenkins.jenkins_update`)
    and each joint's anchors are taken after the update at ``sample``: the state a
    time integration must start from to continue on this periodic orbit.

    Parameters
    ----------
    slip_t : ndarray, shape (n_joints, n_time)
        Slip samples over one period (m).
    bank : JointBank
    sample : int

    Returns
    -------
    ndarray, shape (n_joints, n_sliders)
    """
    slip_t = np.ascontiguousarray(slip_t, dtype=float)
    k, phi = bank.stiffness, bank.slip_limit
    anchor, _, i_max = _aft_start(slip_t, k, phi)
    nj, N = slip_t.shape
    rows = np.arange(nj)
    stop = (sample - i_max) % N              # step at which each joint reaches ``sample``
    out = np.empty_like(anchor)
    for step in range(N):
        _, _, anchor = jenkins_update(slip_t[rows, (i_max + step) % N], anchor, k, phi)
        done = stop == step
        out[done] = anchor[done]
    return out
