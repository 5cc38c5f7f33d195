"""The double-beam report in sentences: the findings and the assumptions, with the run's
numbers (``report.md``, ``report.json``, the command's text output).

``rep`` is a :class:`cases.double_beam.report.DoubleBeamReport`.
"""
from __future__ import annotations

from inverse.iwan_modal import kappa_ratio

__all__ = ["headline", "assumption_statements"]


def headline(rep) -> list[str]:
    """The main findings as sentences with this run's numbers."""
    c = rep.comparison()
    su = rep.setup
    f = rep.study.fit
    k7 = max(i for i, r in enumerate(c) if r["level"] in f)
    lines = []
    em = rep.successful_estimates("measured")
    lines.append("Measured data, levels " + rep.study.fit_levels + ": " + "; ".join(
        f"{k}: chi = {e.chi:.4f}, |kappa1|B = {e.kappa1_B:.4g} 1/s^2, R~ = {e.R:.4g}"
        for k, (e, _, _) in em.items()) + " (paper: chi = -0.37366, |kappa1|B = 29.431).")
    lines.append(
        f"Simulation input ({rep.setup.source.method} estimate): chi = {su.chi:.4f}, "
        f"R = {su.R:.4g} N/m^(chi+2), beta = {su.beta:g}, phi_max = {su.phi_max:.4g} m, "
        f"F_S = {su.F_S:.4g} N at {su.force_scale:g} N/V; viscous zeta_v = "
        f"{100 * su.zeta_viscous:.5f} %.")
    r7, rL = c[k7], c[-1]
    lines.append(
        f"Frequency: from level 1 to level {r7['level']} the simulated omega^2 falls by "
        f"{r7['simulated_loss_from_level1']:.1f} rad^2/s^2, the measured by "
        f"{r7['measured_loss_from_level1']:.1f} ({r7['loss_ratio']:.2f} times); to level "
        f"{rL['level']}: {rL['simulated_loss_from_level1']:.1f} vs "
        f"{rL['measured_loss_from_level1']:.1f} ({rL['loss_ratio']:.2f} times). "
        f"Level 1 itself: simulated {c[0]['omega2_difference']:+.1f} rad^2/s^2 "
        f"({c[0]['omega2_difference_percent']:+.4f} %) from the measurement (the FE mode, "
        f"calibrated to 252.0 Hz, is {su.omega_n ** 2 - rep.measured.omega2[0]:+.0f} above "
        f"it; the joint softens it by {rep.modal_filter.delta_omega2[0]:.0f} at level 1).")
    lines.append(
        f"Damping: simulated zeta at level 1 {100 * c[0]['simulated_zeta']:.5f} % (measured "
        f"{100 * c[0]['measured_zeta']:.4f} %); growth from level 1 to level {r7['level']} "
        f"{100 * r7['simulated_growth_from_level1']:.5f} % vs "
        f"{100 * r7['measured_growth_from_level1']:.5f} % ({r7['growth_ratio']:.2f} times); "
        f"level {rL['level']}: zeta {100 * rL['simulated_zeta']:.4f} % vs "
        f"{100 * rL['measured_zeta']:.4f} % ({100 * rL['zeta_difference']:+.4f} % absolute).")
    macro = rep.first_macro_level
    lines.append(
        f"Joint: the largest slip at resonance reaches {c[-1]['slip_over_phi_max']:.3g} phi_max at "
        f"level {rL['level']} ("
        + (f"macro-slip from level {macro}" if macro else "micro-slip at every level")
        + f"); the glue loses up to {100 * r7['glue_stiffness_loss']:.0f} % of its in-phase "
        f"stiffness at level {r7['level']} ({100 * rL['glue_stiffness_loss']:.0f} % at level "
        f"{rL['level']}); slip per newton grows by "
        f"{100 * (r7['slip_per_force_relative'] - 1):.1f} % up to level {r7['level']} and "
        f"{100 * (rL['slip_per_force_relative'] - 1):.0f} % up to level {rL['level']} (the "
        f"estimator assumes 0).")
    for which, name in (("lscf", "LSCF"), ("modal_filter", "modal filter")):
        ee = rep.successful_estimates(which)
        if ee:
            lines.append(f"Recovery on the simulated data ({name} identification), input chi = "
                         f"{su.chi:.4f}, R = {su.R:.4g}: " + "; ".join(
                             f"{k}: chi = {e.chi:.4f} ({e.chi - su.chi:+.4f}), R~ error "
                             f"{100 * (e.R / su.R - 1):+.0f} %"
                             for k, (e, _, _) in ee.items()) + ".")
    for w in rep.weak_joint_rows:
        errs = [v["chi_error"] for v in w["recovery"]["lscf"].values() if "chi_error" in v]
        rerr = [v["R_error_percent"] for v in w["recovery"]["lscf"].values() if "chi_error" in v]
        if errs:
            lines.append(
                f"With R x {w['R_scale']:g} (same chi; top slip {w['top_slip_over_phi_max']:.3g} "
                f"phi_max) the methods recover chi within {max(map(abs, errs)):.4f} and R~ within "
                f"{max(map(abs, rerr)):.1f} % (LSCF data): the bias scales with the joint's "
                f"softening.")
    mf = rep.modal_filter
    ratio = mf.delta_c / mf.delta_c_decoupled
    lines.append(
        f"Why: the modal joint damping seen through the modal filter is {ratio[0]:.3f} (level 1), "
        f"{ratio[k7]:.3f} (level {r7['level']}) and {ratio[-1]:.3g} (level {rL['level']}) times "
        f"the decoupled eq. 30-32 with the simulated slips: the glue loses in-phase stiffness "
        f"(kappa2/|kappa1| = {kappa_ratio(su.chi, 'exact'):.2f}), the slip grows faster than the "
        f"mode's amplitude and the power law of eq. 33-35 bends upward.")
    return lines


