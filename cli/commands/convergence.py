"""``iwanfe convergence``: mesh convergence of the beam element and of the double beam.

Example::

    iwanfe convergence --out results/convergence
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cli import validate
from cli.executor_options import add_executor_arguments, executor_from_args
from runs.jsonio import print_json, to_jsonable


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "convergence",
        help="mesh convergence: cantilever vs analytic, double beam vs refinement",
        description=(
            "Relative error of the first six cantilever frequencies against the analytic "
            "Euler-Bernoulli values under mesh refinement (observed rate, expected 4), and "
            "the double beam's measured mode (frequency, glue-slip participation) under "
            "refinement of the strip mesh and of the joints in the glued zone."
        ),
    )
    p.add_argument("--out", default=None, metavar="DIR",
                   help="write convergence.json, convergence.txt and convergence.png here")
    p.add_argument("--case", default=None, metavar="NAME|FILE",
                   help="a case (shipped name or case file): its first modes under halving "
                        "of its element size, against its own finest mesh (without --case: "
                        "the cantilever against the analytic values and the shipped default)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_executor_arguments(p)     # where the double-beam meshes run
    p.set_defaults(func=run)


def format_table(report: dict) -> str:
    """Human-readable tables of both studies."""
    c = report["cantilever"]
    err = np.asarray(c["relative_error"], float)
    n_modes = err.shape[1]
    lines = ["Cantilever strip (350 x 50 x 1 mm, E 70 GPa): relative frequency error vs analytic",
             "beta_n L = " + ", ".join(f"{b:.6f}" for b in c["beta_L"]),
             f"{'elements':>8} " + " ".join(f"{'mode ' + str(j + 1):>10}" for j in range(n_modes))]
    # an error within ROUNDOFF_MARGIN x its round-off bound reads round-off (its digits
    # are the BLAS kernel's), the rate over the truncation errors to two decimals
    resolved = np.asarray(c.get("truncation", np.isfinite(err)), bool)
    for n, row, ok in zip(c["elements"], err, resolved):
        lines.append(f"{n:>8} " + " ".join(
            f"{v:10.2e}" if np.isfinite(v) and good else
            f"{'round-off' if np.isfinite(v) else '-':>10}" for v, good in zip(row, ok)))
    lines.append(f"{'rate':>8} " + " ".join(f"{r:10.2f}" for r in c["rate"]))
    lines.append(f"{'best':>8} " + " ".join(f"{v:10.2e}" for v in c["best_error"]))
    lines.append(f"{'at n':>8} " + " ".join(f"{v:>10}" for v in c["best_elements"]))
    lines.append("finest mesh limited by: " + ", ".join(c["finest_limited_by"]))
    d = report["double_beam"]
    lines.append("")
    lines.append(f"Double beam, {d['mode']}")
    es = d["element_size_sweep"]
    lines += _sweep_table("elem_mm", [f"{1e3 * v:8.3f}" for v in es["element_size_m"]], es)
    js = d["joint_sweep"]
    lines += _sweep_table("joints", [f"{v:8d}" for v in js["n_joints"]], js)
    df = d["default"]
    lines.append(f"default mesh ({1e3 * df['element_size_m']:g} mm elements, "
                 f"{df['n_joints']} joints, "
                 f"{df['n_free_dofs']} DOFs): {df['frequency_hz']:.4f} Hz, estimated error "
                 f"{df['frequency_error_estimate']:.1e} (frequency), "
                 f"{df['glue_slip_error_estimate']:.1e} (glue slip)")
    return "\n".join(lines)


def run(args) -> int:
    if args.case is not None:
        return _run_case(args)
    from cases.convergence import convergence_report, joint_spacing

    if args.out:
        validate.output_dir(args.out, "--out")
    executor = executor_from_args(args)
    report = convergence_report(executor=executor)  # ~1 s serial: no progress bar
    table = format_table(report)
    if args.out:
        from viz.convergence_plot import plot_convergence

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "convergence.json").write_text(json.dumps(to_jsonable(report), indent=2) + "\n")
        (out / "convergence.txt").write_text(table + "\n")
        c, d = report["cantilever"], report["double_beam"]
        spacing = joint_spacing(d["joint_sweep"]["n_joints"][:-1])
        plot_convergence(
            out / "convergence.png", c["element_size_m"], c["relative_error"],
            title="Cantilever strip vs analytic Euler-Bernoulli",
            sweeps=[("strip elements: frequency", d["element_size_sweep"]["element_size_m"][:-1],
                     d["element_size_sweep"]["frequency_relative_change"][:-1]),
                    ("joints: frequency", spacing,
                     d["joint_sweep"]["frequency_relative_change"][:-1]),
                    ("joints: glue slip", spacing,
                     d["joint_sweep"]["glue_slip_relative_change"][:-1])],
        )
    if args.json:
        print_json(report)
    else:
        print(table)
        if args.out:
            print(f"wrote {Path(args.out) / 'convergence.png'}, convergence.json, convergence.txt")
    return 0


def _sweep_table(label: str, refinement: list[str], sweep: dict) -> list[str]:
    """Lines of one double-beam refinement table: frequency and glue slip of the measured
    mode per mesh, their relative change against the finest mesh, the observed rates."""
    lines = [f"{label:>8} {'dofs':>6} {'freq_Hz':>12} {'rel_change':>11} {'glue_slip':>10} "
             f"{'rel_change':>11}"]
    for i, r in enumerate(refinement):
        lines.append(f"{r} {sweep['n_free_dofs'][i]:6d} {sweep['frequency_hz'][i]:12.6f} "
                     f"{sweep['frequency_relative_change'][i]:11.2e} {sweep['glue_slip'][i]:10.4e} "
                     f"{sweep['glue_slip_relative_change'][i]:11.2e}")
    lines.append(f"observed rate: frequency {sweep['frequency_rate']:.2f}, "
                 f"glue slip {sweep['glue_slip_rate']:.2f}")
    return lines


def _run_case(args) -> int:
    from cases.case_convergence import case_convergence, format_case_convergence
    from cases.registry import resolve_case

    if args.out:
        raise ValueError("--out is not available with --case (print --json instead)")
    case = resolve_case(args.case)
    case.require("fe_model")
    report = case_convergence(case)
    if args.json:
        print_json(report)
    else:
        print(format_case_convergence(report))
    return 0
