"""The compiled Jenkins-bank kernel that solvers call: selection, self-check, fallback.

:func:`bank_update_kernel` is the return mapping of a bank of Jenkins elements, callable
from Python and from numba-compiled step loops (``fe.aft``, ``fe.newmark_march``). It
runs one of two compiled implementations, bitwise equal to each other:

* :data:`joints.kernel_ir.ir_bank_update`, the fast hand-written 8-lane vector IR;
* :func:`joints.kernel_reference.bank_update_reference`, the plain loop in the same
  summation order, compiled by numba (the fallback; slower, same numbers).

Fallback. The IR kernel depends on llvmlite's IR builder and on numba internals (the
``@intrinsic`` lowering API, the private ``_nrt`` target option), which an upgrade of
numba or llvmlite may change. :func:`compiled_kernel` therefore chooses once per
process, on the first use (never at import: the command line imports this module
and most commands never call the kernel): it imports and compiles the IR kernel and
runs it on a few small banks that take every code path (blocks of 8 and 4, tail,
shared and per-joint parameters, in place and not), comparing force, tangent and
anchors bit for bit with the reference loop run as plain Python. Any failure (import,
IR that no longer builds or compiles, a disagreement) gives one
:class:`KernelFallbackWarning` naming what failed, and the compiled reference loop is
used instead: the results stay the same, the joint updates are slower.

numba cache. numba keys its on-disk cache of a function by the function's own source
file only, so a cached caller that compiled the kernel in (the solvers' loops in
``fe``, and the IR kernel, whose constants come from :mod:`joints.kernel_reference`)
would keep running an old kernel after the kernel's files change. Every such caller
is therefore built by a small factory whose closure holds
:data:`joints.kernel_reference.KERNEL_STAMP`, a hash of the kernel's three source files
(``kernel_reference.py``, ``kernel_ir.py``, this file), and references it in its body;
numba puts the closure's contents into the cache index key (``_Cache._index_key``), so
a changed kernel is a new key: the caller is compiled afresh and never loaded stale,
with no file to delete by hand and nothing done at import but hashing three small files
(about 0.1 ms). Entries of earlier kernels stay in the index until the caller's own
file changes. ``tests/test_kernel_fallback.py`` edits a copy of the kernel and checks
that the cached caller runs the edited code.
"""
from __future__ import annotations

import functools
import warnings

import numpy as np
from numba import njit
from numba.extending import overload

from joints.kernel_reference import bank_update_reference

__all__ = ["bank_update_kernel", "compiled_kernel", "KernelFallbackWarning"]


class KernelFallbackWarning(RuntimeWarning):
    """The hand-written IR kernel is not used in this process (the reference loop is)."""


# the fallback: the reference loop compiled as it is (cached: it lives in one file)
_compiled_reference = njit(cache=True)(bank_update_reference)


def _ir_kernel():
    """The IR kernel's dispatcher (importing it may fail after an upgrade)."""
    from joints.kernel_ir import ir_bank_update
    return ir_bank_update


def _check_banks():
    """Small banks through every path of the kernel: (slip, anchor, k, phi) with 2
    joints, 29 sliders (16 + 8 + 4 + 1) and 7 sliders (4 + 3); per-joint and shared
    parameter rows; anchors that stick, slip, and sit exactly on a limit."""
    rng = np.random.default_rng(20240501)
    banks = []
    for n, k_rows, phi_rows in ((29, 2, 1), (7, 1, 2)):
        k = rng.uniform(1.0, 2.0, (k_rows, n)) * 1e4
        phi = np.sort(rng.uniform(0.1, 1.0, (phi_rows, n)), axis=1) * 1e-5
        slip = np.array([0.6e-5, -0.2e-5])
        anchor = rng.normal(0.0, 0.5e-5, (2, n))
        anchor[0, 3] = slip[0] - phi[0, 3]
        banks.append((slip, anchor, k, phi))
    return banks


def _self_check(kernel) -> None:
    """Raise AssertionError unless ``kernel`` gives the reference loop's bits."""
    for slip, anchor, k, phi in _check_banks():
        for in_place in (False, True):
            ref = [np.empty_like(anchor), np.empty(2), np.empty(2)]
            bank_update_reference(slip, anchor, k, phi, *ref)
            state = anchor.copy()
            got = [state if in_place else np.empty_like(anchor), np.empty(2), np.empty(2)]
            kernel(slip, state, k, phi, *got)
            for g, r in zip(got, ref):
                if not np.array_equal(g.view(np.uint64), r.view(np.uint64)):
                    raise AssertionError("its numbers differ from the reference loop's "
                                         f"on a {anchor.shape[1]}-slider check bank")


@functools.lru_cache(maxsize=None)
def compiled_kernel():
    """The compiled bank update this process uses (chosen once; module docstring).

    Returns
    -------
    numba dispatcher
        The IR kernel if it imports, compiles and passes the self-check, else the
        compiled reference loop, after one :class:`KernelFallbackWarning`.
    """
    try:
        kernel = _ir_kernel()
        _self_check(kernel)
        return kernel
    except Exception as exc:  # noqa: BLE001 - any failure: the reference loop
        reason = (str(exc).strip().splitlines() or [""])[0][:300]
        warnings.warn(KernelFallbackWarning(
            f"the compiled Jenkins kernel (hand-written vector IR, joints/kernel_ir.py) "
            f"cannot be used with this numba/llvmlite ({type(exc).__name__}: {reason}); "
            f"using the reference loop instead: results stay correct (bitwise the same) "
            f"but the joint updates are slower"), stacklevel=2)
        return _compiled_reference


def bank_update_kernel(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
    """Compiled Jenkins-bank return mapping (the kernel of
    :func:`joints.jenkins.jenkins_update`), from Python or from ``@njit`` code.

    Callable from other ``@njit`` code (solvers' step loops; pass preallocated arrays,
    not slices made per call: a view costs more than a small bank). Single-threaded, no
    heap allocation (the IR kernel). Numbers: bitwise those of
    :func:`joints.kernel_reference.bank_update_reference` (sums in its fixed order).

    Parameters
    ----------
    slip : float64[n_joints]
        Joint slips (m).
    anchor : float64[n_joints, n_sliders], C-contiguous
        Committed slider positions (m); only read (unless it is ``out_anchor``).
    stiffness, slip_limit : float64[n_rows, n_sliders], C-contiguous
        ``k_i`` (N/m) and ``phi_i`` (m); ``n_rows`` is 1 (shared by all joints) or
        ``n_joints``.
    out_anchor : float64[n_joints, n_sliders], C-contiguous
        Receives the trial slider positions (m); may be ``anchor`` itself (commit in
        place). Other overlaps are not allowed.
    force, tangent : float64[n_joints]
        Receive the joint force (N) and tangent stiffness (N/m).
    """
    compiled_kernel()(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent)


@overload(bank_update_kernel)
def _bank_update_kernel_compiled(slip, anchor, stiffness, slip_limit, out_anchor, force,
                                 tangent):
    """:func:`bank_update_kernel` inside compiled code: the kernel is chosen when the
    first caller is compiled (a caller loaded from numba's cache needs no choice)."""
    kernel = compiled_kernel()

    def impl(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
        kernel(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent)

    return impl
