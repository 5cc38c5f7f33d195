"""Test-session set-up.

Small dense least-squares problems dominate several tests; multithreaded OpenBLAS on a
loaded 2-core machine makes them 30-400x slower, so the suite runs BLAS on one thread.
This must happen before numpy is imported.
"""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
