"""A case file with the model ``iwanfe update`` fitted (``updated_model.json``): the FE
commands (``backbone``, ``ringdown``, ``modes``, ``render``, ``export``) run on the
updated model with ``--model FILE``.

The update's model (:mod:`feloop.levels`) is the case file's structure, calibrated
as the file asks at the joint stiffness ``K_T``, with every stiffness scaled by
``a = (2 pi f0)^2 / omega_k^2`` (the fitted stuck frequency ``f0`` over the model's own,
structure and joints alike, joint forces ``a`` times), viscous modal damping ``zeta_v``
and one Iwan joint law (``chi``, ``F_S``, ``beta``; ``K_T``, ``F_S`` and ``R`` shared over
the joint elements by their stiffness). As a case file: the calibrated values fixed
(``[calibrate]`` dropped), every material's E and every support spring times ``a``, each
joint interface's ``kt = a K_T kt_i / sum(kt)`` and ``fs = a F_S kt_i / sum(kt)``, the
fitted ``chi`` and ``beta``, ``[damping] zeta = zeta_v``. Only a base model (cause
``none``) is a case file: a fitted cause (an air drag, a hardening spring) has no
case-file form, and the model is refused in one line rather than silently dropped.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from casefile.calibrate import calibrate
from feloop.case_file import refusal
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
    why = refusal(cf)
    if why:                               # update fits Iwan joints only
        raise InputError(f"{where}: an updated model holds Iwan joints; {why}")
    if doc.get("case") != cf.name:
        raise InputError(f"{where}: the update of case {doc.get('case')!r}, not of {cf.name!r}")
    if doc.get("cause", "none") != "none":
        raise InputError(f"{where}: the updated model includes the cause {doc['cause']!r}, "
                         f"which has no case-file form; FE commands take a base model "
                         f"(cause none) only")
    chi = _number(doc, "parameters.chi.value", where)
    a = _number(doc, "joint.stiffness_scale", where)
    K_T = _number(doc, "joint.K_T_N_per_m", where)
    F_S = _number(doc, "joint.F_S_N", where)
    beta = _number(doc, "joint.beta", where)
    zeta = _number(doc, "joint.zeta_v", where)
    if not (a > 0 and K_T > 0 and F_S > 0 and beta >= 0 and -1 < chi < 0 and 0 <= zeta < 1):
        raise InputError(f"{where}: parameters out of range (chi = {chi:g}, scale = {a:g}, "
                         f"K_T = {K_T:g} N/m, F_S = {F_S:g} N, beta = {beta:g}, zeta = {zeta:g})")
    s = K_T / total_kt(cf)
    at_kt = dataclasses.replace(cf, interfaces=tuple(
        dataclasses.replace(i, kt=i.kt * s) if i.tangential == "joint" else i
        for i in cf.interfaces))
    f, _ = calibrate(at_kt)
    total = total_kt(f)
    interfaces = tuple(
        dataclasses.replace(i, kt=a * i.kt, fs=a * F_S * i.kt / total, chi=chi, beta=beta)
        if i.tangential == "joint" else i for i in f.interfaces)
    supports = tuple(dataclasses.replace(sp, k_u=a * sp.k_u, k_w=a * sp.k_w,
                                         k_theta=a * sp.k_theta) for sp in f.supports)
    materials = tuple(dataclasses.replace(m, E=a * m.E) for m in f.materials)
    kinds = dict(f.kinds)
    for k, itf in enumerate(f.interfaces):
        if itf.tangential == "joint":
            for key in ("chi", "fs", "beta", "kt"):
                kinds[f"interface.{k}.{key}"] = ("fitted", f"by iwanfe update ({where})")
    kinds["damping.zeta"] = ("fitted", f"zeta_v by iwanfe update ({where})")
    for k in range(len(materials)):
        kinds[f"material.{k}.E"] = ("fitted", f"times {a:.9g}: f0 of iwanfe update ({where})")
    return dataclasses.replace(f, interfaces=interfaces, supports=supports,
                               materials=materials, zeta=zeta, calibrate=None, kinds=kinds)
