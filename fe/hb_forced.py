"""Multi-harmonic balance of the forced response in the reduced coordinates, any joint law.

The model of :mod:`fe.harmonic_balance` (``M q'' + C q' + K_J q + G^T g(G q) =
Re(p e^{i w t})``) with ``q(t) = sum_c E_c(t) X_c``: real coefficients ``X`` (n_c, r),
rows ``[Re Q_h, Im Q_h]`` per harmonic ``h`` (``Im Q_0`` dropped), the layout of
:func:`fe.harmonic_balance.harmonic_synthesis`. Galerkin projection on the harmonics
gives, for ``x = X.ravel()``,

    R(x, w) = L(w) x + vec(N(G X^T)^T G) - b = 0,                                   (1)

    L(w): per harmonic h  [[K - (h w)^2 M, -h w C], [h w C, K - (h w)^2 M]]   (K for h = 0),

``b`` the load in the ``h = 1`` rows and ``N`` the coefficients of ``g`` from the joint
harmonics (:class:`fe.law_aft.LawHarmonics`: any law by AFT; a Jenkins bank with its
exact compiled Jacobian). The Jacobians are ``dR/dx = L + (G^T (x) I) dN/dY (G (x) I)``
(block per joint) and ``dR/dw = (dL/dw) x``. This is the residual
:func:`fe.continuation.continue_branch` follows and :mod:`fe.hill` linearizes; unlike the
slip-condensed balance of :mod:`fe.harmonic_balance` it keeps every coordinate, so it is
meant for lumped and reduced models (``n_c r`` up to a few hundred). SI units: rad/s, m, N.
"""
from __future__ import annotations

import numpy as np

from fe.harmonic_balance import _layout, _to_complex
from fe.law_aft import LawHarmonics
from fe.reduction import ReducedModel

__all__ = ["ForcedBalance"]


class ForcedBalance:
    """Residual (1) of the module docstring and its Jacobians.

    Parameters
    ----------
    model : ReducedModel
    law : joints.law.JointLaw
        ``law.K_T`` must be the model's ``K_T``.
    load : ndarray, shape (r,)
        Reduced complex load amplitude ``p`` (N) of ``Re(p e^{i w t})``.
    harmonics : sequence of int
        Harmonics kept (``0``: static term; odd ones suffice for a symmetric law).
    n_time : int
        AFT samples per period.
    jacobian : str
        Of the joint harmonics (:class:`fe.law_aft.LawHarmonics`).
    """

    def __init__(self, model: ReducedModel, law, load, harmonics=(1, 3, 5), n_time: int = 128,
                 jacobian: str = "auto", **law_options):
        K_T = np.asarray(law.K_T, dtype=float)
        if K_T.shape != model.K_T.shape or np.any(
                np.abs(K_T - model.K_T) > 1e-9 * np.abs(model.K_T) + 1e-300):
            raise ValueError("the joint law's stuck stiffness does not match the model's K_T")
        self.model, self.law = model, law
        self.load = np.asarray(load, dtype=complex).reshape(model.n_reduced)
        self.n_time, self.jacobian, self.law_options = int(n_time), jacobian, law_options
        self.joints = LawHarmonics(law, harmonics, n_time, jacobian, **law_options)
        self.harmonics = self.joints.harmonics
        self.re, self.im, self.nc = _layout(tuple(int(h) for h in self.harmonics))
        self.r = model.n_reduced
        self.n = self.nc * self.r
        self.b = np.zeros((self.nc, self.r))
        one = np.flatnonzero(self.harmonics == 1)
        if one.size == 0:
            raise ValueError("the harmonics must include 1 (the drive)")
        self.b[self.re[one[0]]] = self.load.real
        self.b[self.im[one[0]]] = self.load.imag
        self.b = self.b.reshape(-1)

    def with_harmonics(self, harmonics) -> "ForcedBalance":
        """The same problem on other harmonics (Hill's method, :mod:`fe.hill`)."""
        return ForcedBalance(self.model, self.law, self.load, harmonics, self.n_time,
                             self.jacobian, **self.law_options)

    def derivative(self, omega: float) -> np.ndarray:
        """``d/dt`` on the coefficients (n_c, n_c): ``(a, b) -> (-h w b, h w a)``."""
        D = np.zeros((self.nc, self.nc))
        for k, h in enumerate(self.harmonics):
            if h:
                D[self.re[k], self.im[k]] = -h * omega
                D[self.im[k], self.re[k]] = h * omega
        return D

    def linear(self, omega: float):
        """``L(w)`` and ``dL/dw`` (n, n): ``I (x) K + D (x) C + D^2 (x) M`` (eq. 1)."""
        m = self.model
        D = self.derivative(omega)
        Dw = self.derivative(1.0)
        L = np.kron(np.eye(self.nc), m.K) + np.kron(D, m.C) + np.kron(D @ D, m.M)
        dL = np.kron(Dw, m.C) + np.kron(2.0 * omega * (Dw @ Dw), m.M)
        return L, dL

    def __call__(self, x: np.ndarray, omega: float):
        """``(R (n,), dR/dx (n, n), dR/dw (n,))`` at the real coefficients ``x`` (m) and
        ``omega`` (rad/s)."""
        G = self.model.G
        X = np.asarray(x, dtype=float).reshape(self.nc, self.r)
        N, JN, _ = self.joints(X @ G.T)
        L, dL = self.linear(omega)
        R = L @ x + (N @ G).reshape(-1) - self.b
        Jx = L + np.einsum("ji,jcd,jk->cidk", G, JN, G).reshape(self.n, self.n)
        return R, Jx, dL @ x

    def stuck(self, omega: float) -> np.ndarray:
        """The stuck-joint (linear, ``g = 0``) solution ``L(w)^{-1} b``."""
        return np.linalg.solve(self.linear(omega)[0], self.b)

    def harmonics_of(self, x: np.ndarray) -> np.ndarray:
        """Complex harmonics ``Q_h`` (n_h, r) of the coefficients ``x``."""
        return _to_complex(np.asarray(x).reshape(self.nc, self.r), self.harmonics)

    def embed(self, x: np.ndarray, other: "ForcedBalance") -> np.ndarray:
        """Coefficients ``x`` of ``other``'s harmonics rewritten in this balance's
        (harmonics missing here dropped, missing there zero)."""
        Xo = np.asarray(x).reshape(other.nc, other.r)
        X = np.zeros((self.nc, self.r))
        for k, h in enumerate(self.harmonics):
            j = np.flatnonzero(other.harmonics == h)
            if j.size:
                X[self.re[k]] = Xo[other.re[j[0]]]
                if h:
                    X[self.im[k]] = Xo[other.im[j[0]]]
        return X.reshape(-1)

    def time_samples(self, x: np.ndarray, n_time: int | None = None) -> np.ndarray:
        """``q(t_n)`` (n_time, r) at ``t_n = n T / n_time``."""
        from fe.harmonic_balance import harmonic_synthesis

        E, _ = harmonic_synthesis(self.harmonics, self.n_time if n_time is None else n_time)
        return E @ np.asarray(x).reshape(self.nc, self.r)
