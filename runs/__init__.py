"""How solvers are driven over many points: stepped-sine protocols, executors (serial,
processes, dask.distributed), resumable result stores, JSON output.

Imports ``fe`` and ``joints`` only. SI units throughout.
"""
