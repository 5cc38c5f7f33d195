"""Stepped-sine campaigns run level by level, resumable on disk.

The protocols and the campaign definition are in :mod:`runs.campaign`; here each
protocol's level runner (:func:`run_level`), the campaign hash and
:func:`run_campaign`. Each level starts from rest with virgin joints, so levels are
independent tasks of :func:`runs.executor.run_sweep` (serial, local processes or a
dask.distributed cluster, bitwise the same numbers). Each finished level is written to
``level_XX.npz`` in the store directory as soon as it is done, with a
``manifest.json`` holding the SHA-256 hash of every input (model, joints, lines,
levels, protocol); a rerun with the same inputs loads the finished levels and computes
only the missing ones, giving the same numbers as an uninterrupted run.

SI units: Hz for line frequencies, N for force amplitudes, m for displacements.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
from pathlib import Path
from typing import Callable

import numpy as np

from fe.harmonic_balance import continuation
from fe.newmark import NewmarkIntegrator, NewmarkSettings, NewmarkState
from fe.newmark_period import PeriodNewton, joint_equivalent, linear_monodromy, period_step
from fe.newton_path import SteadyStateError
from fe.reduction import JointBank, ReducedModel
from runs.campaign import Campaign, CampaignResult, LevelResult, NewmarkProtocol, PaperProtocol
from runs import interrupt
from runs.executor import ExecutorSpec, run_sweep
from runs.store import open_manifest, write_manifest

__all__ = ["campaign_hash", "run_level", "run_campaign"]

FORMAT = "iwanfe-stepped-sine/2"   # 2: fallbacks per line


# --------------------------------------------------------------------------- hashing


def _describe(obj):
    if dataclasses.is_dataclass(obj):
        return {"type": type(obj).__name__,
                **{f.name: _describe(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


def campaign_hash(model: ReducedModel, bank: JointBank | None, campaign: Campaign) -> str:
    """SHA-256 over the reduced model, the joint banks (None: a protocol that carries
    its own joints, the exact path of :mod:`runs.response_control`) and the campaign
    definition."""
    h = hashlib.sha256()
    joints = () if bank is None else (bank.stiffness, bank.slip_limit)
    for a in (model.basis, model.M, model.K, model.C, model.G, model.K_T,
              *joints, campaign.frequency_hz, campaign.force,
              campaign.load, campaign.outputs):
        a = np.ascontiguousarray(a)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(json.dumps(_describe(campaign.protocol), sort_keys=True).encode())
    h.update(FORMAT.encode())
    return h.hexdigest()


# --------------------------------------------------------------------------- one level


def _hb_level(model, bank, campaign, F, tick):
    load = model.load(campaign.load) * F
    sols = continuation(model, bank, load, 2 * np.pi * campaign.frequency_hz,
                        campaign.protocol.settings, progress=tick)
    rec = np.array([s.first_harmonic(model)[campaign.outputs] for s in sols]) / F
    slip = np.array([s.slip[s.harmonics == 1][0] for s in sols])
    amp = np.array([s.slip_amplitude for s in sols])
    work = np.array([s.iterations for s in sols], dtype=float)
    return rec, slip, amp, work, [s.fallback for s in sols]


def _first_harmonic(y, theta):
    """``2/N sum y_n exp(-i theta_n)`` over one period of ``N`` samples; y (N, m)."""
    return (2.0 / theta.size) * (np.exp(-1j * theta) @ y)


def _newmark_level(model, bank, campaign, F, tick):
    pr: NewmarkProtocol = campaign.protocol
    N = pr.steps_per_period
    load = model.load(campaign.load) * F
    Bout = model.basis[campaign.outputs]
    state = NewmarkState.rest(model, bank)
    phase = 0.0
    n_lines = campaign.frequency_hz.size
    rec = np.empty((n_lines, campaign.outputs.size), dtype=complex)
    slip = np.empty((n_lines, model.n_joints), dtype=complex)
    amp = np.empty((n_lines, model.n_joints))
    work = np.empty(n_lines)
    orbits = None
    if pr.hb_start is not None:
        orbits = continuation(model, bank, load, 2 * np.pi * campaign.frequency_hz,
                              pr.hb_start)
        N = pr.steps_for(max(o.slip_amplitude.max() for o in orbits),
                         float(bank.slip_limit.max()))
    k = np.arange(N + 1)
    for li, f_hz in enumerate(campaign.frequency_hz):
        w = 2 * np.pi * f_hz
        if pr.prewarp:
            w = w * np.pi / (N * np.tan(np.pi / N))
        dt = 2 * np.pi / (w * N)
        stepper = NewmarkIntegrator(model, bank, NewmarkSettings(dt=dt, alpha=pr.alpha))
        newton = None
        if orbits is not None:
            o = orbits[li]
            state = NewmarkState.periodic(model, bank, o.harmonics, o.q, w, load.real, N, dt)
            phase = 0.0
            if pr.period_newton and pr.alpha == 0.0:
                newton = _period_newton(model, o, dt, N)
        theta = phase + w * dt * k
        e = np.cos(theta)
        state.e = e[0]
        prev, d_hist, jump = None, [], np.inf
        for p in range(1, pr.max_periods + 1):
            try:
                run = stepper.run(load, e, state, energy=False)
            except RuntimeError as exc:          # the per-step Newton of the joints
                raise SteadyStateError(f"{f_hz:g} Hz", str(exc), solver="Newmark") from None
            start, state = state, run.state
            if newton is not None:   # fe.newmark_period; a growing change: a plain period
                change = np.linalg.norm(np.concatenate([state.q - start.q, state.v - start.v]))
                jump = min(jump, change)
                if change <= 4.0 * jump:
                    state = period_step(model, bank, start, state, newton, load.real)
                else:
                    newton.reset()
                    jump = change
            z = np.concatenate([_first_harmonic(run.q[:-1] @ Bout.T, theta[:-1]),
                                _first_harmonic(run.slip[:-1], theta[:-1])])
            if prev is not None:
                d = np.linalg.norm(z - prev) / max(np.linalg.norm(z), 1e-300)
                d_hist.append(d)
                if p >= pr.min_periods and len(d_hist) >= 4:
                    ratios = np.array(d_hist[-3:]) / np.maximum(np.array(d_hist[-4:-1]), 1e-300)
                    rho = float(np.max(ratios))
                    if d < 1e-13 or (rho < 1.0 and d * rho / (1.0 - rho) < pr.tol):
                        break
            prev = z
        else:
            raise SteadyStateError(f"{f_hz:g} Hz", f"no periodic response after "
                                   f"{pr.max_periods} periods (drift "
                                   f"{d_hist[-1] if d_hist else np.nan:.2e})", solver="Newmark")
        n_out = campaign.outputs.size
        rec[li] = z[:n_out] / F
        slip[li] = z[n_out:]
        s_last = run.slip[:-1]
        amp[li] = 0.5 * (s_last.max(axis=0) - s_last.min(axis=0))
        work[li] = p
        phase = float(np.mod(theta[-1], 2 * np.pi))
        if tick is not None:
            tick.update(1)
    return rec, slip, amp, work, None


def _period_newton(model, orbit, dt, n_steps):
    """Newton on the period map from the monodromy linearized on ``orbit``
    (:mod:`fe.newmark_period`)."""
    k_g, c_g = joint_equivalent(orbit.slip, orbit.joint_force, orbit.harmonics, orbit.omega)
    return PeriodNewton(linear_monodromy(model, dt, n_steps, k_g, c_g))


def _paper_level(model, bank, campaign, F, tick):
    pr: PaperProtocol = campaign.protocol
    N = pr.steps_per_period
    load = model.load(campaign.load) * F
    Bout = model.basis[campaign.outputs]
    n_lines = campaign.frequency_hz.size
    rec = np.empty((n_lines, campaign.outputs.size), dtype=complex)
    slip = np.empty((n_lines, model.n_joints), dtype=complex)
    amp = np.empty((n_lines, model.n_joints))
    work = np.empty(n_lines)
    for li, f_hz in enumerate(campaign.frequency_hz):
        w = 2 * np.pi * f_hz
        dt = 2 * np.pi / (w * N)
        stepper = NewmarkIntegrator(model, bank, NewmarkSettings(dt=dt, alpha=pr.alpha))
        n_settle = int(round(pr.settle / dt))
        n_window = int(round(pr.window / dt))
        state = NewmarkState.rest(model, bank)
        chunk = max(1, int(round(1.0 / dt)))
        done = 0
        while done < n_settle:                       # settle in 1-s chunks, keep nothing
            n = min(chunk, n_settle - done)
            e = np.cos(w * dt * np.arange(done, done + n + 1))
            state = stepper.run(load, e, state, energy=False).state
            done += n
        e = np.cos(w * dt * np.arange(done, done + n_window + 1))
        run = stepper.run(load, e, state, energy=False)
        theta = w * run.t
        A = np.column_stack([np.ones_like(theta), np.cos(theta), np.sin(theta)])
        Y = np.hstack([run.q @ Bout.T, run.slip])
        coef, *_ = np.linalg.lstsq(A, Y, rcond=None)
        z = coef[1] - 1j * coef[2]
        n_out = campaign.outputs.size
        rec[li] = z[:n_out] / F
        slip[li] = z[n_out:]
        amp[li] = 0.5 * (run.slip.max(axis=0) - run.slip.min(axis=0))
        work[li] = (n_settle + n_window) / N
        if tick is not None:
            tick.update(1)
    return rec, slip, amp, work, None


_LEVEL_RUNNERS = {"hb": _hb_level, "newmark": _newmark_level, "paper": _paper_level}


def run_level(model: ReducedModel, bank: JointBank, campaign: Campaign, level: int,
              tick=None) -> LevelResult:
    """Compute one force level of ``campaign`` (all lines), from rest."""
    F = float(campaign.force[level])
    t0 = time.perf_counter()
    # a protocol defined elsewhere brings its own runner (runs.response_control)
    runner = getattr(campaign.protocol, "run_level", None) or _LEVEL_RUNNERS[campaign.protocol.name]
    try:
        with interrupt.deferred():   # Ctrl-C between lines only, never inside compiled code
            rec, slip, amp, work, fallbacks = runner(model, bank, campaign, F,
                                                     interrupt.Ticker(tick))
    except SteadyStateError as exc:
        raise exc.within(f"level {level + 1} of {campaign.force.size} (F = {F:.4g} N)") from None
    fallbacks = np.asarray([""] * len(work) if fallbacks is None else fallbacks, dtype=str)
    return LevelResult(F, rec, slip, amp, work, time.perf_counter() - t0, fallbacks)


def _level_task(level: int, shared) -> LevelResult:
    """One level as an executor task (module level: picklable by reference); ``shared``
    is ``(model, bank, campaign)``, sent once per worker."""
    model, bank, campaign = shared
    return run_level(model, bank, campaign, level)


def _executor_spec(executor, workers) -> ExecutorSpec:
    """The :class:`~runs.executor.ExecutorSpec` of :func:`run_campaign`'s arguments."""
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers
                                or workers < 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if isinstance(executor, ExecutorSpec):
        if workers not in (None, 1):
            raise ValueError("give the number of workers inside the ExecutorSpec")
        return executor
    if executor is None:
        return ExecutorSpec("processes", int(workers)) if workers and workers > 1 \
            else ExecutorSpec("serial")
    if executor == "serial":
        return ExecutorSpec("serial")
    return ExecutorSpec(executor, workers)


