"""chi recovered by the case-file FE update from tables simulated by another route.

For each seed, :func:`cases.stepped_sine_test.simulate` makes the table of a
case file (Jenkins banks, multi-harmonic stepped sine, LSCF; a seeded chi), and the base
FE-levels model (:class:`feloop.case_levels.CaseLevels`, exact describing function at
phase resonance) is fitted to levels 1-7 as ``update`` does. Prints the seeded and the
fitted chi, their difference and whether the seeded one lies within the fit's
linearized 95 % interval; and, as a control, the fit to phase-resonance data of the same
joint (:func:`cases.virtual_test.simulated_table`: the fit's own route).

``python benchmarks/bench_case_file_chi.py [CASE.toml] [--seeds 20 21 22]``
"""
from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from feloop.case_levels import CaseLevels
from casefile.nonlinear import nonlinear_case
from cases.stepped_sine_test import SIGMA_OMEGA2, SIGMA_ZETA, simulate
from cases.virtual_test import simulated_table
from feloop.levels import Simulator
from feloop.select import base_parameters, fe_noise, fit_base
from cases.registry import resolve_case
from inverse.update import NoiseModel, UpdateProblem


def fit_chi(case, data, noise=None):
    fe = CaseLevels.from_data(data, cf=case.file)
    mask = data.level <= 7
    noise = fe_noise(data)[1] if noise is None else noise
    P, starts = base_parameters(data, mask, fe)
    f, _, _ = fit_base(UpdateProblem(Simulator(fe), data.omega2, data.zeta, noise, mask, P), starts)
    return f


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default="docs/case-files/bolted-lap-cantilever.toml")
    ap.add_argument("--seeds", type=int, nargs="+", default=[20, 21, 22])
    args = ap.parse_args(argv)
    case = resolve_case(args.case)
    print(f"{'seed':>4} {'chi seeded':>10} {'fitted':>8} {'error':>7} {'in 95%':>6} "
          f"{'phase-resonance control':>24}")
    for seed in args.seeds:
        data, truth = simulate(case, seed)
        f = fit_chi(case, data)
        sd = f.std_error("chi")
        cf, _ = case.require("calibrated_file")()
        cf = dataclasses.replace(cf, interfaces=tuple(
            dataclasses.replace(i, chi=truth["chi"]) if i.tangential == "joint" else i
            for i in cf.interfaces))
        pr = simulated_table(nonlinear_case(cf, case.fe_model()), data.excitation)
        pr.run_order = data.run_order
        g = fit_chi(case, pr, NoiseModel(SIGMA_OMEGA2 * pr.omega2, SIGMA_ZETA * pr.zeta, "assumed"))
        inside = abs(f.values["chi"] - truth["chi"]) <= 1.96 * sd if np.isfinite(sd) else "n/a"
        print(f"{seed:4d} {truth['chi']:10.4f} {f.values['chi']:8.4f} "
              f"{f.values['chi'] - truth['chi']:+7.4f} {str(inside):>6} "
              f"{g.values['chi'] - truth['chi']:+24.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
