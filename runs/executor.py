"""One executor interface for every sweep: serial, local processes or dask.distributed.

A sweep is a list of independent *tasks* (campaign levels or lines, mesh sizes, Monte
Carlo samples of joint parameters, diagnosis cases) and a function ``func(task)``, or
``func(task, shared)`` with one read-only object sent once to every worker (a reduced
model, a joint bank). :func:`run_sweep` returns ``[func(t) for t in tasks]`` in task
order whatever the executor:

``"serial"``
    a loop in this process;
``"processes"``
    a :class:`concurrent.futures.ProcessPoolExecutor` of ``workers`` spawned processes
    (``func`` must be a module-level function, picklable by reference);
``"dask"``
    a dask.distributed cluster: a :class:`distributed.LocalCluster` of ``workers``
    single-threaded worker processes started for the sweep and closed after it, or the
    existing cluster whose scheduler is at ``scheduler`` (``"tcp://HOST:8786"``, a
    scheduler file written by ``dask scheduler --scheduler-file``, or a connected
    :class:`distributed.Client`).

Reproducibility: a task carries everything random it needs (a seed, see
:func:`task_seeds`), so results do not depend on which worker runs which task, nor
in which order; the same tasks give bitwise the same results on every executor
(tests/test_executor.py). Worker processes run numpy's BLAS on one thread (dask's
default for its workers; set here for the process pool too): with two cores and
several workers, threads per worker only oversubscribe. Code whose floating-point
result depends on the BLAS thread count (large multi-threaded dot products) can then
differ in the last bits from a serial run in a multi-threaded parent; set
``OPENBLAS_NUM_THREADS=1`` there too for bitwise agreement.

Progress: one tqdm bar on stderr counts finished tasks for every executor (dask
futures through :func:`distributed.as_completed`).
"""
from __future__ import annotations

import math
import os
import pickle
import sys
import warnings
from contextlib import closing, contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterable

import numpy as np

from runs import interrupt
from runs.scheduler import check_scheduler, connect_client

__all__ = ["EXECUTORS", "ExecutorSpec", "run_sweep", "task_seeds"]

EXECUTORS = ("serial", "processes", "dask")
_ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
_NO_SHARED = object()
_WORKER_SHARED = None  # the shared object inside a process-pool worker


def task_seeds(seed: int, n_tasks: int) -> list[np.random.SeedSequence]:
    """Independent, reproducible seeds for ``n_tasks`` tasks.

    ``np.random.SeedSequence(seed).spawn(n_tasks)``: task ``i`` draws from
    ``np.random.default_rng(seeds[i])``, the same numbers on any worker and in any
    order of execution.
    """
    return np.random.SeedSequence(seed).spawn(int(n_tasks))


@dataclass(frozen=True)
class ExecutorSpec:
    """Where a sweep runs.

    Attributes
    ----------
    kind : {"serial", "processes", "dask"}
    workers : int, optional
        Processes of the pool, or workers of the local dask cluster (default: the
        number of CPU cores). Not used with ``scheduler``.
    scheduler : str or distributed.Client, optional
        Existing dask cluster: scheduler address (``tcp://HOST:PORT``), scheduler
        file (``*.json``) or a connected client. Only with ``kind="dask"``.
    """

    kind: str = "serial"
    workers: int | None = None
    scheduler: Any = None

    def __post_init__(self):
        if self.kind not in EXECUTORS:
            raise ValueError(f"executor must be one of {', '.join(EXECUTORS)}, got {self.kind!r}")
        if self.workers is not None:
            if isinstance(self.workers, bool) or int(self.workers) != self.workers \
                    or self.workers < 1:
                raise ValueError(f"workers must be an integer >= 1, got {self.workers!r}")
            object.__setattr__(self, "workers", int(self.workers))
        if self.scheduler is not None:
            if self.kind != "dask":
                raise ValueError(f"a scheduler address needs the dask executor, not {self.kind!r}")
            if self.workers is not None:
                raise ValueError("give either workers (a local cluster is started) or a "
                                 "scheduler address (an existing cluster), not both")
            if isinstance(self.scheduler, str) and not _looks_like_address(self.scheduler):
                raise ValueError(f"scheduler must be an address such as tcp://HOST:8786 or a "
                                 f"scheduler file (*.json), got {self.scheduler!r}")

    @property
    def n_workers(self) -> int:
        """Workers of a pool or local cluster this spec starts (CPU cores by default)."""
        return self.workers or os.cpu_count() or 1

    def check(self) -> "ExecutorSpec":
        """Check an existing scheduler now (seconds at most, ``ConnectionError``
        otherwise; :func:`runs.scheduler.check_scheduler`), before any work starts."""
        if isinstance(self.scheduler, str):
            check_scheduler(self.scheduler)
        return self

    def describe(self) -> str:
        """One line for logs and reports."""
        if self.kind == "serial":
            return "serial"
        if self.kind == "processes":
            return f"{self.n_workers} local processes"
        if self.scheduler is None:
            return f"local dask cluster of {self.n_workers} workers"
        name = self.scheduler if isinstance(self.scheduler, str) else "a connected client"
        return f"dask cluster at {name}"

    def run(self, func: Callable, tasks: Iterable, **kwargs) -> list:
        """:func:`run_sweep` on this executor."""
        return run_sweep(func, tasks, executor=self, **kwargs)


