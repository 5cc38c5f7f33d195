"""The FE double beam as an FE-levels model (:class:`feloop.levels.FELevels`):
the double beam's Python model (:mod:`cases.double_beam.model`) at glue stiffness K_T,
the grip calibrated to 252.0 Hz for each K_T
(:func:`cases.double_beam.calibration.calibrate_clamp_length`, 0.3 s, cached), the air
drag acting on the lower strip; the assumed properties ``update --assumptions`` changes
(:data:`ASSUMPTIONS`). SI units.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cases.double_beam.calibration import calibrate_clamp_length
from cases.double_beam.model import DoubleBeamConfig, build_double_beam
from feloop.case_levels import linear_part
from feloop.levels import FELevels, LinearPart
from fe.beam import W

__all__ = ["DEFAULT_KT", "DoubleBeamLevels", "ASSUMPTIONS", "DoubleBeamVariant",
           "assumption_variants"]

#: K_T (N/m) of the shipped case (an assumption, :mod:`cases.double_beam.model`).
DEFAULT_KT = DoubleBeamConfig().glue_tangential_stiffness


class DoubleBeamLevels(FELevels):
    """The measured series' levels simulated by the FE double beam; ``config``: a
    :class:`DoubleBeamConfig` (default the shipped case), the other arguments as
    :class:`FELevels`."""

    default_kt = DEFAULT_KT
    label = "double beam"

    def __init__(self, *args, config: DoubleBeamConfig | None = None, **kw):
        super().__init__(*args, **kw)
        self.config = DoubleBeamConfig() if config is None else config

    def _build(self, K_T: float) -> LinearPart:
        cfg = replace(self.config, glue_tangential_stiffness=K_T)
        if self.config.clamp_length is None:      # the grip calibrated to 252.0 Hz
            cfg = replace(cfg, clamp_length=calibrate_clamp_length(cfg, xtol=1e-10))
        model = build_double_beam(cfg)

        def lambda3(phi):                         # int |phi_w|^3 dx of the lower strip
            w = model.dofmaps[0].component(model.full_vector(phi), W)
            return float(np.sum(model.mesh.tributary_length() * np.abs(w) ** 3))

        return linear_part(self, model, K_T, lambda3, width=cfg.width, grip=cfg.grip)

    def structure(self, lin: LinearPart) -> str:
        if self.config.clamp_length is None:
            return f"grip {1e3 * lin.grip:.3f} mm (calibrated to 252.0 Hz for this K_T)"
        return f"grip {1e3 * lin.grip:.3f} mm (given)"


_D = DoubleBeamConfig()
#: Assumed properties of :class:`DoubleBeamConfig` and the changes tried (handbook
#: ranges of wrought aluminium: E 68-73 GPa, rho 2660-2800 kg/m^3; the masses of a force
#: gauge top + stud and of miniature accelerometers are not given by the paper; the glue
#: zone's discretization).
ASSUMPTIONS = {
    "E 68 GPa (70)": {"E": 68.0e9},
    "E 73 GPa (70)": {"E": 73.0e9},
    "rho 2660 kg/m^3 (2700)": {"rho": 2660.0},
    "rho 2800 kg/m^3 (2700)": {"rho": 2800.0},
    "exciter mass 1 g (2 g)": {"exciter_mass": 0.5 * _D.exciter_mass},
    "exciter mass 4 g (2 g)": {"exciter_mass": 2.0 * _D.exciter_mass},
    "sensor masses 0.5 g (1 g)": {"sensor_mass": 0.5 * _D.sensor_mass},
    "sensor masses 2 g (1 g)": {"sensor_mass": 2.0 * _D.sensor_mass},
    "9 glue elements (5)": {"n_joints": 9},
}


@dataclass(frozen=True)
class DoubleBeamVariant:
    """``levels(data, force_scale=)`` of the double beam with ``changes`` to its
    :class:`DoubleBeamConfig` (picklable)."""

    changes: tuple

    def __call__(self, data, force_scale: float = 1.0) -> DoubleBeamLevels:
        return DoubleBeamLevels.from_data(data, force_scale=force_scale,
                                          config=replace(DoubleBeamConfig(), **dict(self.changes)))


def assumption_variants() -> dict:
    """:data:`ASSUMPTIONS` as the ``variants`` of
    :func:`feloop.assumptions.assumption_sensitivity`."""
    return {name: (changes, DoubleBeamVariant(tuple(changes.items())))
            for name, changes in ASSUMPTIONS.items()}
