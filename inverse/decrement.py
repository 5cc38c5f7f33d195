"""When a weighted least-squares fit has converged: the Gauss-Newton decrement, the one
criterion of every fit of the diagnosis (:mod:`inverse.diagnosis.lm`) and of model
updating (:func:`inverse.update.fit`).

With ``r`` the residuals in noise units (``chi2 = r^T r``), ``J`` their Jacobian,
``g = J^T r`` (half the gradient of chi2) and ``F`` the free coordinates (not held: not
fixed, not on a bound the gradient pushes against), the Gauss-Newton model
``chi2(theta + d) ~ |r + J d|^2`` has its minimum

    delta = g_F^T (J_F^T J_F)^+ g_F                                                 (1)

below the current chi2 (the Newton decrement of Boyd & Vandenberghe 2004, sec. 9.5.1,
with the Gauss-Newton Hessian ``2 J^T J``). Since the parameters' covariance is
``(J^T J)^-1`` when ``r`` is in noise units, ``delta`` is also the squared distance to
that minimum in standard errors. A fit stops when ``delta <= DECREMENT_TOL`` = 1e-4:
its chi2 is within 1e-4 of the local optimum (1e-4 of one unit of ``-2 ln L``) and its
parameters within 0.01 standard errors of it, far below what any decision of the judge
resolves, and far above round-off. It is *converged* when ``delta <= ACCEPT_TOL`` =
1e-2 (within 0.1 standard errors): the margin keeps a fit that stalls just short of its
aim from being converged under one BLAS kernel and not under another (before the
margin, one fit of `benchmarks/blas_repro.py` ended at chi2 85.5243, unconverged, on
one kernel and at 85.5230, converged, on the other). The pseudo-inverse is taken on the
column-scaled ``J_F`` with eigenvalues under 1e-10 of the largest dropped: a direction
the data do not determine carries no gradient either (a cause whose effect fitted to
zero leaves its shape parameters free of the data), so it is not a failure to converge.

Within a box. Eq. (1) trusts the linear model however far its step goes. For a
parameter whose effect vanishes at a bound faster than linearly (a saturation ``(u
s)^m`` near ``u = 0``) the column of ``J`` is tiny, yet the gradient's share in its
(normalized) direction is not, and (1) promises a drop that only a step of many box
widths would bring, where the linear model means nothing. When the parameters live in
a box (widths ``w_j``), the decrement is the drop of the Gauss-Newton model within
reach of the box instead: in box units (``K = J diag(w)``, ``K^T K = sum_k lambda_k v_k
v_k^T``, ``a_k = v_k^T K^T r``) and steps of at most the box's diagonal ``T = sqrt(d)``
along each eigenvector,

    delta_box = sum_k [a_k^2 / lambda_k  if |a_k| <= T lambda_k,
                       else 2 T |a_k| - lambda_k T^2]                                 (2)

It equals (1) when the model's step stays within reach, is never below the drop the
model can make anywhere in the box (the box lies within the ball of radius ``T``, the
quadratic separates along the ``v_k``), and needs no cut of small eigenvalues (a
direction of no curvature gives at most ``2 T |a_k|``).

A fit's decrement (:func:`fit_decrement`) holds the parameters at a bound the gradient
pushes against and the *flat* ones (:data:`FLAT_EFFECT`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["DECREMENT_TOL", "ACCEPT_TOL", "CHECK_STEP", "FLAT_EFFECT", "FLAT_REACH_STEPS",
           "gauss_newton_decrement", "flat_columns", "fit_decrement", "central_jacobian"]

#: Eq. (1) below this (chi2 units) stops a fit: its aim (module doc).
DECREMENT_TOL = 1e-4
#: Eq. (1) below this (chi2 units, the parameters within 0.1 standard errors of the
#: optimum) is *converged*: a margin of 100 between the aim and the verdict, so that a
#: fit stalling just short of its aim (a kink, a curved valley) is not converged on
#: one machine and unconverged on another.
ACCEPT_TOL = 1e-2
_RCOND = 1e-10


def gauss_newton_decrement(J, r, held=None, span=None) -> np.ndarray:
    """Eq. (1) for a batch: ``J`` (B, d, N) the Jacobian of the residuals ``r`` (B, N),
    ``held`` (d,) or (B, d) bool the coordinates not free (None: all free); with
    ``span`` (d,), the widths of a box the parameters live in, eq. (2) instead.

    Returns the decrement (B,) in chi2 units."""
    J = np.asarray(J, float)
    r = np.asarray(r, float)
    if held is not None:
        held = np.broadcast_to(np.asarray(held, bool), J.shape[:2])
        J = np.where(held[:, :, None], 0.0, J)
    if span is not None:
        return _within_box(J * np.asarray(span, float)[None, :, None], r)
    g = np.einsum("bdn,bn->bd", J, r)
    norm = np.sqrt(np.einsum("bdn,bdn->bd", J, J))
    norm = np.where(norm > 0, norm, 1.0)
    M = np.einsum("bdn,ben->bde", J, J) / (norm[:, :, None] * norm[:, None, :])
    w, V = np.linalg.eigh(M)
    keep = w > _RCOND * np.maximum(w.max(axis=1, keepdims=True), 1e-300)
    proj = np.einsum("bdk,bd->bk", V, g / norm)
    return np.sum(np.where(keep, proj**2 / np.where(keep, w, 1.0), 0.0), axis=1)


def _within_box(K, r) -> np.ndarray:
    """Eq. (2): ``K`` (B, d, N) the Jacobian in box units (column ``j`` times the box
    width ``w_j``)."""
    d = K.shape[1]
    reach = np.sqrt(d)                          # the box's diagonal, in box units
    w, V = np.linalg.eigh(np.einsum("bdn,ben->bde", K, K))
    a = np.abs(np.einsum("bdk,bd->bk", V, np.einsum("bdn,bn->bd", K, r)))
    w = np.maximum(w, 0.0)
    inside = (w > 0) & (a <= reach * w)         # the model's optimum along v_k is reached
    full = a**2 / np.where(inside, w, 1.0)
    return np.sum(np.where(inside, full, 2.0 * reach * a - w * reach**2), axis=1)


#: Difference step (units of each parameter's step) of the Jacobian that re-takes a
#: decrement over the tolerance (:mod:`inverse.update`).
CHECK_STEP = 1e-3
#: A parameter whose linear effect over its whole box (``|J_j|`` times the box width,
#: at most :data:`FLAT_REACH_STEPS` steps) moves the residuals by less than this (noise
#: units, root sum of squares) is *flat* where the fit stopped (a joint slipped through
#: or stuck at every level): not determined there, and held, since the column scaling
#: of eq. (1) would blow what is left of its column (round-off of the simulation) up to
#: a direction of its own carrying a share of the misfit; under a model-form misfit
#: (chi2 in the hundreds) that alone read 26 to 422 chi2 units (the FE benchmark's
#: draw 6104).
FLAT_EFFECT = 1e-3
FLAT_REACH_STEPS = 1e4


def flat_columns(J, width) -> np.ndarray:
    """The columns of ``J`` whose linear effect over the box is below :data:`FLAT_EFFECT`."""
    return np.linalg.norm(J, axis=0) * np.minimum(width, FLAT_REACH_STEPS) < FLAT_EFFECT


def fit_decrement(J, r, active_mask, side, width) -> float:
    """Eq. (1) of a fit (:mod:`inverse.update`) from the Jacobian ``J`` (N, k) of the
    residuals ``r`` in the optimizer's coordinates: the parameters at a bound (``side``:
    per column ``"lower"``, ``"upper"`` or False; or the optimizer's ``active_mask``)
    held where the gradient pushes outward, the flat ones (:func:`flat_columns`;
    ``width``: each box's width in the optimizer's coordinates) held."""
    J, r = np.asarray(J, float), np.asarray(r, float)
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
        return np.inf
    g = J.T @ r                                # half the gradient of chi2, per u
    lower = np.array([b == "lower" for b in side]) | (active_mask < 0)
    upper = np.array([b == "upper" for b in side]) | (active_mask > 0)
    held = (lower & (g > 0)) | (upper & (g < 0)) | flat_columns(J, width)
    return float(gauss_newton_decrement(J.T[None], r[None], held[None])[0])


def central_jacobian(funs, u, r, lo, hi, h: float = CHECK_STEP):
    """Jacobian at ``u`` (residuals ``r``) by central differences of step ``h``
    (one-sided three-point rule where ``u +- h`` leaves ``[lo, hi]``), ``funs`` giving
    the residuals of a list of points; and the evaluations it took."""
    points, side = [], []
    for j in range(u.size):
        e = np.zeros(u.size)
        e[j] = h
        s = 0.0 if lo[j] <= u[j] - h and u[j] + h <= hi[j] else \
            (1.0 if u[j] + 2.0 * h <= hi[j] else -1.0)
        points += [u + e, u - e] if s == 0.0 else [u + s * e, u + 2.0 * s * e]
        side.append(s)
    f = funs(points)
    J = np.zeros((r.size, u.size))
    for j, s in enumerate(side):
        a, b = f[2 * j], f[2 * j + 1]
        J[:, j] = (a - b) / (2.0 * h) if s == 0.0 else (-3.0 * r + 4.0 * a - b) / (2.0 * s * h)
    return J, 2 * u.size
