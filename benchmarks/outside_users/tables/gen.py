"""Black-box test series for `iwanfe diagnose` (written from the spec only).

Physics (my own, written independently of the project):
  micro-slip Iwan on one mode, joint amplitude A (arbitrary unit),
  joint modal damping  D(A)  = kB * A**(chi+1)         [rad^2/s^2, = 2 zeta omega^2 growth]
  loss of omega^2      L(A)  = ratio(chi) * D(A),  ratio = B(chi+5/2,1/2)(chi+2)/(chi+1)
  omega2 = w0 - L ; zeta = z0 + D / (2 omega2)
  force control: A = c * E / (zeta * omega2) solved by fixed point (resonant amplitude)
  response control: A is held, E = A * zeta * omega2 / c
Noise: frequency repeatability 0.05 % (sd, relative) -> omega2 0.1 %; damping 3 % relative.
Identification std (when written): 1/30 of the repeatability.
Truth of every series -> truth.json
"""
import json, os
import numpy as np
from scipy.special import beta

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "")   # this folder
F0 = 180.0
W0 = (2 * np.pi * F0) ** 2
Z0 = 0.004
CHI = -0.4
KB = 6000.0
FREQ_REP = 0.0005   # relative sd of frequency
ZETA_REP = 0.03     # relative sd of zeta
ID_FACTOR = 30.0


def ratio(chi):
    return beta(chi + 2.5, 0.5) * (chi + 2) / (chi + 1)


def modal(A, extra=None):
    D = KB * A ** (CHI + 1)
    L = ratio(CHI) * D
    w2 = W0 - L
    z = Z0 + D / (2 * w2)
    if extra:
        w2, z = extra(A, w2, z)
    return w2, z


def solve_force(E, c, extra=None):
    A = c * E / (Z0 * W0)
    for _ in range(500):
        w2, z = modal(A, extra)
        A_new = c * E / (z * w2)
        if abs(A_new - A) < 1e-13 * A:
            break
        A = 0.5 * A + 0.5 * A_new
    return A, w2, z


C_FORCE = Z0 * W0 / 0.5  # A(level 1, E=0.5 N) ~ 1 before damping growth


def series(name, n=10, e1=0.5, step=1.5, control="force", repeats=(), shuffle=False,
           extra=None, time_effect=None, std_cols=False, resp_col=False, seed=0,
           drive_loss=None, truth="", expect=""):
    rng = np.random.default_rng(seed)
    levels = list(range(1, n + 1)) + list(repeats)
    nrun = len(levels)
    if shuffle:
        order = rng.permutation(nrun) + 1     # run_order of each row
    else:
        order = np.arange(1, nrun + 1)
    rows = []
    for lev, ro in zip(levels, order):
        if control == "force":
            E = e1 * step ** (lev - 1)
            Eeff = E if drive_loss is None else E * drive_loss(lev, n)
            A, w2, z = solve_force(Eeff, C_FORCE, extra)
        else:
            A = 1.0 * step ** (lev - 1)
            w2, z = modal(A, extra)
            E = A * z * w2 / C_FORCE
        if time_effect:
            w2, z = time_effect(ro, nrun, w2, z)
        w2n = w2 * (1 + 2 * FREQ_REP * rng.standard_normal())
        zn = z * (1 + ZETA_REP * rng.standard_normal())
        An = A * (1 + 0.01 * rng.standard_normal())
        r = dict(level=lev, excitation=E, omega2=w2n, zeta=zn, run_order=int(ro))
        if resp_col or control == "response":
            r["response_amplitude"] = An if control == "force" else A
        if control == "response":
            r["control"] = "response"
        if std_cols:
            r["omega2_std"] = w2 * 2 * FREQ_REP / ID_FACTOR
            r["zeta_std"] = z * ZETA_REP / ID_FACTOR
        r["_A"] = A
        rows.append(r)
    if shuffle:
        rng.shuffle(rows)
    cols = ["level", "excitation", "omega2", "zeta"]
    if any("response_amplitude" in r for r in rows):
        cols.append("response_amplitude")
    cols.append("run_order")
    if std_cols:
        cols += ["omega2_std", "zeta_std"]
    if control == "response":
        cols.append("control")
    with open(OUT + name + ".csv", "w") as f:
        f.write(",".join(cols) + "\n")
        for r in rows:
            f.write(",".join(fmt(r[c]) for c in cols) + "\n")
    A = [r["_A"] for r in rows if r["level"] == n][0]
    TRUTH[name] = dict(truth=truth, expect=expect, n_levels=n, repeats=list(repeats),
                       shuffled=shuffle, control=control, std_cols=std_cols, seed=seed,
                       A_top=A)


def fmt(v):
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return "%.7g" % v


