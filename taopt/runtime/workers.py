"""Worker processes: started one way, told the same things, and always reaped.

Every process pool of taopt (the capability model's classes, the study runner's scenarios,
the navigation matrix's pairs) is a :class:`WorkerPool`: a ``concurrent.futures`` executor
over processes started with "spawn" (HiGHS's threads do not survive a fork; "fork" on
request), whose workers

* run :func:`become_worker` first: their environment (one solver / BLAS thread each:
  the workers are the parallelism), Ctrl-C ignored (the parent handles it and stops them),
  and death with the parent (Linux ``PR_SET_PDEATHSIG``, and a thread watching
  ``os.getppid()``), so that no worker outlives a killed parent;
* are known to the pool by their own process handles (the ``multiprocessing`` children
  that appeared while the pool started them, from :func:`multiprocessing.active_children`),
  so :meth:`WorkerPool.terminate` kills and reaps them at once, without the private
  attributes of the standard library's executor.

A pool that a worker's death broke (``BrokenProcessPool``), or that was terminated or shut
down, is not :attr:`~WorkerPool.usable`; :func:`shared_pool` hands out one live pool per key
and replaces such a pool on the next request, and :func:`drop_pool` terminates it. Pools are
shut down at interpreter exit (without waiting for running tasks).

A worker that must not share anything with this process (the peers' worker script: the
``ortools`` and ``highspy`` wheels cannot be loaded into one process) is a
:class:`ScriptWorker`: a script run by a fresh interpreter (``subprocess``), talking in
pickle frames on its standard input and output. It gets this process's pid and whether to
ask for ``PR_SET_PDEATHSIG`` as its last two arguments, and runs the same steps as
:func:`become_worker` itself (it does not import taopt); :meth:`ScriptWorker.stop` closes
its input and kills it if it lingers, and its owner stops it at exit.

Example
-------
>>> with WorkerPool(1) as pool:
...     pool.submit(abs, -3).result(timeout=60)
3
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import multiprocessing
import multiprocessing.process
import os
import pickle
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Generic, TypeVar

from taopt.errors import SolverError
from taopt.runtime.deadline import CancelToken, cancel_scope
from taopt.runtime.interrupt import ignore_sigint

_T = TypeVar("_T")

#: Environment of worker processes: one solver / BLAS thread each.
ONE_THREAD_ENV = {
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "TAOPT_SOLVER_THREADS": "1",
}

#: Seconds between two looks of a worker's watch thread at its parent.
WATCH_PERIOD = 0.5

#: Seconds between two looks at a ``stop`` predicate while waiting for a script worker.
STOP_POLL = 0.02

_START_LOCK = threading.Lock()  # one pool starts processes at a time: the new children are its
_POOLS: dict[Hashable, WorkerPool] = {}
_POOLS_LOCK = threading.Lock()


def die_with_parent(parent: int, pdeathsig: bool = True, exit_code: int = 1) -> None:
    """End this process as soon as ``parent`` is gone, even if it was killed.

    Linux's ``PR_SET_PDEATHSIG`` (SIGKILL when the thread that started us ends: ask for it
    only when that is the parent's main thread, ``pdeathsig``), and a daemon thread that
    exits with ``exit_code`` once ``os.getppid()`` is no longer ``parent``.
    """
    if pdeathsig and sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    if os.getppid() != parent:  # the parent died before we could watch it
        os._exit(exit_code)

    def watch() -> None:  # pragma: no cover - runs in workers
        while True:
            time.sleep(WATCH_PERIOD)
            if os.getppid() != parent:
                os._exit(exit_code)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def become_worker(
    parent: int | None = None, env: Mapping[str, str] | None = None, pdeathsig: bool = True
) -> None:
    """What a worker process does first: set ``env``, ignore Ctrl-C, and (when ``parent`` is
    given) die with its parent (:func:`die_with_parent`)."""
    os.environ.update(env or {})
    ignore_sigint()
    if parent is not None:
        die_with_parent(parent, pdeathsig=pdeathsig)


def _initialise(
    parent: int,
    env: Mapping[str, str],
    initializer: Callable[..., Any] | None,
    initargs: tuple[Any, ...],
) -> None:  # pragma: no cover - runs in workers
    become_worker(parent, env)
    if initializer is not None:
        initializer(*initargs)


@contextlib.contextmanager
def main_hidden() -> Iterator[None]:
    """While workers are spawned: hide ``__main__``'s file and spec, so that a spawned
    worker does not run the caller's script again (spawn re-imports it, and a script without
    an ``if __name__ == "__main__":`` guard would start its work anew in every worker). Only
    for pools whose tasks never need ``__main__``'s objects."""
    main = sys.modules.get("__main__")
    if main is None:
        yield
        return
    saved: dict[str, Any] = {
        k: main.__dict__[k] for k in ("__file__", "__spec__") if k in main.__dict__
    }
    main.__dict__.pop("__file__", None)
    main.__spec__ = None
    try:
        yield
    finally:
        main.__dict__.pop("__spec__", None)
        main.__dict__.update(saved)


