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

State update: :func:`jenkins_update` (pure) and :func:`jenkins_update_into` (in place)
check and convert their arguments and run the compiled kernel
:func:`joints.kernel.bank_update_kernel`, which compiled solvers call from their own
``@njit`` step loops: blocks of 8 sliders as explicit 8-lane vector IR, summed in a
fixed order (:mod:`joints.kernel_reference`), so the numbers do not depend on how or
where the kernel was compiled. Anchors are numpy's bit for bit; force and tangent sums
agree with numpy's to rounding. Throughput and cost model: ``benchmarks/README.md``
(``bench_jenkins.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from joints import kernel
from joints.iwan import IwanParameters

__all__ = ["JenkinsDiscretization", "discretize", "discretize_log", "jenkins_update",
           "jenkins_update_into"]


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


def discretize_log(p: IwanParameters, a_low: float,
                   sliders_per_octave: int = 16) -> JenkinsDiscretization:
    """Discretize the Iwan density with slip limits spaced geometrically (per octave).

    For responses whose slip amplitude spans decades (a stepped-sine campaign over a
    factor 512 in force), the uniform-in-``s`` rule of :func:`discretize` wastes its
    sliders near ``phi_max``: the error at amplitude ``A`` is set by the number of
    sliders below ``A`` (module docstring). Here the continuous density ``R phi**chi``
    on ``(0, phi_max)`` (paper eq. 6) is cut at ``e_k = phi_max 2**(-k/n)``, ``k = 0 ..
    K``, ``K = ceil(n log2(phi_max / a_low))``, ``n = sliders_per_octave``, plus the cell
    ``(0, e_K)``. Cell ``(a, b)`` becomes one slider of stiffness ``int_a^b rho = (K_T -
    S) (x_b**(chi+1) - x_a**(chi+1))`` (``x = phi / phi_max``) and slip limit the
    density-weighted mean ``phi_max (chi+1)/(chi+2) (x_b**(chi+2) - x_a**(chi+2)) /
    (x_b**(chi+1) - x_a**(chi+1))`` (exact zeroth and first moments of every cell, so
    the saturated force ``sum k_i phi_i`` is ``F_S`` to rounding). With ``S > 0`` one more
    slider of stiffness ``S`` at ``phi_max`` carries the Dirac term. The stiffnesses sum
    to ``K_T`` to rounding (the telescoping cell sums), so the stuck stiffness is not
    shifted.

    Accuracy (closed-form describing function of each slider against
    :func:`joints.iwan.dissipation_per_cycle` and
    :func:`joints.describing.describing_function`, amplitudes ``A`` from 1e-3
    ``phi_max`` to ``phi_max`` with ``a_low = 2**-6 1e-3 phi_max``, chi from -0.9 to
    -0.1, beta = 0 and 4; ``tests/test_jenkins.py``): the largest relative error of the
    dissipation per cycle and of the in-phase stiffness loss ``K_T - k_in`` is
    3.9e-3 / 7.4e-4 with 8 sliders per octave, 9.9e-4 / 1.7e-4
    with 16 (6.3e-4 / 7.4e-5 at chi = -0.5; 257 sliders) and 2.4e-4 / 8.1e-5 with 32:
    second order in the cell width for chi >= -0.5, larger for chi near 0 (near chi =
    -1 the one slider below ``a_low`` holds a large share, (a_low/phi_max)**(chi+1), and
    limits the gain). In macro-slip (``A`` = 1 to
    4 ``phi_max``, chi = -0.5, 16 per octave) the errors stay below 2.4e-4 / 1.1e-4.
    The uniform :func:`discretize` reaches 1.1e-3 over the same range with 1000 sliders
    and 1.4e-4 with 2000. Below ``a_low`` the bank is resolved by one slider only: keep
    the smallest amplitude of interest a few octaves (6 above) over ``a_low``.

    Parameters
    ----------
    p : IwanParameters
    a_low : float
        Lowest resolved slip limit (m), ``0 < a_low < phi_max``.
    sliders_per_octave : int
        >= 1.

    Returns
    -------
    JenkinsDiscretization
        ``K + 1`` sliders (``K + 2`` with ``S > 0``), slip limits ascending.
    """
    pm = p.phi_max
    if not (isinstance(a_low, (int, float, np.floating)) and 0 < a_low < pm):
        raise ValueError(f"a_low must lie in (0, phi_max = {pm:.4g} m), got {a_low!r}")
    n = int(sliders_per_octave)
    if n != sliders_per_octave or n < 1:
        raise ValueError(f"sliders_per_octave must be an integer >= 1, got "
                         f"{sliders_per_octave!r}")
    n_cuts = int(np.ceil(n * np.log2(pm / a_low)))
    x = np.concatenate([[0.0], 2.0 ** (-np.arange(n_cuts, -1, -1) / n)])
    c = p.chi + 1.0
    cell = np.diff(x ** c)                                   # share of K_T - S per cell
    mean_x = c / (c + 1.0) * np.diff(x ** (c + 1.0)) / cell  # density-weighted mean
    k = (p.K_T - p.S) * cell
    phi = pm * mean_x
    if p.S > 0.0:
        k, phi = np.append(k, p.S), np.append(phi, pm)
    return JenkinsDiscretization(stiffness=k, slip_limit=phi)


# ------------------------------------------------------------------ state update


def _jenkins_update_numpy(slip, anchor, stiffness, slip_limit):
    """The update in numpy for any broadcastable shapes (sums in numpy's pairwise
    order), used outside the kernel's shapes; returns ``(force, tangent, anchor_new)``."""
    col = slip[..., None]
    anchor_new = np.maximum(anchor, col - slip_limit)
    np.minimum(anchor_new, col + slip_limit, out=anchor_new)
    stuck = anchor_new == anchor
    force = np.sum((col - anchor_new) * stiffness, axis=-1)
    tangent = np.sum(np.where(stuck, stiffness, 0.0), axis=-1)
    return force, tangent, anchor_new


def _as_float(a):
    return np.ascontiguousarray(a, dtype=np.float64)


def _kernel_operands(slip, anchor, stiffness, slip_limit):
    """(stiffness, slip_limit) as 2-D (1 or n_joints, n_sliders) views for
    :func:`joints.kernel.bank_update_kernel`, or None when the shapes are not the
    contract's (the numpy path then broadcasts). All inputs are float64 C-contiguous
    already."""
    if anchor.ndim != 2 or slip.ndim != 1:
        return None
    n_joints, n_sliders = anchor.shape
    if slip.shape[0] != n_joints:
        return None
    out = []
    for param in (stiffness, slip_limit):
        if param.ndim == 1:
            if param.shape[0] != n_sliders:
                return None
            param = param[None]
        elif param.ndim != 2 or param.shape[1] != n_sliders or (
                param.shape[0] != n_joints and param.shape[0] != 1):
            return None
        out.append(param)
    return out


def jenkins_update(slip, anchor, stiffness, slip_limit):
    """Trial state of a bank of Jenkins elements for a new slip (return mapping).

    ``anchor_new = minimum(maximum(anchor, slip - slip_limit), slip + slip_limit)``
    (paper eq. 2 integrated over a step: a slider moves only as much as needed to keep
    its spring stretch within ``slip_limit``), ``force = sum_i k_i (slip -
    anchor_new_i)``, and ``tangent = sum of k_i over sliders whose anchor did not move``
    (stuck sliders, including those exactly at their limit).

    Pure function: the committed ``anchor`` is not modified; the caller commits
    ``anchor_new`` once the step is accepted. Runs the compiled kernel
    (:func:`joints.kernel.bank_update_kernel`) for the shapes below, the numpy form for
    other broadcastable shapes: the same anchors, sums equal to rounding.

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
    slip = _as_float(slip)
    anchor = _as_float(anchor)
    stiffness = _as_float(stiffness)
    slip_limit = _as_float(slip_limit)
    ops = _kernel_operands(slip, anchor, stiffness, slip_limit)
    if ops is None:
        return _jenkins_update_numpy(slip, anchor, stiffness, slip_limit)
    force = np.empty(slip.shape[0])
    tangent = np.empty(slip.shape[0])
    anchor_new = np.empty_like(anchor)
    kernel.bank_update_kernel(slip, anchor, ops[0], ops[1], anchor_new, force, tangent)
    return force, tangent, anchor_new


def jenkins_update_into(slip, anchor, stiffness, slip_limit, out_anchor,
                        out_force=None, out_tangent=None):
    """In-place variant of :func:`jenkins_update` for solvers' step loops.

    Same numbers as :func:`jenkins_update`, written into preallocated arrays: the trial
    slider positions go to ``out_anchor``, which may be ``anchor`` itself to commit the
    step in place (each slider is read before it is written; other overlaps of the two
    arrays are not allowed).

    Parameters
    ----------
    slip : ndarray, shape (n_joints,)
        Relative slip of each joint (m).
    anchor : ndarray, shape (n_joints, n_sliders)
        Committed slider positions (m).
    stiffness, slip_limit : ndarray, shape (n_sliders,) or (n_joints, n_sliders)
        Spring stiffnesses (N/m) and slip limits (m). Pass C-contiguous float64 arrays
        to avoid a copy per call.
    out_anchor : ndarray, float64, C-contiguous, shape (n_joints, n_sliders)
        Receives the trial slider positions (m).
    out_force, out_tangent : ndarray, float64, shape (n_joints,), optional
        Receive the force (N) and tangent (N/m); allocated when omitted.

    Returns
    -------
    force, tangent : ndarray, shape (n_joints,)
        ``out_force`` and ``out_tangent`` (or new arrays).
    """
    slip = _as_float(slip)
    anchor = _as_float(anchor)
    stiffness = _as_float(stiffness)
    slip_limit = _as_float(slip_limit)
    if anchor.ndim != 2:
        raise ValueError(f"anchor must have shape (n_joints, n_sliders), got {anchor.shape}")
    n_joints = anchor.shape[0]
    if out_force is None:
        out_force = np.empty(n_joints)
    if out_tangent is None:
        out_tangent = np.empty(n_joints)
    for name, arr, shape in (("out_anchor", out_anchor, anchor.shape),
                             ("out_force", out_force, (n_joints,)),
                             ("out_tangent", out_tangent, (n_joints,))):
        if not (type(arr) is np.ndarray and arr.dtype == np.float64 and arr.shape == shape
                and arr.flags.c_contiguous and arr.flags.writeable):
            raise ValueError(f"{name} must be a writeable C-contiguous float64 array of "
                             f"shape {shape} (anchor {anchor.shape})")
    ops = _kernel_operands(slip, anchor, stiffness, slip_limit)
    if ops is None:
        force, tangent, new = _jenkins_update_numpy(slip, anchor, stiffness, slip_limit)
        if new.shape != out_anchor.shape:
            raise ValueError(f"slip {slip.shape} and anchor {anchor.shape} do not match")
        out_anchor[...] = new
        out_force[...] = force
        out_tangent[...] = tangent
    else:
        kernel.bank_update_kernel(slip, anchor, ops[0], ops[1], out_anchor, out_force,
                                  out_tangent)
    return out_force, out_tangent
