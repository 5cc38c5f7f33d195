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

from llvmlite import ir as _ir
from numba import njit, types as _nbtypes
from numba.extending import intrinsic as _intrinsic

from joints.kernel_reference import INTERLEAVE, KERNEL_STAMP, LANES, slider_return_mapping

__all__ = ["ir_bank_update"]


def _no_refcount_option() -> dict:
    """numba's private switch to compile without reference counting, where it exists."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:
        return {}
    return {"_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {}


_NO_REFCOUNT = _no_refcount_option()



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

    def codegen(context, builder, signature, args):
        s_v, _, _, _, ix_v, ip_v, ik_v, n_v = args
        vty = _ir.VectorType(_ir.DoubleType(), LANES)
        i32 = _ir.IntType(32)
        ity = ix_v.type
        px, pphi, pk = (context.make_array(t)(context, builder, v).data
                        for t, v in zip(signature.args[1:4], args[1:4]))

        def splat(value, width):
            v = _ir.Constant(_ir.VectorType(value.type, width), _ir.Undefined)
            for m in range(width):
                v = builder.insert_element(v, value, _ir.Constant(i32, m))
            return v

        sv_full = splat(s_v, LANES)
        zero = _ir.Constant(vty, [0.0] * LANES)

        def block(i, f_acc, t_acc, width=LANES):
            """Sliders i .. i+width-1: clamp, store, accumulate; new accumulators."""
            vty = _ir.VectorType(_ir.DoubleType(), width)
            sv = splat(s_v, width) if width != LANES else sv_full
            zero = _ir.Constant(vty, [0.0] * width)

            def at(ptr, base):
                return builder.bitcast(builder.gep(ptr, [builder.add(base, i)]),
                                       vty.as_pointer())
            xv = builder.load(at(px, ix_v), align=8)
            pv = builder.load(at(pphi, ip_v), align=8)
            kv = builder.load(at(pk, ik_v), align=8)
            lo = builder.fsub(sv, pv)
            hi = builder.fadd(sv, pv)
            # x86 max/min operand order: NaN anchors stay NaN, a NaN bound keeps x
            y = builder.select(builder.fcmp_ordered(">", lo, xv), lo, xv)
            y = builder.select(builder.fcmp_ordered("<", hi, y), hi, y)
            builder.store(y, at(px, ix_v), align=8)
            f_term = builder.fmul(builder.fsub(sv, y), kv)
            t_term = builder.select(builder.fcmp_ordered("==", y, xv), kv, zero)
            return builder.fadd(f_acc, f_term), builder.fadd(t_acc, t_term)

        def loop(name, start, limit, accs):
            """Blocks from slider ``start`` while ``len(accs)`` more fit below
            ``limit``, block u of each step into accumulator u."""
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
            new = [block(builder.add(i, _ir.Constant(ity, LANES * u)), pf, pt)
                   for u, (pf, pt) in enumerate(phis)]
            latch = builder.basic_block
            builder.branch(head)
            i.add_incoming(nxt, latch)
            for (pf, pt), (f, t) in zip(phis, new):
                pf.add_incoming(f, latch)
                pt.add_incoming(t, latch)
            builder.position_at_end(done)
            return i, phis

        limit = builder.mul(builder.sdiv(n_v, _ir.Constant(ity, LANES)),
                            _ir.Constant(ity, LANES))
        i_end, accs = loop("pairs", _ir.Constant(ity, 0), limit,
                           [(zero, zero)] * INTERLEAVE)
        _, (last,) = loop("single", i_end, limit, [accs[0]])
        accs = [last] + accs[1:]

        def lane_tree(v):
            """((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)) by shuffles: after
            step h, lane 2h m holds the sum of lanes 2h m .. 2h m + 2h - 1."""
            width = v.type.count
            h = 1
            while h < width:
                partner = [m ^ h for m in range(width)]
                v = builder.fadd(v, builder.shuffle_vector(
                    v, v, _ir.Constant(_ir.VectorType(i32, width), partner)))
                h *= 2
            return builder.extract_element(v, _ir.Constant(i32, 0))

        sums = []
        for which in (0, 1):
            v = accs[0][which]
            for a in accs[1:]:
                v = builder.fadd(v, a[which])
            sums.append(lane_tree(v))
        # a half block of 4 when n mod 8 >= 4, its own lane tree added after
        half = LANES // 2
        rem = builder.srem(n_v, _ir.Constant(ity, LANES))
        before = builder.basic_block
        with builder.if_then(builder.icmp_signed(">=", rem, _ir.Constant(ity, half))):
            zero4 = _ir.Constant(_ir.VectorType(_ir.DoubleType(), half), [0.0] * half)
            halves = [lane_tree(v) for v in block(limit, zero4, zero4, half)]
            inside = builder.basic_block
        phis = [builder.phi(_ir.DoubleType()) for _ in (0, 1)]
        for ph, h in zip(phis, halves):
            ph.add_incoming(_ir.Constant(_ir.DoubleType(), 0.0), before)
            ph.add_incoming(h, inside)
        sums = [builder.fadd(v, ph) for v, ph in zip(sums, phis)]
        return context.make_tuple(builder, signature.return_type, sums)

    return sig, codegen

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