def _looks_like_address(text: str) -> bool:
    if text.endswith(".json"):
        return True
    if "://" in text:
        proto, rest = text.split("://", 1)
        return bool(proto) and bool(rest)
    host, _, port = text.rpartition(":")
    return bool(host) and port.isdigit()


def run_sweep(func: Callable, tasks: Iterable, executor: str | ExecutorSpec = "serial",
              workers: int | None = None, scheduler: Any = None, *, shared: Any = _NO_SHARED,
              progress: bool = True, desc: str = "sweep", unit: str = "task",
              chunksize: int | None = None,
              on_result: Callable[[int, Any], None] | None = None) -> list:
    """Run ``func`` on every task; results in task order.

    Parameters
    ----------
    func : callable
        ``func(task)``, or ``func(task, shared)`` when ``shared`` is given. Must be
        deterministic given its arguments (seeds travel in the tasks, see
        :func:`task_seeds`); module-level for ``"processes"``.
    tasks : iterable
        Picklable task descriptions.
    executor : {"serial", "processes", "dask"} or ExecutorSpec
    workers, scheduler
        See :class:`ExecutorSpec` (ignored when ``executor`` is a spec).
    shared : object, optional
        Read-only object passed as second argument, sent once per worker (pool
        initializer, dask ``scatter(broadcast=True)``), not once per task.
    progress : bool
        tqdm bar on stderr counting finished tasks.
    desc, unit : str
        Bar label and unit.
    chunksize : int, optional
        Tasks per job sent to a worker (default: about 16 jobs per worker). Results
        do not depend on it.
    on_result : callable, optional
        ``on_result(index, result)`` in this process as each task finishes (completion
        order), e.g. to save a level as soon as it is done.

    Returns
    -------
    list
        ``[func(t[, shared]) for t in tasks]``.
    """
    spec = executor if isinstance(executor, ExecutorSpec) else ExecutorSpec(
        executor, workers, scheduler)
    tasks = list(tasks)
    results: list = [None] * len(tasks)
    if chunksize is not None and (isinstance(chunksize, bool) or int(chunksize) != chunksize
                                  or chunksize < 1):
        raise ValueError(f"chunksize must be an integer >= 1, got {chunksize!r}")
    size = int(chunksize or max(1, math.ceil(len(tasks) / (16 * spec.n_workers))))
    if not tasks:
        return results
    bar = _progress_bar(len(tasks), desc, unit, progress, spec)

    def finish(index: int, value) -> None:
        results[index] = value
        if on_result is not None:
            on_result(index, value)

    try:
        if spec.kind == "serial":
            for i, task in enumerate(tasks):
                # Ctrl-C waits for the task (which checks at its own safe points) and
                # its storage; see runs.interrupt
                with interrupt.deferred():
                    finish(i, func(task) if shared is _NO_SHARED else func(task, shared))
                bar.update(1)
        else:
            chunks = [(start, tasks[start:start + size]) for start in range(0, len(tasks), size)]
            runner = _run_processes if spec.kind == "processes" else _run_dask
            with closing(runner(func, chunks, spec, shared)) as finished:
                for start, values in finished:
                    with interrupt.deferred():     # a result is stored whole
                        for offset, value in enumerate(values):
                            finish(start + offset, value)
                    bar.update(len(values))
    finally:
        bar.close()
    return results


# ----------------------------------------------------------------- helpers


def _progress_bar(total, desc, unit, enabled, spec):
    from tqdm import tqdm

    where = "" if spec.kind == "serial" else f" [{spec.describe()}]"
    return tqdm(total=total, desc=desc + where, unit=unit, file=sys.stderr,
                disable=not enabled, leave=False, dynamic_ncols=True)


