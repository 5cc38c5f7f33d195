"""``iwanfe reproduce TARGET --control response``: the case's virtual test under response
control, identified as measured data are, against its EPMC backbone and the true joint.

Each level holds the drive-point displacement amplitude that the case's force level
gives the stuck-joint structure at its mode's resonance
(:func:`cases.backbone_routes.linear_resonance_amplitude`: the same ratio between levels
as the paper's forces). The campaign runs on the bank path with the case's harmonic
balance (:mod:`runs.response_control`, stored and resumable under the output
directory), every level is identified by LSCF, the table is written as a measured-data
CSV with ``control = response``, the EPMC backbone is read at the held amplitudes, and
chi and R~ are estimated on the held amplitude (``amplitude`` method, the case's fit
levels, B~ from the FE model at 1 N per excitation unit).
"""
from __future__ import annotations

import time
from pathlib import Path

from cases.backbone_routes import epmc_route, linear_resonance_amplitude, response_route
from cases.nonlinear_case import build_nonlinear_case
from inverse.estimate import estimate

__all__ = ["response_reproduction"]


def response_reproduction(name: str, out, path: str = "bank", progress: bool = True,
                          executor=None) -> dict:
    """Run the response-controlled reproduction of case ``name`` (module docstring) and
    write ``simulated_measured_response.csv`` and ``backbone_response.png`` under ``out``.

    Returns
    -------
    dict
        ``levels`` (per level: held amplitude, force at resonance, identified and EPMC
        frequency and damping, largest slip over phi_max), ``estimate`` (chi, R~ and their
        errors against the true joint), ``files``, ``timings``.
    """
    from ident.measured import write_measured
    from viz.backbone_plot import plot_backbones

    t0 = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    case = build_nonlinear_case(name)
    held = linear_resonance_amplitude(case)
    data, slip = response_route(case, held, path, progress=progress, store=out,
                                executor=executor)
    t_campaign = time.perf_counter() - t0
    ref, _, bb = epmc_route(case, held, path)
    csv = out / "simulated_measured_response.csv"
    write_measured(csv, data)
    est = estimate(data, fit_levels=case.fit_levels, method="amplitude", model=case.fe_model,
                   fe_mode=case.mode, amplitude=held, case_name=case.name)
    png = out / "backbone_response.png"
    plot_backbones([{"label": "EPMC backbone", "amplitude": held, "style": "-",
                     "frequency_hz": ref.omega_hz, "zeta": ref.zeta},
                    {"label": "response-controlled test (LSCF)", "amplitude": held,
                     "style": "o", "frequency_hz": data.omega_hz, "zeta": data.zeta}],
                   xlabel="drive-point amplitude (m)", path=png,
                   title=f"{case.name}, mode {case.mode}: response control ({path} path)")
    ratio = slip.max(axis=1) / case.phi_max
    levels = [{"level": int(lv), "held_amplitude_m": float(a), "force_N": float(F),
               "frequency_hz": float(f), "epmc_frequency_hz": float(fe),
               "zeta": float(z), "epmc_zeta": float(ze), "slip_over_phi_max": float(r)}
              for lv, a, F, f, fe, z, ze, r in zip(data.level, held, data.excitation,
                                                    data.omega_hz, ref.omega_hz, data.zeta,
                                                    ref.zeta, ratio)]
    return {"case": case.name, "mode": case.mode, "path": path, "control": "response",
            "joint": {"chi": case.chi, "R": case.R, "phi_max": case.phi_max,
                      "source": case.joint_source},
            "levels": levels,
            "estimate": {"method": "amplitude", "fit_levels": case.fit_levels,
                         "chi": est.chi, "chi_error": est.chi - case.chi, "R": est.R,
                         "R_relative_error": est.R / case.R - 1.0, "B_tilde": est.B},
            "files": [str(csv), str(png)],
            "timings": {"campaign_s": t_campaign, "total_s": time.perf_counter() - t0},
            "epmc_points": len(bb)}