# --------------------------------------------------------------------------- campaign


def run_campaign(model: ReducedModel, bank: JointBank, campaign: Campaign,
                 store: str | os.PathLike | None = None, progress: bool = True,
                 workers: int | None = None,
                 on_level: Callable[[int, LevelResult], None] | None = None,
                 executor: str | ExecutorSpec | None = None) -> CampaignResult:
    """Run (or resume) a campaign.

    Levels are independent tasks of :func:`runs.executor.run_sweep`: computed serially,
    in local processes or on a dask.distributed cluster, with bitwise the same results
    (each level starts from rest; no random numbers).

    Parameters
    ----------
    model, bank, campaign
    store : path, optional
        Directory holding ``manifest.json`` and one ``level_XX.npz`` per finished
        level, each written as soon as its level is done (whichever worker computed
        it). Finished levels of a campaign with the same hash are loaded, not
        recomputed. A store holding another campaign raises ``ValueError``.
    progress : bool
        tqdm progress bar on stderr (one tick per line when serial, per level
        otherwise).
    workers : int, optional
        Without ``executor``: levels computed in that many local processes (1 or None:
        serial). With ``executor="processes"`` or ``"dask"``: the pool size or the
        number of workers of the local dask cluster started for the campaign.
    on_level : callable, optional
        Called as ``on_level(level, result)`` after each newly computed level has been
        stored (an exception raised there interrupts the campaign after the save).
    executor : {"serial", "processes", "dask"} or runs.executor.ExecutorSpec, optional
        Where the levels run; an :class:`~runs.executor.ExecutorSpec` can name an
        existing dask scheduler (``ExecutorSpec("dask", scheduler="tcp://HOST:8786")``).

    Returns
    -------
    CampaignResult
    """
    spec = _executor_spec(executor, workers)
    digest = campaign_hash(model, bank, campaign)
    n_levels, n_lines = campaign.force.size, campaign.frequency_hz.size
    results: dict[int, LevelResult] = {}
    manifest = None
    if store is not None:
        store = Path(store)
        manifest, results = _open_store(store, digest, campaign)
    loaded = set(results)
    todo = [lv for lv in range(n_levels) if lv not in results]

    def finish(level: int, res: LevelResult) -> None:
        results[level] = res
        if store is not None:
            _save_level(store, manifest, level, res)
        if on_level is not None:
            on_level(level, res)

    if len(todo) <= 1 and spec.scheduler is None:   # nothing to share out: no pool
        spec = ExecutorSpec("serial")
    bar = None
    if progress and todo and spec.kind == "serial":
        from tqdm import tqdm
        bar = tqdm(total=len(todo) * n_lines, unit="line",
                   desc=f"{campaign.protocol.name} campaign", leave=False)
    try:
        if spec.kind == "serial":       # one tick per line
            def func(level, shared):
                return run_level(*shared, level, bar)
        else:
            func = _level_task
        run_sweep(func, todo, executor=spec, shared=(model, bank, campaign),
                  progress=progress and spec.kind != "serial",
                  desc=f"{campaign.protocol.name} campaign", unit="level", chunksize=1,
                  on_result=lambda i, res: finish(todo[i], res))
    finally:
        if bar is not None:
            bar.close()
    return _collect(campaign, results, loaded, digest)


