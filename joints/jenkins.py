"""Discretization of the Iwan density into a bank of Jenkins elements, and its state
update over joints x sliders (Segalman 2005; paper eqs. 1-2).

Each Jenkins element ``i`` is a spring of stiffness ``k_i`` (N/m) in series with a
Coulomb slider that slips when the spring stretch reaches ``phi_i`` (m). Its state is
the slider position (the *anchor*) ``x_i``; the force is ``k_i (u - x_i)``.

Accuracy of :func:`discretize` against the exact continuous model of
:mod:`joints.iwan` (measured for n = 10, 30, 100, 300, 1000 with chi from -0.95 to
-0.05, beta = 0 and 4; see ``tests/test_jenkins.py``): the maximum backbone error over
``|u| <= phi_max`` and the maximum relative micro-slip dissipation error over
``A`` in [0.1, 0.9] ``phi_max`` both fall as ``n**-2`` (log-log slopes -1.90 ... -2.11).
At n = 100: backbone error 3.8e-6 F_S (chi = -0.5, beta = 4) to 2.4e-4 F_S
(chi = -0.8, beta = 0); dissipation error 6.5e-4 (chi = -0.5) to 7.6e-3 (chi = -0.95).
The midpoint rule in ``s = (phi/phi_max)**(chi+1)`` is second order because the
integrands are Lipschitz with one kink. The weakest slider has
``phi_1 = phi_max (1/(2 n_c))**(1/(chi+1))``: below that amplitude the bank is linear
and dissipates nothing. More precisely, the relative micro-slip dissipation error at
amplitude ``A`` is about ``c / m_A**2`` with ``m_A = n (A/phi_max)**(chi+1)`` the number
of sliders that slip at that amplitude, c = 0.5 (chi = -0.2) to 1.2 (chi = -0.5)
(measured, A from 0.01 to 0.3 phi_max): 1e-3 needs m_A of about 35.

State update: :func:`jenkins_update` (pure) and :func:`jenkins_update_into` (in place)
run the compiled kernel :func:`bank_update_kernel`, which compiled solvers may call
from their own ``@njit`` step loops. It is bitwise equal to the plain numpy update
(:func:`_jenkins_update_numpy`; numpy's pairwise summation order is replayed in 8-wide
SIMD lanes). Measured with ``benchmarks/bench_jenkins.py`` (one thread, AMD EPYC, CPU
time medians on a shared 2-core machine): 3.7e9-4.4e9 slider updates/s inside a
compiled loop for banks of 1e3-1e5 sliders (about 30 ns + 0.25 ns per slider per call,
10 ns fixed per joint), 10-16x the straightforward numpy update at those sizes and
40-150x for banks of 100-1000 sliders; a Python-level call costs about 2.5 us plus
the kernel time (numpy: 8-12 us for 2 x 100).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from joints.iwan import IwanParameters

__all__ = ["JenkinsDiscretization", "discretize", "discretize_log", "jenkins_update",
           "jenkins_update_into", "bank_update_kernel"]


@dataclass(frozen=True)
class JenkinsDiscretization:
    """A bank of Jenkins elements in parallel.

    Attributes
    ----------
    stiffness : ndarray, shape (n_sliders,)
        Spring stiffnesses ``k_i`` (N/m); they sum to ``K_T``.
    slip_limit : ndarray, shape (n_sliders,)
        Stretch ``phi_i`` (m) at which slider ``i`` slips, ascending.
    """

    stiffness: np.ndarray
    slip_limit: np.ndarray

    @property
    def n_sliders(self) -> int:
        return int(self.stiffness.size)


def discretize(p: IwanParameters, n_sliders: int) -> JenkinsDiscretization:
    """Discretize the Iwan density into ``n_sliders`` Jenkins elements.

    The continuous part ``R phi**chi`` on ``(0, phi_max)`` has cumulative stiffness
    ``(K_T - S) s`` with ``s = (phi/phi_max)**(chi+1)`` (paper eq. 6). It is
    split into ``n_c`` sliders of equal stiffness ``(K_T - S)/n_c`` placed at the
    midpoints ``s_i = (i - 1/2)/n_c``, i.e. ``phi_i = phi_max s_i**(1/(chi+1))``. When
    ``S > 0`` the last slider carries the Dirac term: stiffness ``S`` at ``phi_max``
    (then ``n_c = n_sliders - 1``, else ``n_c = n_sliders``). Stiffnesses sum to
    ``K_T`` up to rounding, so the stuck stiffness is not shifted; the backbone and
    micro-slip dissipation converge as ``n**-2`` (module docstring).

    Parameters
    ----------
    p : IwanParameters
    n_sliders : int
        Total number of sliders, >= 2.

    Returns
    -------
    JenkinsDiscretization
    """
    n = int(n_sliders)
    if n != n_sliders or n < 2:
        raise ValueError(f"n_sliders must be an integer >= 2, got {n_sliders!r}")
    S = p.S
    with_dirac = S > 0.0
    n_c = n - 1 if with_dirac else n
    s_mid = (np.arange(n_c) + 0.5) / n_c
    phi = p.phi_max * s_mid ** (1.0 / (p.chi + 1.0))
    k = np.full(n_c, (p.K_T - S) / n_c) if with_dirac else np.full(n_c, p.K_T / n_c)
    if with_dirac:
        phi = np.append(phi, p.phi_max)
        k = np.append(k, S)
    return JenkinsDiscretization(stiffness=k, slip_limit=phi)


def discretize_log(p: IwanParameters, a_low: float,
                   sliders_per_octave: int = 16) -> JenkinsDiscretization:
    """Discretize the Iwan density with slip limits spaced geometrically (per octave).

    For responses whose slip amplitude spans decades (a stepped-sine campaign over a
    factor 512 in force), the uniform-in-``s`` rule of :func:`discretize` wastes its
    sliders near ``phi_max``: the error at amplitude ``A`` is set by the number of
    sliders below ``A`` (module docstring). Here the continuous density ``R phi**chi``
    on ``(0, phi_max)`` (paper eq. 6) is cut at ``e_k = phi_max 2**(-k/n)``, ``k = 0 ..
    K``, ``K = ceil(n log2(phi_max / a_low))``, ``n = sliders_per_octave``, plus the cell
    ``(0, e_K)``. Cell ``(a, b)`` becomes one slider of stiffness ``int_a^b rho = (K_T -
    S) (x_b**(chi+1) - x_a**(chi+1))`` (``x = phi / phi_max``) and slip limit the
    density-weighted mean ``phi_max (chi+1)/(chi+2) (x_b**(chi+2) - x_a**(chi+2)) /
    (x_b**(chi+1) - x_a**(chi+1))`` (exact zeroth and first moments of every cell, so
    the saturated force ``sum k_i phi_i`` is ``F_S`` to rounding). With ``S > 0`` one more
    slider of stiffness ``S`` at ``phi_max`` carries the Dirac term. The stiffnesses sum
    to ``K_T`` to rounding (the telescoping cell sums), so the stuck stiffness is not
    shifted.

    Accuracy (closed-form describing function of each slider against
    :func:`joints.iwan.dissipation_per_cycle` and :func:`joints.iwan.describing_function`,
    amplitudes ``A`` from 1e-3 ``phi_max`` to ``phi_max`` with ``a_low = 2**-6 1e-3
    phi_max``, chi from -0.9 to -0.1, beta = 0 and 4; ``tests/test_jenkins.py``): the
    largest relative error of the dissipation per cycle and of the in-phase stiffness
    loss ``K_T - k_in`` is 3.9e-3 / 7.4e-4 with 8 sliders per octave, 9.9e-4 / 1.7e-4
    with 16 (6.3e-4 / 7.4e-5 at chi = -0.5; 257 sliders) and 2.4e-4 / 8.1e-5 with 32:
    second order in the cell width for chi >= -0.5, larger for chi near 0 (near chi =
    -1 the one slider below ``a_low`` holds a large share, (a_low/phi_max)**(chi+1), and
    limits the gain). In macro-slip (``A`` = 1 to
    4 ``phi_max``, chi = -0.5, 16 per octave) the errors stay below 2.4e-4 / 1.1e-4.
    The uniform :func:`discretize` reaches 1.1e-3 over the same range with 1000 sliders
    and 1.4e-4 with 2000. Below ``a_low`` the bank is resolved by one slider only: keep
    the smallest amplitude of interest a few octaves (6 above) over ``a_low``.

    Parameters
    ----------
    p : IwanParameters
    a_low : float
        Lowest resolved slip limit (m), ``0 < a_low < phi_max``.
    sliders_per_octave : int
        >= 1.

    Returns
    -------
    JenkinsDiscretization
        ``K + 1`` sliders (``K + 2`` with ``S > 0``), slip limits ascending.
    """
    pm = p.phi_max
    if not (isinstance(a_low, (int, float, np.floating)) and 0 < a_low < pm):
        raise ValueError(f"a_low must lie in (0, phi_max = {pm:.4g} m), got {a_low!r}")
    n = int(sliders_per_octave)
    if n != sliders_per_octave or n < 1:
        raise ValueError(f"sliders_per_octave must be an integer >= 1, got "
                         f"{sliders_per_octave!r}")
    n_cuts = int(np.ceil(n * np.log2(pm / a_low)))
    x = np.concatenate([[0.0], 2.0 ** (-np.arange(n_cuts, -1, -1) / n)])
    c = p.chi + 1.0
    cell = np.diff(x ** c)                                   # share of K_T - S per cell
    mean_x = c / (c + 1.0) * np.diff(x ** (c + 1.0)) / cell  # density-weighted mean
    k = (p.K_T - p.S) * cell
    phi = pm * mean_x
    if p.S > 0.0:
        k, phi = np.append(k, p.S), np.append(phi, pm)
    return JenkinsDiscretization(stiffness=k, slip_limit=phi)


# ------------------------------------------------------------------ state update
#
# One definition, two implementations. For each joint j and slider i::
#
#     x_new = minimum(maximum(x, s - phi), s + phi)      (numpy NaN/tie semantics)
#     force_j   = pairwise_sum_i( (s - x_new) * k )
#     tangent_j = pairwise_sum_i( k if x_new == x else 0.0 )
#
# ``pairwise_sum`` is numpy's summation along a contiguous axis (``np.sum(a, axis=-1)``
# on a C-contiguous array: ``+0.0 + pairwise(a)``, with blocks of <= 128 terms summed
# in 8 interleaved accumulators and longer runs halved recursively). The compiled
# kernel replays that order term by term, so the two implementations agree bit for bit
# (tests/test_jenkins_kernel.py), signed zeros, ties, infinities and NaN slips or
# anchors included. The one exception is a NaN in ``slip_limit`` (never produced by
# :func:`discretize`): the kernel then leaves that slider where it was.

_PAIRWISE_BLOCK = 128  # numpy's PW_BLOCKSIZE


def _jenkins_update_numpy(slip, anchor, stiffness, slip_limit):
    """Reference numpy implementation of :func:`jenkins_update` (any broadcastable
    shapes); returns ``(force, tangent, anchor_new)``."""
    col = slip[..., None]
    anchor_new = np.maximum(anchor, col - slip_limit)
    np.minimum(anchor_new, col + slip_limit, out=anchor_new)
    stuck = anchor_new == anchor
    terms = np.ascontiguousarray((col - anchor_new) * stiffness)
    force = np.sum(terms, axis=-1)
    tangent = np.sum(np.ascontiguousarray(np.where(stuck, stiffness, 0.0)), axis=-1)
    return force, tangent, anchor_new


try:  # the compiled kernel; numpy fallback if numba is missing
    from llvmlite import ir as _ir
    from numba import carray as _carray, njit, types as _nbtypes
    from numba.core import cgutils as _cgutils
    from numba.extending import intrinsic as _intrinsic
except ImportError:  # pragma: no cover - numba is a declared dependency
    njit = None

_LANES = 8  # numpy's pairwise_sum keeps 8 interleaved accumulators

if njit is not None:

    def _make_slide_blocks(nan_exact):
        """Build the vector intrinsic ``f(s, x, phi, k, out, ix, ip, ik, n_blocks)``.

        It runs the return mapping of ``n_blocks`` blocks of 8 sliders as 8-wide
        vector IR (one SIMD register on AVX-512, two on AVX2) on C-contiguous arrays
        indexed flat: anchors ``x[ix + i]``, limits ``phi[ip + i]``, stiffnesses
        ``k[ik + i]`` for ``i < 8 n_blocks``, trial positions written to
        ``out[ix + i]``. It returns the 8 force and the 8 tangent
        accumulators of numpy's pairwise sum (lane ``m`` adds terms ``m, 8 + m, ...``
        in order, from -0.0, the exact additive identity). No fast-math flags: every
        lane rounds exactly as the scalar numpy operations do.

        ``nan_exact=False`` clamps with one unordered compare per bound (``x`` if
        ``x > lo`` or unordered, then ``y`` if ``y < hi`` or unordered): NaN anchors
        propagate and ties give the bound, as in numpy, but a NaN bound (NaN slip or
        limit, inf - inf) would be ignored. ``nan_exact=True`` reproduces
        ``np.maximum``/``np.minimum`` for every input (two more compares per bound);
        the kernel uses it for joints whose slip is not finite.
        """

        @_intrinsic
        def slide_blocks(typingctx, s, x, phi, k, out, ix, ip, ik, n_blocks):
            ok = all(isinstance(a, _nbtypes.Array) and a.dtype == _nbtypes.float64
                     and a.layout == "C" for a in (x, phi, k, out))
            if not ok or s != _nbtypes.float64 or not out.mutable:
                return None
            intp = _nbtypes.intp
            sig = _nbtypes.UniTuple(_nbtypes.float64, 2 * _LANES)(
                s, x, phi, k, out, intp, intp, intp, intp)

            def codegen(context, builder, signature, args):
                s_v, x_v, phi_v, k_v, out_v, ix_v, ip_v, ik_v, nb_v = args
                vty = _ir.VectorType(_ir.DoubleType(), _LANES)
                i32 = _ir.IntType(32)
                px, pphi, pk, pout = (context.make_array(t)(context, builder, v).data
                                      for t, v in zip(signature.args[1:5], args[1:5]))
                sv = _ir.Constant(vty, _ir.Undefined)
                for m in range(_LANES):
                    sv = builder.insert_element(sv, s_v, _ir.Constant(i32, m))
                negzero = _ir.Constant(vty, [-0.0] * _LANES)
                zero = _ir.Constant(vty, [0.0] * _LANES)
                ity = ix_v.type
                entry = builder.basic_block
                head = builder.append_basic_block("blocks.head")
                body = builder.append_basic_block("blocks.body")
                done = builder.append_basic_block("blocks.done")
                builder.branch(head)
                builder.position_at_end(head)
                ib = builder.phi(ity)
                f_acc = builder.phi(vty)
                t_acc = builder.phi(vty)
                ib.add_incoming(_ir.Constant(ity, 0), entry)
                f_acc.add_incoming(negzero, entry)
                t_acc.add_incoming(negzero, entry)
                builder.cbranch(builder.icmp_signed("<", ib, nb_v), body, done)
                builder.position_at_end(body)
                step = builder.mul(ib, _ir.Constant(ity, _LANES))

                def at(ptr, base):
                    elem = builder.gep(ptr, [builder.add(base, step)])
                    return builder.bitcast(elem, vty.as_pointer())

                xv = builder.load(at(px, ix_v), align=8)
                phiv = builder.load(at(pphi, ip_v), align=8)
                kv = builder.load(at(pk, ik_v), align=8)
                lo_b = builder.fsub(sv, phiv)
                hi_b = builder.fadd(sv, phiv)
                # np.maximum(x, lo) then np.minimum(., hi): the first operand if it
                # wins or is NaN, else the second (ties give the second operand)
                if nan_exact:
                    keep = builder.or_(builder.fcmp_ordered(">", xv, lo_b),
                                       builder.fcmp_unordered("uno", xv, xv))
                    y = builder.select(keep, xv, lo_b)
                    keep = builder.or_(builder.fcmp_ordered("<", y, hi_b),
                                       builder.fcmp_unordered("uno", y, y))
                    y = builder.select(keep, y, hi_b)
                else:
                    y = builder.select(builder.fcmp_unordered(">", xv, lo_b), xv, lo_b)
                    y = builder.select(builder.fcmp_unordered("<", y, hi_b), y, hi_b)
                builder.store(y, at(pout, ix_v), align=8)
                f_new = builder.fadd(f_acc, builder.fmul(builder.fsub(sv, y), kv))
                stuck_k = builder.select(builder.fcmp_ordered("==", y, xv), kv, zero)
                t_new = builder.fadd(t_acc, stuck_k)
                i_next = builder.add(ib, _ir.Constant(ity, 1))
                latch = builder.basic_block
                builder.branch(head)
                ib.add_incoming(i_next, latch)
                f_acc.add_incoming(f_new, latch)
                t_acc.add_incoming(t_new, latch)
                builder.position_at_end(done)
                lanes = [builder.extract_element(f_acc, _ir.Constant(i32, m))
                         for m in range(_LANES)]
                lanes += [builder.extract_element(t_acc, _ir.Constant(i32, m))
                          for m in range(_LANES)]
                return context.make_tuple(builder, signature.return_type, lanes)

            return sig, codegen

        return slide_blocks

    _slide_blocks = _make_slide_blocks(False)
    _slide_blocks_exact = _make_slide_blocks(True)

    @njit(cache=True, inline="always")
    def _slide(s, x, p):
        """One slider's return mapping, ``np.minimum(np.maximum(x, s - p), s + p)``."""
        lo = s - p
        hi = s + p
        xn = x if ((x > lo) | (x != x)) else lo
        return xn if ((xn < hi) | (xn != xn)) else hi

    def _make_stack_buffer(nbtype, size):
        """Intrinsic returning a pointer to ``size`` items of stack memory in the
        calling function's frame (no heap allocation, no reference counting)."""

        @_intrinsic
        def stack_buffer(typingctx):
            def codegen(context, builder, signature, args):
                return _cgutils.alloca_once(builder, context.get_value_type(nbtype),
                                            size=size)

            return _nbtypes.CPointer(nbtype)(), codegen

        return stack_buffer

    _STACK = 64          # pairwise recursion depth bound (n < 128 * 2**63)
    _stack_int64 = _make_stack_buffer(_nbtypes.int64, 3 * _STACK)
    _stack_float64 = _make_stack_buffer(_nbtypes.float64, 2 * _STACK)

    @njit(cache=True, inline="always")
    def _leaf(s, x, phi, k, out, j, rp, rk, lo, n, nan_exact):
        """Sliders ``lo .. lo+n-1`` (n <= 128) of joint ``j`` (rows ``rp`` of ``phi``,
        ``rk`` of ``k``): trial positions into ``out`` and (force, tangent) summed as
        numpy sums a block (``res = 0.; res += a`` below 8 terms; else 8 interleaved
        accumulators combined pairwise, then the tail)."""
        if n < _LANES:
            fs = 0.0
            ts = 0.0
            for i in range(lo, lo + n):
                xi = x[j, i]
                xn = _slide(s, xi, phi[rp, i])
                out[j, i] = xn
                fs += (s - xn) * k[rk, i]
                ts += k[rk, i] if xn == xi else 0.0
            return fs, ts
        nb = n // _LANES
        width = x.shape[1]
        if nan_exact:
            r = _slide_blocks_exact(s, x, phi, k, out, j * width + lo, rp * width + lo,
                                    rk * width + lo, nb)
        else:
            r = _slide_blocks(s, x, phi, k, out, j * width + lo, rp * width + lo,
                              rk * width + lo, nb)
        fs = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        ts = ((r[8] + r[9]) + (r[10] + r[11])) + ((r[12] + r[13]) + (r[14] + r[15]))
        for i in range(lo + nb * _LANES, lo + n):
            xi = x[j, i]
            xn = _slide(s, xi, phi[rp, i])
            out[j, i] = xn
            fs += (s - xn) * k[rk, i]
            ts += k[rk, i] if xn == xi else 0.0
        return fs, ts

    @njit(cache=True, inline="always")
    def _row(s, x, phi, k, out, j, rp, rk, frames, values):
        """All sliders of joint ``j``, summed in numpy's pairwise order: runs of <= 128
        terms are leaves, a longer run is split at ``n//2 - (n//2) % 8`` and its halves
        added (numpy's recursive ``pairwise_sum``, run with the explicit stack
        ``frames`` int64[64, 3], ``values`` float64[64, 2])."""
        n = x.shape[1]
        nan_exact = not (s - s == 0.0)   # slip NaN or infinite
        if n <= _PAIRWISE_BLOCK:
            return _leaf(s, x, phi, k, out, j, rp, rk, 0, n, nan_exact)
        top = 0
        nv = 0
        frames[0, 0] = 0      # first slider of the run
        frames[0, 1] = n      # length of the run
        frames[0, 2] = 0      # 0: left half next, 1: right half next, 2: add them
        while top >= 0:
            lo = frames[top, 0]
            m = frames[top, 1]
            if m <= _PAIRWISE_BLOCK:
                f, t = _leaf(s, x, phi, k, out, j, rp, rk, lo, m, nan_exact)
                values[nv, 0] = f
                values[nv, 1] = t
                nv += 1
                top -= 1
                continue
            half = m // 2
            half -= half % _LANES
            stage = frames[top, 2]
            frames[top, 2] = stage + 1
            if stage == 0:
                top += 1
                frames[top, 0] = lo
                frames[top, 1] = half
                frames[top, 2] = 0
            elif stage == 1:
                top += 1
                frames[top, 0] = lo + half
                frames[top, 1] = m - half
                frames[top, 2] = 0
            else:
                nv -= 1
                values[nv - 1, 0] = values[nv - 1, 0] + values[nv, 0]
                values[nv - 1, 1] = values[nv - 1, 1] + values[nv, 1]
                top -= 1
        return values[0, 0], values[0, 1]

    @njit(cache=True)
    def bank_update_kernel(slip, anchor, stiffness, slip_limit, out_anchor, force, tangent):
        """Compiled Jenkins-bank return mapping (the kernel of :func:`jenkins_update`).

        Callable from other ``@njit`` code (solvers' step loops). Single-threaded, no
        fast-math, no heap allocation: bitwise equal to the numpy reference (8-wide
        SIMD lanes reproduce numpy's pairwise summation order).

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
            Receives the trial slider positions (m); may be ``anchor`` itself (commit
            in place: each block is read before it is written).
        force, tangent : float64[n_joints]
            Receive the joint force (N) and tangent stiffness (N/m).
        """
        frames = _carray(_stack_int64(), (_STACK, 3))
        values = _carray(_stack_float64(), (_STACK, 2))
        per_joint_k = stiffness.shape[0] != 1
        per_joint_phi = slip_limit.shape[0] != 1
        for j in range(anchor.shape[0]):
            f, t = _row(slip[j], anchor, slip_limit, stiffness, out_anchor, j,
                        j if per_joint_phi else 0, j if per_joint_k else 0, frames, values)
            force[j] = 0.0 + f     # numpy's reduction starts from the identity +0.0
            tangent[j] = 0.0 + t

