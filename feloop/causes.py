"""The causes of the diagnosis catalogue as FE physics of any jointed FE model.

Each cause's FE realization lives in its own file beside its one-mode model
(``inverse/diagnosis/causes/<id>.py``, ``FE_REALIZATION``: an
:class:`inverse.diagnosis.fe_realization.Extension`, the physics and the literature in
its comments); :data:`EXTENSIONS` collects them from the catalogue, so adding a cause
with an FE realization is its plug-in file alone. A cause without one is listed as not
tested at the FE level (:func:`feloop.select.untestable`).
"""
from __future__ import annotations

from inverse.diagnosis.causes import CATALOGUE
from inverse.diagnosis.fe_realization import Combined, Extension

__all__ = ["Extension", "Combined", "EXTENSIONS", "MacroSlip", "force_scale_power"]

#: cause id -> its FE realization, in their fit order (``Extension.fit_order``)
EXTENSIONS = {m.ID: m.FE_REALIZATION for m in sorted(
    (m for m in CATALOGUE.values() if m.FE_REALIZATION is not None),
    key=lambda m: (m.FE_REALIZATION.fit_order, m.ID))}
#: the macro-slip realization's class (``update`` reads its micro-slip limit)
MacroSlip = type(CATALOGUE["macro-slip"].FE_REALIZATION)


def force_scale_power(parameter: str) -> int:
    """How the fitted ``parameter`` scales with the assumed force scale s: s^power
    (:attr:`Extension.force_scale_power`; 0 for the base parameters and any other)."""
    return next((e.force_scale_power for e in EXTENSIONS.values()
                 if e.parameter == parameter), 0)