def _call_chunk(func, tasks, shared=_NO_SHARED):
    """Run one chunk of tasks (top level: picklable by reference)."""
    if shared is _NO_SHARED:
        return [func(t) for t in tasks]
    return [func(t, shared) for t in tasks]


def _call_chunk_pool(func, tasks, use_shared):
    return _call_chunk(func, tasks, _WORKER_SHARED if use_shared else _NO_SHARED)


def _init_pool_worker(shared_bytes):
    global _WORKER_SHARED
    _WORKER_SHARED = pickle.loads(shared_bytes) if shared_bytes is not None else None


@contextmanager
def _environment(values: dict):
    """Temporarily set environment variables (inherited by processes started inside)."""
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _run_processes(func, chunks, spec, shared):
    """Yield ``(start, results)`` per chunk as the pool finishes them."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    try:
        pickle.dumps(func)
    except (pickle.PicklingError, AttributeError, TypeError) as exc:
        name = getattr(func, "__qualname__", func)
        raise ValueError(f"the processes executor needs a module-level function; "
                         f"{name!r} cannot be pickled ({exc})") from None
    use_shared = shared is not _NO_SHARED
    payload = pickle.dumps(shared, protocol=pickle.HIGHEST_PROTOCOL) if use_shared else None
    pool = ProcessPoolExecutor(max_workers=min(spec.n_workers, len(chunks)),
                               mp_context=multiprocessing.get_context("spawn"),
                               initializer=_init_pool_worker, initargs=(payload,))
    try:
        # workers start during the submissions: one BLAS thread, and SIGINT blocked (the
        # terminal's Ctrl-C reaches the whole process group; this process stops them)
        with _environment(_ONE_THREAD), interrupt.sigint_blocked():
            futures = {pool.submit(_call_chunk_pool, func, part, use_shared): start
                       for start, part in chunks}
        for fut in as_completed(futures):
            yield futures[fut], fut.result()
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown()


def _stop_pool(pool) -> None:
    """Cancel what has not started and end the running workers now (an interrupt or an
    error: their results would be thrown away, and waiting could take minutes)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()


def _connect(spec):
    """(client, cluster or None, whether to close the client)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - a declared dependency
        raise ValueError("the dask executor needs the 'distributed' package") from None
    if isinstance(spec.scheduler, Client):
        return spec.scheduler, None, False
    if spec.scheduler is not None:   # checked, with time limits (runs.scheduler)
        return connect_client(spec.scheduler), None, True
    with warnings.catch_warnings():  # "Port 8787 is already in use": another port is used
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        # on the loopback interface, any free port, no dashboard: nothing to resolve or
        # to collide with (the workers are this machine's processes)
        with interrupt.sigint_blocked():   # its processes never see the terminal's Ctrl-C
            cluster = LocalCluster(n_workers=spec.n_workers, threads_per_worker=1,
                                   processes=True, host="127.0.0.1", dashboard_address=None)
    try:
        client = Client(cluster)
    except BaseException:
        cluster.close()
        raise
    return client, cluster, True


def _quiet_logs() -> None:
    import logging

    for name in ("distributed", "asyncio", "tornado"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _local_worker_setup() -> None:
    """In a worker of a local cluster: the terminal's Ctrl-C is for the parent, which
    stops the cluster (and reports every task's error itself), so no own handler and no
    closing chatter on stderr."""
    interrupt.ignore_sigint()
    _quiet_logs()


def _run_dask(func, chunks, spec, shared):
    """Yield ``(start, results)`` per chunk as the cluster finishes them."""
    from distributed import as_completed

    client, cluster, close = _connect(spec)
    futures = []
    try:
        if cluster is not None:   # our own workers: Ctrl-C and errors are reported here
            client.run(_local_worker_setup)
        extra = ()
        if shared is not _NO_SHARED:
            extra = (client.scatter(shared, broadcast=True, hash=False),)
        futures = [client.submit(_call_chunk, func, part, *extra, pure=False)
                   for _, part in chunks]
        start_of = {fut.key: start for fut, (start, _) in zip(futures, chunks)}
        for fut in as_completed(futures):
            yield start_of[fut.key], fut.result()
    except BaseException:
        # an interrupt or error: the cluster's closing chatter (workers killed, scattered
        # data lost, pending messages) is expected, not news
        _quiet_logs()
        raise
    finally:
        if cluster is None:   # a remote cluster keeps running: cancel what is left
            for fut in futures:
                if not fut.done():
                    fut.cancel()
        if close:
            client.close()
        if cluster is not None:
            cluster.close()