else:  # pragma: no cover
    bank_update_kernel = None


def _as_float(a):
    return np.ascontiguousarray(a, dtype=np.float64)


def _kernel_operands(slip, anchor, stiffness, slip_limit):
    """(stiffness, slip_limit) as 2-D (1 or n_joints, n_sliders) views for
    :func:`bank_update_kernel`, or None when the shapes are not the contract's (the
    numpy path then broadcasts). All inputs are float64 C-contiguous already."""
    if bank_update_kernel is None or anchor.ndim != 2 or slip.ndim != 1:
        return None
    n_joints, n_sliders = anchor.shape
    if slip.shape[0] != n_joints:
        return None
    out = []
    for param in (stiffness, slip_limit):
        if param.ndim == 1:
            if param.shape[0] != n_sliders:
                return None
            param = param[None]
        elif param.ndim != 2 or param.shape[1] != n_sliders or (
                param.shape[0] != n_joints and param.shape[0] != 1):
            return None
        out.append(param)
    return out


def jenkins_update(slip, anchor, stiffness, slip_limit):
    """Trial state of a bank of Jenkins elements for a new slip (return mapping).

    ``anchor_new = minimum(maximum(anchor, slip - slip_limit), slip + slip_limit)``
    (paper eq. 2 integrated over a step: a slider moves only as much as needed to keep
    its spring stretch within ``slip_limit``), ``force = sum_i k_i (slip -
    anchor_new_i)``, and ``tangent = sum of k_i over sliders whose anchor did not move``
    (stuck sliders, including those exactly at their limit). Sums over sliders are
    numpy's pairwise sums (``np.sum(..., axis=-1)``).

    Pure function: the committed ``anchor`` is not modified; the caller commits
    ``anchor_new`` once the step is accepted. Runs the compiled kernel
    (:func:`bank_update_kernel`) for the shapes below, the numpy reference for other
    broadcastable shapes; both give bitwise the same numbers (``slip_limit`` without
    NaN).

    Parameters
    ----------
    slip : array_like, shape (n_joints,)
        Relative slip of each joint (m).
    anchor : ndarray, shape (n_joints, n_sliders)
        Committed slider positions (m).
    stiffness, slip_limit : ndarray, shape (n_sliders,) or (n_joints, n_sliders)
        Spring stiffnesses (N/m) and slip limits (m).

    Returns
    -------
    force : ndarray, shape (n_joints,)
        Joint force (N).
    tangent : ndarray, shape (n_joints,)
        Tangent stiffness d force / d slip (N/m).
    anchor_new : ndarray, shape (n_joints, n_sliders)
        Trial slider positions (m).
    """
    slip = _as_float(slip)
    anchor = _as_float(anchor)
    stiffness = _as_float(stiffness)
    slip_limit = _as_float(slip_limit)
    ops = _kernel_operands(slip, anchor, stiffness, slip_limit)
    if ops is None:
        return _jenkins_update_numpy(slip, anchor, stiffness, slip_limit)
    force = np.empty(slip.shape[0])
    tangent = np.empty(slip.shape[0])
    anchor_new = np.empty_like(anchor)
    bank_update_kernel(slip, anchor, ops[0], ops[1], anchor_new, force, tangent)
    return force, tangent, anchor_new


