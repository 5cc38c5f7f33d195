"""``iwanfe diagnose``: what the Iwan modal model gets wrong, the cause(s), and the gain.

Reads a measured-data CSV (``docs/formats/measured-data.md``) and runs
:func:`inverse.diagnose.diagnose` (``docs/formats/diagnosis.md`` v2): the base model
(one micro-slip Iwan joint), each cause of the catalogue and every pair, weighed by
AIC against the noise of the data; contradictions stated with numbers; ``none`` /
a cause (+ ``also``) / ``unexplained``; errors on held-out levels.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from cli import validate
from cases.registry import resolve_case
from cli.commands.diagnose_report import noise_words
from cli.rig_options import add_rig_argument, rig_from_args
from cli.series_options import add_series_arguments, series_from_args
from ident.errors import InputError
from ident.measured import read_measured
from inverse.diagnose import T_CAUSE, W_AMBIGUOUS, diagnose
from runs.jsonio import print_json, to_jsonable

NAME = "diagnose"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        NAME,
        help="name what the Iwan model gets wrong in amplitude-dependent modal data",
        description=(
            "Fit the base model (one micro-slip four-parameter Iwan joint on the mode; "
            "frequency drop and damping growth tied by the exact kappa2/|kappa1| of "
            "chi), each cause of the catalogue (macro-slip, nonproportional-amplitude, "
            "geometric-hardening, thermal-drift, quadratic-damping) and every pair of "
            "them, against the noise of the data (the identification's stds plus the "
            "test's repeatability: from repeated levels, else the scatter about a smooth "
            "curve). Weights are Akaike weights with a cost of "
            f"{T_CAUSE:g} in AIC per cause; an explanation with at least "
            f"{W_AMBIGUOUS:.2g} of the named one's weight makes it ambiguous. "
            "Contradictions with the Iwan model are stated with numbers; when no "
            "candidate brings the data within their noise the cause is unexplained. "
            "Errors: rms standardized prediction errors on held-out levels."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_series_arguments(parser, required=False)   # FILE...: a table or FRF files
    parser.add_argument("--case", default=None, metavar="NAME|FILE",
                        help="instead of FILE: a case (shipped name or case file) with its "
                             "measured data, or 'synthetic:LABEL:SEED' (a simulated, "
                             "identified series hiding LABEL: none, a cause, two causes "
                             "joined by '+', or out-of-catalogue); with FILE: the model "
                             "case. A case with an FE-levels model (joints of one law) also gets "
                             "the FE-level diagnosis")
    parser.add_argument("--mode", type=int, default=None,
                        help="mode label in the file (default: the only/first one)")
    parser.add_argument("--backbone", action="store_true",
                        help="with FILE and --case (a case with a joint setup): also "
                             "predict every level from the FE backbone (EPMC) of the joint "
                             "estimated from the levels "
                             "below the top three (iwanfe estimate --backbone)")
    add_rig_argument(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="write report.md, diagnosis.json and the PNG figures there")
    parser.set_defaults(func=run)


def load(file: str | None, case: str | None, args=None):
    """The MeasuredData to diagnose, and the hidden truth for synthetic cases.

    ``FILE`` alone, ``--case`` alone (its measured data or a synthetic case), or ``FILE``
    with a model case (the file's data, the case's FE-level checks).
    """
    if file is None and case is None:
        raise InputError("give FILE, --case NAME|FILE, or both (FILE with a model case)")
    if file is not None:
        if case is not None:
            resolve_case(case)          # a model case: one line when unknown
        return (series_from_args(args) if args is not None else read_measured(file)), None
    parts = case.split(":")
    if len(parts) == 3 and parts[0] == "synthetic":
        from synthetic import generate_series, truth_of

        try:
            truth_of(parts[1])
            seed = int(parts[2])
        except ValueError as exc:
            raise InputError(f"--case: {exc}" if "label" in str(exc) else
                             f"--case: seed must be an integer, got {parts[2]!r}") from None
        s = generate_series(parts[1], seed)
        return s.data, {"label": parts[1], "seed": seed, "causes": list(s.truth["causes"]),
                        "chi": s.truth["chi"], "out_of_catalogue": s.truth["ooc"]}
    return read_measured(resolve_case(case).measured_data()), None


def model_case(case: str | None):
    """The :class:`cases.case.Case` of ``--case`` (None for none or a synthetic series)."""
    if case is None or case.startswith("synthetic:"):
        return None
    return resolve_case(case)


def _fmt(v) -> str:
    if v is None:
        return "n/a"
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _g(v, spec=".3g"):
    return "n/a" if v is None else format(v, spec)


def format_text(r: dict, source: str) -> str:
    """Human-readable summary of a diagnosis."""
    kind = (f"{r['control']} control" if r.get("test", "stepped-sine") == "stepped-sine"
            else f"{r['test']} test")
    lines = [f"{source}: mode {r['mode']} ({kind}, "
             f"{len(r['levels']['level'])} levels)",
             f"cause: {r['cause']}" + (f"   also: {', '.join(r['also'])}" if r["also"] else "")
             + f"   ambiguous: {'yes' if r['ambiguous'] else 'no'}",
             f"  {r['summary']}"]
    if r["ambiguity"]:
        for name, w, how in zip(r["ambiguity"]["between"][1:], r["ambiguity"]["weights"][1:],
                                r["ambiguity"]["measurement"]):
            lines.append(f"  rival {name} (weight {w:.2f}): to separate, {how}")
    if r["contradictions"]:
        lines.append("contradictions (what no micro-slip Iwan joint can do):")
        lines += [f"  - {c}" for c in r["contradictions"]]
    lines.append(f"errors on held-out levels: base {_g(r['base_error'])}, extended "
                 f"{_g(r['extended_error'])}, gain {_g(r['gain'])} (leave one level out); "
                 f"top levels held out: gain {_g(r['gain_held_out'])}")
    lines.append(f"  ({r['error_measure']})")
    ft = r["fit_test"]
    lines.append(f"fit of {ft['model']}: rms residual {ft['rms_standardized']:.3g} noise "
                 f"standard deviations, p = {_g(ft['p_value'], '.2g')} ({ft['test']})")
    lines.append(f"parameters ({r['parameters']['model']}; fitted to this series):")
    lines += [f"  {k:24s} {_fmt(v)}" for k, v in r["parameters"].items() if k != "model"]
    lines.append("candidates (weight: Akaike weight with the cost per cause, the causes' "
                 "drops taken at their known-noise equivalent when the noise is estimated "
                 "(docs/judge.md); dAIC: AIC of none minus the candidate's, as is; p: fit "
                 "test; only a nameable candidate is named or makes the verdict ambiguous):")
    ranked = sorted(r["evidence"].items(), key=lambda kv: -kv[1]["weight"])
    for name, e in ranked:
        if not e["available"]:
            lines.append(f"  {name:46s} n/a ({e['reason']})")
            continue
        gain = next((a["gain"] for a in r["alternatives"] if a["causes"] == e["causes"]), None)
        lines.append(f"  {name:46s} w {e['weight']:.3f}  dAIC {_g(e['delta_aic'], '8.1f')}  "
                     f"k {e['n_params']:2d}  p {_g(e['p_value'], '.2g'):>7}  gain {_g(gain)}"
                     + (f"  not nameable: {e['why_not']}" if e.get("why_not") else ""))
    sep = r["separability"]
    for p in sep["inseparable"]:
        lines.append(f"cannot separate {p['causes'][0]} from {p['causes'][1]} with these "
                     f"levels: {p['measurement']}")
    for c, why in sep["untestable"].items():
        lines.append(f"not tested: {c} ({why})")
    lines.append("noise (identification + repeatability): " + noise_words(r["noise"]))
    vid = r.get("verdict_identification_only")
    lines.append("with the identification's noise alone: " + (
        f"{vid['cause']}" + (f" + {', '.join(vid['also'])}" if vid["also"] else "")
        + (" (the verdict changes)" if r["verdict_changes_with_identification_only"]
           else " (the same verdict)") if vid else f"not judged ({r['identification_only_note']})"))
    if r["at_bound"]:
        lines.append(f"on a bound in the {r['parameters']['model']} fit: "
                     f"{', '.join(r['at_bound'])}")
    fl = r["failures"]
    names = (fl.get("unconverged") or {}).get("fits") or []
    lines.append(f"failures: {fl['fits']} fits, {fl['folds']} cross-validation folds, "
                 f"{fl['held_out']} held-out fits; not converged: "
                 f"{fl.get('unconverged_fits', 0)} fits"
                 + (f" ({', '.join(names)})" if names else "")
                 + f", {fl.get('unconverged_folds', 0)} folds, "
                 f"{fl.get('unconverged_profile_points', 0)} profile points")
    preds = r["held_out_predictions"]["levels"]
    if preds:
        inside = sum(p[c]["inside"] for p in preds for c in ("omega2", "zeta"))
        lines.append(f"held-out top levels ({r['held_out_predictions']['model']} fitted to "
                     f"the lower ones): {inside} of {2 * len(preds)} values inside their "
                     f"nominal 95 % prediction interval")
    lines += [f"warning: {w}" for w in r["data_warnings"]]
    if "synthetic_truth" in r:
        t = r["synthetic_truth"]
        lines.append(f"synthetic truth: {t['label']} (named should be "
                     f"{', '.join(t['causes']) or 'none'}), chi {t['chi']:.3f}")
    if "fe_check" in r:
        from cases.double_beam.fe_check import format_fe_check

        lines.extend(format_fe_check(r["fe_check"]))
    if "fe" in r:
        from feloop.diagnosis_report import format_fe
        lines.extend(format_fe(r["fe"]))
    return "\n".join(lines)


def write_report(result: dict, out: Path, source: str) -> list[Path]:
    """Write report.md, diagnosis.json, diagnosis_fits.png and diagnosis_evidence.png."""
    from cli.commands.diagnose_report import markdown
    from viz.diagnosis_plots import plot_diagnosis_fits, plot_weights

    out.mkdir(parents=True, exist_ok=True)
    r, lv = result, result["levels"]
    fits_png = out / "diagnosis_fits.png"
    plot_diagnosis_fits(lv, extended_label=f"extended: {r['parameters']['model']}",
                        abscissa_label=("response amplitude" if r["control"] == "response"
                                        else "excitation"),
                        title=f"{source}, mode {r['mode']}: cause = {r['cause']}"
                        + (f" + {', '.join(r['also'])}" if r["also"] else ""),
                        path=fits_png)
    ev_png = out / "diagnosis_evidence.png"
    alts = r["alternatives"][:8]
    plot_weights(["+".join(a["causes"]) for a in alts], [a["weight"] for a in alts],
                 named=r["parameters"]["model"], gains=[a["gain"] for a in alts],
                 title="weight of each explanation", path=ev_png)
    json_path = out / "diagnosis.json"
    json_path.write_text(json.dumps(to_jsonable(r), indent=2) + "\n", encoding="utf-8")
    report = out / "report.md"
    report.write_text(markdown(r, source), encoding="utf-8")
    return [report, json_path, fits_png, ev_png]


def _backbone_prediction(args, data, mode) -> dict:
    """``--backbone``: the estimator's joint (method exact, all levels but the top three,
    B~ from the case's FE model) put into the FE model, every level read off its EPMC
    backbone (:func:`feloop.backbone.predict_from_backbone` on the case's
    FE-levels model)."""
    case = model_case(args.case)
    if case is None or not args.files:
        raise InputError("--backbone needs FILE and --case")
    from feloop.backbone import predict_from_backbone
    from inverse.estimate import estimate

    levels = case.require("fe_levels")

    d = data.for_mode(mode)
    if len(d) < 6:
        raise InputError(f"--backbone: mode {mode} has {len(d)} levels; the fit needs at "
                         "least 3 below the 3 held out")
    est = estimate(data, fit_levels=[int(v) for v in d.level[:-3]], method="exact",
                   mode=mode, model=case.fe_model(), case_name=case.name)
    return predict_from_backbone(data, est, levels, case_name=case.name)


def run(args) -> int:
    if args.out:
        validate.output_dir(args.out, "--out")   # cli.validate: one output-path rule
    args.file = " ".join(args.files) or None
    refusing = model_case(args.case)
    if refusing is not None and "fe_levels" in refusing.refused:
        refusing.require("fe_levels")     # a law the FE level does not fit: one line, exit 2
    data, truth = load(args.file, args.case, args)
    data.rig_repeatability = rig_from_args(args)
    source = args.file or args.case
    result = diagnose(data, mode=args.mode)
    if truth is not None:
        result["synthetic_truth"] = truth
    case = model_case(args.case)
    if case is not None and "fe_check" in case.capabilities:  # its FE-level check
        level1 = data.for_mode(result["mode"])
        result["fe_check"] = case.require("fe_check")(float(level1.omega2[0]))
    if case is not None and "fe_levels" in case.capabilities:
        # the FE model refitted, base vs extended (issue 13), by the one judge
        from feloop.diagnosis_report import add_fe_diagnosis
        add_fe_diagnosis(result, data, out=args.out, levels=case.require("fe_levels"),
                         model_key=case.source)
        if case.file is not None:          # the fitted joint against the file's interfaces
            from feloop.case_file import fitted_plausibility
            result["fe"]["plausibility"] = fitted_plausibility(case.file, result["fe"])
    if args.backbone:
        result["backbone"] = _backbone_prediction(args, data, result["mode"])
    if args.out:
        write_report(result, Path(args.out), Path(source).name if args.file else source)
    if args.json:
        print_json(result)
    else:
        print(format_text(result, source))
        if "backbone" in result:
            from cli.commands.backbone import format_prediction
            print(format_prediction(result["backbone"]))
        if args.out:
            print(f"report: {Path(args.out) / 'report.md'}")
    return 0
