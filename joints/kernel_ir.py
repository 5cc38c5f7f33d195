"""The Jenkins-bank kernel as hand-written 8-lane vector IR (llvmlite, numba intrinsic).

:data:`ir_bank_update` is the fast compiled return mapping of a bank of Jenkins
elements: each joint's sliders in blocks of 8 as explicit 8-lane vector IR, summed in
the fixed order of :mod:`joints.kernel_reference` (comment above ``LANES`` there), so
that every compilation gives the same bits; compiled without reference counting where
numba offers that (private) switch. It relies on llvmlite's IR builder and on numba's
intrinsic and target-option internals, which an upgrade may change: callers do not use
it directly but through :func:`joints.kernel.bank_update_kernel`, which checks it
against :func:`joints.kernel_reference.bank_update_reference` on its first use and
falls back to that loop if it does not build or does not agree.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from llvmlite import ir as _ir
from numba import njit, types as _nbtypes
from numba.extending import intrinsic as _intrinsic

from joints.kernel_reference import INTERLEAVE, KERNEL_STAMP, LANES, slider_return_mapping

if TYPE_CHECKING:
    from numba.core.base import BaseContext
    from numba.core.typing.templates import Signature

__all__ = ["ir_bank_update"]


def _no_refcount_option() -> dict:
    """numba's private switch to compile without reference counting, where it exists."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:
        return {}
    return {"_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {}


_NO_REFCOUNT = _no_refcount_option()


@dataclass(frozen=True)
class _Sliders:
    """One joint's sliders as the IR sees them: the builder, the vector type of a full
    block, the slip (scalar and splat over ``LANES``), the data pointers of anchors,
    limits and stiffnesses and the offsets of the joint's row in each."""
    builder: _ir.IRBuilder
    vty: _ir.VectorType
    s: _ir.Value
    s_full: _ir.Value
    px: _ir.Value
    pphi: _ir.Value
    pk: _ir.Value
    ix: _ir.Value
    ip: _ir.Value
    ik: _ir.Value


def _splat(builder: _ir.IRBuilder, value: _ir.Value, width: int) -> _ir.Value:
    """``value`` in every lane of a ``width``-lane vector."""
    i32 = _ir.IntType(32)
    v = _ir.Constant(_ir.VectorType(value.type, width), _ir.Undefined)
    for m in range(width):
        v = builder.insert_element(v, value, _ir.Constant(i32, m))
    return v


def _sliders(context: BaseContext, builder: _ir.IRBuilder, signature: Signature,
             args: list) -> _Sliders:
    """The intrinsic's arguments as :class:`_Sliders`; emits the slip's splat."""
    s_v, _, _, _, ix_v, ip_v, ik_v, _ = args
    vty = _ir.VectorType(_ir.DoubleType(), LANES)    # first use of llvmlite's IR builder
    px, pphi, pk = (context.make_array(t)(context, builder, v).data
                    for t, v in zip(signature.args[1:4], args[1:4]))
    return _Sliders(builder, vty, s_v, _splat(builder, s_v, LANES), px, pphi, pk,
                    ix_v, ip_v, ik_v)


def _block(sl: _Sliders, i: _ir.Value, f_acc: _ir.Value, t_acc: _ir.Value,
           width: int = LANES) -> tuple[_ir.Value, _ir.Value]:
    """Sliders i .. i+width-1: clamp, store, accumulate; new accumulators."""
    builder = sl.builder
    vty = _ir.VectorType(_ir.DoubleType(), width)
    sv = _splat(builder, sl.s, width) if width != LANES else sl.s_full
    zero = _ir.Constant(vty, [0.0] * width)

    def at(ptr, base):
        return builder.bitcast(builder.gep(ptr, [builder.add(base, i)]), vty.as_pointer())
    xv = builder.load(at(sl.px, sl.ix), align=8)
    pv = builder.load(at(sl.pphi, sl.ip), align=8)
    kv = builder.load(at(sl.pk, sl.ik), align=8)
    lo = builder.fsub(sv, pv)
    hi = builder.fadd(sv, pv)
    # x86 max/min operand order: NaN anchors stay NaN, a NaN bound keeps x
    y = builder.select(builder.fcmp_ordered(">", lo, xv), lo, xv)
    y = builder.select(builder.fcmp_ordered("<", hi, y), hi, y)
    builder.store(y, at(sl.px, sl.ix), align=8)
    f_term = builder.fmul(builder.fsub(sv, y), kv)
    t_term = builder.select(builder.fcmp_ordered("==", y, xv), kv, zero)
    return builder.fadd(f_acc, f_term), builder.fadd(t_acc, t_term)


def _loop(sl: _Sliders, name: str, start: _ir.Value, limit: _ir.Value,
          accs: list) -> tuple[_ir.Value, list]:
    """Blocks from slider ``start`` while ``len(accs)`` more fit below ``limit``, block
    u of each step into accumulator u; the loop's index and accumulators after it."""
    builder, vty, ity = sl.builder, sl.vty, sl.ix.type
    entry = builder.basic_block
    head = builder.append_basic_block(name + ".head")
    body = builder.append_basic_block(name + ".body")
    done = builder.append_basic_block(name + ".done")
    builder.branch(head)
    builder.position_at_end(head)
    i = builder.phi(ity)
    i.add_incoming(start, entry)
    phis = []
    for f, t in accs:
        pf, pt = builder.phi(vty), builder.phi(vty)
        pf.add_incoming(f, entry)
        pt.add_incoming(t, entry)
        phis.append((pf, pt))
    nxt = builder.add(i, _ir.Constant(ity, LANES * len(accs)))
    builder.cbranch(builder.icmp_signed("<=", nxt, limit), body, done)
    builder.position_at_end(body)
    new = [_block(sl, builder.add(i, _ir.Constant(ity, LANES * u)), pf, pt)
           for u, (pf, pt) in enumerate(phis)]
    latch = builder.basic_block
    builder.branch(head)
    i.add_incoming(nxt, latch)
    for (pf, pt), (f, t) in zip(phis, new):
        pf.add_incoming(f, latch)
        pt.add_incoming(t, latch)
    builder.position_at_end(done)
    return i, phis


def _full_blocks(sl: _Sliders, n: _ir.Value) -> tuple[_ir.Value, list]:
    """The ``n // 8`` full blocks: pairs into the ``INTERLEAVE`` accumulators, a last odd
    one into accumulator 0; returns (first slider after them, accumulators)."""
    ity = sl.ix.type
    zero = _ir.Constant(sl.vty, [0.0] * LANES)
    limit = sl.builder.mul(sl.builder.sdiv(n, _ir.Constant(ity, LANES)),
                           _ir.Constant(ity, LANES))
    i_end, accs = _loop(sl, "pairs", _ir.Constant(ity, 0), limit,
                        [(zero, zero)] * INTERLEAVE)
    _, (last,) = _loop(sl, "single", i_end, limit, [accs[0]])
    return limit, [last] + accs[1:]


def _lane_tree(builder: _ir.IRBuilder, v: _ir.Value) -> _ir.Value:
    """((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)) by shuffles: after step h,
    lane 2h m holds the sum of lanes 2h m .. 2h m + 2h - 1."""
    i32 = _ir.IntType(32)
    width = v.type.count
    h = 1
    while h < width:
        partner = [m ^ h for m in range(width)]
        v = builder.fadd(v, builder.shuffle_vector(
            v, v, _ir.Constant(_ir.VectorType(i32, width), partner)))
        h *= 2
    return builder.extract_element(v, _ir.Constant(i32, 0))


def _lane_sums(builder: _ir.IRBuilder, accs: list) -> list:
    """(force, tangent): the accumulators added lane by lane, then each lane tree."""
    sums = []
    for which in (0, 1):
        v = accs[0][which]
        for a in accs[1:]:
            v = builder.fadd(v, a[which])
        sums.append(_lane_tree(builder, v))
    return sums


def _with_half_block(sl: _Sliders, n: _ir.Value, start: _ir.Value, sums: list) -> list:
    """``sums`` plus, when ``n mod 8 >= 4``, the lane trees of the half block of 4 at
    slider ``start`` (0.0 otherwise)."""
    builder, ity = sl.builder, sl.ix.type
    half = LANES // 2
    rem = builder.srem(n, _ir.Constant(ity, LANES))
    before = builder.basic_block
    with builder.if_then(builder.icmp_signed(">=", rem, _ir.Constant(ity, half))):
        zero4 = _ir.Constant(_ir.VectorType(_ir.DoubleType(), half), [0.0] * half)
        halves = [_lane_tree(builder, v) for v in _block(sl, start, zero4, zero4, half)]
        inside = builder.basic_block
    phis = [builder.phi(_ir.DoubleType()) for _ in (0, 1)]
    for ph, h in zip(phis, halves):
        ph.add_incoming(_ir.Constant(_ir.DoubleType(), 0.0), before)
        ph.add_incoming(h, inside)
    return [builder.fadd(v, ph) for v, ph in zip(sums, phis)]


def _codegen(context: BaseContext, builder: _ir.IRBuilder, signature: Signature,
             args: list) -> _ir.Value:
    """The IR of :func:`_simd_blocks`: full blocks, their lane sums, the half block."""
    sl = _sliders(context, builder, signature, args)
    n_v = args[7]
    limit, accs = _full_blocks(sl, n_v)
    sums = _with_half_block(sl, n_v, limit, _lane_sums(builder, accs))
    return context.make_tuple(builder, signature.return_type, sums)


@_intrinsic
def _simd_blocks(typingctx, s, x, phi, k, ix, ip, ik, n):
    """Return mapping of the ``n // 8`` full blocks of 8 sliders of one joint and of
    the next 4 when ``n mod 8 >= 4``, in place on ``x`` (flat C-contiguous arrays:
    anchors ``x[ix + i]``, limits ``phi[ip + i]``, stiffnesses ``k[ik + i]``);
    returns their (force, tangent) summed in the order of
    :mod:`joints.kernel_reference`."""
    ok = all(isinstance(a, _nbtypes.Array) and a.dtype == _nbtypes.float64
             and a.layout == "C" for a in (x, phi, k))
    if not ok or s != _nbtypes.float64 or not x.mutable:
        return None
    intp = _nbtypes.intp
    sig = _nbtypes.UniTuple(_nbtypes.float64, 2)(s, x, phi, k, intp, intp, intp, intp)
    return sig, _codegen


@njit(inline="always")     # only ever inlined into ir_bank_update: nothing to cache
def _row_in_place(s, x, j, k, rk, phi, rp):
    """Return mapping of joint ``j``'s sliders, committed into ``x[j]``; returns
    (force, tangent): the blocks of 8 and 4 by :func:`_simd_blocks`, the n mod 4
    last sliders in order (independently, then added)."""
    n = x.shape[1]
    f_tail = 0.0
    t_tail = 0.0
    for i in range(n - n % (LANES // 2), n):
        y, f_term, t_term = slider_return_mapping(s, x[j, i], phi[rp, i], k[rk, i])
        x[j, i] = y
        f_tail += f_term
        t_tail += t_term
    f, t = _simd_blocks(s, x, phi, k, j * n, rp * n, rk * n, n)
    return f + f_tail, t + t_tail


def _compile(kernel_stamp):
    """The IR kernel as a numba dispatcher whose on-disk cache is keyed by
    ``kernel_stamp`` (its code comes from two files; see :mod:`joints.kernel`)."""

    @njit(cache=True, **_NO_REFCOUNT)
    def ir_bank_update(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
        """Compiled Jenkins-bank return mapping (arguments of
        :func:`joints.kernel.bank_update_kernel`).

        Single-threaded, no heap allocation, compiled without reference counting
        (``_nrt=False``: the array arguments' incref/decref around the copy branch
        cost ~75 ns per call, more than a 300-slider joint). All arrays float64 and
        C-contiguous; ``out_anchor`` may be ``anchor`` itself, other overlaps are not
        allowed.
        """
        kernel_stamp  # noqa: B018 - in the closure: the cache key
        k_step = 1 if stiffness.shape[0] != 1 else 0
        phi_step = 1 if slip_limit.shape[0] != 1 else 0
        if anchor.ctypes.data != out_anchor.ctypes.data:
            for j in range(anchor.shape[0]):
                for i in range(anchor.shape[1]):
                    out_anchor[j, i] = anchor[j, i]
        for j in range(anchor.shape[0]):
            f, t = _row_in_place(slip[j], out_anchor, j, stiffness, j * k_step,
                                 slip_limit, j * phi_step)
            force[j] = f
            tangent[j] = t

    return ir_bank_update


ir_bank_update = _compile(KERNEL_STAMP)
