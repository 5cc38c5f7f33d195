"""What the double-beam reproduction computed, and its tables.

:class:`DoubleBeamReport` holds the study's settings, joint, measured and simulated
modal data, the campaign and the estimates; its methods derive the per-level
comparison, the paper's Tables 3-6 beside ours, the recovery of the input chi and R on
the simulated data and the JSON form (``iwanfe reproduce double-beam --json``). The
prose is :mod:`cases.double_beam.statements` and :mod:`cases.double_beam.markdown`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from cases.double_beam.joint_setup import JointSetup
from cases.double_beam.settings import DoubleBeamStudy
from cases.double_beam.statements import assumption_statements
from ident.levels import LevelIdentification
from ident.measured import MeasuredData
from ident.modal_filter import ModalFilterLevels

__all__ = ["DoubleBeamReport"]


@dataclass
class DoubleBeamReport:
    """Everything one simulation of the study computed (SI units, zeta as fractions):
    :func:`cases.double_beam.pipeline.simulate_study`, and the weak-joint rows of
    :func:`cases.double_beam.study.run_study`."""

    study: DoubleBeamStudy
    setup: JointSetup
    measured: MeasuredData
    simulated: MeasuredData
    campaign: object            # runs.stepped_sine.CampaignResult
    identification: LevelIdentification
    modal_filter: ModalFilterLevels
    estimates_measured: dict    # method -> (Estimate, B_sim, R_sim) or error text
    estimates_simulated: dict   # the same on the LSCF-identified simulation
    estimates_filtered: dict    # the same on the modal-filter simulation
    force_scale_rows: list
    weak_joint_rows: list
    store: str | None
    timings: dict
    sliders_per_joint: int = 0
    response_dof: int = 0
    files: list = field(default_factory=list)
    protocol: str = "hb"
    protocol_comparison: dict | None = None     # cases.double_beam.protocols
    calibration: dict | None = None             # GripCalibration.to_dict()

    # ------------------------------------------------------------------ derived
    @property
    def slip_over_phi_max(self) -> np.ndarray:
        """Largest joint slip at resonance per level over phi_max."""
        return np.nanmax(self.identification.slip, axis=1) / self.setup.phi_max

    @property
    def glue_stiffness_loss(self) -> np.ndarray:
        """Per level, the largest relative loss of in-phase stiffness of a joint element at
        its slip at resonance, ``1 - k_in(A)/K_T`` (exact describing function)."""
        from joints.describing import describing_function

        out = np.zeros(self.identification.slip.shape[0])
        for j, p in enumerate(self.setup.params):
            k_in, _ = describing_function(p, np.maximum(self.identification.slip[:, j], 1e-300))
            out = np.maximum(out, 1.0 - np.asarray(k_in) / p.K_T)
        return out

    @property
    def first_macro_level(self) -> int | None:
        lv = np.flatnonzero(self.slip_over_phi_max >= 1.0)
        return int(self.measured.level[lv[0]]) if lv.size else None

    def comparison(self) -> list[dict]:
        """Measured vs simulated per level (differences stated, sim - meas)."""
        m, s = self.measured, self.simulated
        per_force = self.identification.slip_eff / self.setup.force
        loss = self.glue_stiffness_loss
        rows = []
        for i, lv in enumerate(m.level):
            lossm = float(m.omega2[0] - m.omega2[i])
            losss = float(s.omega2[0] - s.omega2[i])
            growm = float(m.zeta[i] - m.zeta[0])
            grows = float(s.zeta[i] - s.zeta[0])
            rows.append({
                "level": int(lv), "excitation_V": float(m.excitation[i]),
                "force_N": float(self.setup.force[i]),
                "measured_omega2": float(m.omega2[i]), "simulated_omega2": float(s.omega2[i]),
                "omega2_difference": float(s.omega2[i] - m.omega2[i]),
                "omega2_difference_percent": 100.0 * float(s.omega2[i] / m.omega2[i] - 1.0),
                "measured_loss_from_level1": lossm, "simulated_loss_from_level1": losss,
                "loss_ratio": losss / lossm if i and lossm > 0 else None,
                "measured_zeta": float(m.zeta[i]), "simulated_zeta": float(s.zeta[i]),
                "zeta_difference": float(s.zeta[i] - m.zeta[i]),
                "measured_growth_from_level1": growm, "simulated_growth_from_level1": grows,
                "growth_ratio": grows / growm if i and growm > 0 else None,
                "slip_over_phi_max": float(self.slip_over_phi_max[i]),
                "slip_eff_m": float(self.identification.slip_eff[i]),
                "glue_stiffness_loss": float(loss[i]),
                "slip_per_force_relative": float(per_force[i] / per_force[0]),
                "regime": "macro-slip" if self.slip_over_phi_max[i] >= 1.0 else "micro-slip",
                "held_out": int(lv) not in self.study.fit,
            })
        return rows

    def tables(self) -> dict:
        """Paper Tables 3-6 beside ours (per method) and the simulation.

        Every row: ``measured`` (the data the estimates used), ``paper`` (``estimate``,
        ``error_percent`` as printed), ``simulated`` and ``methods[k]`` (``value``,
        ``error_percent`` = 100 (value - measured) / measured); Tables 4 and 6 also hold
        ``measured_printed`` (the printed absolute values, see cases/data/README.md).
        """
        from cases.paper_data import paper_tables

        pt = paper_tables()
        m, s = self.measured, self.simulated
        preds = {k: {p["level"]: p for p in v[0].predictions}
                 for k, v in self.estimates_measured.items() if not isinstance(v, str)}

        def printed(tab, col, i):
            c = pt[tab][col].value
            return float(c[i]) if 0 <= i < c.size and np.isfinite(c[i]) else None

        def err(value, meas):
            return None if value is None or not meas else 100.0 * (value - meas) / meas

        def row(key, meas, sim, tab, cols, i, pred_key, scale=1.0):
            return {key: meas,
                    "paper": {"estimate": printed(tab, cols[0], i),
                              "error_percent": printed(tab, cols[1], i)},
                    "simulated": {"value": sim, "error_percent": err(sim, meas)},
                    "methods": {k: {"value": None if pr.get(lv) is None
                                    or pr[lv][pred_key] is None else scale * pr[lv][pred_key],
                                    "error_percent": None if pr.get(lv) is None
                                    else pr[lv][f"{pred_key}_error_percent"]}
                                for k, pr in preds.items()}}

        t3, t4, t5, t6 = [], [], [], []
        for i, lv in enumerate(map(int, m.level)):
            base = {"level": lv, "held_out": lv not in self.study.fit}
            om2, ze = float(m.omega2[i]), float(m.zeta[i])
            r4 = row("measured", om2, float(s.omega2[i]), "table4",
                     ("paper_estimated_rad2_s2", "paper_error_percent"), lv - 1, "omega2")
            r6 = row("measured", 100 * ze, 100 * float(s.zeta[i]), "table6",
                     ("paper_estimated_percent", "paper_error_percent"), lv - 1, "zeta", 100.0)
            r4["measured_printed"] = printed("table4", "measured_rad2_s2", lv - 1)
            r6["measured_printed"] = printed("table6", "measured_percent", lv - 1)
            t4.append({**base, **r4})
            t6.append({**base, **r6})
            if i == 0:
                continue
            pair = {"from_level": int(m.level[i - 1]), "to_level": lv, "held_out": base["held_out"]}
            r3 = row("measured", float(m.omega2[i - 1] - m.omega2[i]),
                     float(s.omega2[i - 1] - s.omega2[i]), "table3",
                     ("paper_estimated_rad2_s2", "paper_error_percent"), lv - 2, "delta_omega2")
            r5 = row("measured", 100 * float(m.zeta[i] - m.zeta[i - 1]),
                     100 * float(s.zeta[i] - s.zeta[i - 1]), "table5",
                     ("paper_estimated_percent", "paper_error_percent"), lv - 2, "delta_zeta",
                     100.0)
            t3.append({**pair, **r3})
            t5.append({**pair, **r5})
        return {"table3_delta_omega2": t3, "table4_omega2": t4,
                "table5_delta_zeta_percent": t5, "table6_zeta_percent": t6}

    def recovery(self, source: str = "lscf") -> dict:
        """Estimates on the simulated data (``source`` "lscf" or "modal_filter") against
        the simulation's input chi and R."""
        out = {}
        ests = self.estimates_simulated if source == "lscf" else self.estimates_filtered
        for k, v in ests.items():
            if isinstance(v, str):
                out[k] = {"error": v}
                continue
            e, B_sim, R_sim = v
            held = [p for p in e.predictions if p["held_out"] and p["delta_omega2"] is not None]
            out[k] = {"chi": e.chi, "chi_input": self.setup.chi,
                      "chi_error": e.chi - self.setup.chi,
                      "chi_interval": list(e.chi_interval), "kappa1_B": e.kappa1_B,
                      "R_linear_inverse": e.R, "R_simulated_B": R_sim, "R_input": self.setup.R,
                      "R_error_percent": 100.0 * (e.R / self.setup.R - 1.0),
                      "R_simulated_B_error_percent": 100.0 * (R_sim / self.setup.R - 1.0),
                      "held_out_delta_omega2_error_percent":
                          [p["delta_omega2_error_percent"] for p in held],
                      "held_out_delta_zeta_error_percent":
                          [p["delta_zeta_error_percent"] for p in held]}
        return out

    def successful_estimates(self, which: str) -> dict:
        """method -> (Estimate, B_sim, R_sim) of the estimates that did not fail, on the
        ``which`` data: "measured", "lscf" or "modal_filter"."""
        src = {"measured": self.estimates_measured, "lscf": self.estimates_simulated,
               "modal_filter": self.estimates_filtered}[which]
        return {k: v for k, v in src.items() if not isinstance(v, str)}

    # ------------------------------------------------------------------ output
    def _method_dict(self, v) -> dict:
        if isinstance(v, str):
            return {"error": v}
        e, B_sim, R_sim = v
        d = e.to_dict()
        d.update(B_linear_inverse=e.B, R_linear_inverse=e.R, B_simulated=B_sim,
                 R_simulated=R_sim)
        return d

    def to_dict(self) -> dict:
        """Plain JSON form (``iwanfe reproduce double-beam --json``)."""
        from cases.paper_data import PUBLISHED

        st, s, ident = self.study, self.simulated, self.identification
        camp = self.campaign
        return {
            "case": "double-beam",
            "fit_levels": st.fit,
            "methods": {k: self._method_dict(v) for k, v in self.estimates_measured.items()},
            "simulated": {
                "level": s.level, "excitation_V": s.excitation, "force_N": self.setup.force,
                "frequency_hz": ident.frequency_hz, "omega2": s.omega2, "zeta": s.zeta,
                "slip_at_resonance_m": ident.slip, "slip_eff_m": ident.slip_eff,
                "slip_over_phi_max": self.slip_over_phi_max,
                "response_amplitude_m": ident.response,
                "first_macro_slip_level": self.first_macro_level,
                "estimates": {k: self._method_dict(v) for k, v in self.estimates_simulated.items()},
                "recovery": {"lscf": self.recovery("lscf"),
                             "modal_filter": self.recovery("modal_filter")},
                "modal_filter": dataclasses.asdict(self.modal_filter),
            },
            "comparison": self.comparison(),
            "tables": self.tables(),
            "paper": PUBLISHED,
            "assumptions": {**self.setup.to_dict(),
                            "lines_hz": [float(st.lines[0]), float(st.lines[-1]), float(st.df_hz),
                                         int(st.lines.size)],
                            "sliders_per_joint": int(self.sliders_per_joint),
                            "sliders_per_octave": st.sliders_per_octave,
                            "n_modes": st.n_modes, "static_joint_modes": True,
                            "hb": dataclasses.asdict(st.hb),
                            "statements": assumption_statements(self)},
            "force_scale_dependence": self.force_scale_rows,
            "weak_joint_recovery": self.weak_joint_rows,
            "campaign": {"protocol": self.protocol, "hash": camp.hash, "store": self.store,
                         "levels_computed": int(camp.computed.sum()),
                         "elapsed_s": camp.elapsed,
                         ("newton_iterations_mean" if self.protocol == "hb"
                          else "periods_per_line_mean"): camp.work.mean(axis=1),
                         "fallbacks": camp.fallback_lines()},
            "calibration": self.calibration,
            "protocol_comparison": self.protocol_comparison,
            "timings_s": self.timings,
            "files": [str(f) for f in self.files],
        }
