"""Conversions shared by the modal identification: poles <-> natural frequency and
damping ratio, the modal assurance criterion (MAC) between mode shapes, and FRF
quantity (mobility, accelerance) -> receptance."""
from __future__ import annotations

import numpy as np

QUANTITIES = ("receptance", "mobility", "accelerance")
#: The power of ``i w`` that turns a receptance into each quantity.
QUANTITY_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}


def pole_to_modal(pole) -> tuple[np.ndarray, np.ndarray]:
    """(omega_n rad/s, zeta) of poles ``lambda = -zeta w_n + i w_n sqrt(1-zeta^2)``."""
    pole = np.asarray(pole)
    wn = np.abs(pole)
    return wn, -pole.real / np.where(wn > 0, wn, 1.0)


def modal_to_pole(omega_n, zeta) -> np.ndarray:
    """Pole of upper half-plane for natural frequency (rad/s) and damping ratio."""
    omega_n, zeta = np.asarray(omega_n, float), np.asarray(zeta, float)
    return -zeta * omega_n + 1j * omega_n * np.sqrt(1.0 - zeta**2)


def mac(a, b) -> np.ndarray:
    """Modal assurance criterion ``|a^H b|^2 / (|a|^2 |b|^2)`` between columns.

    a: (n_points, n_a), b: (n_points, n_b) (or 1-D) -> (n_a, n_b)."""
    a = np.atleast_2d(np.asarray(a).T).T if np.ndim(a) == 1 else np.asarray(a)
    b = np.atleast_2d(np.asarray(b).T).T if np.ndim(b) == 1 else np.asarray(b)
    num = np.abs(a.conj().T @ b) ** 2
    den = np.outer(np.sum(np.abs(a) ** 2, 0), np.sum(np.abs(b) ** 2, 0))
    return num / np.where(den > 0, den, 1.0)


def to_receptance(freq_hz, frf, quantity: str) -> np.ndarray:
    """Convert mobility (divide by i w) or accelerance (divide by -w^2) to receptance."""
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    w = 2 * np.pi * np.asarray(freq_hz, float)
    shape = (-1,) + (1,) * (np.ndim(frf) - 1)
    if quantity == "mobility":
        return frf / (1j * w.reshape(shape))
    if quantity == "accelerance":
        return frf / (-(w.reshape(shape)) ** 2)
    return np.asarray(frf)


def modal_receptance(pole, residues, freq_hz) -> np.ndarray:
    """One mode's receptance ``A/(i w - lambda) + conj(A)/(i w - conj(lambda))`` at
    ``freq_hz`` (Hz) for residues ``A`` (n_points,): (n_freq, n_points), m/N."""
    iw = 2j * np.pi * np.atleast_1d(np.asarray(freq_hz, float))[:, None]
    a = np.atleast_1d(np.asarray(residues, complex))[None, :]
    return a / (iw - pole) + np.conj(a) / (iw - np.conj(pole))
