"""Entry point of the one-mode diagnosis: :func:`inverse.diagnosis.run.diagnose`."""
from inverse.diagnosis.run import ALL_CAUSES, CAUSES, T_CAUSE, W_AMBIGUOUS, diagnose

__all__ = ["ALL_CAUSES", "CAUSES", "T_CAUSE", "W_AMBIGUOUS", "diagnose"]
