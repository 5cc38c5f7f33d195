"""Modal filtering of a stepped-sine campaign: the mode as the structure's response sees it.

``D(w) = phi_d / (phi^T M x(w))`` of the response ``x`` of every DOF to a force at the
drive DOF projects the response on one mass-normalized mode ``phi`` (mass-orthogonality
filters the others out): exact for a linear proportionally damped structure, and with
joints it carries their describing-function stiffness as the mode sees it. Used as the
identification-free check of the LSCF identification (:mod:`ident.levels`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ident.levels import spline_at
from joints.describing import kappa1

__all__ = ["ModalFilterLevels", "modal_filter_levels"]


@dataclass
class ModalFilterLevels:
    """Per level, the mode seen through the modal filter at its resonance (SI units).

    ``frequency_hz`` and ``omega2 = Omega^2`` where ``Re D = 0``; ``zeta = Im D /
    (2 Omega^2)``; ``delta_c = Im D - Omega c_n`` and ``delta_omega2 = omega_n^2 -
    Omega^2`` (the joint's modal damping and softening at the resonance amplitude);
    ``slip`` (n_levels, n_joints) there (m); ``delta_c_decoupled`` and
    ``delta_omega2_decoupled``: paper eq. 30-32 with the input R, chi and these slips,
    ``|kappa1| B`` and ``kappa2 B`` (exact kappa2)."""

    frequency_hz: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    delta_c: np.ndarray
    delta_omega2: np.ndarray
    slip: np.ndarray
    delta_c_decoupled: np.ndarray
    delta_omega2_decoupled: np.ndarray


def modal_filter_levels(freq_hz, receptance, M, phi, drive_dof: int, omega_n: float,
                        c_n: float, slip_amplitude, slip_rows, shares, R: float,
                        chi: float) -> ModalFilterLevels:
    """Modal damping and frequency at resonance by modal filtering (exact projection).

    ``D(w) = phi_d / (phi^T M x(w))`` with ``x`` the receptance of every DOF to a unit
    force at ``drive_dof`` (mass-orthogonality filters the other modes out): for the
    linear structure ``D = omega_n^2 - w^2 + i w c_n`` exactly; with the joints it carries
    their describing-function stiffness as seen by the mode (paper eq. 26 projected on
    ``phi``, without the decoupling of eq. 29-30). The resonance is the root of ``Re D``
    (cubic spline over the lines).

    Parameters
    ----------
    freq_hz : (n_lines,) Hz.
    receptance : (n_levels, n_lines, n) complex, m/N, every DOF.
    M : (n, n) mass (kg); phi : (n,) mass-normalized mode; drive_dof : int.
    omega_n : float (rad/s); c_n : modal viscous damping ``2 zeta_v omega_n`` (rad/s).
    slip_amplitude : (n_levels, n_lines, n_joints) m.
    slip_rows : (n_joints, n) ``G``; shares : (n_joints,) ``w_m``; R, chi : input joint.
    """
    from scipy.interpolate import CubicSpline

    from joints.describing import kappa2_exact

    f = np.asarray(freq_hz, dtype=float)
    D = phi[int(drive_dof)] / (np.asarray(receptance) @ (M @ phi))     # (L, n_lines)
    L = D.shape[0]
    fr, imd = np.full(L, np.nan), np.full(L, np.nan)
    sl = np.full((L, slip_amplitude.shape[2]), np.nan)
    for lv in range(L):
        re = CubicSpline(f, D[lv].real)
        roots = re.roots(extrapolate=False)
        if roots.size == 0:
            continue
        fr[lv] = roots[np.argmin(np.abs(roots - omega_n / (2 * np.pi)))]
        imd[lv] = CubicSpline(f, D[lv].imag)(fr[lv])
        sl[lv] = spline_at(f, slip_amplitude[lv], fr[lv])
    Om = 2 * np.pi * fr
    dc = imd - Om * c_n
    gphi2 = np.asarray(slip_rows @ phi).ravel() ** 2
    B = (np.asarray(shares) * gphi2 * sl ** (chi + 1.0)).sum(axis=1)
    return ModalFilterLevels(frequency_hz=fr, omega2=Om ** 2, zeta=imd / (2 * Om ** 2),
                             delta_c=dc, delta_omega2=omega_n ** 2 - Om ** 2, slip=sl,
                             delta_c_decoupled=abs(kappa1(R, chi)) * B,
                             delta_omega2_decoupled=kappa2_exact(R, chi) * B)
