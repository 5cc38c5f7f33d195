"""Jenkins-bank slider updates per second: the compiled kernel of joints/kernel.py
against straightforward vectorized numpy updates, measured side by side in one run.

Usage::

    python benchmarks/bench_jenkins.py            # full run, about a minute
    python benchmarks/bench_jenkins.py --quick    # smoke run, a few seconds

Everything runs on one thread (NUMBA_NUM_THREADS, OPENBLAS/OMP/MKL_NUM_THREADS = 1,
set before numpy is imported). Each figure is the median over interleaved repetitions
of the thread's CPU time (``time.thread_time``), so other processes on a shared
machine inflate it less than wall-clock time would; wall-clock medians are printed
beside. A "slider update" is one return mapping of one Jenkins element together with
its share of the force and tangent sums.

Sections:
1. rates of the kernel inside a compiled step loop (what a compiled solver sees), of
   the Python-level calls :func:`jenkins_update_into` and :func:`jenkins_update`, of
   a straightforward numpy update (``np.clip``, ``np.sum``) and of the previous numpy
   ``jenkins_update`` (maximum/minimum, BLAS matrix-vector sums); the accuracy column
   is the largest force difference against the numpy update over the whole driven
   history, relative to the largest force, and whether anchors, forces and tangents
   are bitwise equal;
2. cost exponent: log-log slope of the time per step against the number of joints
   (1..1000 joints x 100 sliders) and of sliders (10..10000 sliders x 10 joints).
"""
from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

from joints.iwan import IwanParameters  # noqa: E402
from joints.jenkins import discretize, jenkins_update, jenkins_update_into  # noqa: E402
from joints.kernel import bank_update_kernel  # noqa: E402

TARGET_RATE = 5e8          # slider updates per second, one core
TARGET_RATIO = 20.0        # kernel / straightforward numpy
TARGET_EXPONENT = (0.9, 1.1)
PAPER = IwanParameters(chi=-0.5, K_T=1.1e5, F_S=400.0, beta=4.0)
STEPS_PER_CYCLE = 64


# ----------------------------------------------------------------- implementations


def numpy_clip_update(slip, anchor, k, phi):
    """Straightforward vectorized numpy update (np.clip, np.sum)."""
    col = slip[:, None]
    new = np.clip(anchor, col - phi, col + phi)
    force = ((col - new) * k).sum(axis=1)
    tangent = np.where(new == anchor, k, 0.0).sum(axis=1)
    return force, tangent, new


def previous_numpy_update(slip, anchor, k, phi):
    """joints.jenkins.jenkins_update before the compiled kernel (numpy, BLAS sums)."""
    col = slip[:, None]
    new = np.subtract(col, phi)
    np.maximum(anchor, new, out=new)
    work = np.add(col, phi)
    np.minimum(new, work, out=new)
    stuck = new == anchor
    stretch = np.subtract(col, new, out=work)
    if k.ndim == 1:
        return stretch @ k, stuck @ k, new
    return np.einsum("ij,ij->i", stretch, k), np.einsum("ij,ij->i", stuck, k), new


@njit
def compiled_march(slips, anchor, k, phi, force, tangent):
    """Step loop calling the kernel from compiled code, committing in place, on
    preallocated slip/force/tangent vectors as the solvers do (fe/newmark_march.py): a
    row view ``slips[t]`` made per call would cost ~30 ns, more than a 100-slider joint."""
    n_joints = slips.shape[1]
    s = np.empty(n_joints)
    f = np.empty(n_joints)
    kt = np.empty(n_joints)
    for t in range(slips.shape[0]):
        for j in range(n_joints):
            s[j] = slips[t, j]
        bank_update_kernel(s, anchor, k, phi, anchor, f, kt)
        for j in range(n_joints):
            force[t, j] = f[j]
            tangent[t, j] = kt[j]


def python_march(update, slips, anchor, k, phi):
    """Step loop over a pure update (commits the returned anchors)."""
    force = np.empty(slips.shape)
    tangent = np.empty(slips.shape)
    for t in range(slips.shape[0]):
        force[t], tangent[t], anchor = update(slips[t], anchor, k, phi)
    return force, tangent, anchor


def into_march(slips, anchor, k, phi):
    force = np.empty(slips.shape)
    tangent = np.empty(slips.shape)
    for t in range(slips.shape[0]):
        jenkins_update_into(slips[t], anchor, k, phi, anchor, force[t], tangent[t])
    return force, tangent, anchor


