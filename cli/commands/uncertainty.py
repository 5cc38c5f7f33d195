"""``iwanfe uncertainty``: Monte Carlo of the FE predictions over the identified joint.

Draws joint parameters (chi, R~) from the fit uncertainty of the ``exact`` estimate of
the fit levels (``iwanfe estimate``: paper eq. 33-37), simulates each sample with the
case's nonlinear FE model through every level and prints per level the measured value,
the nominal FE prediction, the sample median and central interval. A case with its own
``uncertainty`` capability (the double beam: a harmonic-balance stepped sine and modal
filter per sample, with the estimator's closed-form interval beside,
:mod:`cases.double_beam.uncertainty`) runs that; any other case with an FE-levels model
(a case file with joints of one law) runs :mod:`feloop.uncertainty` instead: the
parameters of the model ``update`` selects for the same levels drawn from its fit (the
nominal is ``update``'s model; unphysical samples counted failed), each simulated by
exact describing function at phase resonance. With ``--model DIR/updated_model.json``
(any case with an FE-levels model, the double beam's case file too) the samples are
drawn around that model of ``update`` (its values and its fit's covariance,
:mod:`feloop.given_model`) instead. Every finished sample is stored under
``--out``; a rerun computes only the missing ones.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from cli import validate
from cli.executor_options import add_executor_arguments, executor_from_args, int_at_least
from cli.model_options import add_model_argument
from runs.jsonio import print_json

NAME = "uncertainty"


def register(subparsers) -> None:
    from cases.double_beam.uncertainty import DEFAULT_CONFIDENCE, DEFAULT_SAMPLES, DEFAULT_SEED
    from cases.registry import DEFAULT_CASE
    from inverse.uncertainty import DISTRIBUTIONS

    parser = subparsers.add_parser(
        NAME,
        help="Monte Carlo over the identified chi and R: uncertainty of the FE-predicted "
             "frequency and damping at every level",
        description=(
            "Draw joint parameters (chi, R~) from the fit uncertainty of the 'exact' "
            "estimate of the fit levels (Student t with the fit's degrees of freedom and "
            "linearized covariance of (chi+1, ln((chi+1)|kappa1|B)), truncated to -1 < chi "
            "< 0), simulate every sample with the case's nonlinear FE model through all "
            "levels, and report per level the measured value, the nominal FE prediction, "
            "the sample median and central interval. The double beam: harmonic-balance "
            "stepped sine and modal filter per sample, beside the estimator's closed-form "
            "delta-method interval (paper eq. 43, 46). A case file: the parameters of the "
            "model 'update' selects for the same levels, drawn from that fit (its nominal "
            "is update's model; samples that fail or are not physical are counted failed "
            "with the reason), each simulated by exact describing function at phase "
            "resonance (its FE-levels model, ms per sample); with --model, drawn around "
            "that updated model and its fit's covariance instead (no model choice run). "
            "Writes uncertainty.json (and for the double beam uncertainty.png) under --out "
            "and stores every "
            "finished sample there: a rerun computes only the missing ones, and more "
            "--samples extends a finished run."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", nargs="?", default=None,
                        help="measured-data CSV (default: the case's measured data)")
    parser.add_argument("--case", default=DEFAULT_CASE, metavar="NAME|FILE",
                        help="FE model of the per-sample simulation: a shipped case or a "
                             "case file (.toml)")
    parser.add_argument("--mode", type=int, default=None,
                        help="mode label in the data (case files; default: the case's)")
    parser.add_argument("--samples", type=int_at_least(1), default=DEFAULT_SAMPLES, metavar="N",
                        help="Monte Carlo samples (one nonlinear simulation each)")
    parser.add_argument("--seed", type=int_at_least(0), default=DEFAULT_SEED, metavar="S",
                        help="root seed (each sample has its own stream)")
    parser.add_argument("--fit-levels", default=None, metavar="LEVELS",
                        help="levels of the chi fit; the others are predicted (default: "
                             "1-7 for the double beam; a case file: all but the top three "
                             "levels)")
    parser.add_argument("--confidence", type=float, default=DEFAULT_CONFIDENCE,
                        help="central interval of the samples and level of the "
                             "delta-method interval, in (0, 1) (0.9: 5-95 %%)")
    parser.add_argument("--distribution", choices=DISTRIBUTIONS, default="t",
                        help="t: Student t with the fit's degrees of freedom (matches the "
                             "estimator's t-intervals); normal: same covariance")
    parser.add_argument("--force-scale", type=float, default=None, metavar="N_PER_V",
                        help="force per volt of drive (default 1; the simulated modal data "
                             "do not depend on it)")
    parser.add_argument("--out", default="results/uncertainty", metavar="DIR",
                        help="output directory (report, plot, sample store)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    sim = parser.add_argument_group("per-sample stepped sine of a case with its own "
                                    "uncertainty capability (defaults: module docstring of "
                                    "cases.double_beam.uncertainty)")
    sim.add_argument("--band", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                     help="stepped-sine lines and band, Hz (default 236 268)")
    sim.add_argument("--df", type=float, default=None, metavar="HZ",
                     help="line spacing, Hz (default 0.5)")
    sim.add_argument("--sliders-per-octave", type=int, default=None,
                     help="Jenkins sliders per octave of slip limit (default 8)")
    add_model_argument(parser, help=(
        "draw the samples around this model of iwanfe update on the case (its fitted "
        "values the nominal, its fit's covariance, misfit scale, dof and bounds the "
        "distribution) instead of re-running update's model choice; its mode, fit levels "
        "and force scale are the defaults, and a model of another case, data, mode, fit "
        "levels or force scale is refused (exit 2). Any candidate (the base model or a "
        "cause); the per-sample route is the case's FE-levels model (the double beam's "
        "case file)"))
    add_executor_arguments(parser)     # --workers/--scheduler/--executor: where samples run
    parser.set_defaults(func=run)


def _settings(args):
    import dataclasses

    from cases.double_beam.settings import measured_levels
    from cases.double_beam.uncertainty import SAMPLE_STUDY, UncertaintySettings

    kw = {}
    if args.file is not None:
        kw["data_path"] = str(validate.input_file(args.file))
    kw["fit_levels"] = args.fit_levels or "1-7"
    for name, key in (("force_scale", "force_scale"), ("df", "df_hz"),
                      ("sliders_per_octave", "sliders_per_octave")):
        v = getattr(args, name)
        if v is not None:
            if isinstance(v, float):
                validate.positive(v, f"--{name.replace('_', '-')}")
            kw[key] = v
    if args.band is not None:
        kw["band_hz"] = validate.band(args.band, lowest=1e-300)
    if not 0 < args.confidence < 1:
        raise ValueError(f"--confidence {args.confidence:g}: must lie in (0, 1)")
    try:
        study = dataclasses.replace(SAMPLE_STUDY, **kw)
        settings = UncertaintySettings(study=study, n_samples=args.samples, seed=args.seed,
                                       confidence=args.confidence,
                                       distribution=args.distribution)
    except ValueError as exc:
        raise ValueError(f"--band/--df/--sliders-per-octave/--fit-levels: {exc}") from None
    validate.stepped_sine(study, measured_levels(study))
    validate.output_dir(args.out, "--out")
    return settings


def _f(x, spec):
    return "nan" if x is None or not math.isfinite(x) else format(x, spec)


def text_report(rep, source: str, files, wall: float, case_name: str) -> str:
    """The readable report of an
    :class:`~cases.double_beam.uncertainty_report.UncertaintyReport`."""
    st, src, dist = rep.settings, rep.source, rep.distribution
    c = st.confidence
    lo, hi = (100 * q for q in st.quantiles)
    iv = f"{lo:g}..{hi:g} %"
    ci = src.chi_interval
    study = st.study
    lines = [f"iwanfe uncertainty {source}  case {case_name}  {src.method} estimate of levels "
             f"{study.fit_levels}",
             f"  chi = {src.chi:.4f} ({c:.0%} t-interval {ci[0]:.3f} .. {ci[1]:.3f}), "
             f"|kappa1|B = {src.kappa1_B:.4g} 1/s^2, R~ = {src.R:.4g} N/m^(chi+2), "
             f"{src.dof} dof",
             f"  {st.n_samples} samples of (chi+1, ln Kt) ~ "
             + ("normal" if dist.dof == math.inf else f"Student t ({dist.dof:g} dof)")
             + f", truncated to -1 < chi < 0 ({100 * dist.admissible_fraction():.1f} % of the "
               f"mass; acceptance {100 * rep.acceptance:.0f} %), seed {st.seed}; "
               f"{st.n_samples - rep.n_failed} simulated ({rep.n_retried} with lower first "
               f"lines, {rep.n_fallback} with a steady state reached by a fallback), "
               f"{rep.n_failed} failed",
             f"  per sample: FE double beam, {study.n_levels} levels x {study.lines.size} lines "
             f"({study.band_hz[0]:g}-{study.band_hz[1]:g} Hz), HB {study.hb.n_harmonics} "
             f"harmonics / {study.hb.n_time} AFT samples, {study.sliders_per_octave} sliders "
             f"per octave; frequency and damping by the modal filter",
             ""]
    rows = rep.per_level()
    head = (f" level     measured      nominal    MC median  {'MC ' + iv:^26s}  closed form  "
            f"{'delta method ' + iv:^26s}")
    for name, key, scale, spec in (("natural frequency (Hz)", "frequency_hz", 1.0, "10.4f"),
                                   ("damping ratio (%)", "zeta", 100.0, "10.5f")):
        lines.append(f"{name}; * = held out of the fit")
        lines.append(head)
        for r in rows:
            mc = r[f"mc_{key}"]
            civ = r[f"closed_form_{key}_interval"]
            lines.append(
                f" {r['level']:>4}{'*' if r['held_out'] else ' '} "
                f"{_f(scale * r[f'measured_{key}'], spec)}  {_f(scale * r[f'nominal_{key}'], spec)}"
                f"  {_f(scale * mc['median'], spec)}  {_f(scale * mc['lo'], spec)} .. "
                f"{_f(scale * mc['hi'], spec)}  {_f(scale * r[f'closed_form_{key}'], spec)}  "
                f"{_f(scale * civ[0], spec)} .. {_f(scale * civ[1], spec)}")
        lines.append("")
    top = rows[-1]
    lines.append(f"macro-slip (largest slip >= phi_max) at level {top['level']} in "
                 f"{100 * top['mc_macro_slip_fraction']:.0f} % of the samples; LSCF and modal "
                 f"filter differ by > 10 % in zeta in {rep.lscf_disagreements()} samples")
    for f in rep.failures()[:5]:
        lines.append(f"failed sample {f['index']} (chi = {f['chi']:.4f}): {f['status']}")
    t = rep.timings
    lines.append("files: " + ", ".join(str(p) for p in files)
                 + f"; samples in {rep.store} ({t['computed']} computed, {t['loaded']} loaded)")
    lines.append(f"time: {t['per_sample_median']:.2f} s per sample (median), sweep "
                 f"{t['sweep']:.1f} s ({t['executor']}), total {wall:.1f} s")
    return "\n".join(lines)


def write_outputs(rep, out: Path) -> list[Path]:
    """``uncertainty.json`` (the report's :meth:`to_dict`) and ``uncertainty.png``."""
    import json

    import numpy as np

    from runs.jsonio import to_jsonable
    from viz.uncertainty_plot import plot_uncertainty_bands

    out.mkdir(parents=True, exist_ok=True)
    rows = rep.per_level()
    lo, hi = (100 * q for q in rep.settings.quantiles)
    panels = []
    for key, ylabel, scale in (("frequency_hz", "natural frequency (Hz)", 1.0),
                               ("zeta", "damping ratio (%)", 100.0)):
        samples = rep.values(key)
        with np.errstate(all="ignore"):
            quartiles = np.nanquantile(samples, [0.25, 0.75], axis=0)
        panels.append({
            "ylabel": ylabel, "scale": scale,
            "lo": [r[f"mc_{key}"]["lo"] for r in rows],
            "median": [r[f"mc_{key}"]["median"] for r in rows],
            "hi": [r[f"mc_{key}"]["hi"] for r in rows],
            "nominal": [r[f"nominal_{key}"] for r in rows],
            "closed_form": [r[f"closed_form_{key}"] for r in rows],
            "closed_form_lo": [r[f"closed_form_{key}_interval"][0] for r in rows],
            "closed_form_hi": [r[f"closed_form_{key}_interval"][1] for r in rows],
            "measured": [r[f"measured_{key}"] for r in rows],
            "inner_lo": quartiles[0], "inner_hi": quartiles[1],
            "samples": samples})
    png = out / "uncertainty.png"
    st = rep.settings
    plot_uncertainty_bands(
        [r["level"] for r in rows], panels, held_out=np.array([r["held_out"] for r in rows]),
        band_label=f"Monte Carlo {lo:g}-{hi:g} %",
        title=f"Double beam: FE predictions over {st.n_samples} joint samples from the fit of "
              f"levels {st.study.fit_levels} (chi = {rep.source.chi:.3f}, seed {st.seed})",
        path=png)
    js = out / "uncertainty.json"
    js.write_text(json.dumps(to_jsonable(rep.to_dict()), indent=1))
    return [js, png]


def run(args) -> int:
    from cases.registry import resolve_case

    case = resolve_case(args.case)     # --model: the nominal, not a changed case file
    if "uncertainty" not in case.capabilities or args.model is not None:
        from cli.commands.uncertainty_levels import run_levels

        return run_levels(args, case)
    from cases.double_beam.settings import DEFAULT_DATA

    run_uncertainty = case.require("uncertainty")
    if args.mode is not None:
        raise ValueError(f"--mode: case {case.name!r} studies its own mode")
    t0 = time.perf_counter()
    settings = _settings(args)
    executor = executor_from_args(args)
    out = Path(args.out)
    source = args.file or str(DEFAULT_DATA.relative_to(Path.cwd())
                              if DEFAULT_DATA.is_relative_to(Path.cwd()) else DEFAULT_DATA)
    progress = not args.no_progress
    if progress:
        print(f"iwanfe uncertainty: {settings.n_samples} samples + nominal, store under {out}",
              file=sys.stderr)
    rep = run_uncertainty(settings, out=out, executor=executor, progress=progress)
    files = write_outputs(rep, out)
    wall = time.perf_counter() - t0
    rep.timings["total"] = wall
    if args.json:
        d = rep.to_dict()
        d["file"] = source
        d["files"] = [str(f) for f in files]
        print_json(d)
    else:
        print(text_report(rep, source, files, wall, case.name))
    return 0
