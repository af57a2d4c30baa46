"""HiGHS's runtime hooks: its interrupt callbacks (Ctrl-C, deadlines, cancellation) and its
quiet start.

:mod:`taopt.models.highs` is the HiGHS adapter (models built, solved, results read); what
belongs to *running* HiGHS lives here:

* :func:`run_interruptibly` — ``Highs.run()`` that Ctrl-C stops within
  :data:`INTERRUPT_GRACE` seconds through HiGHS's interrupt callbacks
  (``kCallbackSimplexInterrupt``, ``kCallbackIpmInterrupt``, ``kCallbackMipInterrupt``);
  :func:`cvxpy_interruptible` does the same for the ``Highs`` object cvxpy builds itself;
* :func:`interrupt_when` — the same callbacks stop a run when a predicate holds (a
  :class:`~taopt.runtime.deadline.Deadline` expired or its cancel token was set): HiGHS
  looks at its own ``time_limit`` rarely inside an LP, these callbacks come every simplex /
  IPM iteration and MIP node;
* :func:`stdout_discarded` and :func:`flush_c_stdout` — HiGHS prints its banner from C++
  straight to file descriptor 1 before any option can be set;
* :func:`run_arrays` — a model given as numpy arrays run in a fresh ``Highs`` with both
  stops, its answer returned as plain data: a task a worker process can run (HiGHS has
  phases that look at neither its clock nor its callbacks, e.g. the analytic centre its MIP
  solver computes with IPX at the root; only a process can be stopped there).

The Ctrl-C state (a run was interrupted, a run was abandoned) is kept by
:mod:`taopt.runtime.interrupt`.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from typing import Any

import highspy
import numpy as np
from highspy._core import _Highs

from taopt.runtime import interrupt

#: Seconds a Ctrl-C waits for HiGHS to stop at its next interrupt callback before the run
#: is abandoned (HiGHS calls ``kCallbackMipInterrupt`` between nodes, but may go seconds
#: without one at the root).
INTERRUPT_GRACE = 1.0

#: The callbacks through which HiGHS can be asked to stop.
INTERRUPT_CALLBACKS = ("cbSimplexInterrupt", "cbIpmInterrupt", "cbMipInterrupt")


def flush_c_stdout() -> None:
    """Flush the C library's ``stdout`` buffer (HiGHS prints through it)."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # no libc symbol table (not on Linux/macOS)
        pass


@contextlib.contextmanager
def stdout_discarded() -> Iterator[None]:
    """Send file descriptor 1 to the null device for the duration of the block.

    HiGHS writes its banner from C++ straight to the process's standard output,
    before any option can be set, so ``output_flag`` cannot stop it; only the
    file descriptor can. Python's and C's buffers are flushed on both sides so
    no line of anybody else's is lost or moved.
    """
    try:
        sys.stdout.flush()
    except (AttributeError, ValueError, OSError):
        pass
    flush_c_stdout()
    try:
        saved = os.dup(1)
    except OSError:  # no standard output at all: nothing to protect
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        flush_c_stdout()
        os.dup2(saved, 1)
        os.close(saved)


def _interrupt_hook(stop: Callable[[], bool], clear: bool = False) -> Callable[[Any], None]:
    """An interrupt callback that asks HiGHS to stop once ``stop()`` is true; with
    ``clear``, it also lowers the flag while ``stop()`` is false (see :func:`interrupt_when`)."""

    def on_interrupt(event: Any) -> None:
        if stop():
            event.interrupt()
        elif clear:
            event.interrupt(False)

    return on_interrupt


def _subscribe(highs: highspy.Highs, hook: Callable[[Any], None], on: bool = True) -> None:
    for name in INTERRUPT_CALLBACKS:
        callback = getattr(highs, name)
        if on:
            callback.subscribe(hook)
        else:
            callback.unsubscribe(hook)


@contextlib.contextmanager
def interrupt_when(highs: highspy.Highs, stop: Callable[[], bool]) -> Iterator[None]:
    """While the block runs, HiGHS stops at its next interrupt callback once ``stop()``
    is true (e.g. ``deadline.expired`` of a :class:`~taopt.runtime.deadline.Deadline`).

    HiGHS (1.11 to 1.16 at least) keeps the ``user_interrupt`` flag of an interrupted run in
    its callback input, so the next run of the same object with any interrupt callback
    subscribed would stop at its first callback; this hook lowers the flag while ``stop()``
    is false. Enter it before any other interrupt hook (e.g. the Ctrl-C hook of
    :func:`run_interruptibly`, which only raises the flag): callbacks fire in the order
    they were subscribed.
    """
    hook = _interrupt_hook(stop, clear=True)
    _subscribe(highs, hook)
    try:
        yield
    finally:
        _subscribe(highs, hook, on=False)


#: What :func:`run_interruptibly` returns for a run left running past its ``give_up`` time.
DETACHED = "detached"

#: Seconds a run past its ``give_up`` time is waited for, once asked to stop, before it is
#: left to end on its own (:func:`run_interruptibly`).
DETACH_GRACE = 0.25


