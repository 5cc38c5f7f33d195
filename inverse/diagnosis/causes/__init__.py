"""The catalogue of causes of the one-mode diagnosis: this folder, one file per cause.

Every module here (not starting with ``_``) is a cause and is discovered at import; the
catalogue order is each module's ``ORDER``. A cause module defines:

* ``ID`` (the spec's id), ``ORDER`` (int), ``WORDS`` (one sentence: what it does to the
  data), ``ADVICE`` (what measurement strengthens the evidence for or against it);
* ``NONLINEAR``: ``[(name, lower, upper, grid), ...]`` its nonlinear parameters with
  their bounds and the grid of the global search; ``LINEAR``: names of its linear
  parameters, ``NONNEG``: those that must be >= 0; ``EFFECT``: the linear parameter
  whose 0 means the cause is absent (or None);
* ``columns(obs, col, log_s, p, w2) -> (omega2 columns, zeta columns)``: its linear
  columns in the one-mode model (``col`` the nonlinear parameters by name, (G, 1)
  each; ``log_s`` (G, n) the effective log amplitude; ``p = chi + 1``; ``w2`` (1, n)
  the measured omega2). Optional: ``REPLACES_JOINT = True`` when its columns replace
  the base model's power-law joint column ``K1`` (macro-slip), and
  ``transform_log_s(log_s, col)`` when it changes the amplitude (a force shortfall);
* ``parameters(lin, nl, obs, log_s, chi) -> dict`` its physical parameters (key
  ``K1_top`` when it replaces the joint column);
* ``signature(obs, base) -> (d_omega2, d_zeta, d_log_response)``: a typical change it
  adds to a base fit (``base``: the base model's physical parameters), for the
  separability analysis;
* ``testable(obs) -> (bool, reason)``: whether these data can test it at all;
* ``FE_REALIZATION``: its FE-level realization, an
  :class:`inverse.diagnosis.fe_realization.Extension` (or None: the FE level then lists
  it as not tested there).

Adding a cause: drop a file here, its FE realization in it (no other file needs to
change; the pair advice of
:mod:`inverse.diagnosis.separability` falls back to "add levels above the top one"
unless a line is added there).
"""
from __future__ import annotations

import importlib
import pkgutil

__all__ = ["CATALOGUE", "CAUSES", "cause"]

_REQUIRED = ("ID", "ORDER", "WORDS", "ADVICE", "NONLINEAR", "LINEAR", "NONNEG", "EFFECT",
             "columns", "parameters", "signature", "testable", "FE_REALIZATION")


def _discover() -> dict:
    mods = [importlib.import_module(f"{__name__}.{m.name}")
            for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")]
    for m in mods:
        missing = [a for a in _REQUIRED if not hasattr(m, a)]
        if missing:
            raise ImportError(f"cause module {m.__name__} lacks {', '.join(missing)}")
    return {m.ID: m for m in sorted(mods, key=lambda m: (m.ORDER, m.ID))}


#: Cause id -> its module, in catalogue order.
CATALOGUE = _discover()
#: The catalogue of causes (spec ids), in catalogue order.
CAUSES = tuple(CATALOGUE)


def cause(cid: str):
    """The module of cause ``cid``."""
    return CATALOGUE[cid]
