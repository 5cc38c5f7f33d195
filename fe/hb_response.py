"""Phase resonance at a held response amplitude, for many levels at once.

The response-controlled counterpart of :func:`fe.hb_resonance.resonance_levels`: per
level the drive force ``F`` is not given but found, together with the frequency ``w``,
so that the mode's modal filter is at phase resonance (``Re D_k = 0``,
:mod:`fe.hb_resonance`) *and* the first harmonic of the response at one DOF,
``x = c . q`` (``c`` the basis row of that DOF), has the held amplitude ``|x| = A``.
This is what a response-controlled stepped sine holds at resonance, and (single
nonlinear mode, Krack 2015 Sec. 5) the EPMC backbone read at amplitude ``A``: the
natural model of a free decay's rows too.

Newton's method on ``(ln w, ln F)`` per level, vectorized over levels, on the two
equations

    Re D_k(w, F) / w^2 = 0,        ln(|x(w, F)| / A) = 0,

each evaluation a warm-started Newton solve of the condensed first-harmonic balance
(eq. 1 of :mod:`fe.hb_resonance`) at ``(w, F)``, the 2 x 2 Jacobian by forward
differences (two more solves; a warm start reuses its guess's Jacobian while the
residual falls tenfold per step); steps limited to 5 % in ``w`` and a factor e in ``F``
(deep macro slip from a linear start) and halved where the residual norm does not fall.
Where this does not converge in ``max_steps`` (deep macro slip, slips tens of
``phi_max``), a slower fallback takes over: force-route phase resonances with ``ln F``
by a bracketed secant (:func:`_bracketed`).

Many force-route problems at once: :mod:`fe.hb_batch`. SI units: rad/s, m, N.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fe.hb_resonance import ResonanceLevels, _Balance, resonance_levels
from fe.newton_path import stall_words
from fe.reduction import ReducedModel

__all__ = ["ResponseLevels", "response_levels"]

#: Largest Newton step of ``ln F`` (a factor e) and the relative difference step.
MAX_LOG_STEP, FD = 1.0, 1e-7
#: Step halvings of the line search (the residual norm must fall).
MAX_HALVINGS = 6
#: The per-level fields of a result (the fallback fills its levels in).
PER_LEVEL = ("omega", "omega2", "zeta", "slip", "slip_amplitude", "element_amplitude", "q",
             "element_harmonics", "force", "response")
#: How a level reached by the bracketed fallback says so (its ``fallbacks`` entry).
BRACKETED = "bracketed secant on ln F (Newton on (ln w, ln F) did not hold the amplitude)"
#: What a failed steady state raises (no steady state, a singular system, an overflow).
_FAILURES = (RuntimeError, ValueError, ArithmeticError)


@dataclass
class ResponseLevels(ResonanceLevels):
    """:class:`fe.hb_resonance.ResonanceLevels` plus the force amplitude that holds each
    level's response (``force``, N) and the held DOF's first harmonic (``response``);
    a level where the Newton iteration gave way to the bracketed fallback says so in its
    ``fallbacks`` entry (:data:`BRACKETED`); the last Jacobian of the Newton iteration
    (``jacobian``, (L, 2, 2)) starts the next call."""

    force: np.ndarray | None = None
    response: np.ndarray | None = None
    jacobian: np.ndarray | None = None


def response_levels(model: ReducedModel, joints, load, amplitudes, response_row,
                    mode_index: int, scale=None, elements=(), tol: float = 1e-10,
                    max_steps: int = 8, max_newton: int = 100,
                    guess: ResponseLevels | None = None) -> ResponseLevels:
    """Phase resonance of basis vector ``mode_index`` at each held response amplitude
    (module docstring).

    Parameters
    ----------
    model, joints, load, mode_index, scale, elements : as
        :func:`fe.hb_resonance.resonance_levels`.
    amplitudes : (L,) held first-harmonic amplitudes at the response DOF (m).
    response_row : (r,) the basis row of the response DOF (``x = response_row . q``).
    tol : float
        Bound on ``|ln(|x| / A)|`` and on ``|Re D_k| / w^2`` (Newton: ``tol / 100``).
    max_steps : int
        Newton steps on ``(ln w, ln F)`` before the fallback takes the levels left.
    guess : ResponseLevels, optional
        A previous solution with the same number of levels and elements.

    Returns
    -------
    ResponseLevels
    """
    A = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if np.any(~np.isfinite(A)) or np.any(A <= 0):
        raise ValueError("held response amplitudes must be finite and > 0")
    c = np.asarray(response_row, dtype=float)
    b = _Balance(model, joints, load, np.ones(A.size), scale, elements)
    k = int(mode_index)
    if abs(b.p[k] * c[k]) == 0.0:
        raise ValueError(f"the drive or the response DOF does not see basis vector {k}")
    warm = guess is not None and guess.force is not None and guess.force.shape == A.shape \
        and guess.element_amplitude.shape[1] == b.ny - b.nj
    w, lnF, F0, Y = _start(model, joints, load, b, A, c, k, scale, elements,
                           guess if warm else None)
    held = _Held(b, k, c, A, tol, max_newton)
    x = _Iterate(w, lnF, *held.state(w, lnF, Y))
    miss0 = x.eq[:, 1].copy()
    J = guess.jacobian if warm and guess.jacobian is not None else None
    J, steps, upd_at = _newton(held, x, J, max_steps)
    done = np.all(np.abs(x.eq) <= tol, axis=1)
    out = _levels(held, x, J, steps, upd_at)
    if not done.all():     # deep macro slip: the bracketed secant on ln F there
        i = np.flatnonzero(~done)
        # start from the force of the Newton iterate or of the start, whichever held
        # the amplitude better
        start = np.where(np.abs(x.eq[i, 1]) < np.abs(miss0[i]), out.force[i], F0[i])
        sub = _bracketed(model, joints, load, A[i], c, k, b.a[i], elements, tol, start)
        for name in PER_LEVEL:
            getattr(out, name)[i] = getattr(sub, name)
        for j, words in zip(i, sub.fallbacks):
            out.fallbacks[j] = words
        out.secant_steps += sub.secant_steps
        out.newton_iterations += sub.newton_iterations
    return out


def _start(model: ReducedModel, joints, load, b: _Balance, A: np.ndarray, c: np.ndarray,
           k: int, scale, elements, guess: ResponseLevels | None
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The first iterate ``(w, ln F, F0, Y)``: the guess scaled to the held amplitudes,
    or the phase resonance at the linear mode's force for ``|x| = A``."""
    if guess is not None:
        ratio = A / np.abs(guess.response)
        F0 = guess.force * ratio
        w, lnF = guess.omega.copy(), np.log(F0)
        Y = np.concatenate([guess.slip, guess.element_harmonics], axis=1) * ratio[:, None]
        return w, lnF, F0, Y
    w = np.sqrt(b.a * b.k[k])
    F = A * np.maximum(b.c[k] * w, 1e-4 * w * w) / abs(c[k] * b.p[k])
    start = resonance_levels(model, joints, load, F, k, scale=scale, elements=elements)
    Y = np.concatenate([start.slip, start.element_harmonics], axis=1)
    return start.omega, np.log(F), F, Y


