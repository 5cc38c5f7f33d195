"""The jointed (nonlinear) model of a case file: four-parameter Iwan joints on the joint
elements, a reduced model, the drive point (:class:`cases.nonlinear_case.NonlinearCase`).

Each joint element of an interface carries ``IwanParameters(chi, K_T = kt w_j, F_S = fs
w_j, beta)`` with ``w_j`` its stiffness share (:func:`casefile.build.joint_shares`):
``F_S`` and ``K_T`` shared alike keep ``phi_max`` (Segalman 2005, eq. 12) the interface's
at every element. The structure: :func:`fe.reduction.ritz_basis` (stuck-joint modes plus
static joint modes) with the file's modal damping ratio ``[damping] zeta``. SI units.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from casefile.build import joint_shares
from casefile.jointed import NonlinearCase
from casefile.laws import law_keys
from fe.reduction import JointBank, JointedSystem, ritz_basis
from ident.errors import InputError
from joints.iwan import IwanParameters

#: stuck-joint modes in the Ritz basis (besides one static mode per joint)
N_RITZ_MODES = 12
#: default force levels of a virtual test, N (10 levels, log-spaced)
DEFAULT_FORCES = np.geomspace(0.01, 10.0, 10)


def missing_joint_parameters(cf) -> list[str]:
    """``interface.i.key`` of every joint parameter the file leaves to be fitted."""
    return [f"interface.{i}.{k}" for i, itf in enumerate(cf.interfaces)
            if itf.tangential == "joint" for k in law_keys(itf.law) if getattr(itf, k) is None]


def joint_parameters(cf) -> list[IwanParameters]:
    """One :class:`IwanParameters` per joint element, in the model's joint order."""
    out = []
    for itf in cf.interfaces:
        if itf.tangential != "joint":
            continue
        for w in joint_shares(itf):
            out.append(IwanParameters(chi=itf.chi, K_T=itf.kt * w, F_S=itf.fs * w, beta=itf.beta))
    return out


def _joint_source(cf) -> str:
    """Where the joint parameters come from: the file, or the update that fitted them
    (:mod:`feloop.updated_model` marks them ``fitted``)."""
    fitted = {src for key, (kind, src) in cf.kinds.items()
              if key.startswith("interface.") and key.endswith(".chi") and kind == "fitted"}
    return f"fitted {sorted(fitted)[0]}" if fitted else f"given in {cf.path.name}"


def nonlinear_case(cf, model, mode: int | None = None) -> NonlinearCase:
    """The case file's jointed model; InputError naming what is missing."""
    other = [i.law for i in cf.interfaces if i.tangential == "joint" and i.law != "iwan4"]
    if other:
        raise InputError(f"{cf.path}: law {other[0]!r}: the nonlinear model takes law iwan4")
    missing = missing_joint_parameters(cf)
    if missing:
        raise InputError(f"{cf.path}: {', '.join(missing)} not given (fitted by update): a "
                         f"nonlinear model needs them in the file")
    if model.joint_stiffness.size == 0:
        raise InputError(f"{cf.path}: no joint interface (tangential = 'joint'): "
                         "no nonlinear model")
    if cf.drive is None:
        raise InputError(f"{cf.path}: [drive] missing: a nonlinear model needs the drive point")
    n = model.n_free
    system = JointedSystem(M=model.M, K=model.K_without_joints, C=sp.csr_matrix((n, n)),
                           G=model.slip_matrix, K_T=model.joint_stiffness)
    red = ritz_basis(system, min(N_RITZ_MODES, n - model.joint_stiffness.size - 2), cf.zeta)
    params = joint_parameters(cf)
    phi = np.array([p.phi_max for p in params])
    bank = JointBank.log_spaced(params, 1e-4 * float(phi.min()))
    omega, shapes = model.modes(N_RITZ_MODES)
    order = model.bending_order(omega, shapes)
    studied = (cf.measured.mode if cf.measured is not None and cf.measured.mode else 1)
    default_mode = int(np.flatnonzero(order == studied)[0]) + 1 if np.any(order == studied) else 1
    mode = default_mode if mode is None else int(mode)
    if not 1 <= mode <= red.n_reduced:
        raise InputError(f"mode must be in 1..{red.n_reduced}, got {mode}")
    f = omega[mode - 1] / (2 * np.pi)
    itfs = [i for i in cf.interfaces if i.tangential == "joint"]
    return NonlinearCase(
        name=cf.name, model=red, bank=bank, joints=params, fe_model=model,
        drive_dof=int(model.drive_dof), response_dof=int(model.response_dof), mode=mode,
        chi=float(itfs[0].chi), R=float(sum(p.R for p in params)), phi_max=float(phi.max()),
        force=DEFAULT_FORCES.copy(), lines_hz=np.linspace(0.9 * f, 1.1 * f, 81),
        band_hz=(0.9 * f, 1.1 * f),
        joint_source=_joint_source(cf) + ": " + "; ".join(
            f"chi = {i.chi:g}, kt = {i.kt:g} N/m, fs = {i.fs:g} N, beta = {i.beta:g}"
            for i in itfs))
