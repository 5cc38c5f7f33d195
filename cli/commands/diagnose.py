"""``iwanfe diagnose``: what the Iwan modal model gets wrong, the cause, and the gain.

Reads a measured-data CSV (``shared/spec/measured-data.md``), fits the base model (one
micro-slip Iwan joint, amplitude proportional to excitation, frequency drop and damping
growth tied through chi) and one extension per cause of ``shared/spec/diagnosis.md``,
names the cause that earns its extra parameters (AICc drop and a cross-validated gain)
or ``none``, and reports the base and extended errors on held-out levels.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cli import validate
from cases.registry import CASES, MEASURED_DATA, fe_check
from cli.series_options import add_series_arguments, series_from_args
from inverse.diagnose import AICC_THRESHOLD, CANDIDATES, diagnose
from ident.errors import InputError
from runs.jsonio import print_json, to_jsonable
from ident.measured import read_measured

NAME = "diagnose"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="name what the Iwan model gets wrong in amplitude-dependent modal data",
        description=(
            "Fit the base model (one micro-slip four-parameter Iwan joint on the mode, "
            "joint amplitude proportional to the excitation; frequency drop and damping "
            "growth tied by the exact kappa2/|kappa1| of chi) jointly to omega2 and zeta, "
            "and one extension per cause: macro-slip, nonproportional-amplitude, "
            "geometric-hardening, thermal-drift, quadratic-damping. The cause is the "
            "extension with the largest AICc drop, if it exceeds "
            f"{AICC_THRESHOLD:g} and lowers the leave-one-level-out prediction error; "
            "else none. Errors are rms held-out prediction errors in noise units."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_series_arguments(parser, required=False)   # FILE...: a table or FRF files
    parser.add_argument("--case", default=None, metavar="NAME",
                        help="instead of FILE: 'double-beam' (the shipped paper data) or "
                             "'synthetic:CAUSE:SEED' (a simulated test hiding CAUSE)")
    parser.add_argument("--mode", type=int, default=None,
                        help="mode label in the file (default: the only/first one)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="write report.md, diagnosis.json and the PNG figures there")
    parser.add_argument("--cv-all", action="store_true",
                        help="cross-validate every candidate, not only those past the "
                             "AICc threshold")
    parser.set_defaults(func=run)


def load(file: str | None, case: str | None, args=None):
    """The MeasuredData to diagnose, and the hidden truth for synthetic cases.

    ``FILE`` alone, ``--case`` alone (its shipped data or a synthetic case), or ``FILE``
    with a model case (``--case double-beam``: the file's data, the case's FE check).
    """
    if file is None and case is None:
        raise InputError("give FILE, --case NAME, or both (FILE with a model case)")
    if file is not None:
        if case is not None and case not in CASES:
            raise InputError(f"--case {case!r} with FILE: the case must be a model "
                             f"({', '.join(CASES)})")
        return (series_from_args(args) if args is not None else read_measured(file)), None
    if case in MEASURED_DATA:
        return read_measured(MEASURED_DATA[case]), None
    parts = case.split(":")
    if len(parts) == 3 and parts[0] == "synthetic":
        from cases.synthetic import CAUSES, generate_case

        if parts[1] not in CAUSES:
            raise InputError(f"--case: unknown cause {parts[1]!r}; choose from "
                             f"{', '.join(CAUSES)}")
        try:
            seed = int(parts[2])
        except ValueError:
            raise InputError(f"--case: seed must be an integer, got {parts[2]!r}") from None
        c = generate_case(parts[1], seed)
        return c.data, {"cause": c.cause, "seed": seed,
                        "effect_size": c.truth["effect_sigma"], "chi": c.truth["chi"]}
    raise InputError(f"--case: unknown case {case!r}; use "
                     f"{', '.join(MEASURED_DATA)} or synthetic:CAUSE:SEED")


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def format_text(result: dict, source: str) -> str:
    """Human-readable summary of a diagnosis."""
    r = result
    lines = [f"{source}: mode {r['mode']}",
             f"cause: {r['cause']}",
             f"  {r['summary']}",
             f"base error {r['base_error']:.3f}, extended error {r['extended_error']:.3f}, "
             f"gain {r['gain']:.3f}  ({r['error_measure']})",
             "parameters (" + r["parameters"]["model"] + "):"]
    for k, v in r["parameters"].items():
        if k != "model":
            lines.append(f"  {k:24s} {_fmt(v)}")
    lines.append(f"evidence (AICc drop vs base; named if > {r['aicc_threshold']:g} and "
                 f"cv gain > 1):")
    for c in CANDIDATES:
        e = r["evidence"][c]
        if not e["available"]:
            lines.append(f"  {c:26s} n/a ({e['reason']})")
            continue
        cv = f"  cv gain {e['cv_gain']:.3f}" if "cv_gain" in e else ""
        lines.append(f"  {c:26s} dAICc {e['delta_aicc']:8.2f}  dBIC {e['delta_bic']:8.2f}"
                     f"  +{e['extra_parameters']} par{cv}")
    for w in r["data_warnings"]:
        lines.append(f"warning: {w}")
    if "synthetic_truth" in r:
        t = r["synthetic_truth"]
        lines.append(f"synthetic truth: cause {t['cause']}, effect size "
                     f"{t['effect_size']:.3g}, chi {t['chi']:.3f}")
    if "fe_check" in r:
        from cases.double_beam.fe_check import format_fe_check

        lines.extend(format_fe_check(r["fe_check"]))
    if "fe" in r:
        from cases.double_beam.fe_diagnosis_report import format_fe
        lines.extend(format_fe(r["fe"]))
    return "\n".join(lines)


def write_report(result: dict, out: Path, source: str) -> list[Path]:
    """Write report.md, diagnosis.json, diagnosis_fits.png and diagnosis_evidence.png."""
    import json

    from viz.diagnosis_plots import plot_diagnosis_fits, plot_evidence

    out.mkdir(parents=True, exist_ok=True)
    r, lv = result, result["levels"]
    noise = r["noise"]
    resp = lv["response_amplitude"]
    kw = {}
    if resp is not None:
        kw = dict(response=resp, base_response=np.exp(lv["base_log_response"]),
                  extended_response=np.exp(lv["extended_log_response"]),
                  sigma_response=noise["sigma_response"])
    fits_png = out / "diagnosis_fits.png"
    plot_diagnosis_fits(lv["excitation"], lv["omega2"], lv["zeta"], lv["base_omega2"],
                        lv["base_zeta"], lv["extended_omega2"], lv["extended_zeta"],
                        noise["sigma_omega2"], noise["sigma_zeta"],
                        extended_label=f"extended: {r['cause']}",
                        title=f"{source}, mode {r['mode']}: cause = {r['cause']}",
                        path=fits_png, **kw)
    ev_png = out / "diagnosis_evidence.png"
    names = list(CANDIDATES)
    d = [r["evidence"][c].get("delta_aicc", np.nan) for c in names]
    gains = {c: r["evidence"][c]["cv_gain"] for c in names if "cv_gain" in r["evidence"][c]}
    plot_evidence(names, d, r["aicc_threshold"], chosen=r["cause"], cv_gain=gains,
                  title="evidence against the base model", path=ev_png)
    json_path = out / "diagnosis.json"
    json_path.write_text(json.dumps(to_jsonable(r), indent=2) + "\n", encoding="utf-8")

    rows = "\n".join(f"| {k} | {_fmt(v)} |" for k, v in r["parameters"].items()
                     if k != "model")
    ev_rows = []
    for c in names:
        e = r["evidence"][c]
        if not e["available"]:
            ev_rows.append(f"| {c} | n/a | n/a | | {e['reason']} |")
        else:
            g = f"{e['cv_gain']:.3f}" if "cv_gain" in e else ""
            ev_rows.append(f"| {c} | {e['delta_aicc']:.2f} | {e['delta_bic']:.2f} | {g} | "
                           f"+{e['extra_parameters']} parameters |")
    warn = "\n".join(f"- {w}" for w in r["data_warnings"]) or "- none"
    md = f"""# Diagnosis of {source}, mode {r['mode']}

