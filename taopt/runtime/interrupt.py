"""Ctrl-C and other stop signals: one place that installs, restores and remembers them.

What a Ctrl-C does in taopt (docs/architecture.md, "the runtime contract"):

* Python code stops between bytecodes with ``KeyboardInterrupt``; the command line prints one
  line and exits with :data:`EXIT_INTERRUPTED` (130).
* A HiGHS run is stopped through HiGHS's interrupt callbacks
  (:func:`taopt.runtime.highs.run_interruptibly`), which records it here
  (:func:`note_solver_interrupted`); a run that does not stop within its grace is
  *abandoned* (:func:`abandon`): it may still be running in C++ when the interpreter
  ends, so the process then ends at once with code 130 (:func:`exit_now`), never through
  the interpreter's teardown, which would race HiGHS's threads and static objects.
* Worker processes ignore SIGINT (:func:`ignore_sigint`): the parent stops them
  (:mod:`taopt.runtime.workers`).
* A study turns SIGTERM (a job scheduler's stop) into the same ``KeyboardInterrupt``
  (:func:`handled` with :func:`raise_interrupt`).

Handlers can only be installed from the main thread; every function here is a no-op
elsewhere (and says so in its return value).

Example
-------
>>> import signal
>>> with handled(signal.SIGTERM, raise_interrupt) as installed:
...     signal.getsignal(signal.SIGTERM) is raise_interrupt
True
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any, NoReturn

#: Exit code of a process stopped by Ctrl-C (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130

_INTERRUPTED = threading.Event()  # a solver run of this process was stopped by Ctrl-C
_ABANDONED: list[threading.Event] = []  # the "finished" events of runs left running
_ABANDON_LOCK = threading.Lock()
_DETACHED: list[threading.Event] = []  # the "finished" events of runs left past a deadline


def on_main_thread() -> bool:
    """Whether this is the main thread (the only one that receives signals)."""
    return threading.current_thread() is threading.main_thread()


def sigint_catchable() -> bool:
    """Whether a Ctrl-C can reach this code as ``KeyboardInterrupt``: on the main thread,
    with a Python handler for SIGINT (not ignored, as in a worker process)."""
    return on_main_thread() and callable(signal.getsignal(signal.SIGINT))


def raise_interrupt(signum: int, frame: Any) -> NoReturn:
    """A signal handler that raises ``KeyboardInterrupt`` (SIGTERM handled as Ctrl-C)."""
    raise KeyboardInterrupt


@contextlib.contextmanager
def handled(signum: int, handler: Any) -> Iterator[bool]:
    """Install ``handler`` for ``signum`` in the block, then restore the previous one.

    Yields whether it was installed (False off the main thread, where nothing changes).
    """
    if not on_main_thread():
        yield False
        return
    previous = signal.signal(signum, handler)
    try:
        yield True
    finally:
        signal.signal(signum, previous)


class OutOfTime(Exception):
    """Raised inside an :func:`alarm_after` block when its seconds are up."""


@contextlib.contextmanager
def alarm_after(seconds: float) -> Iterator[bool]:
    """Raise :class:`OutOfTime` in the block after ``seconds`` of wall-clock time (a SIGALRM
    interval timer): the stop for pure-Python code that takes no deadline of its own.

    Yields whether the timer was set: False off the main thread or where the platform has no
    ``setitimer`` (Windows); the block then runs unbounded and the caller must say so. The
    previous SIGALRM handler and a zero timer are restored on the way out.
    """
    if not on_main_thread() or not hasattr(signal, "setitimer"):
        yield False
        return

    def alarm(signum: int, frame: Any) -> None:
        raise OutOfTime

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, max(float(seconds), 1e-6))
    try:
        yield True
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def ignore_sigint() -> bool:
    """Ignore Ctrl-C in this process from now on (a worker: its parent handles it).
    Returns whether it could (main thread)."""
    if not on_main_thread():
        return False
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except (ValueError, OSError):
        return False
    return True


def note_solver_interrupted() -> None:
    """Record that Ctrl-C stopped a native solver run in this process."""
    _INTERRUPTED.set()


def solver_interrupted() -> bool:
    """Whether Ctrl-C stopped a native solver (HiGHS) run in this process.

    The interpreter's teardown after such a run can race the solver's own threads and static
    objects (an abort or a segmentation fault at exit, now and then), so the command line
    ends the process at once (:func:`exit_now`) when this is true.
    """
    return _INTERRUPTED.is_set()


def abandon(finished: threading.Event) -> None:
    """Leave a native run that did not stop in time to finish on its own; ``finished`` is
    set when it ends. Until then, the end of the interpreter is :func:`exit_now` (code 130)."""
    with _ABANDON_LOCK:
        if not _ABANDONED:
            atexit.register(_exit_if_abandoned)
        _ABANDONED.append(finished)


def detach(finished: threading.Event) -> None:
    """Leave a native run that was asked to stop at a deadline, and did not, to finish on its
    own; ``finished`` is set when it ends. At the end of the interpreter it is waited for (it
    was asked to stop, so it ends at its next look at its callbacks or its clock): C++ still
    running during the interpreter's teardown could abort the process."""
    with _ABANDON_LOCK:
        if not _DETACHED:
            atexit.register(_wait_detached)
        _DETACHED.append(finished)


def detached() -> int:
    """How many runs left past a deadline are still running."""
    with _ABANDON_LOCK:
        return sum(not finished.is_set() for finished in _DETACHED)


def wait_detached() -> None:
    """Wait until every run left past a deadline has ended (HiGHS before 1.12 keeps one task
    scheduler for the process: a new run must not overlap one still going)."""
    with _ABANDON_LOCK:
        waiting = list(_DETACHED)
    for finished in waiting:
        finished.wait()
    with _ABANDON_LOCK:
        _DETACHED[:] = [finished for finished in _DETACHED if not finished.is_set()]


def _wait_detached() -> None:
    wait_detached()


def abandoned() -> int:
    """How many abandoned runs are still running."""
    with _ABANDON_LOCK:
        return sum(not finished.is_set() for finished in _ABANDONED)


def wait_abandoned(timeout: float | None = None) -> bool:
    """Wait up to ``timeout`` seconds for every abandoned run to end; whether all ended."""
    with _ABANDON_LOCK:
        waiting = list(_ABANDONED)
    return all(finished.wait(timeout) for finished in waiting)


def _exit_if_abandoned() -> None:
    """At interpreter exit: a run abandoned on Ctrl-C still running in C++ would race the
    interpreter's teardown; end the process at once with the interrupt's exit code."""
    if abandoned():
        exit_now(EXIT_INTERRUPTED)


def exit_now(code: int = EXIT_INTERRUPTED) -> NoReturn:
    """End the process at once with ``code`` (``os._exit``), after flushing the standard
    streams: no exit hooks, no teardown (callers have nothing left to write; files are
    written atomically)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


__all__ = [
    "EXIT_INTERRUPTED",
    "on_main_thread",
    "sigint_catchable",
    "raise_interrupt",
    "handled",
    "ignore_sigint",
    "note_solver_interrupted",
    "solver_interrupted",
    "abandon",
    "abandoned",
    "detach",
    "detached",
    "wait_detached",
    "wait_abandoned",
    "exit_now",
]
