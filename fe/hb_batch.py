"""Many force-route problems at once (:func:`resonance_batch`, the columns of a difference
Jacobian, the fits of a cross-validation): where a guess (a nearby problem's solution)
is at hand, Newton's method on (1) and the phase condition ``Re D_k / w^2 = 0``
together, in ``(Y, ln w)`` with the exact Jacobian (the *joint path*: three iterations
where the secant path of :func:`fe.hb_resonance.resonance_levels` takes ten); a problem
whose joint steps leave :data:`JOINT_STEP` in ``ln w`` or do not converge in
:data:`JOINT_ITERATIONS` takes the secant path from its guess. Both stop at a relative
update of ``w`` and ``Y`` under ``tol``.
SI units: rad/s, m, N.
"""
from __future__ import annotations

import copy

import numpy as np

from fe.hb_resonance import (_COEF, ResonanceLevels, _Balance, _PerLevel, _per_level,
                             _resonate, resonance_levels)
from fe.newton_path import ROUNDOFF, STALL_FACTOR, stall_words

__all__ = ["resonance_batch", "JOINT_STEP", "JOINT_ITERATIONS"]

#: What a failed steady state raises (no steady state, a singular system, an overflow).
_FAILURES = (RuntimeError, ValueError, ArithmeticError)

#: Largest ``|d ln w|`` of a joint Newton step (the secant path's steps are clipped to
#: the same 5 %) and its iterations, before a problem takes the secant path.
JOINT_STEP, JOINT_ITERATIONS = 0.05, 16

def _take(b: _Balance, idx) -> _Balance:
    """The levels ``idx`` (boolean or index array, in order) of ``b`` as a balance."""
    s = copy.copy(b)
    s.F, s.a, s.cl, s.group = b.F[idx], b.a[idx], b.cl[idx], b.group[idx]
    s.L, s.law = s.F.size, b.law.take(idx)
    s.starts = np.flatnonzero(np.diff(s.group, prepend=-1))
    s.elements = [_per_level(e, getattr(e, _COEF[type(e)])[idx]) for e in b.elements]
    return s


def _stack(bs) -> _Balance | None:
    """One balance of the levels of ``bs`` (group ``i``: those of ``bs[i]``); None unless
    they share stiffness, load and rows, their joints are Iwan's, their elements known."""
    b0, cat = bs[0], np.concatenate
    kinds = [type(e) for e in b0.elements]
    if not all(b.law is not None and [type(e) for e in b.elements] == kinds
               and np.array_equal(b.k, b0.k) and np.array_equal(b.X, b0.X)
               and np.array_equal(b.p, b0.p) for b in bs) or not all(t in _COEF for t in kinds):
        return None
    s = copy.copy(b0)
    s.F, s.a, s.cl = (cat([getattr(b, n) for b in bs]) for n in ("F", "a", "cl"))
    s.group = cat([np.full(b.L, i) for i, b in enumerate(bs)])
    s.L, s.starts = s.F.size, cat([[0], np.cumsum([b.L for b in bs])[:-1]]).astype(int)
    s.law = _PerLevel(cat([b.law.block for b in bs]), b0.nj)
    s.elements = [_per_level(e, cat([getattr(b.elements[i], _COEF[type(e)]) for b in bs]))
                  for i, e in enumerate(b0.elements)]
    return s


def _joint(b: _Balance, k: int, w, Y, tol):
    """The joint path (module docstring) of every group of ``b`` from ``w``, ``Y``:
    per level ``w, Y, N, Dinv``, last relative update, iterations, and whether its group
    converged there (each group stops when all its levels have, or leaves)."""
    fin = [np.empty(b.L), np.empty((b.L, b.ny), complex), np.empty((b.L, b.ny), complex),
           np.empty((b.L, b.k.size), complex), np.empty(b.L), np.zeros(b.L, dtype=int)]
    ok, rows, ny, Xk = np.zeros(b.L, bool), np.arange(b.L), b.ny, b.X[:, k]

    def phase(w, Y):       # (1) and g = Re D_k / w^2 = Re(D_kk rho) / w^2 at (w, Y)
        R, Ylin, Dinv = b.operator(w)
        res, N, dx, dy, size = b.residual(Y, R, Ylin, w)
        rho = b.p[k] * b.F / (b.p[k] * b.F - N @ Xk)
        Dkk = b.a * b.k[k] - w ** 2 + 1j * w * b.cl[:, k]
        return [R, Ylin, Dinv, res, N, dx, dy, size, rho, Dkk, (Dkk * rho).real / w ** 2]

    st = phase(w, Y)
    scale = np.maximum(np.abs(st[1]).max(axis=1), 1e-300)
    for it in range(1, JOINT_ITERATIONS + 1):
        R, Ylin, Dinv, res, N, dx, dy, size, rho, Dkk, g = st
        # d(1)/d ln w = -w X (1/D (2 w - i c) q); g's row by the chain rule through N
        dF = -w[:, None] * ((Dinv * (2.0 * w[:, None] - 1j * b.cl) * b.response(N, Dinv))
                            @ b.X.T)
        cg = (Dkk * rho ** 2 / (b.p[k] * b.F * w ** 2))[:, None] * Xk
        Jac = b.jacobian(R, dx, dy, 1)
        Jac[:, :ny, -1], Jac[:, ny:-1, -1] = dF.real, dF.imag
        Jac[:, -1, :ny], Jac[:, -1, ny:-1] = (cg * dx).real, (cg * dy).real
        Jac[:, -1, -1] = ((1j * b.cl[:, k] - 2.0 * w) * rho).real / w - 2.0 * g
        d = np.linalg.solve(Jac, -np.concatenate([res.real, res.imag, g[:, None]], 1)[..., None])
        step, dl = d[:, :ny, 0] + 1j * d[:, ny:-1, 0], d[:, -1, 0]
        floor = np.linalg.norm(res, axis=1) <= ROUNDOFF * np.sqrt(ny) * size
        Y, w = Y + step, w * np.exp(dl)
        st = phase(w, Y)
        upd = np.maximum(np.abs(step).max(axis=1)
                         / np.maximum(np.abs(Y).max(axis=1), 1e-12 * scale), np.abs(dl))
        leave = b.whole(~(np.abs(dl) <= JOINT_STEP) | ~np.isfinite(st[-1]) | ~(upd < 1e3),
                        every=False)
        done = b.whole((upd < tol) | ((upd < STALL_FACTOR * tol) & floor)) & ~leave
        for o, v in zip(fin, (w, Y, st[4], st[2], upd, it)):
            o[rows[done]] = v if np.ndim(v) == 0 else v[done]
        ok[rows[done]] = True
        keep = ~(done | leave)
        if not keep.any():
            break
        if not keep.all():
            rows, b, w, Y, scale = rows[keep], _take(b, keep), w[keep], Y[keep], scale[keep]
            st = [v[keep] for v in st]
    return fin, ok


