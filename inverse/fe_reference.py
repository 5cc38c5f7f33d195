"""B~ of an FE model (paper eq. 37): its slipping mode and joint slips at resonance.

The model is any object with ``M``, ``K`` (stiffness with the stuck joints ``K_J``),
``slip_matrix``, ``joint_stiffness``, ``drive_dof`` and ``modes(n)``; the shipped ones
come from :mod:`cases.registry`.

``B~`` is eq. 1 of :mod:`inverse.iwan_modal` with the FE mode and the joint slip
amplitudes at the reference level, from ``(K_J - w^2 M + i w C) x = f`` at the model's
resonance (the linear-inverse variant of the paper's Sec. 3). ``C = (2 zeta/omega_l) K_J``
gives the mode the measured damping ``zeta``. The force is ``force_scale * e_ref``
(N); the paper never gives newtons (5 mV .. 2.56 V drive), so ``force_scale`` is an
explicit input (default :data:`inverse.estimate.DEFAULT_FORCE_SCALE`), and ``R~``
scales exactly as ``force_scale^-(chi+1)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ident.errors import InputError
from inverse.iwan_modal import b_tilde


@dataclass
class FEReference:
    """FE side of the estimate: B~ (eq. 37) and what it was computed from."""

    name: str
    fe_mode: int
    fe_frequency_hz: float
    force_scale: float
    reference_force: float
    slip_amplitudes: np.ndarray
    shares: np.ndarray
    B: float
    B_of_chi: object = field(repr=False, default=None)


def joint_slip_at_resonance(M, K, slip_rows, force, omega, zeta) -> np.ndarray:
    """Joint slip amplitudes of the linear model driven at resonance.

    Solves ``(K - omega^2 M + i omega C) x = force`` with ``C = (2 zeta / omega) K``
    (the mode at ``omega`` gets damping ratio ``zeta``; paper Sec. 3, "inverse
    matrix"), returns ``|slip_rows x|``.

    Parameters
    ----------
    M, K : sparse (n, n)
        Mass (kg) and stiffness with the stuck joints ``K_J`` (N/m).
    slip_rows : sparse (n_joints, n)
    force : ndarray (n,)
        Force amplitude vector, N.
    omega : float
        Drive frequency (the model's natural frequency), rad/s.
    zeta : float
        Damping ratio of that mode.

    Returns
    -------
    ndarray (n_joints,)
        Slip amplitudes, m.
    """
    Z = (sp.csc_matrix(K) * (1.0 + 2j * zeta) - omega ** 2 * sp.csc_matrix(M)).tocsc()
    x = spla.spsolve(Z, np.asarray(force, dtype=complex))
    return np.abs(np.asarray(slip_rows @ x)).ravel()


def pick_fe_mode(model, omega_measured: float, n_modes: int = 24) -> int:
    """1-based index of the model mode nearest ``omega_measured`` that slips the joints.

    Modes whose joint slip ``|slip_matrix phi|`` is below 1e-6 of the largest one (e.g.
    out-of-phase modes of identical strips) cannot show the joint and are skipped.
    """
    omega, shapes = model.modes(n_modes)
    slip = np.linalg.norm(np.asarray(model.slip_matrix @ shapes), axis=0)
    ok = slip > 1e-6 * slip.max()
    cand = np.flatnonzero(ok)
    return int(cand[np.argmin(np.abs(omega[cand] - omega_measured))] + 1)


def fe_reference(model, d, ref: int, force_scale: float, fe_mode=None, chi: float = -0.5,
                 name: str = "model") -> FEReference:
    """B~ (eq. 37) of the FE ``model`` at the reference level of the measured data ``d``.

    The mode is ``fe_mode`` (1-based) or :func:`pick_fe_mode`; the joint slips come
    from :func:`joint_slip_at_resonance` at the model's natural frequency with the
    measured damping ratio of the reference level and the force
    ``force_scale * excitation[ref]`` (N) at ``model.drive_dof``; shares are
    ``joint_stiffness / sum(joint_stiffness)`` (each element carries its share of the
    glue's Iwan density). ``name`` labels the result (the case name).
    """
    omega_meas = math.sqrt(float(d.omega2[ref]))
    if fe_mode is None:
        fe_mode = pick_fe_mode(model, omega_meas)
    fe_mode = int(fe_mode)
    if fe_mode < 1:
        raise InputError(f"--fe-mode must be >= 1, got {fe_mode}")
    omega, shapes = model.modes(max(fe_mode, 1))
    if fe_mode > omega.size:
        raise InputError(f"--fe-mode {fe_mode}: the model has only {omega.size} modes")
    w_l, phi = float(omega[fe_mode - 1]), shapes[:, fe_mode - 1]
    n = model.M.shape[0]
    force = np.zeros(n)
    F = force_scale * float(d.excitation[ref])
    force[int(model.drive_dof)] = F
    slips = joint_slip_at_resonance(model.M, model.K, model.slip_matrix, force, w_l,
                                    float(d.zeta[ref]))
    kj = np.asarray(model.joint_stiffness, dtype=float)
    shares = kj / kj.sum()

    def B_of_chi(c):
        return b_tilde(model.slip_matrix, phi, slips, c, shares)

    return FEReference(name=str(name), fe_mode=fe_mode, fe_frequency_hz=w_l / (2 * math.pi),
                       force_scale=float(force_scale), reference_force=F,
                       slip_amplitudes=slips, shares=shares, B=B_of_chi(chi),
                       B_of_chi=B_of_chi)
