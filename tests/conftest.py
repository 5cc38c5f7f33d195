"""Test-session set-up.

Small dense least-squares problems dominate several tests; multithreaded OpenBLAS on a
loaded 2-core machine makes them 30-400x slower, so the suite runs BLAS on one thread.
This must happen before numpy is imported.

The paper's figures as transcribed by the project's hosts (``shared/data/paper``) sit
beside the checkout; ``IWANFE_SHARED`` points elsewhere. The tests that compare the
shipped transcription with them skip where they are absent.
"""
import os
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

SHARED_PAPER = Path(os.environ.get("IWANFE_SHARED", Path(__file__).resolve().parents[2]
                                   / "shared")) / "data" / "paper"
