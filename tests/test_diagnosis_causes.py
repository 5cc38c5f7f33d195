"""Causes as plug-ins: the catalogue is the folder inverse/diagnosis/causes."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from inverse.diagnosis.causes import CATALOGUE, CAUSES

ROOT = Path(__file__).resolve().parents[1]

DUMMY = '''"""Cause ``dummy-cubic-damping`` (a test plug-in): zeta += q s**3."""
import numpy as np

ID = "dummy-cubic-damping"
ORDER = 99
WORDS = "a cubic damping term"
ADVICE = "add levels above the top one"
NONLINEAR = []
LINEAR = ["q3"]
NONNEG = ("q3",)
EFFECT = "q3"
FE_REALIZATION = None


def columns(obs, col, log_s, p, w2):
    return [np.zeros_like(log_s)], [np.exp(3 * log_s)]


def parameters(lin, nl, obs, log_s, chi):
    return {"q3_top": lin["q3"] * np.exp(3 * np.max(log_s))}


def signature(obs, base):
    z = np.zeros(obs.n)
    return z, obs.s**3, z


def testable(obs):
    return True, None
'''

PROBE = '''
import json, numpy as np
from ident.modal_data import MeasuredData
from inverse.diagnose import CAUSES, diagnose
s = np.geomspace(0.05, 1.0, 9)
w2 = 4e6 * (1 - 2e-3 * s**0.5)
z = 0.004 + 0.002 * s**0.5 + 0.003 * s**3
d = MeasuredData(level=np.arange(1, 10), excitation=s, omega2=w2, zeta=z,
                 mode=np.ones(9, int), run_order=None, omega2_std=1e-6 * w2,
                 zeta_std=1e-3 * z)
r = diagnose(d)
print(json.dumps({"causes": list(CAUSES), "evidence": sorted(r["evidence"]),
                  "cause": r["cause"], "also": r["also"]}))
'''


def test_every_cause_file_fills_the_contract():
    assert CAUSES == ("macro-slip", "nonproportional-amplitude", "geometric-hardening",
                      "thermal-drift", "quadratic-damping")
    for cid, mod in CATALOGUE.items():
        assert mod.ID == cid
        # its FE realization in the same file, for the same cause (every shipped one has one)
        assert mod.FE_REALIZATION is not None and mod.FE_REALIZATION.cause == cid
        assert all(lo < hi for _, lo, hi, _ in mod.NONLINEAR)
        assert set(mod.NONNEG) <= set(mod.LINEAR)


def test_a_cause_dropped_into_the_folder_is_picked_up(tmp_path):
    """A dummy cause added to a copy of the package is fitted, weighed and named,
    touching no file outside the folder."""
    shutil.copytree(ROOT / "inverse", tmp_path / "inverse",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "inverse" / "diagnosis" / "causes" / "dummy_cubic.py").write_text(DUMMY)
    env = dict(os.environ, PYTHONPATH=f"{tmp_path}{os.pathsep}{ROOT}",
               OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, cwd=tmp_path,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["causes"][-1] == "dummy-cubic-damping"
    assert "dummy-cubic-damping" in r["evidence"]
    assert "quadratic-damping+dummy-cubic-damping" in r["evidence"]
    assert r["cause"] == "dummy-cubic-damping" or "dummy-cubic-damping" in r["also"]
