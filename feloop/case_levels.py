"""The FE-levels model of any case file: omega^2 and zeta of the measured mode at every
force level, as a function of the fit parameters.

:class:`CaseLevels` is a :class:`feloop.levels.FELevels` (the joint parameters of the
file's law, :mod:`feloop.joint_forms`: for Iwan joints ``chi``, ``ln_dc1`` =
``|kappa1| B~`` of the joints at level 1 (paper eq. 30-32, 37), optional ``ln_phimax``;
``zeta_v``, ``f0_hz``, optional ``log10_kt``; the
first-harmonic balance with the exact describing function at phase resonance,
:func:`fe.hb_resonance.resonance_levels`) with the structure taken from a case file
instead of the double beam's Python model (reduced by :func:`linear_part`, the
double beam's too), so the one judge
(:func:`feloop.select.fe_select`) and ``run_update`` run on it:

* ``K_T`` (``log10_kt``) is the total stuck stiffness of every joint element of every
  joint interface; a value other than the file's scales every interface's ``kt`` alike
  (the shares and the file's ``[calibrate]`` are kept: each K_T is calibrated again).
  The default is the file's total ``kt`` (assumed, or calibrated by the file).
* Every joint element carries ``w_j R~`` and ``w_j K_T`` with ``w_j = k_j / K_T`` (one
  ``phi_max``, Segalman 2005 eq. 12; another law its slip force ``w_j F_S``): the file's
  joint keys are the nominal model; ``update`` fits the joint in the variables the data
  determine.
* Air drag (``quadratic-damping``): ``lambda3 = int b |phi_w|^3 dx`` over the
  projected area (the strip widths folded in, so ``width = 1``); where strips are
  stacked over a lap, the one with the largest ``b |phi_w|^3`` (one exposed area).

SI units.
"""
from __future__ import annotations

import dataclasses
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from casefile.build import build_model
from casefile.calibrate import calibrate
from fe.reduction import JointedSystem, reduced_basis
from casefile.nonlinear import file_law
from feloop.joint_forms import FORMS, BoucWenForm, JointForm
from feloop.levels import FELevels, LinearPart, abscissa_of
from inverse.fe_reference import joint_slip_at_resonance, pick_fe_mode

__all__ = ["total_kt", "form_of", "linear_part", "CaseLevels"]


def total_kt(cf) -> float:
    """Total stuck stiffness (N/m) of the joint interfaces of case file ``cf``."""
    return float(sum(i.kt for i in cf.interfaces if i.tangential == "joint"))


def form_of(cf) -> JointForm:
    """The joint form (:mod:`feloop.joint_forms`) of case file ``cf``'s one law
    (:func:`casefile.nonlinear.file_law`); a Bouc-Wen file's ``shape`` given, or assumed
    when the file leaves it (or its interfaces differ in it)."""
    law = file_law(cf)
    if law == "bouc-wen":
        shapes = {i.shape for i in cf.interfaces if i.tangential == "joint"}
        return BoucWenForm(shapes.pop() if len(shapes) == 1 else None)
    return FORMS[law]()


