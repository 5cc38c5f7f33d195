"""The FE loop of a case file: its FE-levels model (:class:`cases.casefile.levels.
CaseLevels`) and ``update`` (:func:`cases.double_beam.update_study.run_update` on it, the
one judge of :func:`cases.double_beam.fe_select.fe_select` choosing the model), for a
file whose joint interfaces all have law ``iwan4`` and a ``kt``, with a ``[drive]`` and
a ``[measured]`` table.

Defaults a command may override: the data are the file's table, the mode label the
file's ``[measured] mode`` when the table has it (else the table's only mode label),
the fit levels all but the top three of the table (at least 5 fitted). The file's ``chi``, ``fs``, ``beta`` are
the nominal joint: ``update`` fits ``chi`` and the joint strength to the data.
"""
from __future__ import annotations

from ident.errors import InputError

__all__ = ["qualifies", "levels_builder", "update_builder"]


def qualifies(cf) -> bool:
    """The file has what the FE loop needs (module docstring)."""
    joints = [i for i in cf.interfaces if i.tangential == "joint"]
    return bool(joints) and all(i.law == "iwan4" and i.kt for i in joints) \
        and cf.drive is not None and cf.measured is not None and cf.measured.file is not None


def levels_builder(cf):
    """``levels(data, force_scale=1.0)``: the :class:`CaseLevels` of ``data``."""
    def levels(data, force_scale: float = 1.0):
        from cases.casefile.levels import CaseLevels

        return CaseLevels.from_data(data, cf=cf, force_scale=force_scale)
    return levels


def _defaults(cf) -> dict:
    from ident.measured import read_measured

    table = read_measured(cf.measured.file)
    labels = sorted({int(m) for m in table.mode})
    mode = cf.measured.mode if cf.measured.mode in labels else labels[0]
    if len(labels) > 1 and mode != cf.measured.mode:
        raise InputError(f"{cf.path}: [measured] mode = {cf.measured.mode} is none of the "
                         f"table's mode labels {labels}: give --mode")
    levels = sorted(int(v) for v in table.for_mode(mode).level)
    fit = levels[:-3] if len(levels) >= 8 else levels
    return {"data_path": str(cf.measured.file), "mode_label": int(mode),
            "fit_levels": ",".join(map(str, fit))}


def update_builder(cf):
    """``update(executor, progress, store, **settings)`` (fields of
    :class:`cases.double_beam.update_study.UpdateSettings`; the defaults of the module
    docstring fill what is not given)."""
    def update(executor="serial", progress=False, store=None, **settings):
        from cases.double_beam.update_study import UpdateSettings, run_update

        if settings.get("assumptions"):
            raise InputError(f"{cf.path}: --assumptions refits the double beam's Python model "
                             "under changed properties; not available for a case file")
        settings = {**_defaults(cf), **{k: v for k, v in settings.items() if v is not None}}
        return run_update(UpdateSettings(**settings), executor=executor, progress=progress,
                          store=store, levels=levels_builder(cf), case_name=cf.name,
                          model_key=cf.path.read_text())
    return update