def assumption_statements(rep) -> list[str]:
    """The decisions of :mod:`cases.double_beam.joint_setup` and
    :mod:`cases.double_beam.settings` with this run's numbers, one per line."""
    su, st = rep.setup, rep.study
    src = su.source
    model = []
    if rep.calibration is not None:
        model.append(f"Model: {rep.calibration['statement']}; every other FE property "
                     f"assumed (cases/double_beam/model.py).")
    solver = (f"harmonic balance ({st.hb.n_harmonics} harmonics, odd={st.hb.odd_only}, "
              f"{st.hb.n_time} AFT samples) with continuation")
    if rep.protocol == "newmark":
        from cases.double_beam.protocols import NEWMARK_STEPS, NEWMARK_TOL

        solver = (f"Newmark time integration (average acceleration, {NEWMARK_STEPS} steps per "
                  f"period, pre-warped), every line started on its harmonic-balance orbit "
                  f"and integrated until periodic to {NEWMARK_TOL:g}")
    return model + [
        f"Joints: one Iwan element per glue node ({su.shares.size}), shares "
        f"{', '.join(f'{w:.3g}' for w in su.shares)} of K_T = {su.K_T:.3g} N/m; chi = {su.chi:.5f} "
        f"and R = {su.R:.4g} N/m^(chi+2) from the '{src.method}' estimate of measured levels "
        f"{st.fit_levels}" + (" (overridden)" if st.chi is not None or st.R is not None else "")
        + ".",
        f"beta = {su.beta:g}: phi_max = (K_T (chi+1)/((1+beta) R))^(1/(chi+1)) = "
        f"{su.phi_max:.4g} m is largest at beta = 0 (F_S = {su.F_S:.4g} N for the whole glue).",
        f"Force scale {su.force_scale:g} N/V (assumed; the paper gives volts only): level 1 = "
        f"{su.force[0]:.4g} N, level {rep.measured.level[-1]} = {su.force[-1]:.4g} N. R~ scales "
        f"as s^-(chi+1), phi_max as s; simulated FRFs, omega2, zeta and slip/phi_max do not "
        f"depend on it.",
        f"Viscous damping: modal, zeta_v = {100 * su.zeta_viscous:.5f} % on every basis vector "
        f"(measured level-1 zeta {100 * rep.measured.zeta[0]:.4f} % less the joint share "
        f"|kappa1|B / (2 Omega^2) at level 1).",
        f"Lines: {st.lines.size} lines, {st.band_hz[0]:g}-{st.band_hz[1]:g} Hz every "
        f"{st.df_hz:g} Hz (the paper: 2 Hz over 50-450 Hz), swept upward, {solver}; every "
        f"level starts from virgin joints.",
        f"Reduced model: {st.n_modes} stuck-glue modes + {su.shares.size} static joint modes; "
        f"Jenkins banks of {rep.sliders_per_joint} sliders per joint, {st.sliders_per_octave} "
        f"per octave of slip limit.",
        f"Identification: LSCF + refinement of the receptance at Acc. 1 (upper strip, exciter "
        f"position), the mode nearest the FE mode, weights '{st.identify_weighting}', "
        f"out-of-band terms {'on' if st.identify_pseudo_modes else 'off'} (zeta moves by "
        f"< 1e-9 at levels 1-8 under 1e-11 perturbations of the FRF, as with the default "
        f"options); checked "
        f"against the modal filter of every DOF's response; slips at resonance interpolated at "
        f"the identified frequency.",
    ]
