"""From test files to modal parameters: FRF files (CSV, UFF 58), the measured-data table,
LSCF with automatic pole selection, the modal filter, mode tracking across levels.

Imports ``fe`` and ``joints`` only (none today). SI units throughout.
"""
