"""Test-session set-up.

Small dense least-squares problems dominate several tests; multithreaded OpenBLAS on a
loaded 2-core machine makes them 30-400x slower, so the suite runs BLAS on one thread.
This must happen before numpy is imported.

The paper's figures as transcribed by the project's hosts (``shared/data/paper``) sit
beside the checkout (in a folder above it); ``IWANFE_SHARED`` points elsewhere. The tests
that compare the shipped transcription with them skip where they are absent.
"""
import os
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

def _shared_paper() -> Path:
    """``$IWANFE_SHARED/data/paper``, else ``shared/data/paper`` in the nearest folder
    above the checkout that holds one (the hosts' layout puts it beside the checkout)."""
    if os.environ.get("IWANFE_SHARED"):
        return Path(os.environ["IWANFE_SHARED"]) / "data" / "paper"
    for above in Path(__file__).resolve().parents[1:]:
        if (above / "shared" / "data" / "paper").is_dir():
            return above / "shared" / "data" / "paper"
    return Path(__file__).resolve().parents[1] / "shared" / "data" / "paper"   # absent


SHARED_PAPER = _shared_paper()
