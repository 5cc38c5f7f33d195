"""Synthetic stepped-sine series of one jointed mode, simulated at the FRF level by a
generator independent of the diagnosis, and identified as measured data are.

Independence: nothing here imports ``inverse`` (``tests/test_synthetic_series.py``
parses the imports, transitively within the project), and no functional form or
bound of the diagnosis is used: the Iwan joint is a bank of Jenkins sliders summed by
quadrature (no Dirac share), every mechanism is a force law or an energy law whose
first harmonic is taken numerically (:mod:`.first_harmonic`), and sizes are set in
noise units of the simulated test, not in the diagnosis's parameters.

=========================  ==============================================  =============================================
cause id (truth)           generator: mechanism (family)                   diagnosis on main (``inverse.diagnosis_models``)
=========================  ==============================================  =============================================
``none``                   Jenkins bank of density R phi^chi, chi in        base: omega2 = W - K2 s^p, zeta = c/(2 omega)
                           (-0.9, -0.1), top slip 0.2-0.9 phi_max, no       + K1 s^p/(2 omega2), tie K2/K1 = kappa(chi)
                           Dirac; joint damping 0.3-3 zeta0 at the top
``macro-slip``             ``slip-ring``: a second patch, uniform slider    exact four-parameter Iwan DF past phi_max
                           density on [0.4-0.8, 1] phi_r, top 1.2-3 phi_r;  (incomplete Beta; Dirac weight S)
                           ``tapered-edge``: the density ends in a taper
                           (1-u)^0.5-2 over [0.55-0.85, 1] phi_m, top
                           1.15-2.5 phi_m, no Dirac
``quadratic-damping``      ``snubber-squeeze-film``: viscous force past a   zeta += q s^m / (1 + (u s)^m), m in [0.3, 3],
                           clearance 0.25-0.7 X_top (no stiffness);         u in [0, 5]
                           ``lazan-knee``: loss per cycle J X^n1 (1 +
                           (X/X_k)^(n2-n1)), n1 2.2-2.6, n2 6-8
``geometric-hardening``    ``power-spring``: k |x|^a sgn x, a in            omega2 += h s^n C(s_c/s), n = nu + 1.5 w,
                           [1.5, 2.2] or [5.5, 7] (frequency exponent       nu in [0, 3], linear contact past s_c in
                           0.5-1.2 or 4.5-6: outside 1.5-4.5);              [0, 0.9]
                           ``hertz-stop``: one-sided (x - g)^1.5 past
                           g = 0.1-0.6 X_top
``thermal-drift``          ``temperature-step`` at a random test time;      omega2 += d (1 - e^(-b t))/(1 - e^(-b)),
                           ``room-cycle``: ramp + sine of the clock time    t = run order scaled, b in [-4, 8]
                           (run durations 0.7-1.3), not of the run index
``nonproportional-         ``shaker-impedance``: voltage drive, coil R-L,   Box-Cox on log s: gamma (s^kappa - 1)/kappa,
amplitude``                back-EMF Bl^2/R = 0.5-4 x the mode's damping,    gamma in [-0.95, 0.6], kappa in [0, 5]
                           armature mass 0.02-0.15, suspension;
                           ``amplifier-clipping``: g V_s tanh(V/V_s),
                           top V/V_s 0.6-1.4; held level = volts
``unexplained``            ``bolt-loosening-step`` (slip limits x lam,      (no model: the fit test fails)
                           K_T x lam^(1/3) from a test time);
                           ``capped-dashpot`` (viscous force capped by a
                           slider: damping falls); ``softening-spring``
                           (-k |x|^a, a 2.5-4); ``damping-drift`` (viscous
                           damping follows the room clock)
=========================  ==============================================  =============================================

Every mechanism is sized (:mod:`.design`) to a visibility drawn in [5, 40] noise units
(identification sd and planted repeatability) and its honest visibility, from
noise-free FRFs simulated with and without it and identified, is stored in the truth; a
draw below 3 units is drawn again. The test: 4-12 levels (ratio 1.15-1.6, jittered),
force control (70 %) or response control, run order ascending, descending, shuffled or
interleaved (time mechanisms never monotone), 0-2 repeated levels (the lowest at the
end, a middle one later), repeatability in half the draws (frequency sd 2e-4..1e-3
relative, damping sd 1-5 %, each run its own offsets), FRF noise 0.05-0.8 % of |H|
plus 0.01-0.3 % of the peak, a force column in 85 % of the draws, 25-90 lines per
level or one fixed grid, a linear neighbour mode's residual in 40 %. Natural frequency
15-800 Hz, viscous damping 0.15-2 %, top amplitude 1e-6..1e-4 m.
"""
from cases.synthetic_series.draw import (CATALOGUE, FAMILIES, OUT_OF_CATALOGUE,
                                         SyntheticSeries, generate_series, truth_of,
                                         without_stds)

__all__ = ["CATALOGUE", "FAMILIES", "OUT_OF_CATALOGUE", "SyntheticSeries",
           "generate_series", "truth_of", "without_stds"]
