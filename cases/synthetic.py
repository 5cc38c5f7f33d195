"""Synthetic measured-data sets from a simulated stepped-sine campaign.

Each case is a virtual test of one mode of a built-up structure, independent of the
diagnosis's fitting formulas:

1. **Structure**: a single-DOF modal oscillator (unit modal mass) carrying a
   four-parameter Iwan joint on its modal coordinate ``q`` (slip ``u = q``), viscous
   damping ``zeta0``, and the hidden effect of the case.
2. **Steady state** at every frequency line ``W`` of every level: first-harmonic
   balance with the exact describing function of the joint
   (:func:`joints.iwan.describing_function`, valid in micro- and macro-slip),

       [w_lin^2 + k_in(X) + 3/4 k3 X^2 - W^2
        + i (2 zeta0 w0 W + k_q(X) + 8/(3 pi) c2 W^2 X + W c_e)] q = G(V) V,

   with ``X = |q|``. ``k3``: cubic hardening spring (first-harmonic term
   ``3/4 k3 X^2``); ``c2``: quadratic damper ``c2 |qdot| qdot`` (equivalent viscous
   ``8 c2 W X / (3 pi)``); ``c_e``: back-EMF damping of a voltage-driven electrodynamic
   exciter (force drop-out at resonance), ``G(V)``: its force gain. The force measured
   by the transducer is ``F = G V - i W c_e q`` so the measured FRF ``q/F`` is the
   structure's own. ``w_lin^2`` may drift with the run order (thermal drift).
   ``X`` is found per line by bisection on ``X |D(X, W)| = |G V|`` (the root is
   unique: cases whose response folds over are rejected and redrawn).
3. **Identification**: ``omega2`` and ``zeta`` of each level from the simulated FRF by
   :func:`ident.identify.identify_modes` (LSCF + LSFD refinement; the inverse-FRF line
   fit of :func:`identify_sdof` if it fails). The response
   amplitude is the steady amplitude of a dwell at the identified natural frequency
   (paper Table 1 procedure).
4. **Noise** as in the paper's tables: ``omega2`` relative 1e-5, ``zeta`` absolute
   1e-5, ``response_amplitude`` relative 1 %, all Gaussian. Run orders are shuffled.

Effect sizes are drawn at random (log-uniform) in units of the noise at the top level,
from barely detectable (a few sigma) to large; ``chi`` in (-0.8, -0.2). For every
cause but ``macro-slip`` the top slip amplitude stays in (0.4, 0.95) phi_max; for
``macro-slip`` it is set past phi_max (at most 2.2 phi_max) where the exact describing
function departs from the micro-slip power law by the drawn effect size.

SI units: rad/s, rad^2/s^2, modal displacement in m (unit modal mass), force in N,
drive in V.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ident.identify import identify_modes
from ident.measured import MeasuredData
from joints.describing import describing_function, kappa1, kappa2_exact
from joints.iwan import IwanParameters

__all__ = [
    "CAUSES",
    "SIGMA_OMEGA2_REL",
    "SIGMA_ZETA",
    "SIGMA_RESPONSE_REL",
    "EFFECT_RANGE",
    "ModalOscillator",
    "Exciter",
    "SyntheticCase",
    "steady_amplitude",
    "simulate_level",
    "generate_case",
    "generate_cases",
]

CAUSES = ("none", "macro-slip", "nonproportional-amplitude", "geometric-hardening",
          "thermal-drift", "quadratic-damping")

SIGMA_OMEGA2_REL = 1e-5    # relative noise of identified omega2 (paper Table 4 digits)
SIGMA_ZETA = 1e-5          # absolute noise of identified zeta (paper Table 6 digits)
SIGMA_RESPONSE_REL = 0.01  # relative noise of the response amplitude

#: Effect size ranges (log-uniform): top-level shift in noise units (omega2 for
#: hardening and drift, zeta for quadratic damping, the larger of the two departures
#: from the micro-slip power law for macro-slip) and, for nonproportional-amplitude,
#: the fraction of exciter force lost at the top level.
EFFECT_RANGE = {
    "macro-slip": (12.0, 150.0),
    "nonproportional-amplitude": (0.06, 0.4),
    "geometric-hardening": (12.0, 80.0),
    "thermal-drift": (8.0, 60.0),
    "quadratic-damping": (8.0, 50.0),
}


@dataclass
class ModalOscillator:
    """One mode with an Iwan joint and optional extra effects (unit modal mass).

    Attributes
    ----------
    omega2_lin : float
        Modal stiffness without the joint, rad^2/s^2.
    zeta0 : float
        Viscous damping ratio, referred to ``omega0 = sqrt(omega2_lin + K_T)``.
    joint : IwanParameters
        Iwan joint on the modal coordinate (K_T in N/m per unit modal mass, i.e. s^-2).
    k3 : float
        Cubic hardening stiffness (N/m^3 per unit mass); 0 for none.
    c2 : float
        Quadratic damping coefficient (N s^2/m^2 per unit mass); 0 for none.
    drift_per_run : float
        Relative change of ``omega2_lin`` per unit run order (thermal drift).
    """

    omega2_lin: float
    zeta0: float
    joint: IwanParameters
    k3: float = 0.0
    c2: float = 0.0
    drift_per_run: float = 0.0

    @property
    def omega0(self) -> float:
        """Small-amplitude natural frequency ``sqrt(omega2_lin + K_T)``, rad/s."""
        return float(np.sqrt(self.omega2_lin + self.joint.K_T))


@dataclass
class Exciter:
    """Voltage-driven electrodynamic exciter.

    Force ``F = G(V) V - i W c_e q`` with ``G(V) = gain / sqrt(1 + (V/v_sat)^2)``
    (amplifier/armature compression; ``v_sat = inf`` for none) and ``c_e`` the back-EMF
    damping ``(Bl)^2 / R_coil`` (N s/m per unit modal mass).
    """

    gain: float = 1.0
    c_e: float = 0.0
    v_sat: float = np.inf

    def force_gain(self, volts):
        volts = np.asarray(volts, dtype=float)
        return self.gain / np.sqrt(1.0 + (volts / self.v_sat) ** 2)


@dataclass
class SyntheticCase:
    """A generated data set with its hidden truth (never shown to the diagnosis)."""

    data: MeasuredData
    cause: str
    seed: int
    truth: dict = field(default_factory=dict)


def _dynamic_stiffness(osc: ModalOscillator, exc: Exciter, X, W, run):
    """Total first-harmonic dynamic stiffness including the exciter's back-EMF.

    Returns (D_structure, D_total) for amplitude ``X`` (m) and line ``W`` (rad/s)."""
    X = np.maximum(X, 1e-30)
    k_in, k_q = describing_function(osc.joint, X)
    w2_lin = osc.omega2_lin * (1.0 + osc.drift_per_run * (run - 1.0))
    real = w2_lin + k_in + 0.75 * osc.k3 * X**2 - W**2
    imag = (2.0 * osc.zeta0 * osc.omega0 * W + k_q
            + 8.0 / (3.0 * np.pi) * osc.c2 * W**2 * X)
    D = real + 1j * imag
    return D, D + 1j * W * exc.c_e


def steady_amplitude(osc: ModalOscillator, exc: Exciter, volts, W, run=1.0, n_iter=80):
    """Steady first-harmonic modal amplitude ``X`` (m) and structure FRF ``q/F``.

    Solves ``X |D_total(X, W)| = G(V) V`` by bisection in ``log X`` (vectorized over
    the broadcast shape of ``volts`` and ``W``).

    Returns
    -------
    X : ndarray
        Amplitude, m.
    frf : ndarray, complex
        Receptance ``q / F`` seen through the force transducer, ``1 / D_structure``.
    fold : bool
        True if ``X |D|`` is not monotone over the bracket at some line (multiple
        steady states: the response folds over).
    """
    volts, W = np.broadcast_arrays(np.asarray(volts, float), np.asarray(W, float))
    target = exc.force_gain(volts) * volts
    _, D0 = _dynamic_stiffness(osc, exc, 1e-9 * osc.joint.phi_max * np.ones_like(W), W, run)
    X_lin = target / np.abs(D0)
    lo, hi = np.log(X_lin * 1e-2), np.log(X_lin * 1.5)
    for _ in range(n_iter):
        mid = 0.5 * (lo + hi)
        _, Dt = _dynamic_stiffness(osc, exc, np.exp(mid), W, run)
        too_big = np.exp(mid) * np.abs(Dt) > target
        hi = np.where(too_big, mid, hi)
        lo = np.where(too_big, lo, mid)
    X = np.exp(0.5 * (lo + hi))
    Ds, _ = _dynamic_stiffness(osc, exc, X, W, run)
    # fold check: X |D_total| must increase with X between 0.3 X and 1.5 X_lin
    grid = np.linspace(0.3, 1.0, 24)[:, None] * X_lin.ravel()[None, :] * 1.5
    _, Dg = _dynamic_stiffness(osc, exc, grid, W.ravel()[None, :], run)
    fold = bool(np.any(np.diff(grid * np.abs(Dg), axis=0) <= 0.0))
    return X, 1.0 / Ds, fold


def simulate_level(osc: ModalOscillator, exc: Exciter, volts: float, lines, run: float):
    """Stepped-sine test at one drive level; identify omega2, zeta; dwell at resonance.

    Returns (omega2, zeta, response_amplitude, fold) without measurement noise."""
    lines = np.asarray(lines, float)
    X, frf, fold = steady_amplitude(osc, exc, volts, lines, run)
    omega2, zeta = identify_sdof(lines, frf)
    Xr, _, fold_r = steady_amplitude(osc, exc, volts, np.array([np.sqrt(omega2)]), run)
    return omega2, zeta, float(Xr[0]), fold or fold_r


def identify_sdof(lines, frf):
    """(omega2, zeta) of the one mode of a stepped-sine receptance.

    :func:`ident.identify.identify_modes` (LSCF + LSFD) with ``n_modes=1``; if it fails,
    the inverse-receptance line fit (Dobson 1987): least squares of
    ``1/H = m (omega2 - W^2) + i m c W`` over the lines, weighted by ``|H|^2``, gives
    ``omega2 = A0/A2``, ``zeta = A1 / (2 A2 sqrt(omega2))``."""
    try:
        with np.errstate(all="ignore"):
            mode = identify_modes(lines / (2 * np.pi), frf, n_modes=1)[0]
        if np.isfinite(mode.omega2) and 0.0 < mode.zeta < 1.0:
            return float(mode.omega2), float(mode.zeta)
    except (ValueError, np.linalg.LinAlgError, IndexError):
        pass
    inv = 1.0 / frf
    wgt = np.abs(frf)
    M = np.concatenate([np.stack([np.ones_like(lines), -lines**2, 0 * lines], 1),
                        np.stack([0 * lines, 0 * lines, lines], 1)]) * np.concatenate([wgt, wgt])[:, None]
    rhs = np.concatenate([inv.real, inv.imag]) * np.concatenate([wgt, wgt])
    A0, A2, A1 = np.linalg.lstsq(M, rhs, rcond=None)[0]
    omega2 = A0 / A2
    return float(omega2), float(A1 / (2.0 * A2 * np.sqrt(omega2)))


def _loguniform(rng, lo, hi):
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def generate_case(cause: str, seed: int, response_column: bool | None = None) -> SyntheticCase:
    """Generate one synthetic measured-data set with the hidden ``cause``.

    Parameters
    ----------
    cause : str
        One of :data:`CAUSES`.
    seed : int
        Seed of every random draw (structure, effect size, run order, noise).
    response_column : bool or None
        Include ``response_amplitude``; None: always for ``nonproportional-amplitude``,
        with probability 1/2 otherwise.

    Returns
    -------
    SyntheticCase
        ``truth`` holds the drawn parameters, the effect size in noise units
        (``effect_sigma``) and the true slip amplitudes.
    """
    if cause not in CAUSES:
        raise ValueError(f"unknown cause {cause!r}; choose from {', '.join(CAUSES)}")
    rng = np.random.default_rng([int(seed), CAUSES.index(cause)])
    for attempt in range(20):
        case = _draw_and_simulate(cause, rng, response_column)
        if case is not None:
            case.seed = int(seed)
            case.truth["attempts"] = attempt + 1
            return case
    raise RuntimeError(f"could not draw a non-folding case for seed {seed}")


def _macro_deviation(joint, omega0, x):
    """Departure of the exact describing function from the micro-slip power law at
    slip amplitude ``x phi_max``, in noise units: (omega2 channel, zeta channel)."""
    A = x * joint.phi_max
    chi, R = joint.chi, joint.R
    k_in, k_q = describing_function(joint, A)
    dev_w = joint.K_T - kappa2_exact(R, chi) * A ** (chi + 1) - k_in
    dev_z = (k_q + kappa1(R, chi) * A ** (chi + 1)) / (2 * omega0**2)
    return dev_w / (SIGMA_OMEGA2_REL * omega0**2), dev_z / SIGMA_ZETA


def _macro_amplitude(joint, omega0, target, x_max=2.2):
    """Top slip amplitude (units of phi_max) whose departure from the power law is
    ``target`` sigma (bisection; None if even ``x_max`` falls short)."""
    def size(x):
        return max(abs(v) for v in _macro_deviation(joint, omega0, x))
    if size(x_max) < target:
        return None
    lo, hi = 1.0, x_max
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if size(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def _draw_and_simulate(cause, rng, response_column):
    n_levels = int(rng.integers(10, 13))
    ratio = rng.uniform(1.5, 2.0)
    chi = rng.uniform(-0.8, -0.2)
    beta = _loguniform(rng, 0.3, 5.0)
    f0 = _loguniform(rng, 40.0, 400.0)
    omega0 = 2 * np.pi * f0
    zeta0 = _loguniform(rng, 0.008, 0.03)
    # joint strength: damping growth at the top level (micro-slip law) of 8..40 sigma
    dzeta_top = _loguniform(rng, 8.0, 40.0) * SIGMA_ZETA
    x_top = rng.uniform(0.4, 0.95)
    macro_target = _loguniform(rng, *EFFECT_RANGE["macro-slip"])
    x_micro = 1.0 if cause == "macro-slip" else x_top
    phi_max = 1e-4  # m (modal); only the ratio X / phi_max matters
    # k_q(A) = |kappa1| A^(chi+1) with R from K_T: solve for R giving dzeta_top at x_micro
    k1_unit = -kappa1(1.0, chi)  # |kappa1| per unit R
    R = dzeta_top * 2.0 * omega0**2 / (k1_unit * (x_micro * phi_max) ** (chi + 1.0))
    S = beta * R * phi_max ** (chi + 1.0) / (chi + 1.0)
    joint = IwanParameters.from_density(R, chi, phi_max, S)
    if cause == "macro-slip":
        x_top = _macro_amplitude(joint, omega0, macro_target)
        if x_top is None:
            return None
    omega2_lin = omega0**2 - joint.K_T
    if omega2_lin <= 0:
        return None

    truth = dict(chi=chi, beta=beta, R=R, phi_max=phi_max, K_T=joint.K_T,
                 omega0=omega0, zeta0=zeta0, x_top=x_top, n_levels=n_levels,
                 ratio=ratio, dzeta_top_iwan=dzeta_top,
                 dOmega2_top_iwan=kappa2_exact(R, chi) * (x_micro * phi_max) ** (chi + 1.0))
    osc = ModalOscillator(omega2_lin=omega2_lin, zeta0=zeta0, joint=joint)
    # exciter: back-EMF damping 1..4 x the structural viscous damping
    c_e = rng.uniform(1.0, 4.0) * 2.0 * zeta0 * omega0
    exc = Exciter(gain=1.0, c_e=c_e)
    volts = ratio ** np.arange(n_levels)
    # amplitude scale: drive so that the top level reaches x_top * phi_max at resonance
    c_tot = 2 * zeta0 * omega0 + c_e + (-kappa1(R, chi)) * (x_micro * phi_max) ** (chi + 1) / omega0
    exc.gain = x_top * phi_max * c_tot * omega0 / volts[-1]
    X_top_est = x_top * phi_max
    effect_sigma = 0.0
    if cause == "geometric-hardening":
        effect_sigma = _loguniform(rng, *EFFECT_RANGE["geometric-hardening"])
        osc.k3 = effect_sigma * SIGMA_OMEGA2_REL * omega0**2 / (0.75 * X_top_est**2)
    elif cause == "quadratic-damping":
        effect_sigma = _loguniform(rng, *EFFECT_RANGE["quadratic-damping"])
        # extra zeta at top = 8 c2 W X / (3 pi) / (2 omega0)  (W = omega0)
        osc.c2 = effect_sigma * SIGMA_ZETA * 2.0 * 3.0 * np.pi / (8.0 * X_top_est)
    elif cause == "thermal-drift":
        effect_sigma = (_loguniform(rng, *EFFECT_RANGE["thermal-drift"])
                        * rng.choice([-1.0, 1.0]))
        osc.drift_per_run = effect_sigma * SIGMA_OMEGA2_REL / (n_levels - 1)
    elif cause == "nonproportional-amplitude":
        # force drop-out: gain at the top level falls to 1 - loss
        loss = _loguniform(rng, *EFFECT_RANGE["nonproportional-amplitude"])
        v_sat = volts[-1] / np.sqrt(1.0 / (1.0 - loss) ** 2 - 1.0)
        exc.v_sat = v_sat
        exc.gain /= (1.0 - loss)  # keep the top slip amplitude at x_top
        effect_sigma = loss
    truth.update(k3=osc.k3, c2=osc.c2, drift_per_run=osc.drift_per_run,
                 c_e=c_e, v_sat=exc.v_sat, effect_sigma=effect_sigma)

    run_order = rng.permutation(n_levels) + 1
    span = 6.0 * (zeta0 + c_e / (2 * omega0) + dzeta_top)
    lines = omega0 * (1.0 + span * np.linspace(-1.0, 1.0, 61))
    omega2 = np.empty(n_levels)
    zeta = np.empty(n_levels)
    resp = np.empty(n_levels)
    for i in range(n_levels):
        w2, z, X, fold = simulate_level(osc, exc, volts[i], lines, float(run_order[i]))
        if fold:
            return None
        omega2[i], zeta[i], resp[i] = w2, z, X
    if cause == "macro-slip":
        # departure of the exact describing function from the micro-slip power law at
        # the top slip amplitude, in noise units (largest of the two channels)
        dev_w, dev_z = _macro_deviation(joint, omega0, resp[-1] / phi_max)
        truth["macro_deviation_omega2_sigma"] = dev_w
        truth["macro_deviation_zeta_sigma"] = dev_z
        truth["effect_sigma"] = float(max(abs(truth["macro_deviation_omega2_sigma"]),
                                          abs(truth["macro_deviation_zeta_sigma"])))
    truth["slip_amplitude"] = resp.copy()
    truth["slip_over_phi_max"] = resp / phi_max
    truth["omega2_clean"] = omega2.copy()
    truth["zeta_clean"] = zeta.copy()
    a_exc = volts / volts[0]
    a_true = resp / resp[0]
    truth["nonproportionality"] = float(np.max(np.abs(np.log(a_true / a_exc))))

    omega2 = omega2 * (1.0 + SIGMA_OMEGA2_REL * rng.standard_normal(n_levels))
    zeta = zeta + SIGMA_ZETA * rng.standard_normal(n_levels)
    resp_meas = resp * (1.0 + SIGMA_RESPONSE_REL * rng.standard_normal(n_levels))
    if response_column is None:
        response_column = cause == "nonproportional-amplitude" or bool(rng.integers(0, 2))
    data = MeasuredData(level=np.arange(1, n_levels + 1), excitation=volts, omega2=omega2,
                        zeta=zeta, mode=np.ones(n_levels, int), run_order=run_order,
                        response_amplitude=resp_meas if response_column else None,
                        source="synthetic")
    return SyntheticCase(data=data, cause=cause, seed=-1, truth=truth)


def generate_cases(seeds, causes=CAUSES):
    """All (cause, seed) combinations, cause-major. Returns list[SyntheticCase]."""
    return [generate_case(c, int(s)) for c in causes for s in seeds]