def linear_part(levels: FELevels, model, K_T: float, lambda3, width: float,
                grip) -> LinearPart:
    """The :class:`feloop.levels.LinearPart` of FE-levels model ``levels`` (any case's)
    from an FE ``model`` with joints (``M``, ``K_without_joints``, ``slip_matrix``,
    ``joint_stiffness``, ``drive_dof``, ``response_dof``, ``modes``), reduced to its
    normal and static joint modes; ``lambda3(phi)``: ``int |phi_w|^3 dx`` of the strip
    the air drag acts on (m kg^-3/2), ``width`` its width (m)."""
    n = model.M.shape[0]
    system = JointedSystem(M=model.M, K=model.K_without_joints, C=sp.csr_matrix((n, n)),
                           G=model.slip_matrix, K_T=model.joint_stiffness)
    red = reduced_basis(system, min(levels.n_modes, n - 2), static_joint_modes=True)
    r = red.n_reduced
    red = replace(red, M=np.eye(r), K=np.diag(red.omega ** 2), C=np.zeros((r, r)))
    fe_mode = pick_fe_mode(model, levels.omega_1)
    omega, shapes = model.modes(fe_mode)
    phi = shapes[:, fe_mode - 1]
    k = int(np.argmax(np.abs(red.basis.T @ (model.M @ phi))))
    f = np.zeros(n)
    f[int(model.drive_dof)] = 1.0
    gphi = np.asarray(model.slip_matrix @ phi).ravel()
    if levels.abscissa == "force":
        slips1 = joint_slip_at_resonance(model.M, model.K, model.slip_matrix,
                                         f * levels.force_scale * levels.excitation[0],
                                         float(omega[fe_mode - 1]), levels.zeta_1)
    else:     # the mode's slips at the level-1 response amplitude (or RMS)
        slips1 = np.abs(gphi) * levels.response_amplitude[0] \
            / abs(phi[int(model.response_dof)])
    kj = np.asarray(model.joint_stiffness, dtype=float)
    sign = np.sign(red.basis[:, k] @ (model.M @ phi))
    return LinearPart(K_T=K_T, grip=grip, red=red, k=k, omega_k=float(red.omega[k]),
                      load=red.load(f), shares=kj / kj.sum(),
                      gphi=gphi, slips1=slips1,
                      lambda3=lambda3(phi), phi_drive=float(sign * phi[int(model.drive_dof)]),
                      width=width, response_row=red.basis[int(model.response_dof)].copy(),
                      drive_dof=int(model.drive_dof), fe_mode=int(fe_mode))



def _lambda3(model, phi) -> float:
    """``int b |w|^3 dx`` over the assembly's projected area of a free-DOF shape (m^2 x
    shape^3): on each interval between the strips' nodes the strip covering it with the
    largest ``b |w|^3`` (stacked strips over a lap expose one area), trapezoidal rule."""
    meshes, disps = model.strip_meshes, model.strip_displacements(phi)
    grid = np.unique(np.concatenate([np.asarray(m.x, float) for m in meshes]))
    dx = np.diff(grid)
    best = np.zeros(dx.size)
    for mesh, disp in zip(meshes, disps):
        x = np.asarray(mesh.x, float)
        w3 = float(np.mean(mesh.width)) * np.abs(disp["w"]) ** 3
        inside = (grid[:-1] >= x[0]) & (grid[1:] <= x[-1])
        seg = 0.5 * (np.interp(grid[:-1], x, w3) + np.interp(grid[1:], x, w3)) * dx
        best = np.maximum(best, np.where(inside, seg, 0.0))
    return float(best.sum())


class CaseLevels(FELevels):
    """The measured series' levels simulated by the case file's FE model (module
    docstring). ``cf``: a checked :class:`casefile.spec.CaseFile` with joint
    interfaces; the other arguments as :class:`FELevels`."""

    def __init__(self, cf, excitation, run_order, omega2_1: float, zeta_1: float,
                 force_scale: float = 1.0, n_modes: int = 40):
        super().__init__(excitation, run_order, omega2_1, zeta_1, force_scale=force_scale,
                         n_modes=n_modes)
        if total_kt(cf) <= 0.0:
            raise ValueError(f"{cf.path}: no joint interface with kt > 0")
        self.cf = cf
        self.form = form_of(cf)
        self.default_kt = total_kt(cf)
        self.label = f"case {cf.name}"

    @classmethod
    def from_data(cls, data, cf=None, **kw) -> "CaseLevels":
        route = abscissa_of(data)
        if route != "force":     # the double beam's response routes are not checked here
            raise ValueError(f"{data.source}: the FE loop of a case file simulates "
                             f"force-controlled stepped sine; {route} rows are not supported")
        return cls(cf, data.excitation, data.run_order, data.omega2[0], data.zeta[0], **kw)

    def _build(self, K_T: float):
        s = K_T / total_kt(self.cf)
        itfs = tuple(dataclasses.replace(i, kt=i.kt * s) if i.tangential == "joint" else i
                     for i in self.cf.interfaces)
        f, _ = calibrate(dataclasses.replace(self.cf, interfaces=itfs))
        model = build_model(f).model
        return linear_part(self, model, K_T, lambda phi: _lambda3(model, phi), width=1.0,
                           grip=None)
