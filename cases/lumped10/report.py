"""The report of the 10-DOF reproduction (per-mode results, JSON form) and the
paper's published section-3 numbers it is compared with (Tables 1, 2, Fig. 5 chi).
"""
from __future__ import annotations

import csv as _csv
import io as _io
from dataclasses import dataclass

import numpy as np

from cases.lumped10.improved_fit import ImprovedFit
from cases.lumped10.model import ModeTopology

__all__ = [
    "LumpedReport",
    "ModeResult",
    "PAPER_CHI",
    "TABLE1_TEXT",
    "TABLE2_TEXT",
    "paper_table",
]

#: Paper Table 1 (half peak-to-peak joint slips, m), transcribed (identical to
#: shared/data/paper/table1_lumped_relative_displacement.csv; checked by the tests).
TABLE1_TEXT = """experiment,mode2_iwan1,mode2_iwan2,mode4_iwan1,mode4_iwan2,mode6_iwan1,mode6_iwan2
1,0.00005,0.00016,0.00001,0.00003,0.00001,0.00001
2,0.00010,0.00030,0.00003,0.00006,0.00002,0.00002
3,0.00018,0.00057,0.00005,0.00011,0.00004,0.00004
4,0.00034,0.00106,0.00010,0.00021,0.00007,0.00007
5,0.00061,0.00191,0.00019,0.00041,0.00015,0.00013
6,0.00107,0.00337,0.00037,0.00078,0.00028,0.00025
7,0.00149,0.00471,0.00069,0.00146,0.00053,0.00048
8,0.00193,0.00592,0.00127,0.00268,0.00098,0.00089
9,0.00275,0.00855,0.00214,0.00451,0.00179,0.00162
10,0.00439,0.01372,0.00284,0.00601,0.00322,0.00291
11,0.00791,0.02345,0.00447,0.00935,0.00486,0.00455
12,0.01467,0.04335,0.00720,0.01493,0.00691,0.00658
"""

#: Paper Table 2 (R errors, percent), transcribed (shared/data/paper/table2_*.csv).
TABLE2_TEXT = """nu_minus_1,mode2_inverse_matrix,mode2_newmark,mode4_inverse_matrix,mode4_newmark,mode6_inverse_matrix,mode6_newmark
0,13.199,10.574,31.887,15.272,100.000,100.000
1,9.937,7.214,28.839,12.608,135.950,37.369
2,8.675,5.913,28.704,12.490,67.009,2.768
3,10.367,7.656,22.844,7.368,67.679,2.379
4,18.818,16.363,22.321,6.911,68.544,1.875
5,117.323,123.895,21.789,6.446,64.167,4.423
6,217.785,227.395,20.967,5.727,61.796,5.804
7,169.117,177.255,59.959,39.806,58.587,7.672
8,63.680,68.630,295.122,245.344,54.384,10.119
9,69.430,68.505,306.771,255.524,239.717,97.781
10,132.867,133.861,292.655,243.187,385.652,182.743
"""

#: The paper's chi from Fig. 5 (modes 2, 4, 6).
PAPER_CHI = {2: -0.528, 4: -0.526, 6: -0.531}


def paper_table(text: str) -> dict[str, np.ndarray]:
    """Columns of a transcribed paper table as float arrays."""
    rows = list(_csv.DictReader(_io.StringIO(text)))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


@dataclass
class ModeResult:
    """Everything computed for one studied mode (SI units, zeta as fractions)."""

    mode: int
    band: tuple
    frequency_hz: np.ndarray          # (12,) identified (LSCF) natural frequency
    zeta: np.ndarray                  # (12,) identified damping ratio
    table1: np.ndarray                # (12, 2) joint amplitudes at the identified resonance
    fit_levels: list
    paper_estimate: object            # inverse.estimate_result.Estimate (method "paper")
    amplitude_estimate: object        # inverse.estimate_result.Estimate (method "amplitude")
    B_inverse: float
    B_simulated: float
    R_paper: float
    R_per_difference_inverse: np.ndarray   # (11,) eq. 37 per successive difference
    R_per_difference_simulated: np.ndarray
    improved: ImprovedFit


@dataclass
class LumpedReport:
    """The reproduction of paper section 3 and the improved method."""

    study: object                     # cases.lumped10.study.LumpedStudy
    protocol: str
    topology: ModeTopology
    campaign: object                  # runs.stepped_sine.CampaignResult
    modes: dict                       # mode -> ModeResult
    R_true: float
    chi_true: float
    timings: dict

    def to_dict(self) -> dict:
        """Plain JSON form (``iwanfe reproduce lumped --json``)."""
        t1p = paper_table(TABLE1_TEXT)
        t2p = paper_table(TABLE2_TEXT)
        keys = [str(m) for m in self.modes]

        def err(R):
            return 100.0 * (R / self.R_true - 1.0)

        out = {
            "chi_true": self.chi_true,
            "R_true": self.R_true,
            "protocol": self.protocol,
            "chi_paper_method": {k: self.modes[int(k)].paper_estimate.chi for k in keys},
            "chi_improved": {k: self.modes[int(k)].improved.chi for k in keys},
            "chi_amplitude_regression": {k: self.modes[int(k)].amplitude_estimate.chi
                                         for k in keys},
            "chi_improved_with_frequency": {k: self.modes[int(k)].improved.chi_with_frequency
                                            for k in keys},
            "chi_paper_published": {str(m): PAPER_CHI[m] for m in self.modes},
            "R_error_percent": {k: {"paper_method": err(self.modes[int(k)].R_paper),
                                    "improved": err(self.modes[int(k)].improved.R)}
                                for k in keys},
            "fit_levels": {k: self.modes[int(k)].fit_levels for k in keys},
            "improved_levels": {k: self.modes[int(k)].improved.levels for k in keys},
            "table1": {}, "table2": {}, "identified": {},
            "topology": {
                "frequency_hz": self.topology.frequency_hz,
                "joint_modes": self.topology.joint_modes(),
                "in_phase_modes": np.flatnonzero(~self.topology.moves_joints) + 1,
                "joint_slip_ratio": {str(m): float(abs(self.topology.joint_slip[m - 1, 0]
                                                       / self.topology.joint_slip[m - 1, 1]))
                                     for m in self.modes},
            },
            "campaign_fallbacks": self.campaign.fallback_lines(),
            "timings_s": self.timings,
        }
        for k in keys:
            mr = self.modes[int(k)]
            out["table1"][k] = {
                "level": list(range(1, 13)), "force_N": self.campaign.force,
                "frequency_hz": mr.frequency_hz,
                "iwan1": mr.table1[:, 0], "iwan2": mr.table1[:, 1],
                "paper_iwan1": t1p[f"mode{k}_iwan1"], "paper_iwan2": t1p[f"mode{k}_iwan2"],
            }
            out["table2"][k] = {
                "nu_minus_1": list(range(mr.R_per_difference_inverse.size)),
                "inverse_matrix": err(mr.R_per_difference_inverse),
                "simulated": err(mr.R_per_difference_simulated),
                "paper_inverse_matrix": t2p[f"mode{k}_inverse_matrix"],
                "paper_newmark": t2p[f"mode{k}_newmark"],
            }
            out["identified"][k] = {"frequency_hz": mr.frequency_hz, "zeta": mr.zeta}
        return out
