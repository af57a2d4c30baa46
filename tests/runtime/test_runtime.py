"""The runtime home (taopt.runtime): deadlines and cancellation, signal handling, worker pools
and HiGHS's interrupt hooks (docs/architecture.md, "the runtime contract").

Cheap on purpose: an already-expired deadline, a pre-set cancel token, a pool of one worker
terminated at once; no sleeps waiting for a clock.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures.process import BrokenProcessPool

import numpy as np
import pytest
import runtime_tasks

import taopt
from taopt.runtime import (
    MIN_SHARE,
    CancelToken,
    Deadline,
    cancel_scope,
    current_token,
    interrupt,
    overrun_allowance,
    workers,
)


# -- deadlines and cancellation ----------------------------------------------------------------
def test_expired_deadline():
    """A deadline of 0 s is expired at once: 0 s left, the least share, reason time_limit."""
    d = Deadline(0.0)
    assert d.limited and d.expired() and d.remaining() == 0.0
    assert d.share(0.5) == MIN_SHARE and d.reason == "time_limit"


def test_no_limit_never_expires():
    """Without a limit or a token: not limited, never expired, no remaining time or share."""
    d = Deadline(None)
    assert not d.limited and not d.expired(margin=1e9)
    assert d.remaining() is None and d.share(0.5) is None and d.token is None


def test_cancel_token_expires_a_deadline():
    """A pre-set token makes even an unlimited deadline expired, with reason interrupted."""
    token = CancelToken()
    token.cancel()
    d = Deadline(None, cancel=token)
    assert d.cancelled and d.limited and d.expired()
    assert d.remaining() == 0.0 and d.share(0.25) == MIN_SHARE and d.reason == "interrupted"
    assert token.wait(0) and Deadline(100.0, cancel=token).expired()


def test_cancel_scope_reaches_new_deadlines_and_nests():
    """Deadlines made in a cancel_scope carry its token; scopes nest and are restored."""
    outer, inner = CancelToken(), CancelToken()
    assert current_token() is None
    with cancel_scope(outer):
        with cancel_scope(inner):
            assert Deadline(1.0).token is inner
        assert Deadline(None).token is outer and current_token() is outer
    assert current_token() is None and Deadline(None).token is None


def test_overrun_allowance():
    """The overrun allowance is max(1 s, 5 % of T)."""
    assert overrun_allowance(0.2) == 1.0 and overrun_allowance(20.0) == 1.0
    assert overrun_allowance(100.0) == pytest.approx(5.0)


def test_method_stops_on_a_cancelled_token():
    """A heuristic given a cancelled token (taopt.solve's cancel=, or a cancel_scope) stops at
    its first loop head (GA: no generation done out of 100,000) and still returns its scored
    best answer."""
    rng = np.random.default_rng(0)
    problem = taopt.AssignmentProblem(rng.uniform(1, 10, size=(8, 8)), n_targets=6)
    token = CancelToken()
    token.cancel()
    result = taopt.solve(problem, "GA", seed=0, generations=100_000, cancel=token)
    assert result.info["generations_done"] == 0
    assert result.objective == pytest.approx(taopt.evaluate(problem, result.routes))
    with cancel_scope(token):  # the same through a scope around the call
        assert taopt.solve(problem, "GA", seed=0, generations=100_000).info["generations_done"] == 0
    assert current_token() is None


# -- signals ---------------------------------------------------------------------------------
def test_handled_installs_and_restores():
    """handled() installs a handler for the block and restores the previous one after."""
    before = signal.getsignal(signal.SIGTERM)
    with interrupt.handled(signal.SIGTERM, interrupt.raise_interrupt) as installed:
        assert installed and signal.getsignal(signal.SIGTERM) is interrupt.raise_interrupt
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGTERM)  # the handler runs at the next bytecode
    assert signal.getsignal(signal.SIGTERM) is before


def test_off_the_main_thread_nothing_is_installed():
    """Off the main thread handled() and ignore_sigint() change nothing and say so."""
    seen = {}

    def run() -> None:
        with interrupt.handled(signal.SIGTERM, interrupt.raise_interrupt) as installed:
            seen["installed"] = installed
        seen["ignored"] = interrupt.ignore_sigint()
        seen["catchable"] = interrupt.sigint_catchable()

    before = (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT))
    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    assert seen == {"installed": False, "ignored": False, "catchable": False}
    assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == before


def test_abandoned_runs_are_counted_until_they_end():
    """An abandoned run counts until its event is set; wait_abandoned then says all ended."""
    finished = threading.Event()
    interrupt.abandon(finished)
    assert interrupt.abandoned() >= 1 and not interrupt.wait_abandoned(0)
    finished.set()
    assert interrupt.wait_abandoned(0) and interrupt.abandoned() == 0


def test_exit_now_skips_exit_hooks_and_flushes():
    """exit_now(130) ends the process with 130: buffered output is flushed, exit hooks
    (and the interpreter's teardown) are skipped."""
    code = (
        "import atexit, sys\n"
        "from taopt.runtime.interrupt import exit_now\n"
        "atexit.register(print, 'hook')\n"
        "sys.stdout.write('flushed')\n"
        "exit_now(130)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 130 and done.stdout == "flushed", done.stderr


# -- worker processes ------------------------------------------------------------------------
def test_worker_pool_is_set_up_and_terminated():
    """A pool's worker ignores Ctrl-C and has one solver thread; terminate() kills and reaps
    it at once (no child left) and the pool takes no more tasks."""
    pool = workers.WorkerPool(1)
    try:
        # the task is a module-level function of a helper module a spawned worker can import
        pid, sigint, threads = pool.submit(runtime_tasks.worker_state).result(timeout=120)
        assert pool.pids() == [pid] and sigint == signal.SIG_IGN and threads == "1"
        long = pool.submit(signal.sigtimedwait, [signal.SIGUSR1], 600)  # a task that waits
    finally:
        pool.terminate()
    assert pool.pids() == [] and not pool.usable
    assert pid not in {p.pid for p in multiprocessing.active_children()}
    assert long.cancelled() or isinstance(long.exception(timeout=60), BrokenProcessPool)
    with pytest.raises(RuntimeError, match="shut down"):
        pool.submit(abs, -1)


def test_shared_pool_is_replaced_once_broken():
    """shared_pool() reuses a live pool; a worker killed from outside breaks it (the task
    raises BrokenProcessPool) and the next request gets a new pool; drop_pool() kills it."""
    key = ("test_runtime", 1)
    pool = workers.shared_pool(key, 1)
    try:
        assert workers.shared_pool(key, 1) is pool and workers.kept_pool(key) is pool
        pid = pool.submit(os.getpid).result(timeout=120)
        workers.kill_processes([pid])
        with pytest.raises(BrokenProcessPool):
            pool.submit(os.getpid).result(timeout=60)
        assert not pool.usable
        fresh = workers.shared_pool(key, 1)
        assert fresh is not pool and fresh.usable
    finally:
        workers.drop_pool(key)
    assert workers.kept_pool(key) is None and not fresh.usable


def test_main_hidden_restores_main():
    """main_hidden() hides __main__'s file and spec in the block and restores them after."""
    main = sys.modules["__main__"]
    saved = (main.__dict__.get("__file__"), main.__dict__.get("__spec__"))
    with workers.main_hidden():
        assert "__file__" not in main.__dict__ and main.__spec__ is None
    assert (main.__dict__.get("__file__"), main.__dict__.get("__spec__")) == saved


def test_bad_worker_count():
    """A pool of 0, a fraction or a bool of workers is refused, naming the value."""
    for bad in (0, 1.5, True):
        with pytest.raises(ValueError, match="workers"):
            workers.WorkerPool(bad)


# -- HiGHS's interrupt hooks -------------------------------------------------------------------
def knapsack(n: int = 30):
    """A small multi-dimensional 0-1 knapsack: HiGHS needs simplex iterations and nodes for it."""
    import cvxpy as cp

    rng = np.random.default_rng(0)
    x = cp.Variable(n, boolean=True)
    weights = rng.integers(1, 1000, size=(10, n))
    values = rng.integers(1, 1000, size=n)
    return cp.Problem(cp.Maximize(values @ x), [weights @ x <= weights.sum(1) // 2])


def test_highs_stops_when_told():
    """interrupt_when() stops a HiGHS MIP at its first interrupt callback (a pre-set stop,
    e.g. a cancelled token): HiGHS reports kInterrupt, and the hooks are removed after."""
    import highspy

    from taopt.models.highs import HighsModel
    from taopt.runtime.highs import interrupt_when

    model = HighsModel(knapsack())
    token = CancelToken()
    token.cancel()
    with interrupt_when(model.highs, lambda: token.cancelled):
        model.highs.run()
    assert model.highs.getModelStatus() == highspy.HighsModelStatus.kInterrupt
    model.highs.run()  # no hook left: the same model now runs to its optimum
    assert model.highs.getModelStatus() == highspy.HighsModelStatus.kOptimal


def test_highs_model_stops_on_a_cancelled_token():
    """HighsModel.solve under a cancelled cancel_scope stops at once without a proof; the
    same model solved afterwards is proven optimal (HiGHS's stale interrupt flag cleared)."""
    from taopt.models.highs import HighsModel

    model = HighsModel(knapsack())
    token = CancelToken()
    token.cancel()
    with cancel_scope(token):
        stopped = model.solve()
    assert stopped.status != "optimal" and stopped.solver_status == "user_limit"
    assert model.solve(mip_rel_gap=1e-9).status == "optimal"


def test_highs_model_solves_again_after_its_time_limit():
    """A HighsModel stopped by its time limit (through the interrupt callbacks) is proven
    optimal when solved again without one (before the fix the stale flag stopped it)."""
    from taopt.models.highs import HighsModel

    model = HighsModel(knapsack())
    assert model.solve(time_limit=1e-3).status == "time_limit"
    assert model.solve(mip_rel_gap=1e-9).status == "optimal"


ECHO_SCRIPT = """
import pickle, sys
parent, pdeathsig = sys.argv[-2:]
out = sys.stdout.buffer
pickle.dump(("ready", {"args": sys.argv[1:]}), out)
out.flush()
while True:
    try:
        message = pickle.load(sys.stdin.buffer)
    except EOFError:
        sys.exit(0)
    if message == "die":
        sys.exit(3)
    pickle.dump(("echo", message), out)
    out.flush()
"""


def test_script_worker_talks_stops_and_names_its_death(tmp_path):
    """A ScriptWorker gets its arguments plus this pid and "1" (main thread), echoes frames,
    exits on end of input (reaped), and a worker that dies is a SolverError naming it."""
    from taopt.errors import SolverError

    script = tmp_path / "echo.py"
    script.write_text(ECHO_SCRIPT)
    worker = workers.ScriptWorker(script, ["a"], name="echo")
    try:
        assert worker.next_frame(None, "start") == ("ready", {"args": ["a", str(os.getpid()), "1"]})
        worker.send({"x": 1})
        assert worker.next_frame(None, "a call") == ("echo", {"x": 1})
        assert worker.next_frame(0.0, "a call") is None  # nothing more: None at its deadline
    finally:
        worker.stop()
    assert worker.process.returncode == 0 and not worker.alive()
    dying = workers.ScriptWorker(script, [], name="echo")
    try:
        dying.send("die")
        with pytest.raises(SolverError, match=r"echo worker process died \(exit status 3\)"):
            while True:
                dying.next_frame(None, "a call")
    finally:
        dying.stop()


def test_alarm_after_stops_pure_python_and_restores_the_handler():
    """alarm_after raises OutOfTime inside a busy pure-Python block, then restores the previous
    SIGALRM handler and leaves no timer running."""
    import signal

    from taopt.runtime.interrupt import OutOfTime, alarm_after

    before = signal.getsignal(signal.SIGALRM)
    stopped = False
    try:
        with alarm_after(0.01) as armed:
            assert armed
            for _ in range(10**10):  # stopped long before the end
                pass
    except OutOfTime:
        stopped = True
    assert stopped
    assert signal.getsignal(signal.SIGALRM) is before
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)


def test_highs_model_lp_limit_is_per_run():
    """An LP re-solved after a cut gets its own time limit: HiGHS sums an LP's run clock over
    every run of one object, so before the fix a re-solve given half the first solve's time
    stopped at once with ``time_limit`` although it needed a few milliseconds."""
    import scipy.sparse as sp

    from taopt.models.highs import HighsModel

    rng = np.random.default_rng(1)
    n, m = 1000, 700
    matrix = sp.random(m, n, density=0.02, random_state=1, format="csr")
    model = HighsModel.from_arrays(
        -rng.random(n), matrix, np.full(m, -np.inf), np.ones(m), np.zeros(n), np.ones(n)
    )
    began = time.perf_counter()
    assert model.solve().status == "optimal"
    first = time.perf_counter() - began
    cut = sp.csr_matrix(rng.random((1, n)))
    point = np.asarray(model.highs.getSolution().col_value)
    model.add_rows(cut, None, np.array([0.999 * float((cut @ point)[0])]))
    again = model.solve(time_limit=first / 2)
    assert again.status == "optimal", again.solver_status


def test_child_token_follows_its_parent_only():
    """A child token is cancelled with its parent; cancelling the child leaves the parent."""
    from taopt.runtime import CancelToken

    run = CancelToken()
    part = CancelToken(parent=run)
    part.cancel()
    assert part.cancelled and not run.cancelled
    other = CancelToken(parent=run)
    assert not other.wait(0.01)
    run.cancel()
    assert other.cancelled and other.wait(0.0)


def test_background_returns_raises_and_is_cancelled():
    """A Background call returns its value, re-raises its error, and stops on cancel()."""
    from taopt.runtime import Deadline
    from taopt.runtime.workers import Background

    assert Background(lambda: 6 * 7, "value").result(timeout=30) == 42
    failing = Background(lambda: 1 / 0, "error")
    with pytest.raises(ZeroDivisionError):
        failing.result(timeout=30)

    def loop() -> int:
        deadline = Deadline(None)  # carries the task's token (its cancel scope)
        rounds = 0
        while not (deadline.limited and deadline.expired()):
            rounds += 1
            time.sleep(0.001)
        return rounds

    task = Background(loop, "loop")
    assert not task.wait(0.05)
    task.cancel()
    assert task.result(timeout=30) >= 1 and task.done()


def test_background_follows_the_parent_token():
    """Cancelling the run's token (the parent) stops a Background call too."""
    from taopt.runtime import CancelToken, current_token
    from taopt.runtime.workers import Background

    run = CancelToken()
    task = Background(lambda: current_token().wait(30), "child", parent=run)  # type: ignore[union-attr]
    run.cancel()
    assert task.result(timeout=30) is True


def test_script_worker_is_niced(tmp_path):
    """ScriptWorker(nice=k) runs its process k steps nicer than this one, and stops it."""
    from taopt.runtime.workers import ScriptWorker

    script = tmp_path / "idle.py"
    script.write_text("import sys\nsys.stdin.buffer.read()\n")
    worker = ScriptWorker(script, [], name="idle", nice=5)
    try:
        own = os.getpriority(os.PRIO_PROCESS, 0)
        assert os.getpriority(os.PRIO_PROCESS, worker.process.pid) == min(19, own + 5)
        assert worker.next_frame(None, "idle", stop=lambda: True) is None  # stop: at once
    finally:
        worker.stop()
    assert worker.process.poll() is not None


def test_a_run_past_its_give_up_time_is_detached_and_waited_for_at_exit():
    """run_interruptibly(give_up=...) returns DETACHED soon after ``give_up`` when the run
    ignores its callbacks (a sleep stands for HiGHS between two looks at them); the run counts
    as detached until it ends, the next run starts only after it, and the interpreter's exit
    waits for a detached run (exit code 0). A run that ends before ``give_up`` returns its own
    value. In a child process: the main thread with Ctrl-C catchable, as a user's script
    (the child sets Python's own SIGINT handler: a parent started in the background, as
    ``cmd &`` in a script, passes SIGINT on ignored, and the run would then be plain)."""
    code = """
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
import highspy
from taopt.runtime import interrupt
from taopt.runtime.highs import DETACH_GRACE, DETACHED, run_interruptibly
h = highspy.Highs()
began = time.perf_counter()
got = run_interruptibly(h, run=lambda: time.sleep(1.5), give_up=began + 0.2)
took = time.perf_counter() - began
assert got == DETACHED, got
assert 0.2 <= took <= 0.2 + DETACH_GRACE + 0.5, took
assert interrupt.detached() == 1
started = run_interruptibly(h, run=time.perf_counter)  # waits for the detached run first
assert started >= began + 1.5, started - began
assert interrupt.detached() == 0
assert run_interruptibly(h, run=lambda: "done", give_up=time.perf_counter() + 5) == "done"
run_interruptibly(h, run=lambda: time.sleep(0.8), give_up=time.perf_counter())
print("ok", flush=True)
"""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "ok"  # after HiGHS's banner