def run_interruptibly(highs: highspy.Highs, run: Any = None, give_up: float | None = None) -> Any:
    """``highs.run()`` that Ctrl-C stops within :data:`INTERRUPT_GRACE` seconds.

    Python handles a signal only in the main thread and only between bytecodes; while the
    main thread is inside ``Highs.run()`` that happens in HiGHS's callbacks, where the
    ``KeyboardInterrupt`` becomes a HiGHS error, or never (the run goes on to its end).
    So, on the main thread, HiGHS runs in a helper thread (``Highs.run`` releases the GIL)
    while the main thread waits, ready for Ctrl-C. On Ctrl-C the interrupt callbacks
    set ``user_interrupt`` and HiGHS returns; a run that has not stopped after the grace
    period is left to finish on its own (:func:`taopt.runtime.interrupt.abandon`: the
    process, ending, exits at once with code 130). ``KeyboardInterrupt`` is then raised in
    the caller. Off the main thread, or with SIGINT ignored (a worker process), the run is
    plain: the helper thread costs about 2 ms per run.

    Parameters
    ----------
    highs : highspy.Highs
    run : callable, optional
        The run to call (default ``highs.run``).
    give_up : float, optional
        A :func:`time.perf_counter` instant: a run still going then is asked to stop (its
        interrupt callbacks) and, if it has not stopped :data:`DETACH_GRACE` seconds later,
        left to end on its own (:func:`taopt.runtime.interrupt.detach`) and :data:`DETACHED`
        returned. HiGHS's MIP solver can go seconds without looking at its clock or its
        callbacks (sub-MIPs, the root's analytic centre): SOP cut-engine rounds ended 3-9 s
        past their time limit at load 3-6. The caller must not touch ``highs`` again. Only on
        the main thread with Ctrl-C catchable (elsewhere the run is plain). A later call
        waits first for such runs to end, so two runs never overlap.

    Returns
    -------
    HighsStatus or str
        What ``run()`` returned, or :data:`DETACHED`.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C during the run.
    """
    run = run or highs.run
    if interrupt.detached():  # a run left past its deadline is still going: never overlap it
        interrupt.wait_detached()
    if not interrupt.sigint_catchable():
        return run()  # no Ctrl-C to wait for (a worker thread, or SIGINT ignored)
    stop = threading.Event()
    outcome: dict[str, Any] = {}
    # the end of the run, as an Event: Thread.join() interrupted by Ctrl-C can mark a
    # running thread as stopped (CPython's bpo-45274 clean-up), so it cannot be trusted
    finished = threading.Event()

    def target() -> None:
        try:
            outcome["status"] = run()
        except BaseException as exc:  # noqa: BLE001 -- handed to the waiting thread
            outcome["error"] = exc
        finally:
            # HiGHS keeps a task scheduler per calling thread; release this thread's, as
            # highspy's own threaded solve does. After a Ctrl-C, wait for its workers to
            # end: the process is about to exit, and a worker still joinable when HiGHS's
            # static objects are destroyed aborts it ("terminate called ...").
            # (newer highspy only; older versions keep one global scheduler and have nothing
            # per thread to release)
            try:
                reset = getattr(_Highs, "resetThreadScheduler", None)
                if reset is not None:
                    reset(stop.is_set())
            finally:
                finished.set()  # whatever happened, the waiting thread must not hang

    hook = _interrupt_hook(stop.is_set)
    _subscribe(highs, hook)
    worker = threading.Thread(target=target, name="highs-run", daemon=True)
    worker.start()
    try:
        while not finished.wait(0.05):
            if give_up is not None and time.perf_counter() >= give_up:
                stop.set()
                if not finished.wait(DETACH_GRACE):
                    interrupt.detach(finished)
                    return DETACHED
    except KeyboardInterrupt:
        stop.set()
        interrupt.note_solver_interrupted()
        try:
            finished.wait(INTERRUPT_GRACE)  # a second Ctrl-C cuts the grace short
        finally:
            if not finished.is_set():
                interrupt.abandon(finished)
        raise
    finally:
        if finished.is_set():  # an abandoned run keeps its callbacks until it ends
            _subscribe(highs, hook, on=False)
    if "error" in outcome:
        raise outcome["error"]
    return outcome.get("status")


class _InterruptibleHighs(highspy.Highs):
    """``highspy.Highs`` whose ``run()`` is :func:`run_interruptibly` (for cvxpy's object)."""

    def run(self) -> Any:
        return run_interruptibly(self, super().run)


@contextlib.contextmanager
def cvxpy_interruptible() -> Iterator[None]:
    """cvxpy's HiGHS interface builds its own ``highspy.Highs()`` and calls ``run()``: on
    the main thread, let it build an :class:`_InterruptibleHighs` instead."""
    if not interrupt.sigint_catchable() or highspy.Highs is _InterruptibleHighs:
        yield
        return
    original = highspy.Highs
    setattr(highspy, "Highs", _InterruptibleHighs)  # noqa: B010 (mypy: a class attribute)
    try:
        yield
    finally:
        setattr(highspy, "Highs", original)  # noqa: B010


