"""Real modes (mass-normalized) and frequency response functions.

``K phi = omega^2 M phi`` with ``phi^T M phi = 1`` (paper eq. 27). FRFs by modal
summation (paper eq. 31 with the joint terms removed)::

    H_rd(omega) = sum_n phi_n[r] phi_n[d] / (omega_n^2 - omega^2 + 2 i zeta_n omega_n omega)

with modal damping ``zeta_n`` given directly or from proportional damping
``C = a M + b K``: ``zeta_n = a / (2 omega_n) + b omega_n / 2`` (paper eq. 28). With all
modes kept and proportional damping this is exact; it equals the direct solution of
``(K - omega^2 M + i omega C) x = f`` (:func:`frf_direct`). The modal filter
(:func:`modal_inverse_receptance`) goes back from a response of every DOF to one mode.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: Seed of the fixed Lanczos start vector of :func:`normal_modes` (standard normal
#: entries: generic, so no mode is missed by symmetry as with e.g. a vector of ones).
START_SEED = 20050101


def normal_modes(K, M, n_modes: int, sigma: float | None = None, dense_below: int = 1000):
    """Lowest ``n_modes`` undamped modes of ``K phi = omega^2 M phi``.

    Parameters
    ----------
    K, M : sparse or ndarray, shape (n, n)
        Symmetric stiffness (positive semi-definite) and mass (positive definite).
    n_modes : int
        Number of modes wanted (1 <= n_modes <= n).
    sigma : float, optional
        Shift (rad^2/s^2) of the shift-invert Lanczos iteration
        (``scipy.sparse.linalg.eigsh(K, M=M, sigma=sigma)``); the modes nearest
        ``sigma`` are found. Default: ``-1`` on the dense path (keeps ``K - sigma M``
        positive definite even with rigid-body modes) and an automatic shift on the sparse
        path (:func:`_sparse_modes`: ``-1`` there lets the rigid-body modes drown the
        elastic ones in the solve's round-off, so a mode vanishes at some meshes). The
        Lanczos start vector is a fixed generic vector
        (:data:`START_SEED`), not ARPACK's random one, so repeated calls with the same
        matrices return bitwise-identical modes (ARPACK's random start moves them by
        ~1e-7 relative between calls, which would change every hash built on them).
    dense_below : int
        Models with fewer DOFs (or requests for more than ``n - 2`` modes) use a dense
        shift-invert: Cholesky factor ``L`` of ``K - sigma M`` and
        ``scipy.linalg.eigh`` of ``L^-1 M L^-T`` (eigenvalues ``1 / (lambda - sigma)``).
        Below 1000 DOFs it costs < 0.1 s for 40 modes and is the more accurate path on
        stiffly coupled models: on the 402-DOF double beam (glue springs 1e8 N/m) the
        relative residual ``|K phi - lambda M phi| / |K phi|`` of modes 2-3 is 7e-8 /
        1e-8 dense against 1e-6 / 7e-7 with ARPACK, whose mode shapes differ from the
        dense ones by 2e-5 (enough to bias a modal filter). Both paths are deterministic.

    Returns
    -------
    omega : ndarray, shape (n_modes,)
        Natural circular frequencies, rad/s, ascending (negative round-off eigenvalues
        give 0).
    shapes : ndarray, shape (n, n_modes)
        Mass-normalized mode shapes (``shapes.T @ M @ shapes = I``); each column's
        largest-magnitude entry is made positive.
    """
    n = K.shape[0]
    if K.shape != (n, n) or M.shape != (n, n):
        raise ValueError("K and M must be square and of equal size")
    n_modes = int(n_modes)
    if not 1 <= n_modes <= n:
        raise ValueError(f"n_modes must be in 1..{n}, got {n_modes}")
    if n < dense_below or n_modes >= n - 2:
        # dense shift-invert: (K - sigma M)^-1 M phi = phi / (lambda - sigma), via the
        # Cholesky factor of K - sigma M; as accurate for the low modes as eigsh
        Kd = K.toarray() if sp.issparse(K) else np.asarray(K, dtype=float)
        Md = M.toarray() if sp.issparse(M) else np.asarray(M, dtype=float)
        sigma = -1.0 if sigma is None else sigma
        Lc = la.cholesky(Kd - sigma * Md, lower=True)
        C = la.solve_triangular(Lc, la.solve_triangular(Lc, Md, lower=True).T, lower=True)
        mu, v = la.eigh(0.5 * (C + C.T), subset_by_index=[n - n_modes, n - 1])
        lam = sigma + 1.0 / mu
        phi = la.solve_triangular(Lc.T, v, lower=False)
    else:
        lam, phi = _sparse_modes(sp.csc_matrix(K, dtype=float), sp.csc_matrix(M, dtype=float),
                                 n_modes, sigma)
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    Mphi = M @ phi
    norms = np.sqrt(np.einsum("ij,ij->j", phi, Mphi))
    phi = phi / norms
    imax = np.argmax(np.abs(phi), axis=0)
    phi = phi * np.sign(phi[imax, np.arange(phi.shape[1])])
    return np.sqrt(np.clip(lam, 0.0, None)), phi


def _sparse_modes(K, M, n_modes: int, sigma: float | None):
    """Shift-invert Lanczos (``eigsh``) at ``sigma`` or, ``sigma=None``, at a shift scaled
    to the model: the solve ``(K - sigma M)^-1 M v`` carries a round-off of ``eps
    cond(K - sigma M) ~ eps lambda_max / |sigma|`` relative to its rigid-body part, which
    is ``(lambda + |sigma|) / |sigma|`` times larger than an elastic mode's part. At
    ``sigma = -1`` and a 1.2 mm lap (``lambda_max ~ 1e14``, ``lambda_1 ~ 1.6e7``) the
    elastic parts are noise and a mode went missing. So a first solve at ``-1`` gives the
    scale ``lambda_e`` of the lowest elastic eigenvalue (above 1e-6 of the highest found,
    which the rigid-body modes' round-off stays below; Ritz values bound the true ones
    from above) and, unless ``lambda_e`` is within a factor 10 of 1, the solve is repeated
    at ``sigma = -lambda_e`` (error ratio ``~ eps lambda_max / lambda_e``); then a
    Rayleigh-Ritz step on the vectors found. Deterministic (fixed start vector). Returns
    ``(lambda, phi)`` ascending."""
    v0 = np.random.default_rng(START_SEED).standard_normal(K.shape[0])
    shift = -1.0 if sigma is None else float(sigma)
    lam, phi = spla.eigsh(K, k=n_modes, M=M, sigma=shift, which="LM", v0=v0)
    top = float(np.max(lam))
    elastic = lam[lam > 1e-6 * top]
    if sigma is None and top > 0.0 and not 0.1 < np.min(elastic) < 10.0:
        lam, phi = spla.eigsh(K, k=n_modes, M=M, sigma=-float(np.min(elastic)), which="LM", v0=v0)
    # Rayleigh-Ritz on the vectors found: on a 0.25 mm free-free lap the rigid-body modes
    # come back within 0.2 Hz of zero (1.4 Hz without) and its 214 Hz mode within 1e-7 of
    # the finer meshes' (2e-5 off without); a 14.8 Hz mode of a clamped lap at 0.625 mm
    # moves by 1e-6 instead of 6e-5 under 25 um moves of the clamp
    Kp, Mp = phi.T @ (K @ phi), phi.T @ (M @ phi)
    lam, v = la.eigh(0.5 * (Kp + Kp.T), 0.5 * (Mp + Mp.T))
    return lam, phi @ v


def modal_damping_ratios(omega_n, zeta=None, proportional=None) -> np.ndarray:
    """Damping ratio of each mode.

    Parameters
    ----------
    omega_n : array_like, shape (n,)
        Natural frequencies, rad/s.
    zeta : float or array_like, optional
        Modal damping ratios (fractions).
    proportional : (a, b), optional
        Rayleigh coefficients of ``C = a M + b K`` (a in 1/s, b in s):
        ``zeta_n = a / (2 omega_n) + b omega_n / 2`` (paper eq. 28).
    """
    omega_n = np.asarray(omega_n, dtype=float)
    if (zeta is None) == (proportional is None):
        raise ValueError("give exactly one of zeta or proportional=(a, b)")
    if zeta is not None:
        return np.broadcast_to(np.asarray(zeta, dtype=float), omega_n.shape).copy()
    a, b = proportional
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(omega_n > 0, a / (2.0 * omega_n), np.inf if a else 0.0) + 0.5 * b * omega_n


def frf_modal(omega, omega_n, shapes, drive, response, zeta=None, proportional=None) -> np.ndarray:
    """Receptance by modal summation (m/N).

    Parameters
    ----------
    omega : array_like, shape (n_freq,)
        Excitation circular frequencies, rad/s.
    omega_n : array_like, shape (n_modes,)
    shapes : ndarray, shape (n_dofs, n_modes)
        Mass-normalized mode shapes.
    drive, response : int or array_like of int
        Driven and response DOF indices; they broadcast against each other and each
        (drive, response) pair gives one FRF column.
    zeta, proportional
        Damping, see :func:`modal_damping_ratios`.

    Returns
    -------
    H : ndarray, complex, shape (n_freq,) or (n_freq, n_pairs)
        ``H[f, p] = sum_n phi_n[response_p] phi_n[drive_p]
        / (omega_n^2 - omega_f^2 + 2 i zeta_n omega_n omega_f)``.
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    omega_n = np.asarray(omega_n, dtype=float)
    z = modal_damping_ratios(omega_n, zeta=zeta, proportional=proportional)
    d, r = np.broadcast_arrays(np.asarray(drive), np.asarray(response))
    scalar = d.ndim == 0
    d, r = np.atleast_1d(d), np.atleast_1d(r)
    participation = shapes[r, :] * shapes[d, :]  # (n_pairs, n_modes)
    denom = ((omega_n**2)[None, :] - (omega**2)[:, None]
             + 2j * (z * omega_n)[None, :] * omega[:, None])
    H = (1.0 / denom) @ participation.T  # (n_freq, n_pairs)
    return H[:, 0] if scalar else H


def frf_direct(omega, K, M, force, C=None, response=None) -> np.ndarray:
    """Receptance by solving ``(K - omega^2 M + i omega C) x = f`` at each frequency.

    Parameters
    ----------
    omega : array_like, shape (n_freq,)
        rad/s.
    K, M, C : sparse or ndarray, shape (n, n)
        C defaults to zero.
    force : array_like, shape (n,)
        Force amplitude vector, N.
    response : int or array_like of int, optional
        DOFs to return (all if None).

    Returns
    -------
    X : ndarray, complex, shape (n_freq, n) or (n_freq, len(response)) or (n_freq,)
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    K = sp.csc_matrix(K, dtype=complex)
    M = sp.csc_matrix(M, dtype=complex)
    C = sp.csc_matrix(K.shape, dtype=complex) if C is None else sp.csc_matrix(C, dtype=complex)
    f = np.asarray(force, dtype=complex)
    out = []
    for w in omega:  # one sparse factorization per frequency
        x = spla.spsolve((K - w**2 * M + 1j * w * C).tocsc(), f)
        out.append(x if response is None else x[response])
    return np.array(out)


def modal_inverse_receptance(receptance, shape, M, load) -> np.ndarray:
    """Inverse modal receptance by modal filtering, ``D = (phi.f)/(phi.M x)``.

    For a linear structure with proportional damping ``D(w) = w_n^2 - w^2 + i w c_n``
    exactly (the other modes are filtered out by mass orthogonality); with joints,
    ``D`` carries the joints' describing-function stiffness and damping as seen by
    the mode (paper eq. 26 projected on ``phi``). ``receptance`` (..., n_dof) complex
    per newton; returns (...,) complex (rad^2/s^2).
    """
    return (shape @ load) / (np.asarray(receptance) @ (M @ shape))
