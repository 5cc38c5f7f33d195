"""How the updated FE model of a case depends on what the model assumes.

For each assumed property the data cannot fix (the case's ``assumptions`` capability:
name -> the FE-levels model with that property changed, e.g. E, rho, masses, the
number of joint elements), the model is rebuilt with the changed value (calibrated
again as the case calibrates) and the updated parameters are refitted to the same fit
levels from the updated values (and, with macro-slip, from onsets moved by +/- 0.1 and
0.2 in ``ln_phimax``); the report gives the change of chi2 and of the headline figures
(frequency and zeta at the held-out levels, top slip over phi_max). Each change is one
task of :func:`runs.executor.run_sweep`. The joint stiffness K_T and the force scale are
covered elsewhere (K_T by its profile; omega^2 and zeta are exactly invariant to the
force scale).
"""
from __future__ import annotations

from feloop.levels import Simulator
from feloop.select import Headline
from inverse.update import UpdateProblem, fit
from runs.executor import run_sweep

__all__ = ["assumption_sensitivity"]


def _refit(task, shared):
    name, (changes, levels) = task
    data, mask, noise, parameters, values, free, force_scale, ext = shared
    fe = levels(data, force_scale=force_scale)
    prob = UpdateProblem(Simulator(fe, ext), data.omega2, data.zeta, noise, mask, parameters)
    starts = [values]
    if "ln_phimax" in free:     # a sharp macro-slip onset: try it a little earlier/later
        starts += [dict(values, ln_phimax=values["ln_phimax"] + d) for d in (-0.2, -0.1, 0.1, 0.2)]
    f = min((fit(prob, free, start=s) for s in starts), key=lambda f: f.chi2)
    return {"assumption": name, "changes": changes, "chi2": f.chi2, "values": f.values,
            "headline": Headline(fe, ~mask, ext)(f.values)}


def assumption_sensitivity(data, mask, noise, parameters, best, force_scale, variants: dict,
                           executor="serial", extension=None) -> list:
    """Refit ``best`` (a :class:`inverse.update.Fit` of the model with ``extension``)
    under every changed assumption of ``variants`` (name -> ``(changes, levels)``:
    ``changes`` a dict saying what changed, ``levels(data, force_scale=)`` the
    FE-levels model with it; picklable for process executors)."""
    shared = (data, mask, noise, parameters, dict(best.values), best.free, force_scale,
              extension)
    return run_sweep(_refit, list(variants.items()), executor=executor, shared=shared,
                     progress=False)
