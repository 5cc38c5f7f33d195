"""``iwanfe uncertainty --case FILE``: the Monte Carlo of a case's FE-levels model
over ``update``'s selected model, or over a given one (``--model``,
:mod:`feloop.given_model`) (:mod:`feloop.uncertainty`: exact describing function at
phase resonance per sample), for a case without its own ``uncertainty`` study or with
``--model``; options, text and files."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from cli import validate
from cli.executor_options import executor_from_args
from runs.jsonio import print_json, to_jsonable


def _f(x, spec):
    return "nan" if x is None or not math.isfinite(x) else format(x, spec)


def text(r: dict) -> str:
    """The readable report of :func:`feloop.uncertainty.run_fe_uncertainty`."""
    m, c, dist = r["model"], r["confidence"], r["distribution"]
    lo, hi = (100 * (1 - c) / 2, 100 * (1 + c) / 2)
    ch = r["chi"]
    ft = m["fit_test"]
    held = [n for n, b in m["at_bound"].items() if b]
    sd = dict(zip(dist["parameters"], dist["sd"]))
    kept = dist["kept_fraction"]
    who = "the given" if m.get("given") else "update's selected"
    lines = [f"iwanfe uncertainty {r['source']}  case {r['case']}  mode {r['mode']}  "
             f"fit levels {m['fit_levels']}",
             f"  nominal: {who} model '{m['candidate']}' (cause "
             f"{'unexplained' if m['unexplained'] else m['cause']}) with its fitted "
             f"parameters ({m['rule']})",
             f"  it misses its fit levels by {m['rms_misfit_sd']:.3g} noise sd rms "
             f"(chi2 = {m['chi2']:.4g} on {m['n_residuals']} residuals; fit test p = "
             f"{_f(ft.get('p_value'), '.2g')}, {ft.get('test', '')})",
             "  drawn: " + ", ".join(f"{n} = {m['values'][n]:.6g} +- {sd[n]:.3g}"
                                     for n in dist["parameters"])
             + (f"; held at a bound: {', '.join(held)}" if held else ""),
             f"  {r['n_samples']} samples, seed {r['seed']}, {dist['kind']} truncated to the "
             f"parameters' bounds ({_f(None if kept is None else 100 * kept, '.1f')} % of "
             f"the draws kept)"
             + (f": chi median {ch['median']:.4f}, {lo:g}..{hi:g} % {ch['lo']:.4f} .. "
                f"{ch['hi']:.4f}" if ch else "") + f"; {r['n_failed']} failed (not physical or "
             f"not simulated; left out of the quantiles), {r['n_with_fallback']} with a "
             f"steady state reached by a fallback",
             f"  per sample: {r['route']}", ""]
    head = f" level     measured      nominal    MC median  {'MC %g..%g %%' % (lo, hi):^26s}  in"
    for name, key, scale, spec in (("natural frequency (Hz)", "frequency_hz", 1.0, "10.4f"),
                                   ("damping ratio (%)", "zeta", 100.0, "10.5f")):
        lines += [f"{name}; * = held out of the fit", head]
        for row in r["levels"]:
            mc = row[f"mc_{key}"]

            def s(v):
                return _f(None if v is None else scale * v, spec)

            lines.append(f" {row['level']:>4}{'*' if row['held_out'] else ' '} "
                         f"{s(row[f'measured_{key}'])}  {s(row[f'nominal_{key}'])}  "
                         f"{s(mc['median'])}  {s(mc['lo'])} .. {s(mc['hi'])}  "
                         + {True: "yes", False: "no", None: "n/a"}[
                             row[f"measured_{key}_inside"]])
        lines.append("")
    for f in r["failures"][:5]:
        chi = "" if f["chi"] is None else f" (chi = {f['chi']:.4f})"
        lines.append(f"failed sample {f['index']}{chi}: {f['status']}")
    lines.append(f"samples in {r['store']}; total {r['timing_s']['total']:.1f} s "
                 f"({r['executor']})")
    return "\n".join(lines)


def run_levels(args, case) -> int:
    """The command on a case's ``fe_uncertainty`` capability (one line if it has none)."""
    uncertainty = case.require("fe_uncertainty")
    for name in ("band", "df", "sliders_per_octave"):
        if getattr(args, name) is not None:
            raise ValueError(f"--{name.replace('_', '-')}: only for a case with its own "
                             f"stepped-sine study; case {case.name!r} is simulated at phase "
                             "resonance")
    if not 0 < args.confidence < 1:
        raise ValueError(f"--confidence {args.confidence:g}: must lie in (0, 1)")
    force_scale = None if args.force_scale is None else validate.positive(
        args.force_scale, "--force-scale")
    data = None if args.file is None else str(validate.input_file(args.file))
    out = validate.output_dir(args.out, "--out")
    progress = not args.no_progress
    if progress:
        first = "the model choice of update" if args.model is None else args.model
        print(f"iwanfe uncertainty: {first}, then {args.samples} samples "
              f"+ nominal, store under {out}", file=sys.stderr)
    r = uncertainty(data_path=data, mode_label=args.mode, fit_levels=args.fit_levels,
                    force_scale=force_scale, model=args.model, n_samples=args.samples,
                    seed=args.seed,
                    confidence=args.confidence, distribution=args.distribution, out=out,
                    executor=executor_from_args(args), progress=progress)
    Path(out).mkdir(parents=True, exist_ok=True)
    js = Path(out) / "uncertainty.json"
    js.write_text(json.dumps(to_jsonable(r), indent=1))
    r["files"] = [str(js)]
    if args.json:
        print_json(r)
    else:
        print(text(r))
        print(f"files: {js}")
    return 0
