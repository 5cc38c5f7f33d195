"""Newmark per step through each joint law (docs/joint-laws.md): the Jenkins bank's compiled
loop against the plain Python loop over a law's ``step`` (the bank's own reference loop, the
exact Iwan step, Bouc-Wen).

A mass of 1 kg on one joint (K_T = 5e4 N/m, F_S = 30 N; Iwan chi = -0.4, beta = 0.8, bank
of 100 sliders; Bouc-Wen with the same K_T, F_S), 5 N/m/s damping, driven at the stuck
natural frequency with 0.8 F_S, 64 steps a period, 20000 steps. Prints microseconds per
step (wall clock, after a warm-up run) and Newton iterations.

    python benchmarks/bench_joint_laws.py
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fe.newmark import NewmarkSettings, integrate  # noqa: E402
from fe.reduction import JointBank, ReducedModel  # noqa: E402
from joints.bouc_wen import BoucWenJoints, BoucWenParameters  # noqa: E402
from joints.describing import IwanJoints  # noqa: E402
from joints.iwan import IwanParameters  # noqa: E402


def main(n_steps: int = 20000) -> None:
    p = IwanParameters(chi=-0.4, K_T=5e4, F_S=30.0, beta=0.8)
    model = ReducedModel(basis=np.eye(1), omega=np.array([np.sqrt(p.K_T)]), M=np.eye(1),
                         K=np.array([[p.K_T]]), C=np.array([[5.0]]), G=np.eye(1),
                         K_T=np.array([p.K_T]), n_modes=1)
    w = np.sqrt(p.K_T)
    dt = 2 * np.pi / w / 64
    e = np.cos(w * dt * np.arange(n_steps + 1))
    load = np.array([0.8 * p.F_S])
    laws = (("bank, compiled loop", JointBank.from_iwan(p, 100, 1), True),
            ("bank, Python loop", JointBank.from_iwan(p, 100, 1), False),
            ("Iwan exact step", IwanJoints(p, 1), True),
            ("Bouc-Wen step", BoucWenJoints(BoucWenParameters(p.K_T, p.F_S), 1), True))
    for name, law, compiled in laws:
        integrate(model, law, load, e[:100], NewmarkSettings(dt=dt), compiled=compiled)
        t0 = time.perf_counter()
        run = integrate(model, law, load, e, NewmarkSettings(dt=dt), compiled=compiled)
        us = 1e6 * (time.perf_counter() - t0) / n_steps
        print(f"{name:22s} {us:9.2f} us/step   Newton iterations {run.newton_iterations}")


if __name__ == "__main__":
    main()