# ----------------------------------------------------------------- problem set-up


def bank(n_joints, n_sliders, n_steps):
    """Paper joint discretized with n_sliders; joints driven by sines whose amplitudes
    span 0.3 .. 1.2 phi_max (micro- to macro-slip), n_steps steps."""
    d = discretize(PAPER, n_sliders)
    amp = np.linspace(0.3, 1.2, n_joints) * PAPER.phi_max
    theta = 2 * np.pi * np.arange(n_steps) / STEPS_PER_CYCLE
    slips = np.ascontiguousarray(np.sin(theta)[:, None] * amp)
    return slips, d.stiffness, d.slip_limit


def timed(fn, timer):
    t0 = timer()
    fn()
    return timer() - t0


def interleaved(cases, repeats):
    """Median CPU and wall times of each case, repetitions interleaved."""
    cpu = {name: [] for name in cases}
    wall = {name: [] for name in cases}
    for _ in range(repeats):
        for name, fn in cases.items():
            t0, c0 = time.perf_counter(), time.thread_time()
            fn()
            cpu[name].append(time.thread_time() - c0)
            wall[name].append(time.perf_counter() - t0)
    return ({n: float(np.median(v)) for n, v in cpu.items()},
            {n: float(np.median(v)) for n, v in wall.items()})


def steps_for(n_updates_per_step, seconds, rate):
    """Steps so that one repetition lasts about `seconds` at `rate` updates/s."""
    return int(np.clip(seconds * rate / n_updates_per_step, 4, 200000))


# ----------------------------------------------------------------- sections


def rates_table(sizes, repeats, seconds):
    rows = []
    for nj, ns in sizes:
        n_up = nj * ns
        n_c = steps_for(n_up, seconds, 3e9)       # compiled loop
        n_p = steps_for(n_up, seconds, 3e8 if n_up > 5e3 else 5e7)
        slips_c, k, phi = bank(nj, ns, n_c)
        slips_p, _, _ = bank(nj, ns, n_p)
        k2, phi2 = k[None, :].copy(), phi[None, :].copy()
        # accuracy: the same history through the kernel and the numpy updates
        F_ref, T_ref, A_ref = python_march(numpy_clip_update, slips_p, np.zeros((nj, ns)), k, phi)
        F_prev, _, _ = python_march(previous_numpy_update, slips_p, np.zeros((nj, ns)), k, phi)
        F_c, T_c = np.empty(slips_p.shape), np.empty(slips_p.shape)
        A_c = np.zeros((nj, ns))
        compiled_march(slips_p, A_c, k2, phi2, F_c, T_c)
        F_p, T_p, A_p = python_march(jenkins_update, slips_p, np.zeros((nj, ns)), k, phi)
        scale = np.abs(F_ref).max()
        anchors_bitwise = all(np.array_equal(a.view(np.uint64), b.view(np.uint64))
                              for a, b in ((A_c, A_ref), (A_p, A_ref)))
        err_numpy = max(np.abs(F_c - F_ref).max(), np.abs(F_p - F_ref).max(),
                        np.abs(T_c - T_ref).max() / k.sum() * scale) / scale
        err_prev = np.abs(F_c - F_prev).max() / scale

        state = np.zeros((nj, ns))
        Fb, Tb = np.empty(slips_c.shape), np.empty(slips_c.shape)
        cases = {
            "compiled": lambda: compiled_march(slips_c, state, k2, phi2, Fb, Tb),
            "into": lambda: into_march(slips_p, np.zeros((nj, ns)), k2, phi2),
            "update": lambda: python_march(jenkins_update, slips_p, np.zeros((nj, ns)), k, phi),
            "numpy": lambda: python_march(numpy_clip_update, slips_p, np.zeros((nj, ns)), k, phi),
            "previous": lambda: python_march(previous_numpy_update, slips_p,
                                             np.zeros((nj, ns)), k, phi),
        }
        cpu, wall = interleaved(cases, repeats)
        steps = {"compiled": n_c}
        rate = {n: n_up * steps.get(n, n_p) / cpu[n] for n in cases}
        rate_wall = {n: n_up * steps.get(n, n_p) / wall[n] for n in cases}
        rows.append(dict(nj=nj, ns=ns, rate=rate, rate_wall=rate_wall, bitwise=anchors_bitwise,
                         err_numpy=err_numpy, err_prev=err_prev))
    return rows


