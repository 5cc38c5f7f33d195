"""Finite elements and solvers: beams, assembly, modal analysis, reduced bases,
Newmark and harmonic balance with joints, stepped-sine campaigns.

Knows nothing of ``cases`` or ``viz``. SI units throughout.
"""
