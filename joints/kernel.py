"""The compiled Jenkins-bank kernel that solvers call: selection, self-check, fallback.

``bank_update_kernel`` is the return mapping of a bank of Jenkins elements (arguments
in :func:`compiled_kernel`), callable from Python and from numba-compiled step loops
(``fe.aft``, ``fe.newmark_march``), which write ``kernel.bank_update_kernel(...)``
after ``from joints import kernel``. It is one of two compiled implementations, bitwise
equal to each other:

* :data:`joints.kernel_ir.ir_bank_update`, the fast hand-written 8-lane vector IR;
* :func:`joints.kernel_reference.bank_update_reference`, the plain loop in the same
  summation order, compiled by numba (the fallback; slower, same numbers).

Fallback. The IR kernel depends on llvmlite's IR builder and on numba internals (the
``@intrinsic`` lowering API, the private ``_nrt`` target option), which an upgrade of
numba or llvmlite may change. :func:`compiled_kernel` therefore chooses once per
process, on the first access to ``bank_update_kernel`` (a module attribute that
appears then; never at import: the command line imports this module and most commands
never call the kernel; a caller loaded from numba's cache does not ask): it imports and compiles the IR kernel and
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

import warnings
from typing import Callable

import numpy as np
from numba import njit

from joints.kernel_reference import bank_update_reference

__all__ = ["bank_update_kernel", "compiled_kernel", "reference_kernel", "KernelFallbackWarning"]


class KernelFallbackWarning(RuntimeWarning):
    """The hand-written IR kernel is not used in this process (the reference loop is)."""


# the fallback: the reference loop compiled as it is (cached: it lives in one file)
reference_kernel = njit(cache=True)(bank_update_reference)


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


def _select_kernel():
    """The IR kernel if it imports, compiles and passes the self-check, else the
    compiled reference loop after one :class:`KernelFallbackWarning`."""
    try:
        kernel = _ir_kernel()
        _self_check(kernel)
        return kernel
    except Exception as exc:  # noqa: BLE001 - any failure: the reference loop
        reason = " ".join(str(exc).split())[:300]
        warnings.warn(KernelFallbackWarning(
            f"the compiled Jenkins kernel (hand-written vector IR, joints/kernel_ir.py) "
            f"cannot be used with this numba/llvmlite ({type(exc).__name__}: {reason}); "
            f"using the reference loop instead: results stay correct (bitwise the same) "
            f"but the joint updates are slower"), stacklevel=3)
        return reference_kernel


def compiled_kernel():
    """The compiled bank update of this process, chosen on the first call (module
    docstring) and from then on the module attribute :data:`bank_update_kernel`.

    Returns
    -------
    numba dispatcher
        ``kernel(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent)``,
        arguments as :func:`joints.kernel_reference.bank_update_reference`: slips
        ``float64[n_joints]`` (m); committed anchors ``float64[n_joints, n_sliders]``
        (m), only read unless they are ``out_anchor``; stiffnesses (N/m) and slip limits
        (m) ``float64[n_rows, n_sliders]`` with ``n_rows`` 1 (shared by all joints) or
        ``n_joints``; ``out_anchor`` receives the trial anchors (may be ``anchor``
        itself, no other overlap); ``force`` and ``tangent`` ``float64[n_joints]``
        receive the joint forces (N) and tangent stiffnesses (N/m). All C-contiguous.
        Callable from Python and from ``@njit`` code (solvers' step loops: pass
        preallocated arrays, not slices made per call; a view costs more than a small
        bank); single-threaded, no heap allocation (the IR kernel).
    """
    kernel = globals().get("bank_update_kernel")
    if kernel is None:
        kernel = _select_kernel()
        globals()["bank_update_kernel"] = kernel
    return kernel


# The kernel, as a module attribute that appears on first access: compiled callers
# write ``kernel.bank_update_kernel(...)`` (numba resolves it when the caller is
# compiled, which is when the kernel is chosen), Python callers likewise at call time.
bank_update_kernel: Callable


def __getattr__(name: str):
    """Module attribute hook: the first access to ``bank_update_kernel`` chooses it."""
    if name == "bank_update_kernel":
        return compiled_kernel()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
