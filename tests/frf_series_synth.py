"""Synthetic stepped-sine FRF series with known modal parameters (test helper).

A chain of point masses with linear springs and viscous dampers carries one
four-parameter Iwan joint (Segalman 2005) between two DOFs (or a DOF and the ground)
and, optionally, a cubic hardening spring on the same slip. At every frequency line the
steady first-harmonic response follows from the exact describing function of the joint
(:func:`joints.describing.describing_function`): with slip amplitude ``A`` the dynamic
stiffness is

    D(A, w) = K + g g^T (k_in(A) + 3/4 k3 A^2 + i k_q(A)) - w^2 M + i w C,

``x = F D^-1 e_drive``, slip ``s = g . x``. Force control (drive force amplitude ``F``
held): ``A`` solves ``A = F |g . D(A, w)^-1 e|`` (a scalar root in log A). Response
control (drive-point amplitude ``X`` held): ``F = X / |e . D(A, w)^-1 e|`` and
``A = F |g . D^-1 e|``. The FRF written to the file is the receptance ``x / F`` of every
point at the solved ``A``; the optional ``force`` column is ``F`` per line.

Noise: complex Gaussian, relative to |H| (``noise``) and a floor relative to the peak
(``floor``), seeded; the force column gets 0.1 % relative noise.

The truth of each level (what an ideal identification should give) is the linear
system frozen at the slip amplitude of the level's resonance: its eigenvalue nearest
the band (equivalent viscous damping ``k_q / w`` of the joint at the resonance).
SI units: kg, N/m, N s/m, m, Hz in the files.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.linalg import eig
from scipy.optimize import brentq

from ident.frf_files import FRFSet, write_frf
from joints.describing import describing_function
from joints.iwan import IwanParameters


@dataclass
class JointedChain:
    """Masses ``m`` (kg), springs to the previous mass / the ground, the Iwan joint.

    ``k[i]``, ``c[i]``: spring and damper between DOF i-1 and i (DOF 0: to the ground).
    The joint acts on ``slip = x[a] - x[b]`` (``b = None``: ground). ``k3``: cubic
    hardening spring on the same slip (N/m^3)."""

    m: np.ndarray
    k: np.ndarray
    c: np.ndarray
    joint: IwanParameters
    a: int = 0
    b: int | None = None
    k3: float = 0.0
    drive: int = 0

    def __post_init__(self):
        self.m, self.k, self.c = (np.asarray(v, float) for v in (self.m, self.k, self.c))

    @property
    def n(self) -> int:
        return self.m.size

    def _chain(self, v):
        n = self.n
        out = np.zeros((n, n))
        for i in range(n):
            out[i, i] += v[i]
            if i > 0:
                out[i - 1, i - 1] += v[i]
                out[i - 1, i] -= v[i]
                out[i, i - 1] -= v[i]
        return out

    @property
    def g(self) -> np.ndarray:
        g = np.zeros(self.n)
        g[self.a] = 1.0
        if self.b is not None:
            g[self.b] = -1.0
        return g

    def joint_stiffness(self, A):
        """Complex first-harmonic joint stiffness at slip amplitude A (N/m)."""
        k_in, k_q = describing_function(self.joint, A)
        return k_in + 0.75 * self.k3 * A ** 2 + 1j * k_q

    def dynamic_stiffness(self, A, w):
        g = self.g
        return (self._chain(self.k) + np.outer(g, g) * self.joint_stiffness(A)
                - w ** 2 * np.diag(self.m) + 1j * w * self._chain(self.c))

    def unit_response(self, A, w):
        """Response to a unit drive force at slip amplitude A and line w (rad/s)."""
        e = np.zeros(self.n)
        e[self.drive] = 1.0
        return np.linalg.solve(self.dynamic_stiffness(A, w), e)

    def frozen_modes(self, A):
        """Eigenvalues (rad/s) of the linear system frozen at slip amplitude A, with the
        joint's quadrature stiffness as viscous damping k_q / |Im lambda| (iterated)."""
        g = self.g
        kj = self.joint_stiffness(A)
        M = np.diag(self.m)
        K = self._chain(self.k) + np.outer(g, g) * kj.real
        C0 = self._chain(self.c)
        lam = None
        for _ in range(30):
            wd = np.sqrt(np.maximum(np.real(eig(K, M, right=False)), 0)) if lam is None \
                else np.abs(lam.imag)
            out = []
            for w in np.sort(wd):
                C = C0 + np.outer(g, g) * kj.imag / w
                Z = np.zeros_like(M)
                Aa = np.block([[Z, np.eye(self.n)], [-np.linalg.solve(M, K),
                                                      -np.linalg.solve(M, C)]])
                ev = np.linalg.eigvals(Aa)
                ev = ev[ev.imag > 0]
                out.append(ev[np.argmin(np.abs(np.abs(ev.imag) - w))])
            new = np.array(out)
            if lam is not None and np.allclose(new, lam, rtol=1e-14):
                break
            lam = new
        return lam


def _solve_slip(chain, w, held, control):
    """Slip amplitude A at line w under force (held = F) or response (held = X) control."""
    def slip_of(A):
        x = chain.unit_response(A, w)
        s = abs(chain.g @ x)
        force = held if control == "force" else held / abs(x[chain.drive])
        return force * s, force, x

    def h(logA):
        return np.log(slip_of(np.exp(logA))[0]) - logA

    A0 = slip_of(1e-12 * chain.joint.phi_max)[0]
    lo, hi = np.log(A0) - 8.0, np.log(A0) + 6.0
    grid = np.linspace(lo, hi, 60)
    vals = np.array([h(v) for v in grid])
    roots = np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))
    if roots.size != 1:
        raise RuntimeError(f"{roots.size} steady states at {w / 2 / np.pi:.3f} Hz (fold)")
    i = roots[0]
    logA = brentq(h, grid[i], grid[i + 1], xtol=1e-14, rtol=1e-14)
    A = np.exp(logA)
    _, force, x = slip_of(A)
    return A, force, x