def _children() -> dict[int, multiprocessing.process.BaseProcess]:
    return {p.pid: p for p in multiprocessing.active_children() if p.pid is not None}


class WorkerPool(Executor):
    """``workers`` spawned worker processes behind the ``concurrent.futures`` API.

    Parameters
    ----------
    workers : int
        Processes (started on demand, at most this many).
    env : mapping, optional
        Environment set in every worker (default :data:`ONE_THREAD_ENV`).
    context : str
        ``multiprocessing`` start method: "spawn" (default; HiGHS's threads do not survive a
        fork), or "fork" for workers that only compute with numpy / CasADi and are worth
        starting fast (the navigation matrix).
    hide_main : bool
        Start workers with ``__main__`` hidden (:func:`main_hidden`): for tasks that are
        taopt's own functions, so that a caller's script is never re-run by a worker.
    initializer, initargs
        Run in every worker after :func:`become_worker`.
    """

    def __init__(
        self,
        workers: int,
        *,
        env: Mapping[str, str] | None = None,
        context: str = "spawn",
        hide_main: bool = False,
        initializer: Callable[..., Any] | None = None,
        initargs: tuple[Any, ...] = (),
    ) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
        self.workers = workers
        self.hide_main = hide_main
        self._executor = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context(context),
            initializer=_initialise,
            initargs=(
                os.getpid(),
                dict(ONE_THREAD_ENV if env is None else env),
                initializer,
                tuple(initargs),
            ),
        )
        self._processes: dict[int, multiprocessing.process.BaseProcess] = {}
        self._broken = False
        self._closed = False

    # -- the executor API ----------------------------------------------------------------
    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        """Schedule ``fn(*args, **kwargs)`` in a worker (starting one if needed).

        Raises
        ------
        BrokenProcessPool
            A worker of this pool died; the pool is no longer :attr:`usable`.
        RuntimeError
            The pool was shut down or terminated.
        """
        if self._closed:
            raise RuntimeError("cannot submit to a worker pool that was shut down")
        hide = main_hidden() if self.hide_main else contextlib.nullcontext()
        with _START_LOCK, hide:  # the executor starts its processes inside submit()
            before = _children()
            try:
                future = self._executor.submit(fn, *args, **kwargs)
            except BrokenProcessPool:
                self._broken = True
                raise
            finally:
                for pid, process in _children().items():
                    if pid not in before:
                        self._processes[pid] = process
        future.add_done_callback(self._note_broken)
        return future

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop taking tasks; let the workers end when their tasks are done."""
        self._closed = True
        self._executor.shutdown(wait=wait, cancel_futures=cancel_futures)

    # -- what the standard executor does not say ------------------------------------------
    def _note_broken(self, future: Future) -> None:
        if not future.cancelled() and isinstance(future.exception(), BrokenProcessPool):
            self._broken = True

    @property
    def usable(self) -> bool:
        """Whether tasks can still be submitted (not broken, not shut down)."""
        return not (self._broken or self._closed)

    def pids(self) -> list[int]:
        """Process ids of the workers started so far and still alive."""
        return sorted(pid for pid, p in self._processes.items() if p.is_alive())

    def terminate(self) -> None:
        """Kill every worker at once (SIGKILL), cancel the pending tasks and reap them.

        For Ctrl-C, an error, or a task that overran its time: nothing a worker was doing
        is kept. Idempotent.
        """
        self._closed = True
        for process in list(self._processes.values()):
            with contextlib.suppress(Exception):
                process.kill()
        # the executor sees its workers die, marks itself broken and releases its queues
        with contextlib.suppress(Exception):
            self._executor.shutdown(wait=True, cancel_futures=True)
        for process in list(self._processes.values()):
            with contextlib.suppress(Exception):
                process.join(timeout=5)

    def __repr__(self) -> str:
        state = "usable" if self.usable else "broken" if self._broken else "closed"
        return f"WorkerPool({self.workers}, {state}, pids={self.pids()})"


def shared_pool(key: Hashable, workers: int, **options: Any) -> WorkerPool:
    """The live pool kept under ``key`` (e.g. ``("study", jobs)``), made with ``workers``
    and ``options`` (see :class:`WorkerPool`) when there is none or it is no longer
    :attr:`~WorkerPool.usable`. The first task pays the workers' start-up (the imports,
    about a second each); later ones reuse them."""
    with _POOLS_LOCK:
        pool = _POOLS.get(key)
        if pool is None or not pool.usable:
            pool = WorkerPool(workers, **options)
            _POOLS[key] = pool
            atexit.register(pool.shutdown, wait=False, cancel_futures=True)
        return pool


def kept_pool(key: Hashable) -> WorkerPool | None:
    """The pool kept under ``key``, if any (usable or not)."""
    with _POOLS_LOCK:
        return _POOLS.get(key)


def drop_pool(key: Hashable) -> None:
    """Terminate the pool kept under ``key`` (if any) and forget it."""
    with _POOLS_LOCK:
        pool = _POOLS.pop(key, None)
    if pool is not None:
        pool.terminate()


class ScriptWorker:
    """A worker process that is a Python script run by a fresh interpreter, answering pickle
    frames on its standard input with pickle frames on its standard output.

    Started at construction (not waited for); a reader thread puts every frame it sends in a
    queue, read with :meth:`next_frame`. Its own session (``start_new_session``): the
    terminal's Ctrl-C is this process's to handle, and it stops the worker.

    Parameters
    ----------
    script : path
        The script; run as ``python SCRIPT *args PARENT_PID PDEATHSIG`` where ``PDEATHSIG``
        is "1" when the starting thread is the main thread (Linux's ``PR_SET_PDEATHSIG``
        fires when the *thread* that started the child ends, so it is only asked for from
        the thread that lives as long as the process), else "0".
    args : sequence of str
        The script's own arguments.
    name : str
        Names the worker in errors ("pyvrp worker process died ...").
    nice : int
        Added to the worker's niceness (lower CPU priority) right after it is started,
        before its interpreter starts a thread, so every thread it starts inherits it
        (POSIX; ignored elsewhere). 0: this process's priority.
    """

    def __init__(
        self, script: str | os.PathLike[str], args: Sequence[str], name: str, nice: int = 0
    ) -> None:
        self.name = name
        self.owner = os.getpid()
        self.started = time.monotonic()
        pdeathsig = "1" if threading.current_thread() is threading.main_thread() else "0"
        self.process = subprocess.Popen(
            [sys.executable, os.fspath(script), *args, str(os.getpid()), pdeathsig],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            start_new_session=os.name == "posix",
        )
        self.nice = int(nice)
        if self.nice and hasattr(os, "setpriority"):
            with contextlib.suppress(OSError):  # a priority that cannot be set: it runs as is
                own = os.getpriority(os.PRIO_PROCESS, 0)
                os.setpriority(os.PRIO_PROCESS, self.process.pid, min(19, own + self.nice))
        self.frames: queue.Queue[Any] = queue.Queue()
        threading.Thread(target=self._read, name=f"{name}-reader", daemon=True).start()

    def _read(self) -> None:
        """Reader thread: every frame from the worker goes to the queue; None at end of file."""
        stream = self.process.stdout
        while True:
            try:
                self.frames.put(pickle.load(stream))  # type: ignore[arg-type]
            except (EOFError, OSError, pickle.UnpicklingError, ValueError):
                self.frames.put(None)
                return

    def send(self, message: Any) -> None:
        """Write one frame to the worker (``BrokenPipeError`` / ``OSError`` if it is gone)."""
        stdin = self.process.stdin
        assert stdin is not None
        pickle.dump(message, stdin, protocol=pickle.HIGHEST_PROTOCOL)
        stdin.flush()

    def next_frame(
        self, until: float | None, what: str, stop: Callable[[], bool] | None = None
    ) -> Any:
        """The next frame, or None once ``time.monotonic()`` passes ``until`` (None: wait)
        or once ``stop()`` is true (looked at every :data:`STOP_POLL` seconds).

        Raises
        ------
        SolverError
            The worker ended (its output closed) during ``what``; the message names the
            worker, how it ended (exit status or signal) and ``what``.
        """
        poll = 1.0 if stop is None else STOP_POLL
        while True:
            if stop is not None and stop():
                return None
            left = poll if until is None else min(poll, until - time.monotonic())
            if left <= 0:
                return None
            try:
                frame = self.frames.get(timeout=left)
            except queue.Empty:
                continue
            if frame is None:
                code = self.process.wait()
                how = f"killed by signal {-code}" if code < 0 else f"exit status {code}"
                raise SolverError(f"{self.name} worker process died ({how}) during {what}")
            return frame

    def alive(self) -> bool:
        """Whether the worker runs and is this process's (not inherited through a fork)."""
        return self.owner == os.getpid() and self.process.poll() is None

    def stop(self, wait: float = 2.0) -> None:
        """Close the worker's input (it exits), then kill it if it lingers ``wait`` seconds;
        always reaped. Nothing is done in a forked child (the worker is not its own)."""
        if self.owner != os.getpid():
            return
        with contextlib.suppress(OSError):
            if self.process.stdin is not None:
                self.process.stdin.close()
        try:
            self.process.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