TRUTH = {}
if __name__ == "__main__":
    S = 1
    # plain micro-slip
    series("ms10", seed=S, truth="micro-slip Iwan chi=-0.4", expect="none")
    series("ms10_s2", seed=2, truth="micro-slip Iwan chi=-0.4 (other seed)", expect="none")
    series("ms10_s3", seed=3, truth="micro-slip Iwan chi=-0.4 (other seed)", expect="none")
    series("ms10_std", seed=S, std_cols=True,
           truth="micro-slip + std cols (1/30 of repeatability)", expect="none")
    series("ms10_rep", seed=S, repeats=(1, 5, 10),
           truth="micro-slip, levels 1,5,10 re-run at end", expect="none")
    series("ms10_rep_std", seed=S, repeats=(1, 5, 10), std_cols=True,
           truth="micro-slip, repeats + std", expect="none")
    series("ms10_shuf", seed=S, repeats=(1, 5, 10), shuffle=True,
           truth="micro-slip, shuffled run order + repeats", expect="none")
    series("ms10_resp", seed=S, resp_col=True,
           truth="micro-slip with response_amplitude column", expect="none")
    series("ms4", n=4, step=2.5, seed=S, truth="micro-slip 4 levels", expect="none")
    series("ms6", n=6, step=2.0, seed=S, truth="micro-slip 6 levels", expect="none")
    series("ms6_rep_std", n=6, step=2.0, seed=S, repeats=(1, 6), std_cols=True,
           truth="micro-slip 6 levels, repeats, std", expect="none")
    series("rc10", control="response", seed=S, truth="micro-slip, response control", expect="none")
    series("rc6_rep", n=6, step=2.0, control="response", repeats=(1, 3), seed=S,
           truth="micro-slip, response control, 6 levels, repeats", expect="none")

    # bolt loosening: omega2 -0.6 % (freq -0.3 % = 6 repeatability sd) from run 6 on
    def step_eff(ro, nrun, w2, z):
        return (w2 * (1 - 0.006), z * 1.05) if ro >= 6 else (w2, z)
    series("step10", seed=S, time_effect=step_eff,
           truth="freq step -0.3 % from run 6 (bolt loosening), runs in level order",
           expect="not none (out-of-catalogue; unexplained/ thermal-drift/macro-slip plausible)")
    series("step10_shuf", seed=S, repeats=(1, 5, 10), shuffle=True, time_effect=step_eff,
           truth="freq step -0.3 % from run 6, shuffled runs + repeats",
           expect="thermal-drift or unexplained (step in time)")

    # slow drift: omega2 -0.8 % linearly with run order (freq -0.4 % = 8 sd)
    def drift(ro, nrun, w2, z):
        return w2 * (1 - 0.008 * (ro - 1) / (nrun - 1)), z
    series("drift_shuf", seed=S, repeats=(1, 5, 10), shuffle=True, time_effect=drift,
           truth="thermal drift omega2 -0.8 % over runs, shuffled", expect="thermal-drift")
    series("drift_rep", seed=S, repeats=(1, 2), time_effect=drift,
           truth="thermal drift, in order, levels 1,2 re-run at end", expect="thermal-drift")

    # hardening at the top levels
    def hard(A, w2, z):
        return w2 + 0.03 * W0 * (A / 12.0) ** 2, z
    series("hard10", seed=S, extra=hard, truth="geometric hardening +3 % omega2 at A=12 (~top)",
           expect="geometric-hardening")
    series("hard10_rep", seed=S, extra=hard, repeats=(1, 5, 10), std_cols=True,
           truth="hardening + repeats + std", expect="geometric-hardening")

    # quadratic damping (no softening)
    def qd(A, w2, z):
        return w2, z + 0.004 * (A / 12.0) ** 1.5
    series("qdamp10", seed=S, extra=qd, truth="extra damping +0.4 % abs at top, no softening",
           expect="quadratic-damping")

    # macro-slip: above A=5 extra softening and damping growth bends
    def macro(A, w2, z):
        x = max(A - 5.0, 0.0)
        return w2 - 0.004 * W0 * x ** 1.3, z + 0.0008 * x ** 1.0
    series("macro10", seed=S, extra=macro,
           truth="frequency drop bends away above A=5 (macro-slip-like)", expect="macro-slip")

    # nonproportional: exciter force drop-out, 40 % at top
    series("nonprop10", seed=S, resp_col=True,
           drive_loss=lambda lev, n: 1 - 0.4 * ((lev - 1) / (n - 1)) ** 1.5,
           truth="force drop-out 40 % at top, response_amplitude measured",
           expect="nonproportional-amplitude")

    # brief's example form: f = f0(1 - a x^1.6), zeta = z0 + b x^0.7
    # (x = level excitation, normalized)
    rng = np.random.default_rng(7)
    n = 10
    E = 0.5 * 1.5 ** np.arange(n)
    x = E / E[-1]
    f = F0 * (1 - 0.03 * x ** 1.6)
    z = 0.004 + 0.010 * x ** 0.7
    w2 = (2 * np.pi * f) ** 2 * (1 + 2 * FREQ_REP * rng.standard_normal(n))
    zz = z * (1 + ZETA_REP * rng.standard_normal(n))
    with open(OUT + "powerform10.csv", "w") as fh:
        fh.write("level,excitation,omega2,zeta\n")
        for i in range(n):
            fh.write("%d,%s,%s,%s\n" % (i + 1, fmt(E[i]), fmt(w2[i]), fmt(zz[i])))
    TRUTH["powerform10"] = dict(truth="f=f0(1-0.03x^1.6), zeta=0.004+0.01x^0.7 "
                                      "(exponents differ: not Iwan-tied)",
                                expect="not none ideally (breaks the tie); "
                                       "any named cause plausible")
    # noise-free micro-slip (sanity)
    FREQ_REP, ZETA_REP = 1e-7, 1e-6
    series("ms10_clean", seed=S, truth="micro-slip, essentially noise-free", expect="none")
    json.dump(TRUTH, open(OUT + "truth.json", "w"), indent=1)
    print(", ".join(TRUTH))