**Cause: `{r['cause']}`**

{r['summary']}

| | value |
| --- | --- |
| base error | {r['base_error']:.3f} |
| extended error | {r['extended_error']:.3f} |
| gain (base / extended) | {r['gain']:.3f} |

Error measure: {r['error_measure']}. Noise levels (from the `{noise['from_model']}`
fit): sigma_omega2 = {noise['sigma_omega2']:.4g} rad^2/s^2, sigma_zeta =
{noise['sigma_zeta']:.3g}.

## Parameters of the {'base' if r['cause'] == 'none' else 'extended'} model (`{r['parameters']['model']}`)

| parameter | value |
| --- | --- |
{rows}

## Evidence (every candidate against the base)

A cause is named when its AICc drop exceeds {r['aicc_threshold']:g} and its
cross-validated error is below the base model's.

| candidate | AICc drop | BIC drop | cv gain | note |
| --- | --- | --- | --- | --- |
{chr(10).join(ev_rows)}

![evidence](diagnosis_evidence.png)

## Data, fits and residuals

Top: data (black), base model (blue dashed), extended model (red). Bottom: residuals
in units of the noise level (grey band: +/- 2).

![fits](diagnosis_fits.png)

## Data warnings

{warn}
"""
    if "fe_check" in r:
        from cases.double_beam.fe_check import format_fe_check_md

        md += "\n" + format_fe_check_md(r["fe_check"])
    report = out / "report.md"
    report.write_text(md, encoding="utf-8")
    return [report, json_path, fits_png, ev_png]


def run(args) -> int:
    if args.out:
        validate.output_dir(args.out, "--out")   # cli.validate: one output-path rule
    args.file = " ".join(args.files) or None
    data, truth = load(args.file, args.case, args)
    source = args.file or args.case
    result = diagnose(data, mode=args.mode, cv_all=args.cv_all)
    if truth is not None:
        result["synthetic_truth"] = truth
    if args.case in CASES:  # a model case: its FE-level check
        level1 = data.for_mode(result["mode"]) if "mode" in result else data
        result["fe_check"] = fe_check(args.case, float(level1.omega2[0]))
    if args.case == "double-beam":  # the FE model refitted, base vs extended (issue 13)
        from cases.double_beam.fe_diagnosis_report import add_fe_diagnosis
        add_fe_diagnosis(result, data, out=args.out)
    if args.out:
        write_report(result, Path(args.out), Path(source).name if args.file else source)
    if args.json:
        print_json(result)
    else:
        print(format_text(result, source))
        if args.out:
            print(f"report: {Path(args.out) / 'report.md'}")
    return 0