def run_arrays(
    model: Mapping[str, Any],
    options: Mapping[str, Any] | None = None,
    seconds: float | None = None,
    until: float | None = None,
    stop: Callable[[], bool] | None = None,
) -> dict[str, Any]:
    """Run HiGHS on a model given as arrays; stop it at ``seconds`` through its ``time_limit``
    and its interrupt callbacks (:func:`interrupt_when`); return what it found as plain data.

    Light on purpose (highspy and numpy only), so that a spawned worker process
    (:class:`~taopt.runtime.workers.WorkerPool`) can run it after a short start-up and be
    killed by its owner if HiGHS overruns in a phase that looks at neither its clock nor
    its callbacks.

    Parameters
    ----------
    model : mapping
        ``cost``, ``lower``, ``upper`` (row sides), ``column_lower``, ``column_upper``,
        ``start``, ``index``, ``value`` (the matrix by columns, CSC) and ``integrality``
        (1 for an integer column), numpy arrays; ``offset`` optional.
    options : mapping, optional
        HiGHS options by name. ``threads`` defaults to ``TAOPT_SOLVER_THREADS`` when set.
    seconds : float, optional
        The run's wall-clock limit (None: none).
    until : float, optional
        Or its end as a ``time.time()`` instant: for a run handed to a worker process, whose
        start-up then counts against the limit.
    stop : callable, optional
        Also stop once ``stop()`` is true (e.g. a cancel token's; in this process only).

    Returns
    -------
    dict
        ``model_status`` (the ``HighsModelStatus`` name), ``primal_solution_status``,
        ``objective``, ``mip_dual_bound``, ``mip_gap``, ``mip_node_count``, ``col_value``
        (a numpy array, or None without a feasible point) and ``seconds`` (of the run).

    Example
    -------
    >>> import numpy as np
    >>> out = run_arrays({"cost": np.array([1.0]), "lower": np.array([0.5]),
    ...     "upper": np.array([np.inf]), "column_lower": np.array([0.0]),
    ...     "column_upper": np.array([3.0]), "start": np.array([0, 1]),
    ...     "index": np.array([0]), "value": np.array([1.0]), "integrality": np.array([1])})
    >>> out["model_status"], out["objective"]
    ('kOptimal', 1.0)
    """
    began = time.perf_counter()
    if until is not None:
        left = until - time.time()
        seconds = left if seconds is None else min(seconds, left)
    with stdout_discarded():
        highs = highspy.Highs()
        highs.setOptionValue("output_flag", False)
    threads = os.environ.get("TAOPT_SOLVER_THREADS")
    if threads and threads.isdigit():
        highs.setOptionValue("threads", int(threads))
    cost = np.ascontiguousarray(model["cost"], dtype=np.float64)
    lower = np.ascontiguousarray(model["lower"], dtype=np.float64)
    start = np.ascontiguousarray(model["start"], dtype=np.int32)
    index = np.ascontiguousarray(model["index"], dtype=np.int32)
    integrality = np.ascontiguousarray(model["integrality"], dtype=np.int32)
    highs.passModel(
        len(cost),
        len(lower),
        len(index),
        int(highspy.MatrixFormat.kColwise),
        int(highspy.ObjSense.kMinimize),
        float(model.get("offset", 0.0)),
        cost,
        np.ascontiguousarray(model["column_lower"], dtype=np.float64),
        np.ascontiguousarray(model["column_upper"], dtype=np.float64),
        lower,
        np.ascontiguousarray(model["upper"], dtype=np.float64),
        start,
        index,
        np.ascontiguousarray(model["value"], dtype=np.float64),
        integrality,
    )
    for name, value in (options or {}).items():
        highs.setOptionValue(name, value)
    end = math.inf
    if seconds is not None:
        highs.setOptionValue("time_limit", max(float(seconds), 1e-3))
        end = began + float(seconds)
    with interrupt_when(highs, lambda: time.perf_counter() >= end or (stop is not None and stop())):
        run_interruptibly(highs)
    info = highs.getInfo()
    has_point = int(info.primal_solution_status) == 2
    return {
        "model_status": highs.getModelStatus().name,
        "primal_solution_status": int(info.primal_solution_status),
        "objective": float(info.objective_function_value),
        "mip_dual_bound": float(info.mip_dual_bound),
        "mip_gap": float(info.mip_gap),
        "mip_node_count": int(info.mip_node_count),
        "col_value": np.array(highs.getSolution().col_value) if has_point else None,
        "seconds": time.perf_counter() - began,
    }


__all__ = [
    "INTERRUPT_GRACE",
    "INTERRUPT_CALLBACKS",
    "flush_c_stdout",
    "stdout_discarded",
    "interrupt_when",
    "run_interruptibly",
    "DETACHED",
    "cvxpy_interruptible",
    "run_arrays",
]
