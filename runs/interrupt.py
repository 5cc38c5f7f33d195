"""Ctrl-C honoured at safe points: a clean interrupt even inside compiled code.

Python runs a SIGINT handler between bytecodes. The default handler raises
``KeyboardInterrupt`` there, also while a compiled (numba) function is being called or
is returning its result; the dispatcher then returns a result with an exception set and
Python reports ``SystemError: CPUDispatcher(...) returned a result with an exception
set`` with a 40-line traceback instead of the interrupt (measured: 1 in 5 Ctrl-C during a
harmonic-balance campaign). And an interrupt in the middle of saving a finished piece of
work would lose it.

So the command line installs :func:`install`'s handler, which raises at once (Python's
behaviour) except inside a :func:`deferred` block: there it only records the request.
:func:`checkpoint`, called at safe points (between the lines of a level, between the
tasks of a sweep), raises ``KeyboardInterrupt`` if a request is pending, and so does
leaving the outermost :func:`deferred` block. A second Ctrl-C while one is pending raises
at once (the user insists; :func:`caused_by_interrupt` lets the CLI still report it as an
interrupt if it lands inside compiled code).

Library use without :func:`install` (tests, notebooks): every function here does nothing
and Ctrl-C behaves as usual.

Worker processes must not see the terminal's Ctrl-C (their parent stops them):
:func:`sigint_blocked` blocks SIGINT in the parent while it starts them; the blocked mask
is inherited across fork and exec, so the workers never receive it, and the parent gets
its own pending signal as soon as the block ends.
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["install", "uninstall", "deferred", "checkpoint", "requested", "Ticker",
           "caused_by_interrupt", "sigint_blocked", "quiet", "ignore_sigint"]

_state = {"installed": False, "previous": None, "pending": False, "requested": False,
          "depth": 0, "quiet": False}


def _in_import(frame) -> bool:
    """Whether ``frame`` (or a caller) runs in the import machinery: a KeyboardInterrupt
    raised there (e.g. in a module lock's weakref callback) is printed as "Exception
    ignored" and lost, so the request waits for the next safe point instead."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _on_sigint(signum, frame):
    """The SIGINT handler of :func:`install` (runs in the main thread)."""
    _state["requested"] = True
    if _state["quiet"]:
        return
    if _in_import(frame):
        _state["pending"] = True
        return
    if _state["depth"] > 0 and not _state["pending"]:
        _state["pending"] = True
        return
    _state["pending"] = False
    raise KeyboardInterrupt


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def install() -> None:
    """Install the handler (main thread only; a no-op elsewhere or if installed)."""
    if _state["installed"] or not _main_thread():
        return
    _state.update(previous=signal.getsignal(signal.SIGINT), pending=False, requested=False,
                  depth=0, quiet=False)
    signal.signal(signal.SIGINT, _on_sigint)
    _state["installed"] = True


def uninstall() -> None:
    """Restore the handler that :func:`install` replaced."""
    if not _state["installed"] or not _main_thread():
        return
    signal.signal(signal.SIGINT, _state["previous"] or signal.default_int_handler)
    _state.update(installed=False, pending=False, depth=0, quiet=False)


def quiet() -> None:
    """From now on only record Ctrl-C (for the interpreter's exit after a command)."""
    _state["quiet"] = True


def requested() -> bool:
    """Whether a Ctrl-C arrived since :func:`install`."""
    return _state["requested"]


def checkpoint() -> None:
    """Raise ``KeyboardInterrupt`` if a Ctrl-C is pending (a safe point)."""
    if _state["pending"] and _main_thread():
        _state["pending"] = False
        raise KeyboardInterrupt


@contextmanager
def deferred():
    """Inside: Ctrl-C is recorded, raised at the next :func:`checkpoint` or on leaving
    the outermost block (after the block's work is complete)."""
    if not (_state["installed"] and _main_thread()):
        yield
        return
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
    if _state["depth"] == 0:
        checkpoint()


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was raised while handling or because of, a Ctrl-C."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


@contextmanager
def sigint_blocked():
    """Block SIGINT in this thread (processes started inside inherit the block and never
    see Ctrl-C); a SIGINT that arrives meanwhile is delivered when the block ends."""
    mask = getattr(signal, "pthread_sigmask", None)
    if mask is None:  # pragma: no cover - not POSIX
        yield
        return
    # multiprocessing's resource tracker, when it starts, unblocks SIGINT in the thread
    # that starts it (bpo-33613, Python 3.11): start it before the block
    from multiprocessing import resource_tracker
    resource_tracker.ensure_running()
    old = mask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        mask(signal.SIG_SETMASK, old)


class Ticker:
    """A progress bar (or None) whose ``update`` is also a :func:`checkpoint`: loops that
    tick once per unit of work (a line of a stepped sine) become interruptible there."""

    __slots__ = ("bar",)

    def __init__(self, bar=None):
        self.bar = bar

    def update(self, n: int = 1) -> None:
        if self.bar is not None:
            self.bar.update(n)
        checkpoint()


def ignore_sigint() -> None:
    """Ignore SIGINT in this process (a worker whose parent handles Ctrl-C; main thread)."""
    if _main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
