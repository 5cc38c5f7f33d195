"""``iwanfe reproduce TARGET``: rerun a study of the paper and compare with its numbers.

Targets:

* ``lumped``: the 10-DOF model of paper section 3 (eq. 38-40). A stepped-sine
  campaign (12 levels x 0.5 Hz lines, 40-320 Hz) gives Fig. 4; LSCF identification
  of modes 2, 4, 6 at each level, the joint amplitudes at the identified resonances
  (Table 1), the chi fit of eq. 35 (Fig. 5) and the R errors of eq. 37 (Table 2) are
  printed beside the paper's values; then the improved method (simulated joint
  amplitudes, exact kappas, no modal decoupling; :func:`cases.lumped10.fit_improved`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cases.jsonio import print_json

NAME = "reproduce"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="rerun a study of the paper (lumped: section 3) and compare with its tables",
        description=(
            "Reproduce a study of the paper. 'lumped': the 10-DOF model of section 3 "
            "(eq. 38-40): stepped-sine FRFs at 12 force levels (Fig. 4), identified modes "
            "2, 4, 6, joint amplitudes at resonance (Table 1), the chi fit (Fig. 5, eq. 35) "
            "and R errors (Table 2, eq. 37) beside the paper's values, and the improved "
            "method. The campaign is stored under --out and resumes after an interruption."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("target", choices=sorted(TARGETS), help="study to reproduce")
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="output directory (figures, campaign store); default "
                             "results/<target>")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--protocol", choices=("default", "newmark", "paper"), default="default",
                        help="default: harmonic balance + continuation (seconds); newmark: "
                             "time integration until periodic, state carried between lines; "
                             "paper: Newmark 9 s + 1 s per line from rest (hours)")
    parser.add_argument("--n-sliders", type=int, default=100,
                        help="Jenkins elements per Iwan joint")
    parser.add_argument("--workers", type=int, default=1,
                        help="force levels computed in parallel processes")
    parser.add_argument("--bands-only", action="store_true",
                        help="only the lines of the identification bands of modes 2, 4, 6")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    parser.set_defaults(func=run)


def _fmt(x, spec=".5f"):
    return "nan" if x is None or not np.isfinite(x) else format(x, spec)


def _lumped_text(rep, files) -> str:
    d = rep.to_dict()
    lines = []
    top = rep.topology
    lines.append("10-DOF lumped model (paper section 3, eq. 38-40)")
    lines.append("Topology check (stuck joints):")
    for i, f in enumerate(top.frequency_hz):
        kind = "moves joints" if top.moves_joints[i] else "in phase at the interface"
        s = top.joint_slip[i]
        lines.append(f"  mode {i + 1:2d} {f:9.3f} Hz  {kind:26s} slips G phi = "
                     f"({s[0]:+.4f}, {s[1]:+.4f})")
    lines.append(f"Campaign: {rep.campaign.frequency_hz.size} lines x "
                 f"{rep.campaign.force.size} levels, protocol {rep.protocol}, "
                 f"{rep.timings['campaign']:.1f} s ({rep.timings['campaign_levels_computed']} "
                 f"levels computed, the rest loaded from the store)")
    lines.append("")
    lines.append("Table 1: joint slip amplitudes (m) at the identified resonance, ours | paper")
    for k, t in d["table1"].items():
        lines.append(f" mode {k}:  lvl  force N   f_id Hz    Iwan1      Iwan2    | paper Iwan1  Iwan2")
        for i in range(len(t["level"])):
            lines.append(f"         {t['level'][i]:3d} {t['force_N'][i]:7g} {_fmt(t['frequency_hz'][i], '9.3f')}"
                         f"  {t['iwan1'][i]:.3e}  {t['iwan2'][i]:.3e} |  {t['paper_iwan1'][i]:.5f}  "
                         f"{t['paper_iwan2'][i]:.5f}")
    lines.append("")
    lines.append("Fig. 5 / chi (true -0.5):   paper method | paper's value | amplitude "
                 "regression | improved (damping) | improved (damping + frequency)")
    for k in d["chi_paper_method"]:
        lines.append(f"  mode {k}: {d['chi_paper_method'][k]:+.4f} (levels "
                     f"{d['fit_levels'][k][0]}-{d['fit_levels'][k][-1]}) | "
                     f"{d['chi_paper_published'][k]:+.3f} | {d['chi_amplitude_regression'][k]:+.4f}"
                     f" | {d['chi_improved'][k]:+.4f} | {d['chi_improved_with_frequency'][k]:+.4f}")
    lines.append("")
    lines.append(f"R (true {rep.R_true:.4g}) error %:  paper method (fit, B~ simulated) | improved")
    for k, e in d["R_error_percent"].items():
        lines.append(f"  mode {k}: {e['paper_method']:+8.2f} | {e['improved']:+8.3f}")
    lines.append("")
    lines.append("Table 2: R error % per difference (eq. 37), ours inverse-matrix / simulated | "
                 "paper inverse-matrix / Newmark")
    for k, t in d["table2"].items():
        lines.append(f" mode {k}:")
        for i in t["nu_minus_1"]:
            lines.append(f"   nu-1={i:2d}  {_fmt(t['inverse_matrix'][i], '9.2f')} "
                         f"{_fmt(t['simulated'][i], '9.2f')} | {t['paper_inverse_matrix'][i]:9.3f} "
                         f"{t['paper_newmark'][i]:9.3f}")
    lines.append("")
    lines.append("Files: " + ", ".join(str(f) for f in files))
    return "\n".join(lines)


def _run_lumped(args) -> int:
    from cases.commands.estimate import plot_estimate
    from cases.lumped10 import MODE_BANDS, LumpedStudy, run_study
    from viz.frf_plots import plot_damping_growth, plot_frf_levels

    if args.n_sliders < 2:
        raise ValueError(f"--n-sliders must be >= 2, got {args.n_sliders}")
    if args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    out = Path(args.out or "results/lumped")
    out.mkdir(parents=True, exist_ok=True)
    study = LumpedStudy(n_sliders=args.n_sliders, bands_only=args.bands_only)
    rep = run_study(study, protocol=args.protocol, store=out, progress=not args.no_progress,
                    workers=args.workers)
    files = []
    camp = rep.campaign
    fig4 = out / "fig4_frf_levels.png"
    zooms = [(MODE_BANDS[m][0], MODE_BANDS[m][1], f"mode {m}") for m in study.modes]
    plot_frf_levels(camp.frequency_hz, camp.receptance[:, :, study.params.force_dof],
                    camp.force, zooms=zooms,
                    title=f"Driving-point receptance at m5, 12 levels ({rep.protocol})",
                    path=fig4)
    files.append(fig4)
    for m, mr in rep.modes.items():
        path = out / f"fig5_mode{m}.png"
        plot_estimate(mr.paper_estimate, str(path),
                      title=f"Fig. 5, mode {m}: paper method (true chi = -0.5)")
        files.append(path)
    panels = []
    for m, mr in rep.modes.items():
        imp = mr.improved
        used = np.isin(np.arange(1, imp.level_delta_c.size + 1), imp.levels)
        panels.append({"amplitude": imp.level_amplitude.max(axis=1), "delta_c": imp.level_delta_c,
                       "delta_c_model": imp.level_delta_c_model, "used": used,
                       "label": f"mode {m}",
                       "text": f"chi = {imp.chi:.4f}\nR = {imp.R:.4g}"})
    fig5b = out / "fig5_improved.png"
    plot_damping_growth(panels, path=fig5b,
                        title="Improved method: joint damping vs simulated joint amplitude")
    files.append(fig5b)
    if args.json:
        d = rep.to_dict()
        d["files"] = [str(f) for f in files]
        print_json(d)
    else:
        print(_lumped_text(rep, files))
    return 0


#: positional targets of ``iwanfe reproduce``; each takes the parsed args.
TARGETS = {"lumped": _run_lumped}


def run(args) -> int:
    return TARGETS[args.target](args)
