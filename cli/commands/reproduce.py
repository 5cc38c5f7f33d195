"""``iwanfe reproduce TARGET``: rerun a study of the paper and compare with its numbers.

Targets:

* ``lumped``: the 10-DOF model of paper section 3 (eq. 38-40). A stepped-sine
  campaign (12 levels x 0.5 Hz lines, 40-320 Hz) gives Fig. 4; LSCF identification
  of modes 2, 4, 6 at each level, the joint amplitudes at the identified resonances
  (Table 1), the chi fit of eq. 35 (Fig. 5) and the R errors of eq. 37 (Table 2) are
  printed beside the paper's values; then the improved method (simulated joint
  amplitudes, exact kappas, no modal decoupling; :func:`cases.lumped10.improved_fit.fit_improved`).
* ``double-beam``: the FE double beam of paper section 4 with one Iwan element per glue
  node (chi and R~ from the measured levels 1-7), driven through the paper's 10-level
  stepped-sine campaign (5 mV .. 2.56 V); per-level frequency and damping identified
  from the simulated FRFs; chi and R estimated by each method (paper, exact,
  amplitude) from the measured levels 1-7 and levels 8-10 predicted; the same on the
  simulated data; Tables 3-6 beside the paper's, measured vs simulated per level
  (:mod:`cases.double_beam.study`). Writes report.md, report.json,
  simulated_measured.csv and PNGs under --out.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from cli import validate
from cli.executor_options import add_executor_arguments, executor_from_args
from runs.jsonio import print_json

NAME = "reproduce"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="rerun a study of the paper (lumped: section 3; double-beam: section 4) and "
             "compare with its tables",
        description=(
            "Reproduce a study of the paper. 'lumped': the 10-DOF model of section 3 "
            "(eq. 38-40): stepped-sine FRFs at 12 force levels (Fig. 4), identified modes "
            "2, 4, 6, joint amplitudes at resonance (Table 1), the chi fit (Fig. 5, eq. 35) "
            "and R errors (Table 2, eq. 37) beside the paper's values, and the improved "
            "method. 'double-beam': the FE double beam of section 4 with Iwan glue joints "
            "(chi, R~ from measured levels 1-7) through the 10-level stepped-sine campaign; "
            "identified frequency and damping per level, chi and R per method on the "
            "measured and the simulated data, predictions of levels 8-10, Tables 3-6 beside "
            "the paper's, measured vs simulated per level (report.md, report.json, PNGs). "
            "The campaign is stored under --out and resumes after an interruption."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("target", choices=sorted(TARGETS), help="study to reproduce")
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="output directory (figures, campaign store); default "
                             "results/<target>")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--protocol", choices=("default", "newmark", "paper"), default="default",
                        help="default: harmonic balance + continuation (seconds); newmark: "
                             "time integration until periodic (lumped: state carried between "
                             "lines; double-beam: every line started on its harmonic-balance "
                             "orbit, then both runs identified and compared per level); "
                             "paper (lumped only): Newmark 9 s + 1 s per line from rest (hours)")
    parser.add_argument("--n-sliders", type=int, default=100,
                        help="Jenkins elements per Iwan joint")
    parser.add_argument("--bands-only", action="store_true",
                        help="only the lines of the identification bands of modes 2, 4, 6")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_executor_arguments(parser)     # --workers/--scheduler/--executor: where levels run
    parser.add_argument("--control", choices=("force", "response"), default="force",
                        help="response: each level holds the drive-point amplitude "
                             "(cases.response_study; iwanfe backbone)")
    db = parser.add_argument_group("double-beam only")
    db.add_argument("--data", default=argparse.SUPPRESS, metavar="FILE",
                    help="measured-data CSV (default: the shipped paper data)")
    db.add_argument("--fit-levels", default=argparse.SUPPRESS, metavar="LEVELS",
                    help="levels of the chi fit (default 1-7); the others are predicted")
    db.add_argument("--force-scale", type=float, default=argparse.SUPPRESS, metavar="N_PER_V",
                    help="force per volt of drive (default 1; an assumption: R~ and phi_max "
                         "scale with it, the simulated modal data do not)")
    db.add_argument("--beta", type=float, default=argparse.SUPPRESS,
                    help="Iwan beta of the glue joints (default 0: the largest phi_max)")
    db.add_argument("--chi", type=float, default=argparse.SUPPRESS,
                    help="joint chi instead of the estimate of the measured fit levels")
    db.add_argument("--R", type=float, default=argparse.SUPPRESS, dest="R_joint",
                    metavar="R",
                    help="total glue R (N/m^(chi+2)) instead of the estimate's R~")
    db.add_argument("--band", type=float, nargs=2, default=argparse.SUPPRESS,
                    metavar=("LO", "HI"),
                    help="stepped-sine lines and identification band, Hz (default 236 268)")
    db.add_argument("--df", type=float, default=argparse.SUPPRESS, metavar="HZ",
                    help="line spacing, Hz (default 0.5; the paper stepped 2 Hz)")
    db.add_argument("--sliders-per-octave", type=int, default=argparse.SUPPRESS,
                    help="Jenkins sliders per octave of slip limit (default 16)")
    db.add_argument("--glue-kt", type=float, default=argparse.SUPPRESS, metavar="N_PER_M",
                    help="stuck tangential stiffness K_T of the whole glue, 1e6..1e11 N/m "
                         "(default 1e8, assumed); the clamp grip is re-calibrated so that the "
                         "measured mode stays at 252.0 Hz")
    db.add_argument("--no-weak-joint-runs", action="store_true", default=argparse.SUPPRESS,
                    help="skip the two reruns with R/10 and R/100 (estimator recovery)")
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
    lines.append(f"Steady states reached by a fallback: {rep.campaign.fallback_summary()}")
    lines.append("")
    lines.append("Table 1: joint slip amplitudes (m) at the identified resonance, ours | paper")
    for k, t in d["table1"].items():
        lines.append(f" mode {k}:  lvl  force N   f_id Hz    Iwan1      Iwan2    "
                     "| paper Iwan1  Iwan2")
        for i in range(len(t["level"])):
            lines.append(f"         {t['level'][i]:3d} {t['force_N'][i]:7g} "
                         f"{_fmt(t['frequency_hz'][i], '9.3f')}"
                         f"  {t['iwan1'][i]:.3e}  {t['iwan2'][i]:.3e} |  "
                         f"{t['paper_iwan1'][i]:.5f}  "
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


_DOUBLE_BEAM_ONLY = ("data", "fit_levels", "force_scale", "beta", "chi", "R_joint", "band", "df",
                     "sliders_per_octave", "no_weak_joint_runs", "glue_kt")


def _run_lumped(args) -> int:
    from viz.logslope import plot_estimate
    from cases.lumped10.study import MODE_BANDS, LumpedStudy, run_study
    from viz.frf_plots import plot_damping_growth, plot_frf_levels

    for name in _DOUBLE_BEAM_ONLY:
        if getattr(args, name, None) is not None:
            raise ValueError(f"--{name.replace('_joint', '').replace('_', '-')} applies to the "
                             f"double-beam target only")
    if not 2 <= args.n_sliders <= validate.MAX_SLIDERS:
        raise ValueError(f"--n-sliders {args.n_sliders}: must be in 2..{validate.MAX_SLIDERS}")
    executor = executor_from_args(args)
    out = validate.output_dir(args.out or "results/lumped", "--out")
    out.mkdir(parents=True, exist_ok=True)
    study = LumpedStudy(n_sliders=args.n_sliders, bands_only=args.bands_only)
    rep = run_study(study, protocol=args.protocol, store=out, progress=not args.no_progress,
                    executor=executor)
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


def _double_beam_study(args):
    from cases.double_beam.settings import DoubleBeamStudy

    if args.protocol == "paper":
        raise ValueError("--protocol paper applies to the lumped target only (double-beam: "
                         "default or newmark)")
    if args.bands_only:
        raise ValueError("--bands-only applies to the lumped target only")
    if args.n_sliders != 100:
        raise ValueError("--n-sliders applies to the lumped target only (double-beam: "
                         "--sliders-per-octave)")
    kw = {}
    for name, key in (("data", "data_path"), ("fit_levels", "fit_levels"),
                      ("force_scale", "force_scale"), ("beta", "beta"), ("chi", "chi"),
                      ("R_joint", "R"), ("df", "df_hz"),
                      ("sliders_per_octave", "sliders_per_octave")):
        v = getattr(args, name, None)
        if v is not None:
            if isinstance(v, float) and not math.isfinite(v):
                raise ValueError(f"--{name.replace('_joint', '').replace('_', '-')} must be "
                                 f"finite, got {v}")
            kw[key] = v
    if getattr(args, "band", None) is not None:
        kw["band_hz"] = tuple(args.band)
    if getattr(args, "no_weak_joint_runs", False):
        kw["weak_joint_scales"] = ()
    if "data_path" in kw and not Path(kw["data_path"]).is_file():
        raise ValueError(f"--data: no such file: {kw['data_path']}")
    return DoubleBeamStudy(**kw)


def _double_beam_text(rep, files, wall) -> str:
    from cases.double_beam.statements import headline

    solver = "harmonic balance" if rep.protocol == "hb" else "Newmark time integration"
    lines = ["Double beam (paper section 4): FE model + Iwan glue joints, "
             f"{rep.campaign.force.size} levels x {rep.campaign.frequency_hz.size} lines "
             f"({solver})"]
    if rep.calibration is not None:
        lines.append(f"Model: {rep.calibration['statement']}")
    lines.append("")
    lines += [f"- {s}" for s in headline(rep)]
    lines.append("")
    if rep.protocol_comparison is not None:
        from cases.double_beam.protocols import comparison_lines

        lines += comparison_lines(rep.protocol_comparison) + [""]
    lines.append(" level  drive V   omega^2 meas   omega^2 sim     diff   zeta meas %  "
                 "zeta sim %      diff %   slip/phi_max")
    for r in rep.comparison():
        lines.append(f" {r['level']:>4}{'*' if r['held_out'] else ' '} {r['excitation_V']:8.3f} "
                     f"{r['measured_omega2']:13.1f} {r['simulated_omega2']:13.1f} "
                     f"{r['omega2_difference']:+8.1f}   {100 * r['measured_zeta']:9.5f}  "
                     f"{100 * r['simulated_zeta']:9.5f}  {100 * r['zeta_difference']:+9.5f}  "
                     f"{r['slip_over_phi_max']:10.4f}")
    lines.append("  (* = held out of the fit; diff = simulated - measured)")
    lines.append("")
    tab = rep.tables()
    methods = list(tab["table3_delta_omega2"][0]["methods"]) if tab["table3_delta_omega2"] else []
    lines.append("Held-out predictions (Tables 3 and 5), error % = 100 (pred - meas)/meas:")
    head = "  levels   quantity          measured      paper(pub)  " + "  ".join(
        f"{k:>18s}" for k in methods)
    lines.append(head)
    for t3, t5 in zip(tab["table3_delta_omega2"], tab["table5_delta_zeta_percent"]):
        if not t3["held_out"]:
            continue
        for name, r, spec in (("loss omega^2", t3, "10.2f"), ("growth zeta %", t5, "10.3e")):
            pub = r["paper"]["estimate"]
            cells = []
            for k in methods:
                v, e = r["methods"][k]["value"], r["methods"][k]["error_percent"]
                cells.append(f"{format(v, spec) if v is not None else 'nan':>10s} "
                             f"({_fmt(e, '+.1f'):>6s})")
            lines.append(f"  {t3['from_level']:>2}->{t3['to_level']:<3}  {name:14s} "
                         f"{format(r['measured'], spec)}  "
                         f"{format(pub, spec) if pub is not None else '       nan'}  "
                         + "  ".join(cells))
    lines.append("")
    lines.append(f"Files ({Path(files[0]).parent}): " + ", ".join(Path(f).name for f in files))
    if "campaign_hb_check" in rep.timings:
        lines.append(f"Harmonic-balance check run and identified in "
                     f"{rep.timings['campaign_hb_check']:.1f} s")
    lines.append(f"Wall time {wall:.1f} s (campaign {rep.timings['campaign']:.1f} s, "
                 f"{int(rep.campaign.computed.sum())} of {rep.campaign.force.size} levels "
                 f"computed; weak-joint reruns {rep.timings.get('weak_joint_runs', 0.0):.1f} s)")
    lines.append(f"Steady states reached by a fallback: {rep.campaign.fallback_summary()}")
    return "\n".join(lines)


def _run_double_beam(args) -> int:
    from cases.double_beam.files import write_report
    from cases.double_beam.settings import measured_levels
    from cases.double_beam.calibration import calibrated_model
    from cases.double_beam.study import run_study
    t0 = time.perf_counter()
    study = _double_beam_study(args)
    glue_kt = getattr(args, "glue_kt", None)
    validate.stepped_sine(study, measured_levels(study))   # before the campaign
    executor = executor_from_args(args)
    out = validate.output_dir(args.out or "results/double-beam", "--out")
    progress = not args.no_progress
    model, calibration = calibrated_model(glue_kt)
    out.mkdir(parents=True, exist_ok=True)
    protocol = "hb" if args.protocol == "default" else args.protocol
    if progress:
        print(f"iwanfe reproduce double-beam: {study.n_levels} levels x {study.lines.size} "
              f"lines, {calibration.statement()}, store {out}", file=sys.stderr)
    try:
        rep = run_study(study, store=out, progress=progress, executor=executor, model=model,
                        protocol=protocol, calibration=calibration)
    except RuntimeError as exc:     # no steady state (SteadyStateError), no mode identified
        print(f"iwanfe: {exc}".splitlines()[0], file=sys.stderr)
        return 1
    files = write_report(rep, out, t0)
    wall = time.perf_counter() - t0
    if args.json:
        print_json(rep.to_dict())
    else:
        print(_double_beam_text(rep, files, wall))
    return 0


#: positional targets of ``iwanfe reproduce``; each takes the parsed args.
TARGETS = {"lumped": _run_lumped, "double-beam": _run_double_beam}


def run(args) -> int:
    if args.control == "response":
        from cli.commands.backbone import run_response_control
        return run_response_control(args)
    return TARGETS[args.target](args)
