"""Discretization of the Iwan density into a bank of Jenkins elements, and its state
update over joints x sliders (Segalman 2005; paper eqs. 1-2).

Each Jenkins element ``i`` is a spring of stiffness ``k_i`` (N/m) in series with a
Coulomb slider that slips when the spring stretch reaches ``phi_i`` (m). Its state is
the slider position (the *anchor*) ``x_i``; the force is ``k_i (u - x_i)``.

Accuracy of :func:`discretize` against the exact continuous model of
:mod:`joints.iwan` (measured for n = 10, 30, 100, 300, 1000 with chi from -0.95 to
-0.05, beta = 0 and 4; see ``tests/test_jenkins.py``): the maximum backbone error over
``|u| <= phi_max`` and the maximum relative micro-slip dissipation error over
``A`` in [0.1, 0.9] ``phi_max`` both fall as ``n**-2`` (log-log slopes -1.90 ... -2.11).
At n = 100: backbone error 3.8e-6 F_S (chi = -0.5, beta = 4) to 2.4e-4 F_S
(chi = -0.8, beta = 0); dissipation error 6.5e-4 (chi = -0.5) to 7.6e-3 (chi = -0.95).
The midpoint rule in ``s = (phi/phi_max)**(chi+1)`` is second order because the
integrands are Lipschitz with one kink. The weakest slider has
``phi_1 = phi_max (1/(2 n_c))**(1/(chi+1))``: below that amplitude the bank is linear
and dissipates nothing. More precisely, the relative micro-slip dissipation error at
amplitude ``A`` is about ``c / m_A**2`` with ``m_A = n (A/phi_max)**(chi+1)`` the number
of sliders that slip at that amplitude, c = 0.5 (chi = -0.2) to 1.2 (chi = -0.5)
(measured, A from 0.01 to 0.3 phi_max): 1e-3 needs m_A of about 35.

Cost of :func:`jenkins_update` (numpy, one call, shared 2-core machine): 6-12 us for
2 joints x 200 sliders, 24-36 us for 10 x 1000 (2-D stiffness arrays the slower).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from joints.iwan import IwanParameters

__all__ = ["JenkinsDiscretization", "discretize", "jenkins_update"]


@dataclass(frozen=True)
class JenkinsDiscretization:
    """A bank of Jenkins elements in parallel.

    Attributes
    ----------
    stiffness : ndarray, shape (n_sliders,)
        Spring stiffnesses ``k_i`` (N/m); they sum to ``K_T``.
    slip_limit : ndarray, shape (n_sliders,)
        Stretch ``phi_i`` (m) at which slider ``i`` slips, ascending.
    """

    stiffness: np.ndarray
    slip_limit: np.ndarray

    @property
    def n_sliders(self) -> int:
        return int(self.stiffness.size)


def discretize(p: IwanParameters, n_sliders: int) -> JenkinsDiscretization:
    """Discretize the Iwan density into ``n_sliders`` Jenkins elements.

    The continuous part ``R phi**chi`` on ``(0, phi_max)`` has cumulative stiffness
    ``(K_T - S) s`` with ``s = (phi/phi_max)**(chi+1)`` (paper eq. 6). It is
    split into ``n_c`` sliders of equal stiffness ``(K_T - S)/n_c`` placed at the
    midpoints ``s_i = (i - 1/2)/n_c``, i.e. ``phi_i = phi_max s_i**(1/(chi+1))``. When
    ``S > 0`` the last slider carries the Dirac term: stiffness ``S`` at ``phi_max``
    (then ``n_c = n_sliders - 1``, else ``n_c = n_sliders``). Stiffnesses sum to
    ``K_T`` up to rounding, so the stuck stiffness is not shifted; the backbone and
    micro-slip dissipation converge as ``n**-2`` (module docstring).

    Parameters
    ----------
    p : IwanParameters
    n_sliders : int
        Total number of sliders, >= 2.

    Returns
    -------
    JenkinsDiscretization
    """
    n = int(n_sliders)
    if n != n_sliders or n < 2:
        raise ValueError(f"n_sliders must be an integer >= 2, got {n_sliders!r}")
    S = p.S
    with_dirac = S > 0.0
    n_c = n - 1 if with_dirac else n
    s_mid = (np.arange(n_c) + 0.5) / n_c
    phi = p.phi_max * s_mid ** (1.0 / (p.chi + 1.0))
    k = np.full(n_c, (p.K_T - S) / n_c) if with_dirac else np.full(n_c, p.K_T / n_c)
    if with_dirac:
        phi = np.append(phi, p.phi_max)
        k = np.append(k, S)
    return JenkinsDiscretization(stiffness=k, slip_limit=phi)


def jenkins_update(slip, anchor, stiffness, slip_limit):
    """Trial state of a bank of Jenkins elements for a new slip (return mapping).

    ``anchor_new = clip(anchor, slip - slip_limit, slip + slip_limit)`` (paper eq. 2
    integrated over a step: a slider moves only as much as needed to keep its spring
    stretch within ``slip_limit``), ``force = sum_i k_i (slip - anchor_new_i)``, and
    ``tangent = sum of k_i over sliders whose anchor did not move`` (stuck sliders,
    including those exactly at their limit).

    Pure function: the committed ``anchor`` is not modified; the caller commits
    ``anchor_new`` once the step is accepted.

    Parameters
    ----------
    slip : array_like, shape (n_joints,)
        Relative slip of each joint (m).
    anchor : ndarray, shape (n_joints, n_sliders)
        Committed slider positions (m).
    stiffness, slip_limit : ndarray, shape (n_sliders,) or (n_joints, n_sliders)
        Spring stiffnesses (N/m) and slip limits (m).

    Returns
    -------
    force : ndarray, shape (n_joints,)
        Joint force (N).
    tangent : ndarray, shape (n_joints,)
        Tangent stiffness d force / d slip (N/m).
    anchor_new : ndarray, shape (n_joints, n_sliders)
        Trial slider positions (m).
    """
    slip = np.asarray(slip, dtype=float)
    anchor = np.asarray(anchor, dtype=float)
    stiffness = np.asarray(stiffness, dtype=float)
    slip_limit = np.asarray(slip_limit, dtype=float)
    col = slip[:, None]
    anchor_new = np.subtract(col, slip_limit)          # lower bound
    np.maximum(anchor, anchor_new, out=anchor_new)
    work = np.add(col, slip_limit)                     # upper bound
    np.minimum(anchor_new, work, out=anchor_new)
    stuck = anchor_new == anchor
    stretch = np.subtract(col, anchor_new, out=work)
    if stiffness.ndim == 1:
        force = stretch @ stiffness
        tangent = stuck @ stiffness
    else:
        force = np.einsum("ij,ij->i", stretch, stiffness)
        tangent = np.einsum("ij,ij->i", stuck, stiffness)
    return force, tangent, anchor_new
