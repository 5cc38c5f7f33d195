"""How detectable a hidden effect is at all: an upper bound on any diagnosis' power.

For one synthetic series with one hidden effect, the generator's noise-free identified
table is taken twice, with the effect (W) and without it (C), both without the per-run
repeatability offsets. The diagnosis' base model (micro-slip Iwan over the abscissa
of eq. (1) of ``inverse/diagnosis/models.py``) is fitted to C; its fitted values B_C
plus the effect's change W - C form the series the effect alone makes from a
base-model series. Fitted again by the base
model in the true noise units of each level (identification sd and repeatability, as
the generator drew them), its minimum chi2

    lam = min_theta sum_levels [(B_C + W - C - base(theta))^2 / sd^2]   (both channels)

is the squared distance in noise units from that series to the nearest series the base
model can produce: the part of the effect the base model cannot absorb. (Fitting W
directly would count, as signal, what the identification of a nonlinear FRF scatters
from level to level with the line grid: under force control that scatter alone gives a
chi2 of 2-28 on noise-free `none` series of the own generator; as noise it is left out
here, which only raises the bound. Only C's scatter is taken out: where the effect
itself makes the FRF strongly nonlinear, W's own scatter stays in ``lam`` and the bound
overstates what the data allow. Series 80092021, a squeeze-film snubber under force
control: the noise-free identified zeta of the lowest level is 5.17e-3 in its first run
and 8.96e-3 when run again (73 %), and ``lam`` = 1155.)

No test that keeps its false-alarm rate ``alpha`` on that nearest series can detect the
effect with a power above the Neyman-Pearson bound of a known signal in known Gaussian
noise, ``Phi(sqrt(lam) - z_{1 - alpha})`` (a real diagnosis, which estimates noise and
form, stays below it). ``alpha = 0.1`` is the issue's whole false-alarm budget (``none``
called otherwise <= 1 in 10), the most generous choice.

Two tighter bounds separate why a diagnosis falls short (:func:`inverse.judge.naming_power`): the
judge's own threshold (a chi2 drop of ``2 q + T_CAUSE`` for the ``q = 2`` parameters a
cause adds) with the noise known, and the same with the noise estimated on the degrees
of freedom the judge had behind the drop: its channels' dof weighted by the effect's
share of ``lam`` in each, as the judge weights a drop
(:func:`inverse.judge.selection.shared_drop_dof`; until session 9 the channels' dof
were summed, a generous count).
What the judge misses beyond the last bound comes from its noise estimate being larger
than the truth and from its causes' forms differing from the generator's.

The response channel is left out (its noise-free value is not in every truth): for
``nonproportional-amplitude``, whose signal lies mostly there, ``lam`` is not a bound and
such series are reported without one.
"""
from __future__ import annotations

import importlib.util
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from inverse.diagnosis.fit import fit_model
from inverse.diagnosis.models import Model
from inverse.diagnosis.run import observations_from
from inverse.judge import detection_bound, naming_power

__all__ = ["noncentrality", "detection_bound", "naming_power", "own_oracle", "dev_oracle",
           "NO_BOUND"]

#: causes whose signal the omega2/zeta channels do not carry (module doc)
NO_BOUND = ("nonproportional-amplitude",)


def _base_fit(data, omega2, zeta, sd_omega2, sd_zeta):
    """The base model fitted to ``data`` with omega2 [rad^2/s^2], zeta and their noise
    replaced (per row of ``data``): (chi2 per channel {omega2, zeta}, fitted omega2,
    fitted zeta) in row order."""
    clean = replace(data.take(np.arange(len(data))), omega2=np.asarray(omega2, float),
                    zeta=np.asarray(zeta, float), omega2_std=np.asarray(sd_omega2, float),
                    zeta_std=np.asarray(sd_zeta, float))
    order = np.lexsort((clean.run_order, clean.level))   # the row order of for_mode
    obs, d, _, _, _ = observations_from(clean)
    obs.log_r = None
    obs.sigma = {"omega2": np.asarray(d.omega2_std, float),
                 "zeta": np.asarray(d.zeta_std, float)}
    fit = fit_model(Model(), obs)
    r = fit.residual.reshape(2, obs.n)
    w2, z = np.empty(obs.n), np.empty(obs.n)
    w2[order] = d.omega2 - r[0] * d.omega2_std
    z[order] = d.zeta - r[1] * d.zeta_std
    return {"omega2": float(np.sum(r[0] ** 2)), "zeta": float(np.sum(r[1] ** 2))}, w2, z