def jenkins_update_into(slip, anchor, stiffness, slip_limit, out_anchor,
                        out_force=None, out_tangent=None):
    """In-place variant of :func:`jenkins_update` for solvers' step loops.

    Same numbers as :func:`jenkins_update`, written into preallocated arrays: the trial
    slider positions go to ``out_anchor``, which may be ``anchor`` itself to commit the
    step in place (each slider is read before it is written; other overlaps of the two
    arrays are not allowed).

    Parameters
    ----------
    slip : ndarray, shape (n_joints,)
        Relative slip of each joint (m).
    anchor : ndarray, shape (n_joints, n_sliders)
        Committed slider positions (m).
    stiffness, slip_limit : ndarray, shape (n_sliders,) or (n_joints, n_sliders)
        Spring stiffnesses (N/m) and slip limits (m). Pass C-contiguous float64 arrays
        to avoid a copy per call.
    out_anchor : ndarray, float64, C-contiguous, shape (n_joints, n_sliders)
        Receives the trial slider positions (m).
    out_force, out_tangent : ndarray, float64, shape (n_joints,), optional
        Receive the force (N) and tangent (N/m); allocated when omitted.

    Returns
    -------
    force, tangent : ndarray, shape (n_joints,)
        ``out_force`` and ``out_tangent`` (or new arrays).
    """
    slip = _as_float(slip)
    anchor = _as_float(anchor)
    stiffness = _as_float(stiffness)
    slip_limit = _as_float(slip_limit)
    if anchor.ndim != 2:
        raise ValueError(f"anchor must have shape (n_joints, n_sliders), got {anchor.shape}")
    n_joints = anchor.shape[0]
    if out_force is None:
        out_force = np.empty(n_joints)
    if out_tangent is None:
        out_tangent = np.empty(n_joints)
    for name, arr, shape in (("out_anchor", out_anchor, anchor.shape),
                             ("out_force", out_force, (n_joints,)),
                             ("out_tangent", out_tangent, (n_joints,))):
        if not (type(arr) is np.ndarray and arr.dtype == np.float64 and arr.shape == shape
                and arr.flags.c_contiguous and arr.flags.writeable):
            raise ValueError(f"{name} must be a writeable C-contiguous float64 array of "
                             f"shape {shape} (anchor {anchor.shape})")
    ops = _kernel_operands(slip, anchor, stiffness, slip_limit)
    if ops is None:
        force, tangent, new = _jenkins_update_numpy(slip, anchor, stiffness, slip_limit)
        if new.shape != out_anchor.shape:
            raise ValueError(f"slip {slip.shape} and anchor {anchor.shape} do not match")
        out_anchor[...] = new
        out_force[...] = force
        out_tangent[...] = tangent
    else:
        bank_update_kernel(slip, anchor, ops[0], ops[1], out_anchor, out_force, out_tangent)
    return out_force, out_tangent
