"""A nonlinear mode's backbone: frequency, damping and shape against amplitude, and its use
as a prediction.

:class:`Backbone` holds the points of :func:`fe.epmc.epmc_backbone` (Krack 2015): per
amplitude the frequency ``w`` (rad/s), the artificial damping ``xi`` (1/s) and the
damping ratio ``zeta = xi/(2 w)`` (Krack 2015, eq. 8), the reduced displacement
harmonics (the mode shape at that amplitude), the joint slip amplitudes and the energy.
Reading it at an amplitude (:meth:`Backbone.at`) or at the resonance of a force level
(:meth:`Backbone.at_force`) predicts levels that were not tested.

Force at resonance. Driven by ``F cos(W t)`` at DOF ``d`` near the mode, a single
nonlinear mode ``q = Re(a_m psi e^{iWt})`` (``psi^H M psi = 1``) obeys
``(w^2 - W^2 + 2 i zeta w W) a_m = psi_d^* F`` (Krack 2015, Sec. 5; Szemplinska-Stupnicka's
single-mode approximation), so at the resonance ``W = w``

    F = 2 zeta w^2 a_m / |psi_d| = 2 zeta w^2 a_m^2 / |x_d|,                     (1)

with ``a_m = sqrt(Q_1^H M Q_1)`` and ``x_d`` the first-harmonic amplitude at ``d``.
SI units: rad/s, m, N, J.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

__all__ = ["Backbone"]


@dataclass
class Backbone:
    """Points of a nonlinear mode (module docstring), ordered by amplitude.

    Attributes
    ----------
    mode : int
        1-based stuck-joint mode the branch starts from; ``omega_linear`` its frequency.
    path : str
        Joint path (``bank`` or ``exact``, :mod:`fe.joint_harmonics`).
    normalization : str or int
        What the amplitude ``a`` is (``at`` of :func:`fe.epmc.amplitude_functional`).
    amplitude : (n,) the continuation parameter ``a`` (unit of ``at``).
    omega, xi : (n,) rad/s, 1/s.
    harmonics : (n_h,) ints; q : (n, n_h, r) complex reduced displacement harmonics.
    slip_amplitude : (n, n_joints) half peak-to-peak slips (m).
    basis : (n_dof, r) the reduced basis (physical shapes ``basis @ q``).
    mass : (r, r) the reduced mass.
    iterations : (n,) Newton iterations of the last solve of each point.
    fallbacks : (n,) solves of each point that needed a fallback: a restart from the
        previous point after the predictor failed, or a halved amplitude step (0: the
        predictor converged at once).
    """

    mode: int
    path: str
    normalization: object
    omega_linear: float
    amplitude: np.ndarray
    omega: np.ndarray
    xi: np.ndarray
    harmonics: np.ndarray
    q: np.ndarray
    slip_amplitude: np.ndarray
    basis: np.ndarray
    mass: np.ndarray
    iterations: np.ndarray
    fallbacks: np.ndarray | None = None

    @classmethod
    def from_solutions(cls, model, joints, mode, at, L, phi, omega0, points) -> "Backbone":
        """From ``(a, z, slip, iterations, fallbacks)`` tuples of :mod:`fe.epmc`."""
        r, nc = model.n_reduced, joints.nc
        a = np.array([p[0] for p in points])
        Z = np.array([p[1] for p in points])
        Y = Z[:, :nc * r].reshape(-1, nc, r)
        q = a[:, None, None] * (Y[:, 0::2] + 1j * Y[:, 1::2])
        return cls(mode=int(mode), path=joints.path, normalization=at, omega_linear=float(omega0),
                   amplitude=a, omega=Z[:, nc * r], xi=Z[:, nc * r + 1],
                   harmonics=np.asarray(joints.harmonics), q=q,
                   slip_amplitude=np.array([p[2] for p in points]),
                   basis=np.asarray(model.basis), mass=np.asarray(model.M),
                   iterations=np.array([p[3] for p in points]),
                   fallbacks=np.array([p[4] for p in points]))

    def __len__(self) -> int:
        return int(self.amplitude.size)

    # ------------------------------------------------------------------ per point
    @property
    def zeta(self) -> np.ndarray:
        """Damping ratio ``xi / (2 w)`` (Krack 2015, eq. 8)."""
        return self.xi / (2.0 * self.omega)

    @property
    def omega2(self) -> np.ndarray:
        return self.omega ** 2

    @property
    def frequency_hz(self) -> np.ndarray:
        return self.omega / (2.0 * np.pi)

    @property
    def first_harmonic(self) -> np.ndarray:
        """Reduced first-harmonic displacements ``Q_1`` (n, r), complex."""
        return self.q[:, int(np.flatnonzero(self.harmonics == 1)[0])]

    @property
    def modal_amplitude(self) -> np.ndarray:
        """``a_m = sqrt(Q_1^H M Q_1)`` (kg^1/2 m): amplitude of the mass-normalized shape."""
        Q = self.first_harmonic
        return np.sqrt(np.einsum("ni,ij,nj->n", Q.conj(), self.mass, Q).real)

    @property
    def energy(self) -> np.ndarray:
        """Twice the mean kinetic energy, ``sum_h (h w)^2 Q_h^H M Q_h / 2`` (J): for a
        harmonic motion the peak kinetic energy, i.e. the energy of the mode's
        equivalent linear oscillator."""
        hw2 = (self.harmonics[None, :] * self.omega[:, None]) ** 2
        QMQ = np.einsum("nhi,ij,nhj->nh", self.q.conj(), self.mass, self.q).real
        return 0.5 * np.sum(hw2 * QMQ, axis=1)

    def dof_amplitude(self, dof: int) -> np.ndarray:
        """First-harmonic displacement amplitude at physical DOF ``dof`` (m)."""
        return np.abs(self.first_harmonic @ self.basis[int(dof)])

    def shape(self, i: int) -> np.ndarray:
        """Physical first-harmonic shape at point ``i`` (complex, m)."""
        return self.basis @ self.first_harmonic[i]

    def slip_ratio(self, phi_max) -> np.ndarray:
        """Largest joint slip over ``phi_max`` (scalar or per joint) at each point."""
        return np.max(self.slip_amplitude / np.asarray(phi_max, dtype=float), axis=1)

    def force_at_resonance(self, dof: int) -> np.ndarray:
        """Eq. (1): drive amplitude (N) at ``dof`` whose resonance sits at each point."""
        a_m = self.modal_amplitude
        return 2.0 * self.zeta * self.omega ** 2 * a_m ** 2 / self.dof_amplitude(dof)

    # ------------------------------------------------------------------ reading it
    def at(self, x, abscissa=None) -> dict:
        """``omega2``, ``zeta`` and ``slip_amplitude`` interpolated at ``x`` (monotone
        cubic in ``ln x``) of ``abscissa`` (n,), default :attr:`amplitude`. ValueError
        outside the computed range (no extrapolation)."""
        s = self.amplitude if abscissa is None else np.asarray(abscissa, dtype=float)
        x = np.atleast_1d(np.asarray(x, dtype=float))
        if np.any(np.diff(s) <= 0):
            raise ValueError("the backbone's abscissa does not increase along the branch")
        if np.any(~(x > 0)) or np.any(x < s[0] * (1 - 1e-12)) or np.any(x > s[-1] * (1 + 1e-12)):
            raise ValueError(f"amplitude outside the backbone ({s[0]:.4g} .. {s[-1]:.4g})")
        lx, ls = np.log(np.clip(x, s[0], s[-1])), np.log(s)
        if s.size == 1:
            return {"omega2": self.omega2.copy(), "zeta": self.zeta.copy(),
                    "slip_amplitude": self.slip_amplitude.copy()}

        def f(y):
            return PchipInterpolator(ls, y, axis=0)(lx)

        return {"omega2": f(self.omega2), "zeta": f(self.zeta),
                "slip_amplitude": np.exp(f(np.log(np.maximum(self.slip_amplitude, 1e-300))))}

    def at_force(self, force, dof: int) -> dict:
        """The backbone at the resonance of drive amplitudes ``force`` (N) at ``dof``
        (eq. 1): ``at`` on the abscissa :meth:`force_at_resonance`, plus the modal and
        ``dof`` amplitudes there."""
        F = self.force_at_resonance(dof)
        out = self.at(force, F)
        lx, lF = np.log(np.atleast_1d(np.asarray(force, dtype=float))), np.log(F)
        for name, y in (("modal_amplitude", self.modal_amplitude),
                        ("dof_amplitude", self.dof_amplitude(dof))):
            out[name] = np.exp(PchipInterpolator(lF, np.log(y))(lx)) if F.size > 1 else y
        return out

    def to_points(self, phi_max) -> list[dict]:
        """One record per point: ``amplitude`` (largest slip over ``phi_max``),
        ``frequency_hz``, ``zeta``, ``energy`` (J), and ``a`` (the continuation
        parameter), ``omega2``, ``xi``, ``modal_amplitude``, ``max_slip_m``."""
        ratio, E, am = self.slip_ratio(phi_max), self.energy, self.modal_amplitude
        return [{"amplitude": float(ratio[i]), "frequency_hz": float(self.frequency_hz[i]),
                 "zeta": float(self.zeta[i]), "energy": float(E[i]),
                 "a": float(self.amplitude[i]), "omega2": float(self.omega2[i]),
                 "xi": float(self.xi[i]), "modal_amplitude": float(am[i]),
                 "max_slip_m": float(self.slip_amplitude[i].max()),
                 "iterations": int(self.iterations[i])}
                for i in range(len(self))]