def noncentrality(data, with_, without, sd_omega2, sd_zeta) -> dict | None:
    """``lam`` of the module doc per channel ({omega2, zeta}; their sum is ``lam``).
    ``with_`` and ``without``: (omega2 [rad^2/s^2], zeta) noise-free per row of
    ``data``; ``sd_omega2``, ``sd_zeta`` the true noise per row."""
    _, bw2, bz = _base_fit(data, *without, sd_omega2, sd_zeta)
    w2 = bw2 + np.asarray(with_[0]) - np.asarray(without[0])
    z = bz + np.asarray(with_[1]) - np.asarray(without[1])
    lam = _base_fit(data, w2, z, sd_omega2, sd_zeta)[0]
    return lam if np.isfinite(sum(lam.values())) else None


def _rows(data, levels, run_orders):
    """Index of each (level, run order) pair in ``data``'s rows."""
    at = {(int(lv), int(ro)): i for i, (lv, ro) in enumerate(zip(data.level, data.run_order))}
    return np.array([at[(int(lv), int(ro))] for lv, ro in zip(levels, run_orders)])


def own_oracle(data, truth) -> dict | None:
    """``lam`` of a one-effect series of :mod:`synthetic` (its truth's
    noise-free values with and without the mechanism; noise: the table's identification
    sd with the drawn repeatability). None for other series."""
    mechs = truth.get("mechanisms", [])
    if len(mechs) != 1 or "run_order_k" not in truth:
        return None
    idx = _rows(data, truth["run_level"], truth["run_order_k"])

    def per_row(values):
        out = np.full(len(data), np.nan)
        out[idx] = values
        return out
    m = mechs[0]
    with_ = per_row(m["with_omega2"]), per_row(m["with_zeta"])
    without = per_row(m["without_omega2"]), per_row(m["without_zeta"])
    rep = truth["repeatability"]
    s_f, s_z = (rep["s_f"], rep["s_z"]) if rep["on"] else (0.0, 0.0)
    return noncentrality(data, with_, without, np.hypot(data.omega2_std, 2 * s_f * with_[0]),
                         np.hypot(data.zeta_std, s_z * with_[1]))


@lru_cache(maxsize=1)
def _gen_dev(path: str):
    spec = importlib.util.spec_from_file_location("gen_dev", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def dev_oracle(data, truth, gen_dev_path: Path) -> dict | None:
    """``lam`` of a one-effect ``gen_dev`` case: its levels re-simulated from the truth's
    parameters with and without the effect, without the repeatability offsets, and
    identified by gen_dev's own drive-point fit (f, zeta and their sd: CRLB and the
    drawn repeatability). ``data``: one row per level (repeats left out by the caller).
    None for other cases."""
    g = _gen_dev(str(gen_dev_path))
    c = truth["parameters"]
    if len(c["kinds"]) != 1:
        return None
    n = int(c["n_levels"])
    lv = np.asarray(data.level, int) - 1

    def table(drop):
        w = g.ident_levels(c, g.sim_levels(c, drop, rep=False))
        f = np.array([w[v]["f"] for v in range(n)])[lv]
        return ((2 * np.pi * f) ** 2, np.array([w[v]["zeta"] for v in range(n)])[lv],
                np.array([w[v]["sd_f"] for v in range(n)])[lv],
                np.array([w[v]["sd_z"] for v in range(n)])[lv])
    w2, z, sd_f, sd_z = table(())
    c2, cz, _, _ = table((c["kinds"][0],))
    return noncentrality(data, (w2, z), (c2, cz), 2 * sd_f * w2, sd_z)
