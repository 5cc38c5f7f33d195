"""Probe series (second batch): seeds / magnitudes. Imports the physics of gen.py."""
import json
import gen
from gen import series, W0
gen.TRUTH = {}
def drift_f(mag):
    return lambda ro, nrun, w2, z: (w2 * (1 - mag * (ro - 1) / (nrun - 1)), z)
for s in range(1, 6):
    series(f"p_ms6_s{s}", n=6, step=2.0, seed=10 + s, truth="micro-slip 6 levels", expect="none")
    series(f"p_ms4_s{s}", n=4, step=2.5, seed=20 + s, truth="micro-slip 4 levels", expect="none")
for mag in (0.008, 0.02):
    for s in (1, 2, 3):
        series(f"p_drift{mag}_shuf_s{s}", seed=30 + s, repeats=(1, 5, 10), shuffle=True,
               time_effect=drift_f(mag),
               truth=f"drift omega2 -{mag*100:.1f} % linear in run order, shuffled, repeats",
               expect="thermal-drift")
    series(f"p_drift{mag}_shuf_norep", seed=40, shuffle=True, time_effect=drift_f(mag),
           truth=f"drift omega2 -{mag*100:.1f} %, shuffled, no repeats", expect="thermal-drift")
def qd_f(amt):
    return lambda A, w2, z: (w2, z + amt * (A / 12.0) ** 1.5)
for amt in (0.004, 0.01):
    for s in (1, 2):
        series(f"p_qd{amt}_s{s}", seed=50 + s, extra=qd_f(amt),
               truth=f"extra damping +{amt*100:.1f} % abs at A=12, no softening",
               expect="quadratic-damping")
series("p_qd0.01_rc", control="response", seed=55, extra=qd_f(0.01),
       truth="quadratic damping +1 % abs, response control", expect="quadratic-damping")
series("p_hard_rc", control="response", seed=56,
       extra=lambda A, w2, z: (w2 + 0.03 * W0 * (A / 12.0) ** 2, z),
       truth="hardening +3 % omega2 at A=12, response control", expect="geometric-hardening")
def step_f(r0, mag):
    return lambda ro, nrun, w2, z: ((w2 * (1 - mag), z) if ro >= r0 else (w2, z))
series("p_step_rep_end", seed=60, repeats=(1, 2), time_effect=step_f(6, 0.006),
       truth="step omega2 -0.6 % from run 6, in order, levels 1,2 re-run at end",
       expect="thermal-drift/unexplained (time effect shown by repeats)")
series("p_step_big", seed=61, time_effect=step_f(6, 0.02),
       truth="step omega2 -2 % (freq -1 %) from run 6, in order, no repeats", expect="not none")
json.dump(gen.TRUTH, open("truth2.json", "w"), indent=1)
print(len(gen.TRUTH))
