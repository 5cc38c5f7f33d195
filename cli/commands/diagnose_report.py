"""The human report of ``iwanfe diagnose --out DIR``: report.md (the figures are drawn by
:mod:`viz.diagnosis_plots`)."""
from __future__ import annotations


def _g(v, spec=".3g"):
    return "n/a" if v is None else format(v, spec)


def noise_words(noise: dict) -> str:
    """One line per diagnosis: each channel's total noise and where it comes from (an
    identification part of 0 is one the table does not give: no std columns)."""
    def ident(v):
        rel = v["identification_rel"]
        return f"{100 * rel:.2g} %" if rel > 0 else "not given"
    return "; ".join(
        (f"{c} {100 * v['total_rel']:.3g} % (identification {ident(v)}"
         f", repeatability {100 * v['repeatability_rel']:.2g} %: {v['source']})")
        if v["relative"] else f"{c} {v['total_rel']:.3g} ({v['source']})"
        for c, v in noise.items())


def _evidence_rows(r: dict) -> list[str]:
    rows = []
    gains = {"+".join(a["causes"]): a["gain"] for a in r["alternatives"]}
    for name, e in sorted(r["evidence"].items(), key=lambda kv: -kv[1]["weight"]):
        if not e["available"]:
            rows.append(f"| {name} | n/a | | | | | {e['reason']} |")
            continue
        note = e.get("reason", "")
        rows.append(f"| {name} | {e['weight']:.3f} | {_g(e['delta_aic'], '.1f')} | "
                    f"{_g(e['delta_bic'], '.1f')} | {e['n_params']} | "
                    f"{_g(e['p_value'], '.2g')} | {_g(gains.get(name))} {note} |")
    return rows


def markdown(r: dict, source: str) -> str:
    """report.md of a diagnosis result (``inverse.diagnose.diagnose``)."""
    md = _head_md(r, source) + _errors_md(r) + _candidates_md(r) + _limits_md(r)
    if "fe_check" in r:
        from cases.double_beam.fe_check import format_fe_check_md

        md += "\n" + format_fe_check_md(r["fe_check"])
    return md


def _head_md(r: dict, source: str) -> str:
    """The title, the named cause, the summary, any ambiguity and the contradictions."""
    named = r["cause"] + (" + " + " + ".join(r["also"]) if r["also"] else "")
    contra = "\n".join(f"- {c}" for c in r["contradictions"]) or "- none"
    amb = ""
    if r["ambiguity"]:
        amb = "\n".join(f"- `{b}` (weight {w:.2f}): {m}" for b, w, m in zip(
            r["ambiguity"]["between"][1:], r["ambiguity"]["weights"][1:],
            r["ambiguity"]["measurement"]))
        amb = f"\n**Ambiguous** with:\n\n{amb}\n"
    return f"""# Diagnosis of {source}, mode {r['mode']} ({r['control']} control)

**Cause: `{named}`** (ambiguous: {'yes' if r['ambiguous'] else 'no'})

{r['summary']}
{amb}
## Contradictions with the Iwan model

{contra}

"""


def _errors_md(r: dict) -> str:
    """The held-out errors of the base and extended models, the noise and the fit test."""
    n, ft = r["noise"], r["fit_test"]
    crit = r["criterion"]
    return f"""## Errors on levels the fits did not see

| | leave one level out | top levels held out |
| --- | --- | --- |
| base model | {_g(r['base_error'])} | {_g(r['held_out_errors']['base'])} |
| extended model (`{r['parameters']['model']}`) | {_g(r['extended_error'])} | {_g(r['held_out_errors']['extended'])} |
| gain (base / extended) | {_g(r['gain'])} | {_g(r['gain_held_out'])} |

Error measure: {r['error_measure']}. Noise: {noise_words(n)}.
Fit of `{ft['model']}`: rms residual {ft['rms_standardized']:.3g} noise standard
deviations, p = {_g(ft['p_value'], '.2g')} ({ft['test']}); the data count as outside
their noise below p = {crit['p_unexplained']:g}.

"""


def _candidates_md(r: dict) -> str:
    """The fitted parameters of the extended model and the table of every candidate."""
    params = "\n".join(f"| {k} | {v:.6g} |" for k, v in r["parameters"].items()
                       if k != "model")
    crit = r["criterion"]
    return f"""## Parameters of `{r['parameters']['model']}` (fitted to this series)

| parameter | value |
| --- | --- |
{params}

## Every candidate

Weight: Akaike weight with a cost of {crit['t_cause']:g} in AIC per cause (sums to 1);
another explanation with at least {crit['w_ambiguous']:.2g} of the named one's weight
makes the answer ambiguous. dAIC, dBIC: criterion of `none` minus the candidate's;
p: test of fit against the noise; gain: leave-one-level-out error of `none` over the
candidate's.

| candidate | weight | dAIC | dBIC | parameters | p | gain / note |
| --- | --- | --- | --- | --- | --- | --- |
{chr(10).join(_evidence_rows(r))}

![weights](diagnosis_evidence.png)

"""


def _limits_md(r: dict) -> str:
    """What the test cannot separate, the figure of the fits and the data warnings."""
    sep = r["separability"]
    seps = "\n".join(f"- {p['causes'][0]} from {p['causes'][1]}: {p['measurement']}"
                     for p in sep["inseparable"])
    seps += "".join(f"\n- {c} not tested: {why}" for c, why in sep["untestable"].items())
    warn = "\n".join(f"- {w}" for w in r["data_warnings"]) or "- none"
    return f"""## What this test cannot separate

{seps.strip() or '- every pair of testable causes is separable on these levels'}

## Data, fits and residuals

Top: data (black), base model (blue dashed), extended model (red). Bottom: residuals
in units of the noise level (grey band: +/- 2).

![fits](diagnosis_fits.png)

## Data warnings

{warn}
"""