def exponent(sweep, fixed, axis, repeats, seconds):
    """Times per step (compiled loop and Python call) against `sweep` sizes."""
    t_comp, t_py = [], []
    for n in sweep:
        nj, ns = (n, fixed) if axis == "joints" else (fixed, n)
        n_c = steps_for(nj * ns, seconds, 3e9)
        n_p = max(4, min(n_c, steps_for(nj * ns, seconds / 2, 1e8)))
        slips_c, k, phi = bank(nj, ns, n_c)
        slips_p = slips_c[:n_p]
        k2, phi2 = k[None, :].copy(), phi[None, :].copy()
        state = np.zeros((nj, ns))
        Fb, Tb = np.empty(slips_c.shape), np.empty(slips_c.shape)
        cpu, _ = interleaved({
            "compiled": lambda: compiled_march(slips_c, state, k2, phi2, Fb, Tb),
            "into": lambda: into_march(slips_p, np.zeros((nj, ns)), k2, phi2)}, repeats)
        t_comp.append(cpu["compiled"] / n_c)
        t_py.append(cpu["into"] / n_p)
    x = np.log(np.asarray(sweep, float))
    slope_c = np.polyfit(x, np.log(t_comp), 1)[0]
    slope_p = np.polyfit(x, np.log(t_py), 1)[0]
    # slope over the upper decade-and-more only (fixed costs negligible)
    upper = np.asarray(sweep) >= np.asarray(sweep).max() / 30
    slope_hi = np.polyfit(x[upper], np.log(np.asarray(t_comp)[upper]), 1)[0]
    return np.array(t_comp), np.array(t_py), slope_c, slope_p, slope_hi