def _open_store(store: Path, digest: str, campaign: Campaign
                ) -> tuple[dict, dict[int, LevelResult]]:
    """The store's manifest (opened, or started for this campaign) and the finished
    levels it holds."""
    n_lines = campaign.frequency_hz.size
    manifest = open_manifest(
        store, digest, {"format": FORMAT, "protocol": campaign.protocol.name,
                        "force": campaign.force.tolist(),
                        "frequency_hz": [float(campaign.frequency_hz[0]),
                                         float(campaign.frequency_hz[-1]), n_lines],
                        "levels": {}}, "campaign")
    results: dict[int, LevelResult] = {}
    for key, info in manifest.get("levels", {}).items():
        path = store / info["file"]
        if path.exists():
            results[int(key)] = LevelResult.from_npz(path)
    return manifest, results


def _save_level(store: Path, manifest: dict, level: int, res: LevelResult) -> None:
    """Write a finished level to the store and name it in the manifest."""
    name = f"level_{level:02d}.npz"
    res.to_npz(store / name)
    manifest["levels"][str(level)] = {"file": name, "force": res.force,
                                      "elapsed_s": res.elapsed}
    write_manifest(store, manifest)


def _collect(campaign: Campaign, results: dict[int, LevelResult], loaded: set[int],
             digest: str) -> CampaignResult:
    """The campaign's result: every level's, in level order."""
    order = range(campaign.force.size)
    return CampaignResult(
        frequency_hz=campaign.frequency_hz, force=campaign.force,
        receptance=np.array([results[i].receptance for i in order]),
        slip=np.array([results[i].slip for i in order]),
        slip_amplitude=np.array([results[i].slip_amplitude for i in order]),
        work=np.array([results[i].work for i in order]),
        fallbacks=np.array([results[i].fallbacks for i in order]),
        elapsed=np.array([results[i].elapsed for i in order]),
        computed=np.array([i not in loaded for i in order]),
        hash=digest, protocol=campaign.protocol.name)