class Background(Generic[_T]):
    """A call run in a daemon thread beside the caller: submitted at once, collected later.

    The call runs inside :func:`~taopt.runtime.deadline.cancel_scope` of its own
    ``token``, so a :class:`~taopt.runtime.deadline.Deadline` it makes carries the token
    and :meth:`cancel` stops it at its next loop head (a peer call also stops its worker
    process: ``ScriptWorker.next_frame``'s ``stop``). The caller never blocks except in
    :meth:`wait` / :meth:`result`, with a timeout of its choosing. Used by the SOP portfolio
    to run CP-SAT's worker beside its own stages.

    Parameters
    ----------
    call : callable
        Takes no argument; its return value is the result.
    name : str
        The thread's name.
    parent : CancelToken, optional
        The run this call belongs to: cancelling it cancels the call too.

    Example
    -------
    >>> task = Background(lambda: 6 * 7, "answer")
    >>> task.result(timeout=10)
    42
    """

    def __init__(
        self, call: Callable[[], _T], name: str, parent: CancelToken | None = None
    ) -> None:
        self.token = CancelToken(parent)
        self.began = time.perf_counter()
        self.seconds = float("nan")  # how long the call ran, once done
        self._call = call
        self._finished = threading.Event()
        self._value: _T | None = None
        self._error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            with cancel_scope(self.token):
                self._value = self._call()
        except BaseException as exc:  # handed to the caller by result()
            self._error = exc
        finally:
            self.seconds = time.perf_counter() - self.began
            self._finished.set()

    def done(self) -> bool:
        """Whether the call has returned or raised."""
        return self._finished.is_set()

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the call is done or ``timeout`` seconds passed; whether it is done."""
        return self._finished.wait(timeout)

    def cancel(self) -> None:
        """Cancel the call's token (it stops at its next look; idempotent, never blocks)."""
        self.token.cancel()

    def result(self, timeout: float | None = None) -> _T:
        """The call's return value, waiting at most ``timeout`` seconds.

        Raises
        ------
        TimeoutError
            The call is not done after ``timeout`` seconds.
        BaseException
            What the call raised, re-raised here.
        """
        if not self._finished.wait(timeout):
            raise TimeoutError(f"{self.thread.name} not done after {timeout} s")
        if self._error is not None:
            raise self._error
        return self._value  # type: ignore[return-value]

    def __repr__(self) -> str:
        return f"Background({self.thread.name!r}, done={self.done()})"


