"""How far the judge's noise is from the generator's, on the own-generator singles of a
``bench_diagnose.py`` run: named against missed.

For every single-cause series of the own generator (:mod:`synthetic`) in
``bench_diagnose.json``, the series is generated again from its seed and diagnosed
(with the std columns); the judge's total relative noise of omega^2
(``noise.omega2.total_rel``, :func:`inverse.judge.noise_model`) is compared with the
truth the generator drew: the identification's relative sd of omega^2 (the table's
``omega2_std / omega2``, rms over the rows) and the planted repeatability
(``2 s_f``, ``s_f`` the relative sd of the frequency; 0 when it is off),

    ratio = judged / sqrt(ident^2 + (2 s_f)^2).

A ratio above 1 shrinks every chi2 drop by its square: a cause that the data hold is
judged against a noise it does not have. Printed per series (seed, truth, named or
not, ratio, the noise's dof, the oracle's ``lam``) and the medians and counts of
ratios beyond 1.5 and below 1/1.5, named against missed.

Usage::

    python benchmarks/noise_vs_truth.py OUT/bench_diagnose.json
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from synthetic import generate_series  # noqa: E402
from inverse.diagnose import diagnose  # noqa: E402


def noise_ratio(label: str, seed: int) -> tuple[float, float | None]:
    """(judged / true relative noise of omega^2, the judge's dof) of one own series."""
    s = generate_series(label, seed)
    judged = diagnose(s.data)["noise"]["omega2"]
    ident = float(np.sqrt(np.mean((s.data.omega2_std / s.data.omega2) ** 2)))
    true = np.hypot(ident, 2.0 * s.truth["repeatability"]["s_f"])
    return float(np.mean(judged["total_rel"])) / true, judged.get("dof")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print(__doc__.split("Usage::")[1].strip(), file=sys.stderr)
        return 2
    rows = json.loads(Path(argv[0]).read_text())["rows"]
    ratios = {True: [], False: []}
    print(f"{'seed':>9s}  {'truth':26s} {'named':5s}  judged/true  dof   lam")
    for r in rows:
        truth = r.get("truth") or []
        if r["gen"] != "own" or len(truth) != 1 or truth[0] in ("none", "unexplained"):
            continue
        ratio, dof = noise_ratio(r["label"], r["seed"])
        named = r["results"]["with std"].get("cause") == truth[0]
        ratios[named].append(ratio)
        lam = r.get("oracle", {}).get("lam")
        print(f"{r['seed']:>9d}  {truth[0]:26s} {'yes' if named else 'no':5s}  "
              f"{ratio:11.2f}  {'-' if dof is None else f'{dof:3.0f}':>3s}  "
              f"{'-' if lam is None else f'{lam:.0f}'}")
    for named in (True, False):
        x = np.array(ratios[named])
        if x.size:
            print(f"{'named' if named else 'missed'}: n = {x.size}, median ratio "
                  f"{np.median(x):.2f}, above 1.5: {int(np.sum(x > 1.5))}, below 1/1.5: "
                  f"{int(np.sum(x < 1 / 1.5))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
