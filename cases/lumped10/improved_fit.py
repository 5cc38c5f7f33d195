"""The improved estimate of the Iwan ``(chi, R)`` from one mode's damping growth
(simulated joint amplitudes, exact kappas, no modal decoupling; :func:`fit_improved`):
the model's inverse modal receptance (paper eq. 26 without the decoupling) fitted to
the modal-filtered one (:func:`fe.modal.modal_inverse_receptance`).
"""
from __future__ import annotations

import math as _math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares as _least_squares

from fe.modal import modal_inverse_receptance

__all__ = [
    "ImprovedFit",
    "fit_improved",
]


def _model_inverse_receptance(system, shape, load, omega, slip_amplitude, R, chi):
    """``D`` of paper eq. 26 without the decoupling of eq. 29-30: each joint ``m`` adds
    the complex stiffness ``(-kappa2 + i |kappa1|) A_m^(chi+1)`` (exact micro-slip
    kappas of eq. 14/A15) on its slip, at the joint amplitudes ``A`` of each line."""
    from joints.describing import kappa1, kappa2_exact

    w = np.asarray(omega, dtype=float)
    G = np.asarray(system.G)
    Z = (system.K_J[None] - (w ** 2)[:, None, None] * system.M[None]
         + 1j * w[:, None, None] * system.C[None])
    if R is not None:
        dk = (-kappa2_exact(R, chi) + 1j * abs(kappa1(R, chi))) * slip_amplitude ** (chi + 1.0)
        Z = Z + np.einsum("jm,nj,jk->nmk", G, dk, G)
    X = np.linalg.solve(Z, np.broadcast_to(load, (w.size, load.size))[..., None])[..., 0]
    return (shape @ load) / (X @ (system.M @ shape))


@dataclass
class ImprovedFit:
    """Result of :func:`fit_improved` for one mode (SI units)."""

    mode: int
    chi: float
    R: float
    chi_with_frequency: float
    R_with_frequency: float
    levels: list
    n_lines: int
    level_amplitude: np.ndarray      # (n_levels, 2) joint amplitudes at the peak line
    level_delta_c: np.ndarray        # (n_levels,) measured Delta c at the peak line
    level_delta_c_model: np.ndarray  # (n_levels,) fitted model at the same lines


def fit_improved(system, shape, load, freq_hz, receptance, slip_amplitude, mode: int,
                 phi_max: float, band=None, R0: float = 1e5, chi0: float = -0.4) -> ImprovedFit:
    """The improved estimate of ``(chi, R)`` from one mode's damping growth.

    Differences from the paper's eq. 33-37: (i) the joint amplitudes are the
    simulated ones, line by line, instead of ``z^v A_0``; (ii) the joints enter the
    structure's dynamic stiffness as in eq. 26 with the exact ``kappa2`` (A15 with the
    exact Beta-function integral) instead of being decoupled per mode (eq. 29-30,
    which misses the coupling through the joints' in-phase stiffness loss, 4x larger
    than the damping term for chi = -0.5); (iii) no differencing: the linear part is
    the model's. The measured quantity is the modal-filtered inverse receptance
    ``D`` (:func:`fe.modal.modal_inverse_receptance`) on the half-power lines of the mode at
    every level whose joint amplitudes stay below ``phi_max`` (micro-slip); ``(ln R,
    chi)`` minimize ``sum (Im D_meas - Im D_model)^2`` (damping only, as the paper);
    ``*_with_frequency`` also fits ``Re D`` (the frequency drop).

    Parameters
    ----------
    system : JointedSystem
    shape : (n,) mass-normalized stuck mode.
    load : (n,) unit load pattern.
    freq_hz : (n_lines,) line frequencies.
    receptance : (n_levels, n_lines, n) complex first-harmonic receptance.
    slip_amplitude : (n_levels, n_lines, n_joints) simulated joint amplitudes (m).
    mode : mode number (label).
    phi_max : micro-slip limit (m).
    band : (lo, hi) Hz, optional
        Lines considered (default all).
    """
    freq_hz = np.asarray(freq_hz, dtype=float)
    inband = np.ones(freq_hz.size, bool) if band is None else (
        (freq_hz >= band[0]) & (freq_hz <= band[1]))
    if inband.sum() < 3:
        raise ValueError(f"mode {mode}: fewer than 3 lines in the band {band}")
    freq_hz = freq_hz[inband]
    receptance = np.asarray(receptance)[:, inband]
    slip_amplitude = np.asarray(slip_amplitude)[:, inband]
    w_all = 2 * np.pi * freq_hz
    D_all = modal_inverse_receptance(receptance, shape, system.M, load)
    q = 1.0 / np.abs(D_all)
    W, Dm, A, levels = [], [], [], []
    peak_idx = np.argmax(q, axis=1)
    for lv in range(receptance.shape[0]):
        sel = q[lv] >= q[lv].max() / np.sqrt(2.0)
        if slip_amplitude[lv, sel].max() >= phi_max:
            continue
        levels.append(lv + 1)
        W.append(w_all[sel]), Dm.append(D_all[lv, sel]), A.append(slip_amplitude[lv, sel])
    if len(levels) < 2:
        raise ValueError(f"mode {mode}: fewer than 2 micro-slip levels to fit")
    W, Dm, A = np.concatenate(W), np.concatenate(Dm), np.concatenate(A)
    D_lin = _model_inverse_receptance(system, shape, load, W, A, None, None)
    scale = np.mean(np.abs(Dm.imag - D_lin.imag))

    def residual(x, with_freq):
        Dmod = _model_inverse_receptance(system, shape, load, W, A, _math.exp(x[0]), x[1])
        r = (Dmod.imag - Dm.imag) / scale
        return np.concatenate([r, (Dmod.real - Dm.real) / scale]) if with_freq else r

    bounds = ([_math.log(R0) - 30, -0.999], [_math.log(R0) + 30, -0.001])
    out = []
    for with_freq in (False, True):
        sol = _least_squares(residual, [_math.log(R0), chi0], args=(with_freq,),
                             x_scale=[1.0, 0.1], bounds=bounds, xtol=1e-14, ftol=1e-14)
        out.append((float(sol.x[1]), float(_math.exp(sol.x[0]))))
    chi, R = out[0]
    # per-level view (peak line of each level) for Fig. 5
    pk = peak_idx
    lv_all = np.arange(receptance.shape[0])
    wp = w_all[pk]
    Ap = slip_amplitude[lv_all, pk]
    Dp = D_all[lv_all, pk]
    Dl = _model_inverse_receptance(system, shape, load, wp, Ap, None, None)
    Dmod = _model_inverse_receptance(system, shape, load, wp, Ap, R, chi)
    return ImprovedFit(mode=mode, chi=chi, R=R, chi_with_frequency=out[1][0],
                       R_with_frequency=out[1][1], levels=levels, n_lines=int(W.size),
                       level_amplitude=Ap, level_delta_c=Dp.imag - Dl.imag,
                       level_delta_c_model=Dmod.imag - Dl.imag)
