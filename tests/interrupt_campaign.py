"""A short stepped-sine campaign with a store, run under the command line's rules for
errors and Ctrl-C (``cli.main.run_guarded``): the subject of tests/test_interrupt.py.

``python tests/interrupt_campaign.py STORE`` runs 8 force levels x 81 lines of the
paper's 10-DOF model (20 Jenkins sliders per joint, harmonic balance through the compiled
AFT and Jenkins kernels), stores each finished level under STORE (resumable, like
``iwanfe reproduce lumped``) and prints one JSON line: the campaign hash, the number of
levels computed by this run and the receptances (real and imaginary parts).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from cli.main import run_guarded  # noqa: E402


def campaign(store: str) -> int:
    import numpy as np

    from cases.lumped10.study import LumpedStudy, lumped10_setup
    from runs.campaign import Campaign, HBProtocol
    from runs.stepped_sine import run_campaign

    study = LumpedStudy(n_sliders=20, f_lo=50.0, f_hi=70.0, df=0.25)
    setup = lumped10_setup(study)
    camp = Campaign(study.lines, setup.levels[:8], setup.load, np.arange(10), HBProtocol())
    res = run_campaign(setup.model, setup.bank, camp, store=store, progress=False)
    print(json.dumps({"hash": res.hash, "computed": int(res.computed.sum()),
                      "re": res.receptance.real.ravel().tolist(),
                      "im": res.receptance.imag.ravel().tolist()}))
    return 0


if __name__ == "__main__":
    sys.exit(run_guarded(lambda: campaign(sys.argv[1]), restore=False))
