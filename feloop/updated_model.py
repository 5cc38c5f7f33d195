"""A case file with the model ``iwanfe update`` fitted (``updated_model.json``): the FE
commands (``backbone``, ``ringdown``, ``modes``, ``render``, ``export``) run on the
updated model with ``--model FILE``.

The update's model (:mod:`feloop.levels`) is the case file's structure, calibrated
as the file asks at the joint stiffness ``K_T``, with every stiffness scaled by
``a = (2 pi f0)^2 / omega_k^2`` (the fitted stuck frequency ``f0`` over the model's own,
structure and joints alike, joint forces ``a`` times), viscous modal damping ``zeta_v``
and the file's joint law (``iwan4``: ``chi``, ``F_S``, ``beta``; ``jenkins``: ``F_S``;
``bouc-wen``: ``F_S``, ``alpha`` and the file's ``shape``: :mod:`feloop.joint_forms`;
``K_T`` and ``F_S`` shared over the joint elements by their stiffness). As a case file:
the calibrated values fixed (``[calibrate]`` dropped), every material's E and every
support spring times ``a``, each joint interface's ``kt = a K_T kt_i / sum(kt)`` and
``fs = a F_S kt_i / sum(kt)``, the law's other fitted keys, ``[damping] zeta = zeta_v``.
Only a base model (cause
``none``) is a case file: a fitted cause (an air drag, a hardening spring) has no
case-file form, and the model is refused in one line rather than silently dropped.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from casefile.calibrate import calibrate
from casefile.nonlinear import file_law
from feloop.case_levels import total_kt
from ident.errors import InputError

__all__ = ["updated_file"]


def _number(doc: dict, path: str, where: str) -> float:
    node = doc
    for key in path.split("."):
        if not isinstance(node, dict) or key not in node:
            raise InputError(f"{where}: no '{path}' (not an updated_model.json of iwanfe update)")
        node = node[key]
    try:
        return float(node)
    except (TypeError, ValueError):
        raise InputError(f"{where}: '{path}' is not a number: {node!r}") from None


#: each law's fitted keys besides kt and fs: case-file key -> where updated_model.json
#: holds it
_OWN = {"iwan4": (("chi", "parameters.chi.value"), ("beta", "joint.beta")),
        "jenkins": (),
        "bouc-wen": (("alpha", "joint.alpha"), ("shape", "joint.shape"))}


def _in_range(law: str, own: dict) -> bool:
    """The law's own fitted keys within the ranges of :mod:`casefile.laws`."""
    if law == "iwan4":
        return -1 < own["chi"] < 0 and own["beta"] >= 0
    if law == "bouc-wen":
        return 0 <= own["alpha"] < 1 and -1 < own["shape"] <= 1
    return True


def updated_file(cf, model_path):
    """The case file ``cf`` as the update in ``model_path`` left it (module docstring);
    InputError (one line) for a file of another case, a model with a cause or a file
    that is not an update's."""
    where = str(model_path)
    try:
        doc = json.loads(Path(model_path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{where}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{where}: not a JSON file: {exc}") from None
    if not isinstance(doc, dict):
        raise InputError(f"{where}: not an updated_model.json of iwanfe update")
    if doc.get("case") != cf.name:
        raise InputError(f"{where}: the update of case {doc.get('case')!r}, not of {cf.name!r}")
    if doc.get("cause", "none") != "none":
        raise InputError(f"{where}: the updated model includes the cause {doc['cause']!r}, "
                         f"which has no case-file form; FE commands take a base model "
                         f"(cause none) only")
    law, joint = file_law(cf), doc.get("joint")
    fitted_law = joint.get("law", "iwan4") if isinstance(joint, dict) else "iwan4"
    if fitted_law != law:
        raise InputError(f"{where}: an update of {fitted_law} joints; {cf.path.name} has "
                         f"{law} joints")
    a = _number(doc, "joint.stiffness_scale", where)
    K_T = _number(doc, "joint.K_T_N_per_m", where)
    F_S = _number(doc, "joint.F_S_N", where)
    zeta = _number(doc, "joint.zeta_v", where)
    own = {n: _number(doc, path, where) for n, path in _OWN[law]}
    if not (a > 0 and K_T > 0 and F_S > 0 and 0 <= zeta < 1 and _in_range(law, own)):
        raise InputError(f"{where}: parameters out of range (scale = {a:g}, K_T = {K_T:g} "
                         f"N/m, F_S = {F_S:g} N, zeta = {zeta:g}"
                         + "".join(f", {n} = {v:g}" for n, v in own.items()) + ")")
    s = K_T / total_kt(cf)
    at_kt = dataclasses.replace(cf, interfaces=tuple(
        dataclasses.replace(i, kt=i.kt * s) if i.tangential == "joint" else i
        for i in cf.interfaces))
    f, _ = calibrate(at_kt)
    total = total_kt(f)
    interfaces = tuple(
        dataclasses.replace(i, kt=a * i.kt, fs=a * F_S * i.kt / total, **own)
        if i.tangential == "joint" else i for i in f.interfaces)
    supports = tuple(dataclasses.replace(sp, k_u=a * sp.k_u, k_w=a * sp.k_w,
                                         k_theta=a * sp.k_theta) for sp in f.supports)
    materials = tuple(dataclasses.replace(m, E=a * m.E) for m in f.materials)
    kinds = dict(f.kinds)
    for k, itf in enumerate(f.interfaces):
        if itf.tangential == "joint":
            for key in ("kt", "fs", *own):
                kinds[f"interface.{k}.{key}"] = ("fitted", f"by iwanfe update ({where})")
    kinds["damping.zeta"] = ("fitted", f"zeta_v by iwanfe update ({where})")
    for k in range(len(materials)):
        kinds[f"material.{k}.E"] = ("fitted", f"times {a:.9g}: f0 of iwanfe update ({where})")
    return dataclasses.replace(f, interfaces=interfaces, supports=supports,
                               materials=materials, zeta=zeta, calibrate=None, kinds=kinds)