@dataclass
class _Held:
    """The balance at held amplitudes ``A`` of ``x = c . q`` and the Newton iterations
    its solves took (``its``), the last solve's relative update per level (``upd``)."""

    b: _Balance
    k: int
    c: np.ndarray
    A: np.ndarray
    tol: float
    max_newton: int
    its: int = 0
    upd: np.ndarray | None = None

    def state(self, w: np.ndarray, lnF: np.ndarray, Y: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Harmonics, response and the two equations (phase, amplitude) at ``(w, ln F)``."""
        b, k = self.b, self.k
        b.F = np.exp(lnF)
        Y, N, Dinv, it, self.upd = b.solve(w, Y, 0.01 * self.tol, self.max_newton)
        self.its += it
        q = b.response(N, Dinv)
        eq = np.stack([(b.p[k] * b.F / q[:, k]).real / w ** 2,
                       np.log(np.abs(q @ self.c) / self.A)], 1)
        return Y, q, eq


@dataclass
class _Iterate:
    """One Newton iterate on ``(ln w, ln F)``: ``w``, ``ln F``, harmonics ``Y``, response
    ``q`` and the equations ``eq`` (L, 2)."""

    w: np.ndarray
    lnF: np.ndarray
    Y: np.ndarray
    q: np.ndarray
    eq: np.ndarray


def _newton(held: _Held, x: _Iterate, J: np.ndarray | None, max_steps: int
            ) -> tuple[np.ndarray | None, int, np.ndarray]:
    """Newton on ``(ln w, ln F)`` from ``x`` (updated in place); returns the last
    Jacobian, the steps taken and the relative updates of the accepted solves."""
    tol, upd_at, last = held.tol, held.upd, np.inf
    for steps in range(1, max_steps + 1):
        worst = np.abs(x.eq).max()
        if worst <= tol:
            break
        if J is None or worst > 0.1 * last:
            # Newton on (ln w, ln F), the 2 x 2 Jacobian per level by forward
            # differences; kept (a chord step) while the residual falls tenfold a step
            J = np.empty((held.A.size, 2, 2))
            J[:, :, 0] = (held.state(x.w * (1.0 + FD), x.lnF, x.Y)[2] - x.eq) / FD
            J[:, :, 1] = (held.state(x.w, x.lnF + FD, x.Y)[2] - x.eq) / FD
        last = worst
        d = -np.linalg.solve(J, x.eq[..., None])[..., 0]
        d[:, 0] = np.clip(d[:, 0], -0.05, 0.05)
        d[:, 1] = np.clip(d[:, 1], -MAX_LOG_STEP, MAX_LOG_STEP)
        upd_at = _line_search(held, x, d)
    return J, steps, upd_at


def _line_search(held: _Held, x: _Iterate, d: np.ndarray) -> np.ndarray:
    """Take step ``d`` from ``x`` (in place), halved where ``|eq|`` does not fall;
    returns the relative updates of the accepted solve."""
    norm, lam = np.linalg.norm(x.eq, axis=1), np.ones(held.A.size)
    for _ in range(MAX_HALVINGS):       # halve the step where |eq| does not fall
        Yt, qt, et = held.state(x.w * np.exp(lam * d[:, 0]), x.lnF + lam * d[:, 1],
                                x.Y * np.exp(lam * d[:, 1])[:, None])
        upd_at = held.upd
        bad = (np.linalg.norm(et, axis=1) > (1.0 - 1e-4 * lam) * norm) & (norm > held.tol)
        if not bad.any():
            break
        lam = np.where(bad, 0.5 * lam, lam)
    x.w, x.lnF, x.Y, x.q, x.eq = (x.w * np.exp(lam * d[:, 0]), x.lnF + lam * d[:, 1],
                                  Yt, qt, et)
    return upd_at


def _levels(held: _Held, x: _Iterate, J: np.ndarray | None, steps: int,
            upd_at: np.ndarray) -> ResponseLevels:
    """The result of the Newton iteration at its last iterate ``x``."""
    b, k, w, Y, q = held.b, held.k, x.w, x.Y, x.q
    F = b.F.copy()
    Ya = np.abs(Y)
    Dk = b.p[k] * F / q[:, k]
    return ResponseLevels(omega=w, omega2=w ** 2, zeta=Dk.imag / (2.0 * w ** 2),
                          slip=Y[:, :b.nj], slip_amplitude=Ya[:, :b.nj],
                          element_amplitude=Ya[:, b.nj:], q=q, secant_steps=steps,
                          newton_iterations=held.its, element_harmonics=Y[:, b.nj:],
                          force=F, response=q @ held.c, jacobian=J,
                          fallbacks=[stall_words(u, 0.01 * held.tol) for u in upd_at])


def _bracketed(model, joints, load, A, c, k, scale, elements, tol, F, max_steps=60):
    """The fallback of :func:`response_levels`: phase resonance at a force
    (:func:`fe.hb_resonance.resonance_levels`, robust in deep macro slip) with ``ln F``
    found by the secant method, bisecting a bracket where the secant leaves it
    (``|x|`` at resonance rises with ``F``)."""
    def solve(F, g):
        return resonance_levels(model, joints, load, F, k, scale=scale,
                                elements=elements, guess=g)

    res = solve(F, None)
    lo, hi = np.full(A.size, -np.inf), np.full(A.size, np.inf)
    slope, prev = np.ones(A.size), None
    steps, its = res.secant_steps, res.newton_iterations
    for _ in range(max_steps):
        lnF, lnx = np.log(F), np.log(np.abs(res.q @ c))
        miss = np.log(A) - lnx
        if np.all(np.abs(miss) <= tol):
            break
        if prev is not None:
            dlf = lnF - prev[0]
            ok = np.abs(dlf) > 1e-14
            slope = np.where(ok, np.clip((lnx - prev[1]) / np.where(ok, dlf, 1.0), 0.05, 20.0),
                             slope)
        lo = np.where(miss > 0, np.maximum(lo, lnF), lo)
        hi = np.where(miss < 0, np.minimum(hi, lnF), hi)
        new = lnF + np.clip(miss / slope, -3.0 * MAX_LOG_STEP, 3.0 * MAX_LOG_STEP)
        both = np.isfinite(lo) & np.isfinite(hi)
        mid = 0.5 * (np.where(both, lo, 0.0) + np.where(both, hi, 0.0))
        new = np.where(both & ((new <= lo) | (new >= hi)), mid, new)
        prev, F = (lnF, lnx), np.exp(new)
        res = solve(F, res)
        steps, its = steps + res.secant_steps, its + res.newton_iterations
    else:
        raise RuntimeError(f"response-controlled phase resonance not found (worst |x|/A - 1 "
                           f"= {np.abs(np.expm1(miss)).max():.2e})")
    fields = {f: getattr(res, f) for f in res.__dataclass_fields__}
    fields["fallbacks"] = ["; ".join(x for x in (BRACKETED, w) if x) for w in res.fallbacks]
    out = ResponseLevels(**fields, force=F, response=res.q @ c)
    out.secant_steps, out.newton_iterations = steps, its
    return out
