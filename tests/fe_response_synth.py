"""Measured-data series of the FE double beam with a planted joint, made by routes other
than the response route of :class:`cases.double_beam.fe_levels.DoubleBeamLevels` (the
code under test): the EPMC backbone (:func:`fe.epmc.epmc_backbone`, Krack 2015: the
autonomous nonlinear mode with artificial damping, full Newton in the harmonics,
normalized at the response DOF) read at the held amplitudes; and, for a random series,
the energy-weighted Rayleigh expectation of that backbone by adaptive quadrature
(:func:`scipy.integrate.quad` over a monotone interpolant of 60 backbone points), not by
the Gauss-Laguerre nodes the model uses. Seeded noise on omega^2 and zeta, with their
std columns. SI units."""
from __future__ import annotations

import math

import numpy as np
from scipy import integrate
from scipy.interpolate import PchipInterpolator

from cases.double_beam.fe_levels import DoubleBeamLevels
from fe.epmc import epmc_backbone
from fe.joint_harmonics import ExactHarmonics
from ident.modal_data import MeasuredData

#: The planted truth: chi, the joint damping at level 1 (zeta units), zeta_v.
CHI, ZETA_J1, ZETA_V = -0.45, 1.0e-4, 3.0e-4
#: Held amplitudes at the response point (m): 10 levels, ratio 1.5, from deep micro slip
#: (largest glue slip 1 % of phi_max) to the onset of macro slip (45 %).
AMPLITUDES = 2e-9 * 1.5 ** np.arange(10)
#: The response amplitude (m) at which ZETA_J1 defines the planted joint strength.
REFERENCE = 3e-8
OMEGA2_REL_STD, ZETA_REL_STD = 2e-6, 0.01


def planted():
    """(fe, parameters, joint) of the planted model."""
    ref = DoubleBeamLevels([np.nan], [1], (2 * math.pi * 252.0) ** 2, ZETA_J1,
                           abscissa="response", response_amplitude=[REFERENCE])
    lin = ref.linear(1e8)
    p = {"chi": CHI, "ln_dc1": math.log(2 * lin.omega_k ** 2 * ZETA_J1), "zeta_v": ZETA_V,
         "f0_hz": lin.omega_k / (2 * math.pi), "log10_kt": 8.0}
    return ref, p, ref.joint(p)


def backbone(amplitudes):
    """The planted model's EPMC backbone at response amplitudes ``amplitudes`` (m)."""
    ref, p, j = planted()
    lin = j["linear"]
    red = ref.setup(p)[1]                     # f0 = the stuck frequency: scale 1
    mode = int(np.sum(red.omega < red.omega[lin.k])) + 1
    dof = int(np.argmin(np.linalg.norm(red.basis - lin.response_row, axis=1)))
    return epmc_backbone(red, ExactHarmonics(j["params"], red.n_joints), mode, amplitudes, at=dof)


def rayleigh_truth(rms):
    """Energy-weighted expectation of omega^2 and 2 zeta omega^2 over a Rayleigh
    envelope of RMS ``rms`` (eq. 1 of :mod:`inverse.random_amplitude`), by quad."""
    a = np.geomspace(rms.min() * 1e-2, rms.max() * 9.0, 60)
    bb = backbone(a)
    la = np.log(a)
    o2 = PchipInterpolator(la, bb.omega2)
    kq = PchipInterpolator(la, 2 * bb.zeta * bb.omega2)
    out = []
    for s in rms:
        def expect(f):       # weight u e^-u du, A = s sqrt(2u); below a[0]: f(a[0])
            def g(u):
                return u * math.exp(-u) * float(f(max(la[0], math.log(s * math.sqrt(2 * u)))))

            return integrate.quad(g, 0.0, 40.0, epsrel=1e-10, limit=200)[0]
        e_o2, e_kq = expect(o2), expect(kq)
        out.append((e_o2, e_kq / (2 * e_o2)))
    return np.array(out).T


def series(test="free-decay", seed=7, amplitudes=AMPLITUDES) -> MeasuredData:
    """The planted series as the measured-data table a test would give (module doc)."""
    if test == "random":
        omega2, zeta = rayleigh_truth(amplitudes)
    else:
        bb = backbone(amplitudes)
        omega2, zeta = bb.omega2, bb.zeta
    rng = np.random.default_rng(seed)
    s_o2, s_z = OMEGA2_REL_STD * omega2, ZETA_REL_STD * zeta
    n = amplitudes.size
    control = "force" if test == "random" else "response"
    # a random level's drive RMS (any increasing value: the route reads the response)
    excitation = amplitudes * 1e7 if test == "random" else np.full(n, np.nan)
    return MeasuredData(level=np.arange(1, n + 1), excitation=excitation,
                        omega2=omega2 + s_o2 * rng.standard_normal(n),
                        zeta=zeta + s_z * rng.standard_normal(n), mode=np.full(n, 2),
                        run_order=np.arange(1, n + 1), response_amplitude=amplitudes,
                        omega2_std=s_o2, zeta_std=s_z, control=np.full(n, control),
                        test=np.full(n, test), source=f"planted {test} series")