def _piped_main(
    target: Callable[..., Any], conn: Any, args: tuple[Any, ...], parent: int
) -> None:  # pragma: no cover - runs in the worker
    become_worker(parent, ONE_THREAD_ENV)
    target(conn, *args)


class PipedWorker:
    """``target(conn, *args)`` in a spawned worker process (:func:`become_worker` first)
    holding one end of a duplex pipe; its ``conn`` is this process's end. For a worker that
    talks with its parent while both run (the SOP tree's peer, :mod:`taopt.models.sop_split`).

    ``in_thread``: run it in a daemon thread of this process instead (the same pipe; tests).
    :meth:`kill` (SIGKILL; nothing for a thread, which ends on its pipe) and :meth:`join`
    are the owner's to call; the worker dies with its parent in any case.

    Example
    -------
    >>> worker = PipedWorker(lambda conn, x: conn.send(x * 2), (21,), "double", in_thread=True)
    >>> worker.conn.recv()
    42
    >>> worker.join(10)
    """

    def __init__(
        self,
        target: Callable[..., Any],
        args: tuple[Any, ...],
        name: str,
        in_thread: bool = False,
    ) -> None:
        context = multiprocessing.get_context("spawn")
        self.conn, child = context.Pipe(duplex=True)
        self.name = name
        self.process: multiprocessing.process.BaseProcess | None = None
        self.thread: threading.Thread | None = None
        if in_thread:
            self.thread = threading.Thread(
                target=target, args=(child, *args), name=name, daemon=True
            )
            self.thread.start()
            return
        with _START_LOCK, main_hidden():
            self.process = context.Process(
                target=_piped_main,
                args=(target, child, args, os.getpid()),
                name=name,
                daemon=True,
            )
            self.process.start()
        child.close()

    def is_alive(self) -> bool:
        """Whether the worker still runs."""
        if self.thread is not None:
            return self.thread.is_alive()
        assert self.process is not None
        return self.process.is_alive()

    @property
    def exitcode(self) -> int | None:
        """The process's exit code once reaped (0 for a thread that ended)."""
        if self.thread is not None:
            return None if self.thread.is_alive() else 0
        assert self.process is not None
        return self.process.exitcode

    def join(self, timeout: float | None = None) -> None:
        """Wait at most ``timeout`` seconds for the worker to end (reaped if it did)."""
        if self.thread is not None:
            self.thread.join(timeout)
        elif self.process is not None:
            self.process.join(timeout)

    def kill(self) -> None:
        """SIGKILL the process and reap it (a thread is left to end on its pipe)."""
        if self.process is not None and self.process.is_alive():
            self.process.kill()
            self.process.join()


def kill_processes(pids: list[int]) -> None:
    """SIGKILL each of ``pids`` that still exists (processes that are not this pool's
    children, e.g. a local Dask cluster's workers)."""
    for pid in pids:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)


__all__ = [
    "ONE_THREAD_ENV",
    "PipedWorker",
    "STOP_POLL",
    "Background",
    "ScriptWorker",
    "WorkerPool",
    "become_worker",
    "die_with_parent",
    "drop_pool",
    "kept_pool",
    "kill_processes",
    "main_hidden",
    "shared_pool",
]
