"""The FE loop of a case file: its FE-levels model (:class:`feloop.case_levels.
CaseLevels`), ``update`` (:func:`feloop.update.run_update` on it, the one judge
of :func:`feloop.select.fe_select` choosing the model), the assumed properties
``update --assumptions`` changes (:func:`assumption_variants`) and ``uncertainty``
(:func:`feloop.uncertainty.run_fe_uncertainty` on it), for a file whose joint
interfaces have one law (``iwan4``, ``jenkins`` or ``bouc-wen``: :mod:`feloop.joint_forms`)
and a ``kt``, with a point ``[drive]`` (not ``kind = "base"``) and a ``[measured]`` table.

Defaults a command may override: the data are the file's table, the mode label the
file's ``[measured] mode`` when the table has it (else the table's only mode label),
the fit levels all but the top three of the table (at least 5 fitted). The file's
``chi``, ``fs``, ``beta`` are the nominal joint: ``update`` fits ``chi`` and the joint
strength to the data.

Assumed properties (:func:`assumption_variants`), each changed alone: every material's
``E`` by -/+ 3 % and ``rho`` by -/+ 2 % (the spread of handbook values of one alloy), every
point mass and sensor mass halved and doubled (attachments are rarely weighed), every
distributed interface's ``joint_elements`` n -> 2n - 1 (its discretization); a parameter
the file calibrates (``[calibrate]``) is not assumed and is left out.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from casefile.parameters import get_parameter, set_parameter
from casefile.plausibility import joint_plausibility
from casefile.spec import is_base_drive
from ident.errors import InputError

__all__ = ["qualifies", "levels_builder", "assumption_variants",
           "update_builder", "modes_builder", "fitted_plausibility", "uncertainty_builder"]

def qualifies(cf) -> bool:
    """The file has what the FE loop needs (module docstring): joint interfaces of one
    law (:mod:`feloop.joint_forms`), each with a ``kt``, a drive and measured data."""
    joints = [i for i in cf.interfaces if i.tangential == "joint"]
    return bool(joints) and all(i.kt for i in joints) and len({i.law for i in joints}) == 1 \
        and cf.drive is not None and not is_base_drive(cf.drive) \
        and cf.measured is not None and bool(cf.measured.files)


@dataclass(frozen=True)
class CaseFileLevels:
    """``levels(data, force_scale=1.0)``: the :class:`CaseLevels` of ``data`` for case
    file ``cf`` (picklable, for process executors)."""

    cf: object

    def __call__(self, data, force_scale: float = 1.0):
        from feloop.case_levels import CaseLevels

        return CaseLevels.from_data(data, cf=self.cf, force_scale=force_scale)


def levels_builder(cf):
    """``levels(data, force_scale=1.0)``: the :class:`CaseLevels` of ``data``."""
    return CaseFileLevels(cf)


def _assumed(cf) -> list[tuple[str, float]]:
    """(address, factor) of every change of the module docstring."""
    out = []
    for i, _ in enumerate(cf.materials):
        out += [(f"material.{i}.E", f) for f in (0.97, 1.03)]
        out += [(f"material.{i}.rho", f) for f in (0.98, 1.02)]
    for i, _ in enumerate(cf.masses):
        out += [(f"mass.{i}.mass", f) for f in (0.5, 2.0)]
    for i, s in enumerate(cf.sensors):
        if getattr(s, "mass", None):
            out += [(f"sensor.{i}.mass", f) for f in (0.5, 2.0)]
    calibrated = set(cf.calibrate.parameters) if cf.calibrate is not None else set()
    return [(a, f) for a, f in out if a not in calibrated]


def assumption_variants(cf) -> dict:
    """name -> (changes, levels) of every assumed property changed (module docstring),
    the ``variants`` of :func:`feloop.assumptions.assumption_sensitivity`."""
    out = {}
    for address, factor in _assumed(cf):
        old = get_parameter(cf, address)
        out[f"{address} {factor * old:.4g} ({old:.4g})"] = (
            {address: factor * old}, CaseFileLevels(set_parameter(cf, address, factor * old)))
    for i, itf in enumerate(cf.interfaces):
        n = itf.joint_elements
        if itf.tangential == "joint" and n:
            items = list(cf.interfaces)
            items[i] = dataclasses.replace(itf, joint_elements=2 * n - 1)
            out[f"interface.{i}.joint_elements {2 * n - 1} ({n})"] = (
                {f"interface.{i}.joint_elements": 2 * n - 1},
                CaseFileLevels(dataclasses.replace(cf, interfaces=tuple(items))))
    return out


def _defaults(cf, data_path=None, mode=None) -> dict:
    """Data, mode label and fit levels (module docstring) of the table at ``data_path``
    (default the file's) and ``mode`` (default the file's)."""
    from ident.measured import read_measured

    path = cf.measured.file if data_path is None else data_path
    table = read_measured(path)
    labels = sorted({int(m) for m in table.mode})
    if mode is None:
        mode = cf.measured.mode if cf.measured.mode in labels else labels[0]
        if len(labels) > 1 and mode != cf.measured.mode:
            raise InputError(f"{path}: [measured] mode = {cf.measured.mode} is none of the "
                             f"table's mode labels {labels}: give --mode")
    elif int(mode) not in labels:
        raise InputError(f"{path}: no mode {mode} in the table (labels {labels})")
    levels = sorted({int(v) for v in table.for_mode(mode).level})   # a repeat is one level
    fit = levels[:max(5, len(levels) - 3)]
    return {"data_path": str(path), "mode_label": int(mode),
            "fit_levels": ",".join(map(str, fit))}


def _nominal_joint_note(cf) -> str:
    """What the file says of its joints beside what update fits: the nominal joint of
    modes and backbone where the law's keys are given, 'left to be fitted' where one is
    not (the case-file spec allows either)."""
    from casefile.laws import law_keys
    from feloop.case_levels import form_of

    parts, units = [], {"fs": " N"}
    for k, i in enumerate(cf.interfaces):
        if i.tangential != "joint":
            continue
        given = {n: getattr(i, n) for n in law_keys(i.law)}
        missing = [name for name, v in given.items() if v is None]
        if missing:
            parts.append(f"[interface.{k}] {', '.join(missing)} left to be fitted")
        else:
            parts.append(f"[interface.{k}] " + ", ".join(
                f"{n} = {v:g}{units.get(n, '')}" for n, v in given.items())
                + " (nominal joint of modes and backbone)")
    form = form_of(cf)
    fitted = ("chi and the joint strength to the measured levels (beta: the "
              "ln(phi_max/a_ref) row below" if form.law == "iwan4" else
              f"{', '.join(form.names)} to the measured levels (law {form.law}")
    return f"the file's joints: {'; '.join(parts)}; update fits {fitted}; docs/case-file-loop.md)"


def update_builder(cf):
    """``update(executor, progress, store, **settings)`` (fields of
    :class:`feloop.update.UpdateSettings`; the defaults of the module docstring
    fill what is not given)."""
    def update(executor="serial", progress=False, store=None, **settings):
        from feloop.update import UpdateSettings, run_update

        settings = {k: v for k, v in settings.items() if v is not None}
        settings = {**_defaults(cf, settings.get("data_path"), settings.get("mode_label")),
                    **settings}
        variants = assumption_variants(cf) if settings.get("assumptions") else None
        r = run_update(UpdateSettings(**settings), levels_builder(cf), executor=executor,
                       progress=progress, store=store, case_name=cf.name,
                       model_key=cf.path.read_text(), assumptions=variants)
        r["notes"] = [_nominal_joint_note(cf), *r.get("notes", [])]
        r["plausibility"] = fitted_plausibility(cf, r)
        return r
    return update


def modes_builder(cf):
    """``run(fit_modes, predict_modes=(), data_path=None, fit_levels=None,
    force_scale=1.0, rig_repeatability=None)``: :func:`feloop.modes_run.run_modes` on the
    file's FE-levels models (one joint over several modes; the file's table unless
    ``data_path``)."""
    def run(fit_modes, predict_modes=(), data_path=None, fit_levels=None, force_scale=1.0,
            rig_repeatability=None):
        from feloop.modes_run import ModesSettings, run_modes

        path = str(cf.measured.file if data_path is None else data_path)
        settings = ModesSettings(path, tuple(fit_modes), tuple(predict_modes), fit_levels,
                                 force_scale, rig_repeatability)
        r = run_modes(settings, levels_builder(cf), case_name=cf.name)
        r["notes"] = [_nominal_joint_note(cf)]
        return r
    return run


def fitted_plausibility(cf, r: dict) -> list[dict]:
    """:func:`casefile.plausibility.joint_plausibility` of an update's (or an FE
    diagnosis's) fitted joint and, when fitted, its air drag coefficient: ``r`` holds
    ``joint`` (dict) or ``prediction`` and ``fit`` (the update's result)."""
    if "prediction" in r:
        joint, values, free = r["prediction"].joint, r["fit"].values, r["fit"].free
    else:
        joint, values, free = r["joint"], r["extended_fit"]["values"], r["extended_fit"]["free"]
    return joint_plausibility(cf, joint, values["drag_cd"] if "drag_cd" in free else None)


def uncertainty_builder(cf):
    """``uncertainty(data_path, mode_label, fit_levels, force_scale, model, **options)``:
    :func:`feloop.uncertainty.run_fe_uncertainty` on the file's FE-levels model
    (``options``: its ``n_samples``, ``seed``, ``confidence``, ``distribution``, ``out``,
    ``executor``, ``progress``; the defaults of the module docstring fill the rest).
    ``model``: an ``updated_model.json`` of ``update`` on this file, drawn around instead
    of ``update``'s model choice (:mod:`feloop.given_model`); its mode label, fit levels
    and force scale are then the defaults."""
    def uncertainty(data_path=None, mode_label=None, fit_levels=None, force_scale=None,
                    model=None, **options):
        from casefile.build import build_model
        from casefile.calibrate import calibrate
        from feloop.given_model import read_given
        from feloop.uncertainty import LevelsStudy, run_fe_uncertainty

        given = None if model is None else read_given(model, cf.name)
        if given is not None:
            mode_label = given.data["mode"] if mode_label is None else mode_label
            fit_levels = fit_levels or ",".join(map(str, given.fit_levels))
            force_scale = given.data["force_scale"] if force_scale is None else force_scale
        d = _defaults(cf, data_path, mode_label)
        study = LevelsStudy(d["data_path"], d["mode_label"], fit_levels or d["fit_levels"],
                            1.0 if force_scale is None else float(force_scale), cf.name)
        fe_model = build_model(calibrate(cf)[0]).model
        return run_fe_uncertainty(levels_builder(cf), fe_model, study, given=given,
                                  **options)
    return uncertainty
