"""Synthetic stepped-sine series of one jointed mode, simulated at the FRF level and
identified: the test and benchmark data of the diagnosis (:mod:`.draw`)."""
from cases.synthetic_series.draw import (CATALOGUE, OUT_OF_CATALOGUE, SyntheticSeries,
                                         generate_series, truth_of)

__all__ = ["CATALOGUE", "OUT_OF_CATALOGUE", "SyntheticSeries", "generate_series",
           "truth_of"]
