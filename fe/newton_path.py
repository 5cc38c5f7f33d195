"""Globalized Newton's method and step-controlled continuation for steady states.

:func:`damped_newton` solves ``r(y) = 0`` for a piecewise-smooth residual (the harmonic
balance of Jenkins banks, :mod:`fe.harmonic_balance`) with the exact Jacobian and a
backtracking line search on the merit function ``phi(y) = |r(y)|^2 / 2`` (Armijo's rule,
Nocedal & Wright 2006, Algorithm 3.1 with eq. 3.4): the Newton step ``d = -J^{-1} r`` is
a descent direction of ``phi`` (``grad phi . d = -2 phi``), so the step ``lam d`` is
accepted once ``phi(y + lam d) <= (1 - 2 c lam) phi(y)``, halving ``lam`` from 1. Far
from the solution (deep macro-slip started from the stuck-joint guess) the full step
overshoots by orders of magnitude; the line search keeps every iterate at a lower
residual. Near the solution the full step is always accepted, so the iterates (and the
converged numbers) are those of the undamped method; once the residual is at round-off
(below ``ROUNDOFF`` of ``max |y|``) the decrease test means nothing and the full step is
taken too; a last iteration that ends there with its step stalled within
``STALL_FACTOR`` of the tolerance (an ill-conditioned Jacobian, e.g. a glue of 1e11 N/m,
amplifies round-off in the step: 8.7e-13 against 1e-13 on an AVX2 CPU) is converged as
far as the arithmetic allows. Every solver of a steady state uses this one Newton (harmonic balance,
:mod:`fe.hb_exact`, :mod:`fe.epmc`, :mod:`runs.response_control`); the batched
first-harmonic balance of many levels (:mod:`fe.hb_resonance`) applies the same rule
level by level.

:func:`follow` carries a converged solution along a scalar parameter ``p`` (frequency
between two lines, or a load factor) with a secant predictor, halving the step when a
corrector fails and doubling it again after a success (step-size control, Allgower &
Georg 2003, Sec. 6.1): intermediate points only feed the predictor.

Failures raise :class:`SteadyStateError`, a ``RuntimeError`` whose message is one line
with the reason.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

__all__ = ["SteadyStateError", "damped_newton", "stall_words", "follow",
           "natural_continuation"]

#: Armijo constant ``c`` of the sufficient-decrease rule.
ARMIJO = 1e-4
#: Smallest line-search factor tried before the step is declared stalled.
MIN_DAMPING = 2.0 ** -12
#: Residual (relative to ``max |y|``) below which the sufficient-decrease test is
#: round-off and the full Newton step is taken (as the undamped method does).
ROUNDOFF = 64 * np.finfo(float).eps
#: After the last iteration, a step this many times the tolerance with the residual at
#: round-off counts as converged (a step stalled by round-off, not a slow convergence).
STALL_FACTOR = 100.0
#: Halvings of the frequency step between two lines before a line is given up.
FREQUENCY_HALVINGS = 8


class SteadyStateError(RuntimeError):
    """No steady state: ``where`` (e.g. ``"236 Hz"``) and ``reason``, both one line;
    ``context`` is filled in by callers (e.g. ``"level 8 (F = 0.64 N)"``, see
    :meth:`within`); ``solver`` names the method."""

    def __init__(self, where: str, reason: str, context: str = "",
                 solver: str = "harmonic balance"):
        self.where, self.reason, self.context, self.solver = where, reason, context, solver
        super().__init__(where, reason, context, solver)

    def within(self, context: str) -> "SteadyStateError":
        """The same failure located in ``context``."""
        return SteadyStateError(self.where, self.reason, context, self.solver)

    def __str__(self) -> str:
        head = f"{self.context}, line {self.where}" if self.context else self.where
        return f"{self.solver} did not converge at {head}: {self.reason}"


def damped_newton(evaluate: Callable, y0: np.ndarray, tol: float, max_iter: int,
                  scale: float, relative_update: Callable | None = None,
                  admissible: Callable | None = None):
    """Newton's method with an Armijo line search on ``|r|^2/2`` (module docstring).

    Parameters
    ----------
    evaluate : callable
        ``evaluate(y) -> (r, J)``: residual (n,) and its Jacobian (n, n).
    y0 : ndarray, shape (n,)
    tol : float
        Converged when the full Newton step is below ``tol`` relative to ``max |y|``.
    max_iter : int
        Newton iterations (each one Jacobian factorization).
    scale : float
        Magnitude of ``y`` (> 0) below which ``max |y|`` is not used to normalize.
    relative_update : callable, optional
        ``relative_update(y_new, d) -> float``, the size of the full step ``d`` that
        lands at ``y_new`` compared with ``tol`` (default ``max |d| / max(max |y_new|,
        1e-12 scale)``), for unknowns of mixed units.
    admissible : callable, optional
        ``admissible(y) -> bool``: trial points outside the domain (e.g. a frequency
        <= 0) are treated as a failed decrease and the step is halved.

    Returns
    -------
    (y, iterations, relative_update, evaluations)

    Raises
    ------
    SteadyStateError (``where`` left empty) with the reason.
    """
    y = np.asarray(y0, dtype=float).copy()
    r, J = evaluate(y)
    n_eval = 1
    phi = 0.5 * float(r @ r)
    floor = scale * 1e-12
    upd = np.inf
    for it in range(1, max_iter + 1):
        if not np.isfinite(phi):
            raise SteadyStateError("", f"non-finite residual after {it - 1} iterations")
        try:
            d = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            raise SteadyStateError("", f"singular Jacobian after {it - 1} iterations") from None
        upd = (float(np.abs(d).max() / max(np.abs(y + d).max(), floor))
               if relative_update is None else float(relative_update(y + d, d)))
        if not np.isfinite(upd):
            raise SteadyStateError("", f"non-finite Newton step after {it - 1} iterations")
        if upd < tol:
            return y + d, it, upd, n_eval
        lam = 1.0
        roundoff = 0.5 * (ROUNDOFF * max(np.abs(y).max(), floor)) ** 2
        while True:
            yt = y + lam * d
            if admissible is None or admissible(yt):
                rt, Jt = evaluate(yt)
                n_eval += 1
                phit = 0.5 * float(rt @ rt)
            else:
                phit = np.inf
            if phit <= (1.0 - 2.0 * ARMIJO * lam) * phi:
                break
            if lam == 1.0 and np.isfinite(phit) and phi <= roundoff:
                break       # residual at round-off: no decrease to test, full step
            lam *= 0.5
            if lam < MIN_DAMPING:
                raise SteadyStateError(
                    "", f"line search stalled after {it} iterations (residual "
                    f"{np.sqrt(2 * phi) / max(np.abs(y).max(), floor):.2e} of the slip)")
        y, r, J, phi = yt, rt, Jt, phit
    if upd <= STALL_FACTOR * tol and phi <= 0.5 * (ROUNDOFF * max(np.abs(y).max(), floor)) ** 2:
        # the residual is at round-off and the step stalls just above ``tol`` (an
        # ill-conditioned Jacobian amplifies round-off in it): converged as far as the
        # arithmetic allows
        return y, max_iter, upd, n_eval
    raise SteadyStateError("", f"no convergence in {max_iter} iterations (relative update "
                               f"{upd:.2e})")


def stall_words(relative_update: float, tol: float) -> str:
    """How :func:`damped_newton` ended, for a solution's ``fallback``: empty when the
    last full step was below ``tol``, else the step stalled at round-off (accepted by the
    ``STALL_FACTOR`` rule, module docstring) with its size."""
    if relative_update < tol:
        return ""
    return (f"Newton step stalled at round-off (relative update {relative_update:.1e}, "
            f"tolerance {tol:.0e})")


def follow(solve: Callable, history: list, p1: float, predictor: Callable,
           max_halvings: int = 8):
    """Carry the last converged solution of ``history`` to the parameter ``p1`` (module
    docstring).

    Parameters
    ----------
    solve : callable
        ``solve(p, guess) -> x`` or raises ``RuntimeError``.
    history : list of (p, x)
        Converged solutions, the last one the start (two give a secant predictor).
    p1 : float
        Target parameter.
    predictor : callable
        ``predictor(p, history) -> guess`` from the converged ``(p, x)`` of ``history``.
    max_halvings : int
        The step may shrink to ``|p1 - p0| / 2^max_halvings``.

    Returns
    -------
    (x at p1, number of corrector solves)

    Raises
    ------
    The last corrector's ``RuntimeError`` when the step has shrunk to its limit.
    """
    history = list(history[-2:])
    p = history[-1][0]
    span = p1 - p
    step = span
    min_step = abs(span) * 2.0 ** -max_halvings
    n_solves = 0
    while True:
        target = p1 if abs(p1 - p) <= abs(step) * (1 + 1e-12) else p + step
        n_solves += 1
        try:
            x = solve(target, predictor(target, history))
        except RuntimeError:
            if abs(step) * 0.5 < min_step * (1 - 1e-12):
                raise
            step *= 0.5
            continue
        history = history[-1:] + [(target, x)]
        p = target
        if p == p1:
            return x, n_solves
        step = np.sign(span) * min(abs(2.0 * step), abs(p1 - p))


def _secant(w, history):
    """Secant predictor of the slip harmonics at ``w`` from converged ``(omega,
    solution)`` pairs (the last one alone: its slips)."""
    (w2, s2) = history[-1]
    if len(history) < 2:
        return s2.slip
    w1, s1 = history[-2]
    t = (w - w2) / (w2 - w1) if w2 != w1 else 0.0
    return s2.slip + t * (s2.slip - s1.slip)


def natural_continuation(solve, omegas, progress) -> list:
    """Natural-parameter continuation over the lines ``omegas`` (rad/s), in their order.

    Each line starts from a secant extrapolation of the two previous solutions (the
    previous one at the second line; ``guess=None`` at the first, the solver's own
    start), which follows the branch the way a stepped-sine sweep does. A line whose
    corrector fails is recovered by :func:`_recover`. ``solve(omega, guess)`` returns a
    solution with ``omega`` and ``slip`` (complex slip harmonics, the guess's form) or
    raises ``RuntimeError``; ``progress``: a tqdm bar or None (one tick per line).
    """
    sols = []
    for i, w in enumerate(np.asarray(omegas, dtype=float)):
        hist = [(s.omega, s) for s in sols[-2:]]
        guess = _secant(w, hist) if hist else None
        try:
            sol = solve(w, guess)
        except RuntimeError as exc:
            if guess is None:
                raise
            sol = _recover(solve, w, hist, exc)
        sols.append(sol)
        if progress is not None:
            progress.update(1)
    return sols


def _tag(solution, how: str):
    """Record a fallback on a solution that has a ``fallback`` field (not silent)."""
    if hasattr(solution, "fallback"):
        solution.fallback = "; ".join(x for x in (how, solution.fallback) if x)
    return solution


def _recover(solve, w, hist, exc):
    """A line whose secant prediction failed: the previous solution as the guess, then
    the frequency step from the previous line halved until the corrector converges
    (:func:`fe.newton_path.follow`), then a fresh start from the stuck-joint solution
    (``solve(w, None)``: the jump of a stepped-sine test when the branch ends). The
    route taken is recorded in the solution's ``fallback``."""
    first = getattr(exc, "reason", str(exc))
    try:
        return _tag(solve(w, hist[-1][1].slip), f"previous line as the guess ({first})")
    except RuntimeError:
        pass
    try:
        return _tag(follow(solve, hist, w, _secant, max_halvings=FREQUENCY_HALVINGS)[0],
                    f"frequency step from the previous line halved ({first})")
    except RuntimeError:
        pass
    try:
        return _tag(solve(w, None), f"fresh start from the stuck-joint solution ({first})")
    except RuntimeError as fresh:
        reason = getattr(exc, "reason", str(exc))
        df = abs(w - hist[-1][0]) / (2 * np.pi) * 2.0 ** -FREQUENCY_HALVINGS
        raise SteadyStateError(
            f"{w / (2 * np.pi):.6g} Hz",
            f"{reason} (from the previous line; also with the frequency step halved to "
            f"{df:.2g} Hz, and from the stuck-joint solution: "
            f"{getattr(fresh, 'reason', str(fresh))})") from None
