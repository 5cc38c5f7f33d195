"""The Jenkins-bank kernel's contract: its summation order and the plain reference loop.

:func:`bank_update_reference` is the return mapping of a bank of Jenkins elements
(paper eq. 2 over one step) written as a plain loop, with the force and tangent sums
taken in the fixed order of the compiled kernel (:mod:`joints.kernel_ir`, comment
below). It runs as plain Python and uses no hand-written IR and no numba internals
(its one-slider step :func:`slider_return_mapping`, shared with the IR kernel's last
sliders, is registered with numba's public ``register_jitable``), so it is the truth
the compiled kernel is checked against bit for bit (:func:`joints.kernel.compiled_kernel`
at its first use, ``tests/test_jenkins_kernel.py``), and, compiled by numba, the
fallback that keeps the solvers working, with the same numbers, when the hand-written
IR cannot be used.

:data:`KERNEL_STAMP` is a hash of the kernel's source files: the on-disk numba cache of
every function that compiles the kernel in is keyed by it (:mod:`joints.kernel`).
"""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from numba.extending import register_jitable

__all__ = ["LANES", "INTERLEAVE", "slider_return_mapping", "bank_update_reference",
           "KERNEL_STAMP"]

# For each joint j and slider i (paper eq. 2 over one step, a return mapping)::
#
#     x_new     = clamp(x, s - phi, s + phi)      (x if s - phi < x < s + phi)
#     force_j   = sum_i (s - x_new) k
#     tangent_j = sum_i (k if x_new == x else 0)
#
# The compiled kernel runs each joint's sliders in blocks of 8 as explicit 8-lane vector
# IR (one AVX-512 register, two AVX2 ones): two interleaved accumulators (lane m of
# accumulator u adds the terms 16 b + 8 u + m, b = 0, 1, ...; a last odd block goes to
# accumulator 0), then accumulator 0 + accumulator 1 lane by lane, the 8 lanes summed as
# ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)); plus, when n mod 8 >= 4, the next
# 4 sliders as a 4-lane block summed (l0 + l1) + (l2 + l3); plus the n mod 4 last
# sliders summed in order. No fast-math flags: that order is fixed by the IR, so every
# compilation (fresh or from numba's cache, any SIMD width, any machine) gives the same
# bits, which is what makes sweeps bitwise identical on every executor. The sums differ
# from numpy's pairwise ``np.sum`` in the last bits (within (n - 1) eps sum|terms|,
# Higham 2002 eq. 4.6; tests, and tests replay the order above in numpy bit for bit);
# the anchors involve no sum and are numpy's bit for bit (but for the sign of a zero
# anchor on an exact tie). Non-finite input: a NaN anchor stays NaN; an infinite slip
# gives NaN force as in numpy; a NaN slip (or limit) gives NaN force but, unlike numpy,
# leaves the anchors where they were (and counts them stuck).

LANES = 8       # lanes of the vector IR
INTERLEAVE = 2  # independent vector accumulators

# the files whose code a compiled caller of the kernel contains (joints/kernel.py)
_KERNEL_SOURCES = ("kernel_reference.py", "kernel_ir.py", "kernel.py")


def _source_stamp() -> str:
    """First 16 hex digits of the SHA-256 of the kernel's source files."""
    h = hashlib.sha256()
    here = Path(__file__).resolve().parent
    for name in _KERNEL_SOURCES:
        h.update(name.encode())
        h.update((here / name).read_bytes())
    return h.hexdigest()[:16]


KERNEL_STAMP = _source_stamp()


@register_jitable
def slider_return_mapping(s, x, phi, k):
    """One slider of stiffness ``k`` and slip limit ``phi`` at anchor ``x`` under slip
    ``s``: its trial anchor ``y = clamp(x, s - phi, s + phi)`` (a NaN anchor stays NaN,
    a NaN bound keeps ``x``), force term ``(s - y) k`` and tangent term (``k`` if it
    sticks, ``y == x``, else 0). Plain Python, and callable from numba-compiled code
    (the IR kernel's last sliders)."""
    lo = s - phi
    hi = s + phi
    y = lo if lo > x else x
    y = hi if hi < y else y
    return y, (s - y) * k, (k if y == x else 0.0)


def bank_update_reference(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
    """Return mapping of a Jenkins bank as a plain loop, sums in the kernel's order.

    Same arguments and bitwise the same results as
    :func:`joints.kernel.bank_update_kernel`: runs as plain Python (numpy arrays, no
    numba) and compiles with ``numba.njit`` unchanged.

    Parameters
    ----------
    slip : float64[n_joints]
        Joint slips (m).
    anchor : float64[n_joints, n_sliders]
        Committed slider positions (m); only read (unless it is ``out_anchor``).
    stiffness, slip_limit : float64[n_rows, n_sliders]
        ``k_i`` (N/m) and ``phi_i`` (m); ``n_rows`` is 1 (shared by all joints) or
        ``n_joints``.
    out_anchor : float64[n_joints, n_sliders]
        Receives the trial slider positions (m); may be ``anchor`` itself (each slider
        is read before it is written).
    force, tangent : float64[n_joints]
        Receive the joint force (N) and tangent stiffness (N/m).
    """
    n_joints, n = anchor.shape
    k_step = 1 if stiffness.shape[0] != 1 else 0
    phi_step = 1 if slip_limit.shape[0] != 1 else 0
    n_blocks = n // LANES
    n_paired = n_blocks - n_blocks % INTERLEAVE     # blocks in the interleaved loop
    n_half = LANES // 2 if n % LANES >= LANES // 2 else 0
    acc_f = np.zeros((INTERLEAVE, LANES))
    acc_t = np.zeros((INTERLEAVE, LANES))
    lanes_f = np.zeros(LANES)
    lanes_t = np.zeros(LANES)
    for j in range(n_joints):
        s = slip[j]
        rk = j * k_step
        rp = j * phi_step
        acc_f[:, :] = 0.0
        acc_t[:, :] = 0.0
        lanes_f[:] = 0.0            # the half block of 4, in lanes 0..3
        lanes_t[:] = 0.0
        f_tail = 0.0
        t_tail = 0.0
        for i in range(n):
            y, f_term, t_term = slider_return_mapping(s, anchor[j, i], slip_limit[rp, i],
                                                      stiffness[rk, i])
            out_anchor[j, i] = y
            b = i // LANES
            if b < n_blocks:        # interleaved pairs, then a last odd block into 0
                u = b % INTERLEAVE if b < n_paired else 0
                acc_f[u, i % LANES] += f_term
                acc_t[u, i % LANES] += t_term
            elif i < n_blocks * LANES + n_half:
                lanes_f[i % LANES] += f_term
                lanes_t[i % LANES] += t_term
            else:
                f_tail += f_term
                t_tail += t_term
        sums = np.zeros(2)
        for which in range(2):
            acc = acc_f if which == 0 else acc_t
            half = lanes_f if which == 0 else lanes_t
            v = acc[0].copy()
            for u in range(1, INTERLEAVE):
                v += acc[u]
            width = LANES
            while width > 1:        # lane tree: ((l0 + l1) + (l2 + l3)) + ...
                width //= 2
                for m in range(width):
                    v[m] = v[2 * m] + v[2 * m + 1]
            width = LANES // 2
            while width > 1:
                width //= 2
                for m in range(width):
                    half[m] = half[2 * m] + half[2 * m + 1]
            sums[which] = v[0] + half[0]
        force[j] = sums[0] + f_tail
        tangent[j] = sums[1] + t_tail
