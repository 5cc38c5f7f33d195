"""The jointed (nonlinear) model of a case file: the file's joint law on the joint
elements, a reduced model, the drive point (:class:`casefile.jointed.NonlinearCase`).

Each joint element ``j`` of an interface carries the law the file names
(:mod:`casefile.laws`) with ``K_T = kt w_j`` and its force ``fs w_j``, ``w_j`` its
stiffness share (:func:`casefile.build.joint_shares`), so the slip scale is the
interface's at every element: ``iwan4``: ``IwanParameters(chi, kt w_j, fs w_j, beta)``
(``phi_max``, Segalman 2005, eq. 12), time domain by log-spaced Jenkins banks;
``jenkins``: one slider per element (``JointBank``, slip ``fs/kt``), which is also its
time-domain law; ``bouc-wen``: ``BoucWenJoints`` (no bank: time domain by its own step).
All joint interfaces take one law. The structure: :func:`fe.reduction.ritz_basis`
(stuck-joint modes plus static joint modes) with the file's modal damping ratio
``[damping] zeta``; a base drive (``[drive] kind = "base"``) adds the static response to
the base's inertia load ``-(M_all r)_free`` (:mod:`fe.base_excitation`) to the basis and
carries that load reduced (``base_load``, per m/s^2). SI units.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from casefile.build import joint_shares
from casefile.jointed import NonlinearCase
from casefile.laws import law_keys, joint_law
from casefile.spec import is_base_drive
from fe.base_excitation import base_load, enrich_basis
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
    """One :class:`IwanParameters` per joint element, in the model's joint order (law
    ``iwan4``)."""
    itfs = [i for i in cf.interfaces if i.tangential == "joint"]
    return joint_law(itfs, [joint_shares(i) for i in itfs])


def file_law(cf) -> str:
    """The one law of the file's joint interfaces; InputError naming them if they
    differ (one nonlinear model takes one law)."""
    laws = {f"interface.{k}": i.law for k, i in enumerate(cf.interfaces)
            if i.tangential == "joint"}
    if len(set(laws.values())) > 1:
        raise InputError(f"{cf.path}: joint interfaces of different laws ("
                         + ", ".join(f"[{a}] {law}" for a, law in laws.items())
                         + "): the nonlinear model takes one law for all")
    return next(iter(laws.values()), "iwan4")


def _given(itf) -> str:
    """The joint keys of one interface as the file gives them (units)."""
    units = {"kt": " N/m", "fs": " N"}
    keys = ("chi", "kt", "fs", "beta") if itf.law == "iwan4" else ("kt",) + law_keys(itf.law)
    return ", ".join(f"{k} = {getattr(itf, k):g}{units.get(k, '')}" for k in keys)


def _joint_source(cf) -> str:
    """Where the joint parameters come from: the file, or the update that fitted them
    (:mod:`feloop.updated_model` marks them ``fitted``)."""
    fitted = {src for key, (kind, src) in cf.kinds.items()
              if key.startswith("interface.") and key.endswith(".fs") and kind == "fitted"}
    return f"fitted {sorted(fitted)[0]}" if fitted else f"given in {cf.path.name}"


def nonlinear_case(cf, model, mode: int | None = None) -> NonlinearCase:
    """The case file's jointed model; InputError naming what is missing."""
    law = file_law(cf)
    missing = missing_joint_parameters(cf)
    if missing:
        raise InputError(f"{cf.path}: {', '.join(missing)} not given (fitted by update: "
                         f"--model DIR/updated_model.json): a nonlinear model needs them")
    if model.joint_stiffness.size == 0:
        raise InputError(f"{cf.path}: no joint interface (tangential = 'joint'): "
                         "no nonlinear model")
    if cf.drive is None:
        raise InputError(f"{cf.path}: [drive] missing: a nonlinear model needs the drive point")
    n = model.n_free
    system = JointedSystem(M=model.M, K=model.K_without_joints, C=sp.csr_matrix((n, n)),
                           G=model.slip_matrix, K_T=model.joint_stiffness)
    red = ritz_basis(system, min(N_RITZ_MODES, n - model.joint_stiffness.size - 2), cf.zeta)
    base = {}
    if is_base_drive(cf.drive):      # the base's inertia load and its static response
        f_b = base_load(model)
        red = enrich_basis(red, system, f_b, cf.zeta)
        base = {"drive_kind": "base", "base_acceleration": float(cf.drive.acceleration),
                "base_load": red.load(f_b)}
    itfs = [i for i in cf.interfaces if i.tangential == "joint"]
    joints = joint_law(itfs, [joint_shares(i) for i in itfs])
    if law == "iwan4":
        phi = np.array([p.phi_max for p in joints])
        bank = JointBank.log_spaced(joints, 1e-4 * float(phi.min()))
        chi, R = float(itfs[0].chi), float(sum(p.R for p in joints))
    else:     # the law itself; a Jenkins bank of one slider is its own time-domain law
        phi = np.asarray(joints.slip_scale, dtype=float)
        bank = joints if isinstance(joints, JointBank) else None
        chi = R = None
    omega, shapes = model.modes(N_RITZ_MODES)
    order = model.bending_order(omega, shapes)
    studied = (cf.measured.mode if cf.measured is not None and cf.measured.mode else 1)
    default_mode = int(np.flatnonzero(order == studied)[0]) + 1 if np.any(order == studied) else 1
    mode = default_mode if mode is None else int(mode)
    if not 1 <= mode <= red.n_reduced:
        raise InputError(f"mode must be in 1..{red.n_reduced}, got {mode}")
    f = omega[mode - 1] / (2 * np.pi)
    return NonlinearCase(
        name=cf.name, model=red, bank=bank, joints=joints, fe_model=model,
        drive_dof=int(model.drive_dof), response_dof=int(model.response_dof), mode=mode,
        chi=chi, R=R, phi_max=float(phi.max()),
        force=DEFAULT_FORCES.copy(), lines_hz=np.linspace(0.9 * f, 1.1 * f, 81),
        band_hz=(0.9 * f, 1.1 * f),
        joint_source=_joint_source(cf) + ": " + "; ".join(_given(i) for i in itfs),
        law_name=law, **base)
