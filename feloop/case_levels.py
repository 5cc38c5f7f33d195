"""The FE-levels model of any case file with four-parameter Iwan joints: omega^2 and
zeta of the measured mode at every force level, as a function of the fit parameters.

:class:`CaseLevels` is a :class:`feloop.levels.FELevels` (the
parameters ``chi``, ``ln_dc1`` = ``|kappa1| B~`` of the joints at level 1 (paper eq.
30-32, 37), ``zeta_v``, ``f0_hz``, optional ``log10_kt``, ``ln_phimax``; the
first-harmonic balance with the exact describing function at phase resonance,
:func:`fe.hb_resonance.resonance_levels`) with the structure taken from a case file
instead of the double beam's Python model, so the one judge
(:func:`feloop.select.fe_select`) and ``run_update`` run on it:

* ``K_T`` (``log10_kt``) is the total stuck stiffness of every joint element of every
  joint interface; a value other than the file's scales every interface's ``kt`` alike
  (the shares and the file's ``[calibrate]`` are kept: each K_T is calibrated again).
  The default is the file's total ``kt`` (assumed, or calibrated by the file).
* Every joint element carries ``w_j R~`` and ``w_j K_T`` with ``w_j = k_j / K_T`` (one
  ``phi_max``, Segalman 2005 eq. 12): the file's ``chi``, ``fs``, ``beta`` are the nominal
  model; ``update`` fits ``chi`` and the joint strength in the variable the data
  determine.
* Air drag (``quadratic-damping``): ``lambda3 = int b |phi_w|^3 dx`` over the
  projected area (the strip widths folded in, so ``width = 1``); where strips are
  stacked over a lap, the one with the largest ``b |phi_w|^3`` (one exposed area).

SI units.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from casefile.build import build_model
from casefile.calibrate import calibrate
from feloop.levels import FELevels, abscissa_of

__all__ = ["total_kt", "CaseLevels"]


def total_kt(cf) -> float:
    """Total stuck stiffness (N/m) of the joint interfaces of case file ``cf``."""
    return float(sum(i.kt for i in cf.interfaces if i.tangential == "joint"))


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
        return self.reduce(model, K_T, lambda phi: _lambda3(model, phi), width=1.0, grip=None)