@dataclass
class SynthLevel:
    freq_hz: np.ndarray
    frf: np.ndarray          # noise-free receptance (lines, points)
    force: np.ndarray        # drive force amplitude per line, N
    slip: np.ndarray         # slip amplitude per line, m
    held: float
    control: str
    truth_pole: complex      # frozen-system pole at the resonance slip amplitude
    truth_amplitude: float   # drive-point displacement amplitude at the resonance line
    truth_force: float       # force at the resonance line
    extra: dict = field(default_factory=dict)


def simulate_level(chain, held, control, freq_hz, mode_index=0):
    """Stepped-sine level: FRF, force and slip per line, and the frozen-system truth."""
    W = 2 * np.pi * np.asarray(freq_hz, float)
    sol = [_solve_slip(chain, w, held, control) for w in W]
    A = np.array([s[0] for s in sol])
    F = np.array([s[1] for s in sol])
    H = np.array([s[2] for s in sol])
    k = int(np.argmax(np.abs(H[:, chain.drive]) * (F if control == "force" else 1.0)))
    if control == "response":
        k = int(np.argmin(F))
    lam = chain.frozen_modes(A[k])[mode_index]
    # amplitude and force at the frozen mode's resonance (interpolated on the lines)
    amp = np.abs(H[:, chain.drive]) * F
    return SynthLevel(np.asarray(freq_hz, float), H, F, A, float(held), control, complex(lam),
                      float(np.interp(abs(lam.imag) / 2 / np.pi, freq_hz, amp)),
                      float(np.interp(abs(lam.imag) / 2 / np.pi, freq_hz, F)))


def noisy(level: SynthLevel, rng, noise=0.005, floor=1e-4):
    """Measured FRF and force: relative complex noise on H, a floor, 0.1 % on F."""
    H = level.frf
    n = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    n2 = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    Hm = H * (1 + noise * n) + floor * np.abs(H).max() * n2
    Fm = level.force * (1 + 1e-3 * rng.standard_normal(level.force.size))
    return Hm, Fm


def write_level(path, level: SynthLevel, H, F, run_order=None, with_force=True,
                header_excitation=True, points=None):
    """Write one level as an FRF file (CSV or UFF by extension)."""
    points = points or [str(i + 1) for i in range(H.shape[1])]
    write_frf(path, FRFSet(level.freq_hz, H, points, quantity="receptance",
                           excitation=level.held if header_excitation else None,
                           reference=points[0], control=level.control, run_order=run_order,
                           force=F if with_force else None))


def band_lines(center_hz, n=41, step=0.05):
    """n lines of ``step`` Hz centred on ``center_hz`` rounded to the grid."""
    c = round(center_hz / step) * step
    return c + step * (np.arange(n) - (n - 1) / 2)


def planted_series(path, freqs_hz, zetas, held, control="response", seed=0, noise=0.005,
                   n_lines=41, step=0.05, stiffness=2.5e5, with_force=True):
    """One linear SDOF FRF file per level with planted natural frequency and damping
    ratio (viscous), ``n_lines`` lines of ``step`` Hz around each; under response
    control the force column is ``held / |H|``, under force control it is ``held``.
    Returns the written paths."""
    rng = np.random.default_rng(seed)
    Path(path).mkdir(parents=True, exist_ok=True)
    paths = []
    for k, (fn, z, a) in enumerate(zip(freqs_hz, zetas, held)):
        f = band_lines(fn, n_lines, step)
        w, wn = 2 * np.pi * f, 2 * np.pi * fn
        H = (1.0 / (stiffness / wn ** 2 * (wn ** 2 - w ** 2 + 2j * z * wn * w)))[:, None]
        force = a / np.abs(H[:, 0]) if control == "response" else np.full(f.size, a)
        lev = SynthLevel(f, H, force, np.abs(H[:, 0]) * force, a, control, 0j, 0.0, 0.0)
        Hm, Fm = noisy(lev, rng, noise, 1e-4)
        p = Path(path) / f"level_{k + 1:02d}.csv"
        write_level(p, lev, Hm, Fm, run_order=k + 1, with_force=with_force)
        paths.append(str(p))
    return paths


def rattle_series(path, f0=80.0):
    """Five force-controlled linear levels (``planted_series``), the third with a second,
    small resonance 0.9 Hz above the mode (a rattle at that level only). Returns
    (paths, planted natural frequencies Hz, the third level's FRFSet)."""
    from ident.frf_files import read_frf, write_frf

    fn, zeta = f0 * (1 - 0.001 * np.arange(5)), 0.006 * 1.2 ** np.arange(5)
    paths = planted_series(path, fn, zeta, 2.0 ** np.arange(5), control="force",
                           noise=0.002)
    s = read_frf(paths[2])
    w, wx = 2 * np.pi * s.freq_hz, 2 * np.pi * (fn[2] + 0.9)
    s.frf[:, 0] += 0.01 / (2.5e5 / wx ** 2 * (wx ** 2 - w ** 2 + 2j * 0.002 * wx * w))
    write_frf(paths[2], s)
    return paths, fn, s