def _joint_results(b: _Balance, k: int, fin, ok, tol) -> dict:
    """Group -> :class:`fe.hb_resonance.ResonanceLevels` of the groups the joint path
    solved (``secant_steps = 0``)."""
    w, Y, N, Dinv, upd, its = fin
    rows = np.flatnonzero(ok)
    if not rows.size:
        return {}
    q = Dinv[rows] * (b.F[rows, None] * b.p[None] - N[rows] @ b.X)
    Dk, A, at, out = b.p[k] * b.F[rows] / q[:, k], np.abs(Y[rows]), 0, {}
    for g, m in enumerate(np.split(np.arange(b.L), b.starts[1:])):
        if ok[m].all():
            i = slice(at, at + m.size)
            at += m.size
            out[g] = ResonanceLevels(
                omega=w[m], omega2=w[m] ** 2, zeta=Dk[i].imag / (2.0 * w[m] ** 2),
                slip=Y[m, :b.nj], slip_amplitude=A[i, :b.nj], element_amplitude=A[i, b.nj:],
                q=q[i], secant_steps=0, newton_iterations=int(its[m[0]]),
                element_harmonics=Y[m, b.nj:], fallbacks=[stall_words(u, tol) for u in upd[m]])
    return out


def resonance_batch(problems, mode_index: int, guesses=None, tol: float = 1e-12,
                    max_secant: int = 40, max_newton: int = 100) -> list:
    """:func:`fe.hb_resonance.resonance_levels` of each of ``problems`` (``(model, joints,
    load, forces, scale, elements)``) from its guess (``guesses``; None: cold): the joint
    path (module docstring) where there is a guess, else (and where it leaves) the
    secant path of ``resonance_levels``; the problems that share the model's stiffness,
    load and element rows and have Iwan joints in one vectorized iteration, each as it is
    alone (the groups of :class:`fe.hb_resonance._Balance`). Per problem its
    ``ResonanceLevels`` or the exception it raised (``RuntimeError``, ``ValueError``,
    ``ArithmeticError``)."""
    guesses = [None] * len(problems) if guesses is None else list(guesses)
    out, bs, k, seen = [None] * len(problems), [], int(mode_index), {}
    for i, pr in enumerate(problems):
        try:                # like: a balance of the same joints, else the first one
            bs.append((i, _Balance(*pr, like=seen.get(id(pr[1]), bs[0][1] if bs else None))))
            seen.setdefault(id(pr[1]), bs[-1][1])
        except _FAILURES as exc:
            out[i] = exc
    s = None if not bs else bs[0][1] if len(bs) == 1 else _stack([b for _, b in bs])
    groups = [[ib] for ib in bs] if s is None else [bs]
    for part, b in ((g, g[0][1] if len(g) == 1 else s) for g in groups):
        if abs(b.p[k]) == 0.0:
            for i, _ in part:
                out[i] = ValueError(f"the load does not excite basis vector {k}")
            continue
        w0, Y0 = np.sqrt(b.a * b.k[k]), np.empty((b.L, b.ny), complex)
        warm = np.zeros(b.L, bool)
        for (i, _), m in zip(part, np.split(np.arange(b.L), b.starts[1:])):
            g = guesses[i]
            if g is not None and g.q.shape == (m.size, b.p.size) and \
                    g.element_amplitude.shape[1] == b.ny - b.nj:
                w0[m], warm[m] = g.omega, True
                Y0[m] = np.concatenate([g.slip, g.element_harmonics], axis=1)
        solved = {}
        if warm.any():
            try:
                with np.errstate(all="ignore"):    # a group that leaves goes the other way
                    sub = b if warm.all() else _take(b, warm)
                    fin, ok = _joint(sub, k, w0[warm], Y0[warm], tol)
                solved = {int(sub.group[sub.starts[g]]): r
                          for g, r in _joint_results(sub, k, fin, ok, tol).items()}
            except _FAILURES:                       # a singular joint system: the other way
                solved = {}
        for g, ((i, _), m) in enumerate(zip(part, np.split(np.arange(b.L), b.starts[1:]))):
            if g in solved:
                out[i] = solved[g]
                continue
            one = b if len(part) == 1 else _take(b, m)
            try:
                Y = Y0[m] if warm[m[0]] else one.operator(w0[m])[1]
                out[i] = _resonate(one, k, w0[m], Y, tol, max_secant, max_newton)
            except _FAILURES as exc:
                out[i] = exc
    return out