def fmt_rate(r):
    return f"{r:9.3g}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="few sizes, short repetitions")
    parser.add_argument("--repeats", type=int, default=None,
                        help="interleaved repetitions per figure (default 7, quick 3)")
    args = parser.parse_args(argv)
    repeats = args.repeats or (3 if args.quick else 7)
    seconds = 0.004 if args.quick else 0.02

    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    cpu_name = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu_name = next(ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    print(f"# bench_jenkins: {cpu_name}, {os.cpu_count()} cores, load average "
          f"{load[0]:.2f}; Python {platform.python_version()}, numpy {np.__version__}, "
          f"numba {numba.__version__}; one thread")
    print(f"# medians of {repeats} interleaved repetitions, thread CPU time (wall-clock "
          "in brackets); rates in slider updates per second")

    t0 = time.perf_counter()
    # warm-up: compile the kernel and the driver
    s, k, phi = bank(2, 300, 8)
    compiled_march(s, np.zeros((2, 300)), k[None], phi[None], np.empty(s.shape), np.empty(s.shape))
    jenkins_update(s[0], np.zeros((2, 300)), k, phi)

    sizes = ([(2, 100), (100, 1000)] if args.quick else
             [(1, 100), (2, 100), (10, 100), (100, 100), (10, 1000), (100, 1000), (1000, 100),
              (10, 10000)])
    print("\n## 1. rates (accuracy: max |F - F_numpy| / max|F| over the driven history)\n")
    head = (f"{'joints x sliders':>17} | {'compiled loop':>21} | {'jenkins_update_into':>21} | "
            f"{'jenkins_update':>21} | {'numpy np.clip':>21} | {'previous numpy':>21} | "
            f"{'ratio':>6} | {'ratio':>6} | accuracy vs numpy")
    print(head)
    print(f"{'':>17} | {'(kernel)':>21} | {'(Python call)':>21} | {'(Python call)':>21} | "
          f"{'(straightforward)':>21} | {'(maximum/minimum+@)':>21} | {'comp.':>6} | "
          f"{'call':>6} |")
    rows = rates_table(sizes, repeats, seconds)
    for r in rows:
        rt, rw = r["rate"], r["rate_wall"]
        cells = " | ".join(f"{rt[n]:9.3g} [{rw[n]:9.3g}]" for n in
                           ("compiled", "into", "update", "numpy", "previous"))
        acc = (("anchors bitwise, " if r["bitwise"] else "ANCHORS DIFFER, ")
               + f"F, k_t {r['err_numpy']:.1e}")
        print(f"{r['nj']:>8d} x {r['ns']:<6d} | {cells} | {rt['compiled'] / rt['numpy']:6.1f} | "
              f"{rt['update'] / rt['numpy']:6.1f} | {acc} (previous: {r['err_prev']:.1e})")

    big = max(rows, key=lambda r: r["nj"] * r["ns"] * (r["nj"] > 1))
    best = max(r["rate"]["compiled"] for r in rows)
    med = float(np.median([r["rate"]["compiled"] for r in rows if r["nj"] * r["ns"] >= 1e4]
                          or [best]))
    ratios = [r["rate"]["compiled"] / r["rate"]["numpy"] for r in rows]

    print("\n## 2. cost exponent (time per step ~ size^p, compiled loop; Python call in "
          "brackets)\n")
    if args.quick:
        j_sweep, s_sweep = [1, 10, 100], [10, 100, 1000]
    else:
        j_sweep = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000]
        s_sweep = [10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000]
    exps = {}
    points = []                     # (joints, sliders per joint, time per step)
    for label, sweep, fixed, axis in (("joints (x 100 sliders)", j_sweep, 100, "joints"),
                                      ("sliders (x 10 joints)", s_sweep, 10, "sliders")):
        tc, tp, pc, pp, phi_ = exponent(sweep, fixed, axis, repeats, seconds)
        exps[axis] = (pc, phi_)
        points += [((n, fixed) if axis == "joints" else (fixed, n)) + (t,)
                   for n, t in zip(sweep, tc)]
        print(f"{label:>24}: " + "  ".join(f"{n}:{t * 1e6:.3g}us" for n, t in zip(sweep, tc)))
        print(f"{'':>24}  p = {pc:.3f} over {sweep[0]}..{sweep[-1]}, "
              f"p = {phi_:.3f} over the top 1.5 decades  [Python call: p = {pp:.3f}, "
              f"{tp[0] * 1e6:.2f} us at {sweep[0]}]")

    # cost model t = c_call + n_joints c_joint + n_joints n_sliders c_slider, fitted to
    # both sweeps by least squares on relative residuals
    nj_, ns_, t_ = (np.array(v, float) for v in zip(*points))
    A = np.column_stack([np.ones_like(t_), nj_, nj_ * ns_]) / t_[:, None]
    (c_call, c_joint, c_slider), *_ = np.linalg.lstsq(A, np.ones_like(t_), rcond=None)
    model = c_call + nj_ * c_joint + nj_ * ns_ * c_slider
    print(f"\ncost model: t = {c_call * 1e9:.1f} ns per call + {c_joint * 1e9:.2f} ns per joint "
          f"+ {c_slider * 1e9:.3f} ns per slider ({1 / c_slider:.3g} updates/s); "
          f"largest relative misfit {np.abs(model / t_ - 1).max():.2f}; the fixed cost per "
          f"joint equals {c_joint / c_slider:.0f} slider updates")

    print("\n## targets\n")
    lo, hi = TARGET_EXPONENT

    def verdict(ok):
        return "met" if ok else "NOT met"

    print(f"kernel rate >= {TARGET_RATE:.0e}/s: median {med:.3g}/s over banks >= 1e4 "
          f"sliders, best {best:.3g}/s -> {verdict(med >= TARGET_RATE)}")
    print(f"kernel / numpy >= {TARGET_RATIO:.0f}x: {min(ratios):.1f}x .. {max(ratios):.1f}x "
          f"(largest bank {big['nj']}x{big['ns']}: "
          f"{big['rate']['compiled'] / big['rate']['numpy']:.1f}x) -> "
          f"{verdict(min(ratios) >= TARGET_RATIO)} for every size"
          + ("" if min(ratios) >= TARGET_RATIO else
             f", met for {sum(r >= TARGET_RATIO for r in ratios)} of {len(ratios)}"))
    for axis in ("joints", "sliders"):
        pc, ph = exps[axis]
        print(f"cost exponent vs {axis}: {pc:.3f} (top decades {ph:.3f}), target 1.0 +/- 0.1 "
              f"-> {verdict(lo <= pc <= hi)}")
    exact = all(r["bitwise"] for r in rows)
    worst = max(r["err_numpy"] for r in rows)
    print("accuracy: " + ("anchors bitwise equal to numpy in every case" if exact
                          else "anchors NOT bitwise equal: see table")
          + f"; force and tangent within {worst:.1e} of numpy's (relative to the largest)")
    print(f"# total {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
