"""Command-line options that choose where a sweep runs (see :mod:`runs.executor`).

A command that runs a sweep adds the options and turns them into an
:class:`runs.executor.ExecutorSpec`::

    from cli.executor_options import add_executor_arguments, executor_from_args

    def register(subparsers):
        p = subparsers.add_parser("reproduce", ...)
        add_executor_arguments(p)
        p.set_defaults(func=run)

    def run(args):
        spec = executor_from_args(args)           # ValueError on bad input
        results = spec.run(one_level, tasks, desc="levels")

Options:

``--workers N``
    start a local dask.distributed cluster of N single-threaded worker processes for
    the sweep (closed afterwards);
``--scheduler ADDRESS``
    use an existing cluster: ``tcp://HOST:8786`` (started with ``dask scheduler`` and
    ``dask worker tcp://HOST:8786`` on each machine) or a scheduler file ``*.json``;
``--executor {auto,serial,processes,dask}``
    ``auto`` (default): dask when ``--workers`` or ``--scheduler`` is given, else
    serial; ``processes`` uses a plain process pool of ``--workers`` processes.
"""
from __future__ import annotations

import argparse

from runs.executor import ExecutorSpec

__all__ = ["add_executor_arguments", "executor_from_args", "int_at_least"]


def int_at_least(minimum: int):
    """argparse ``type`` for whole numbers >= ``minimum`` (one-line error otherwise)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
        return value

    return parse


def add_executor_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--workers``, ``--scheduler`` and ``--executor`` to a sub-command."""
    group = parser.add_argument_group(
        "parallel execution",
        "Results are identical (bit for bit) whichever executor runs the sweep.")
    group.add_argument("--workers", type=int_at_least(1), default=None, metavar="N",
                       help="start a local dask.distributed cluster of N worker processes "
                            "(one thread each) for this run")
    group.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="run on an existing dask cluster: scheduler address such as "
                            "tcp://HOST:8786 (start it with `dask scheduler`, then "
                            "`dask worker tcp://HOST:8786` on each machine) or a "
                            "scheduler file *.json")
    group.add_argument("--executor", choices=("auto", "serial", "processes", "dask"),
                       default="auto",
                       help="auto (default): dask if --workers or --scheduler is given, "
                            "else serial; processes: a local process pool of --workers")


def executor_from_args(args: argparse.Namespace) -> ExecutorSpec:
    """The :class:`~runs.executor.ExecutorSpec` chosen by the options.

    Raises
    ------
    ValueError
        Contradictory or malformed options (one line, for ``cli.main``).
    ConnectionError
        ``--scheduler`` names a missing scheduler file or an address that does not
        answer within :data:`runs.scheduler.CONNECT_TIMEOUT_S` seconds.
    """
    kind = getattr(args, "executor", "auto") or "auto"
    workers = getattr(args, "workers", None)
    scheduler = getattr(args, "scheduler", None)
    if kind == "auto":
        kind = "dask" if (workers is not None or scheduler is not None) else "serial"
    if kind == "serial" and (workers is not None or scheduler is not None):
        raise ValueError("--executor serial takes neither --workers nor --scheduler")
    if scheduler is not None and kind != "dask":
        raise ValueError(f"--scheduler needs the dask executor, not --executor {kind}")
    if scheduler is not None and workers is not None:
        raise ValueError("give --workers (start a local cluster) or --scheduler (use an "
                         "existing one), not both")
    try:
        # an unreachable scheduler is refused now, in seconds, before any work
        return ExecutorSpec(kind=kind, workers=workers, scheduler=scheduler).check()
    except (ValueError, ConnectionError) as exc:
        if scheduler is None:
            raise
        raise type(exc)(f"--scheduler {scheduler}: {exc}") from None
