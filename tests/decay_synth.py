"""Free decays for the tests, simulated independently of the identification.

``iwan_sdof_decay``: a single-DOF oscillator with a four-parameter Iwan joint in micro
slip, ``m q'' + c q' + k0 q + F(q) = 0``, started from rest at ``q = 0`` with a
velocity (an impact): the joint loads along its backbone to the first reversal, then
along Masing branches ``F = F_r + 2 F_bb((q - q_r)/2)`` (exact for an Iwan joint while
every excursion is smaller than the last, as in a decay), written out here from
Segalman's closed form (not ``joints.iwan``). Integrated by ``scipy.integrate.solve_ivp``
(DOP853, rtol 1e-12) from reversal to reversal (events at zero velocity), sampled on a
uniform grid from the dense output.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from joints.iwan import IwanParameters


def micro_slip_backbone(p: IwanParameters):
    """``F_bb(u) = K_T u - R |u|^(chi+2) sign(u) / ((chi+1)(chi+2))`` (|u| < phi_max)."""
    K, R, e = p.K_T, p.R, p.chi + 2.0
    c = R / ((p.chi + 1.0) * (p.chi + 2.0))

    def f(u):
        return K * u - c * math.copysign(abs(u) ** e, u)
    return f


def iwan_sdof_decay(p: IwanParameters, m, k0, c, v0, fs, t_end):
    """(t, q) of the decay (module doc); every slip stays below ``phi_max`` (checked)."""
    bb = micro_slip_backbone(p)
    t_out = np.arange(0.0, t_end, 1.0 / fs)
    q_out = np.full(t_out.size, np.nan)
    t0, state, rev, direction = 0.0, [0.0, v0], None, -1.0
    while t0 < t_end:
        if rev is None:
            def force(q):
                return bb(q)
        else:
            qr, fr = rev

            def force(q, qr=qr, fr=fr):
                return fr + 2.0 * bb(0.5 * (q - qr))

        def rhs(t, y, force=force):
            return [y[1], -(c * y[1] + k0 * y[0] + force(y[0])) / m]

        def turn(t, y):
            return y[1]
        turn.terminal, turn.direction = True, direction
        sol = solve_ivp(rhs, (t0, t_end), state, method="DOP853", rtol=1e-12,
                        atol=1e-15 * abs(v0), events=turn, dense_output=True)
        t1 = sol.t[-1]
        sel = (t_out >= t0) & (t_out <= t1)
        q_out[sel] = sol.sol(t_out[sel])[0]
        if sol.status != 1:
            break
        q1 = float(sol.y_events[0][0][0])
        if abs(q1) >= p.phi_max:
            raise ValueError("the decay leaves micro slip")
        rev, state, t0, direction = (q1, force(q1)), [q1, 0.0], t1, -direction
    return t_out, q_out


def linear_decay(f_hz, zeta, amplitude, fs, t_end, phase=0.7):
    """``amplitude e^(-zeta w t) cos(w_d t + phase)`` on a uniform grid."""
    w = 2 * np.pi * f_hz
    t = np.arange(0.0, t_end, 1.0 / fs)
    return t, amplitude * np.exp(-zeta * w * t) * np.cos(w * np.sqrt(1 - zeta ** 2) * t + phase)
