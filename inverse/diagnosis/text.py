"""Plain words of a diagnosis: its own contradictions and the summary paragraph."""
from __future__ import annotations

import math

import numpy as np

from inverse.contradictions import Contradiction, threshold
from inverse.diagnosis.causes import CATALOGUE

__all__ = ["own_contradictions", "chi_at_bound", "describe", "extrapolation_note"]

def own_contradictions(d, base_params: dict, base_zeta, noise) -> list:
    """The diagnosis's own statements: the base fit collapsing to no joint while the
    damping grows (``no-joint``), or putting chi on the edge of (-1, 0)
    (``chi-at-bound``), each judged at :func:`inverse.contradictions.threshold` noise
    standard deviations."""
    z = np.asarray(d.zeta, float)
    a, b = 0, z.size - 1
    s_g = math.hypot(noise.zeta[a], noise.zeta[b])
    growth = z[b] - z[a]
    if growth / s_g <= threshold(getattr(noise, "dof_zeta", math.inf)):
        return []
    fitted = float(base_zeta[b] - base_zeta[a])
    out = []
    la, lb = int(d.level[a]), int(d.level[b])
    if fitted < 0.1 * growth:
        out.append(Contradiction("no-joint", (
            f"the base model's best fit has no joint to speak of (kappa1 B = "
            f"{base_params['kappa1_B']:.3g} rad^2/s^2): it draws a nearly flat line "
            f"(+{100 * fitted:.3g} % in damping ratio) through a damping ratio that grows "
            f"{100 * z[a]:.4g} % -> {100 * z[b]:.4g} % ({z[b] / z[a]:.3g}x, level {la} -> "
            f"{lb}): no micro-slip joint tied to the measured frequency change gives that "
            f"growth"), {"kappa1_B": base_params["kappa1_B"], "zeta": [z[a], z[b]],
                         "fitted_growth": fitted, "z_score": growth / s_g}))
    chi = base_params["chi"]
    if not -0.98 < chi < -0.02:
        out.append(Contradiction("chi-at-bound", (
            f"the base fit puts chi at {chi:.3f}, on the edge of the Iwan range -1 < chi "
            f"< 0: the frequency change and the damping growth "
            f"({100 * z[a]:.4g} % -> {100 * z[b]:.4g} %) are hardly tied by any "
            f"micro-slip joint"), {"chi": chi}))
    return out


def chi_at_bound(params: dict, model: str):
    """Statement when the named model's fit puts chi on the edge of (-1, 0), or None."""
    chi = params.get("chi")
    if chi is None or -0.98 < chi < -0.02:
        return None
    return Contradiction("chi-at-bound", (
        f"the named model ({model}) puts chi at {chi:.3f}, on the edge of the Iwan range "
        f"-1 < chi < 0: its joint is hardly a micro-slip Iwan joint (the fit leans on "
        f"the bound)"), {"chi": chi, "model": model})


def _fmt_causes(cause, also):
    return " and ".join(f"`{c}`" for c in [cause, *also])


def describe(cause: str, also: list, params: dict, gain, test: dict, contradictions: list,
             closest: str, rivals: list, n_levels: int, inseparable: list,
             unfit: list = ()) -> str:
    """One paragraph naming the cause in plain words (``summary``); ``unfit`` the
    candidates with more parameters than data."""
    chi = params.get("chi", float("nan"))
    g = "n/a" if gain is None else f"{gain:.2g}"
    if cause == "unexplained":
        p = "n/a" if test["p_value"] is None else f"{test['p_value']:.2g}"
        text = (f"No cause of the catalogue, alone or two together, brings the data "
                f"within their noise: the closest candidate (`{closest}`) leaves an rms "
                f"residual of {test['rms_standardized']:.3g} noise standard deviations "
                f"(p = {p}, {test['test']}).")
        if unfit:
            text += (f" {len(unfit)} candidate(s) have more parameters than these "
                     f"{n_levels} levels give data ({', '.join(unfit)}): with more levels "
                     f"they might explain the data.")
    elif cause == "none":
        if contradictions:
            text = (f"The base model is kept (rms residual {test['rms_standardized']:.2f} "
                    f"noise standard deviations; no extension earned its extra "
                    f"parameters), with a caveat the data raise (see contradictions: none "
                    f"of them refutes it).")
        elif params.get("kappa1_B", 0.0) <= 0.0:
            text = ("The data show no amplitude dependence beyond their noise: no joint "
                    "is visible (kappa1 B = 0).")
        else:
            text = (f"The base model (one micro-slip Iwan joint, chi = {chi:.3f}) explains "
                    f"the frequency drop and the damping growth together within the noise "
                    f"(rms residual {test['rms_standardized']:.2f} noise standard "
                    f"deviations): no extension earned its extra parameters.")
    else:
        words = "; ".join(CATALOGUE[c].WORDS for c in [cause, *also])
        gain_text = (f"cuts the leave-one-level-out prediction error by a factor {g}"
                     if gain is not None else "cannot be tested on unseen levels: it has "
                     "as many parameters as the data left without one level, so it is "
                     "named on its fit test and information criterion alone")
        text = (f"Cause {_fmt_causes(cause, also)}: {words}. The extended model "
                f"{gain_text} (chi = {chi:.3f}).")
    if rivals:
        text += (" Ambiguous: " + ", ".join(f"`{r}`" for r in rivals)
                 + " explain(s) the data nearly as well.")
    if inseparable and (cause == "none" or n_levels < 8):
        pairs = "; ".join(f"{p['causes'][0]} from {p['causes'][1]}" for p in inseparable)
        text += f" With {n_levels} levels this test cannot separate {pairs}."
    return text


def extrapolation_note(cause: str, gain_held_out, n_top: int) -> str:
    """A sentence when the named model, fitted without the top ``n_top`` levels,
    predicts them worse than the base model (``gain_held_out`` < 1): its form is then
    not confirmed beyond the levels it was fitted to. Empty otherwise."""
    if cause in ("none", "unexplained") or gain_held_out is None or gain_held_out >= 1.0:
        return ""
    return (f" Fitted without the top {n_top} levels, the {cause} model predicts them "
            f"worse than the base model (gain {gain_held_out:.3g}): its form is not "
            f"confirmed beyond the levels it was fitted to; test above the top level "
            f"before relying on an extrapolation.")
