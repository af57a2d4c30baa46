"""Ctrl-C in `taopt solve`, `verify`, `simulate` and `claims`: one line, exit 130, no traceback.

Each command runs in a subprocess with SIGINT at its default (as from a terminal, even when
pytest runs in the background with SIGINT ignored; see tests/orchestration/test_study.py), is sent SIGINT
once it is running, and must stop promptly with exit code 130 and the single line
``taopt COMMAND: interrupted`` on stderr (a 60 s hang guard separates "stopped" from "ran
on"). Two in-process tests check the HiGHS mechanism itself: a MIP stopped through its
interrupt callback within the grace (not abandoned), on both of taopt's ways to run HiGHS.
How fast each stops is a wall-clock property: the ``timing`` group at the end of this file
(``pytest -m timing -n 0``, docs/architecture.md "Tests"; 2 s is the target on an idle
machine, :data:`STOP_BOUND` the bound under load).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cvxpy as cp
import numpy as np
import pytest

from taopt.models.highs import HighsModel, solve_highs
from taopt.runtime import interrupt as runtime_interrupt
from taopt.runtime.highs import INTERRUPT_GRACE

#: Seconds from SIGINT to exit accepted here (interpreter teardown included, under load).
STOP_BOUND = 6.0

#: ``taopt ARGS`` after the heavy imports (cvxpy, the models), so that "ready" means the
#: command starts its work at once.
LAUNCH = (
    "import sys, taopt.orchestration.cli, taopt.orchestration.solving\n"
    "print('ready', flush=True)\n"
    "sys.exit(taopt.orchestration.cli.main())\n"  # as the `taopt` script: arguments from sys.argv
)


def interrupt(tmp_path: Path, args: list[str], delay: float) -> tuple[int, str, float]:
    """Run ``taopt ARGS``, send SIGINT ``delay`` s after it is ready; (code, stderr, seconds)."""
    process = subprocess.Popen(
        [sys.executable, "-c", LAUNCH, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    assert process.stdout.readline().strip() == "ready", process.communicate()
    time.sleep(delay)
    assert process.poll() is None, f"finished before the signal: {process.communicate()}"
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    try:
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    return process.returncode, err, time.monotonic() - sent


def assert_interrupted(code: int, err: str, command: str) -> None:
    """Exit code 130 and the one line ``taopt COMMAND: interrupted``, no traceback."""
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in err, err
    assert code == 130, err
    assert lines == [f"taopt {command}: interrupted"], err


def delivery_file(tmp_path: Path, n: int) -> Path:
    """A delivery instance with ``n`` customers (layered precedences), saved as JSON."""
    from reference import layered_grid_delivery

    instance = layered_grid_delivery(n)
    path = tmp_path / f"delivery{n}.json"
    instance.save(path)
    return path


def solve_milp_args(tmp_path: Path) -> list[str]:
    """`taopt solve --methods milp` on 10 customers (the cvxpy-HiGHS MILP, minutes)."""
    path = delivery_file(tmp_path, 10)
    return ["solve", str(path), "--methods", "milp", "--quiet"]


def test_solve_delivery_milp(tmp_path):
    """`taopt solve --methods milp` on 10 customers (the cvxpy-HiGHS MILP, minutes): Ctrl-C."""
    code, err, _ = interrupt(tmp_path, solve_milp_args(tmp_path), delay=1.0)
    assert_interrupted(code, err, "solve")


def verify_exact_args(tmp_path: Path) -> list[str]:
    """`taopt verify --exact` re-solving 24 customers without precedences (2^24 order
    ideals: the exact DP runs for minutes)."""
    import taopt
    from taopt.delivery.instance import DeliveryInstance

    customers = np.random.default_rng(0).uniform(0, 1000, size=(24, 2))
    path = tmp_path / "free24.json"
    DeliveryInstance.grid(customers, 11, 1000.0, 1.0, 1.0, 300.0).save(path)
    plan = taopt.solve(DeliveryInstance.load(path), "NIA")
    plan.replace(status="optimal", bound=plan.objective).save(tmp_path / "nia.json")
    return ["verify", str(tmp_path / "nia.json"), str(path), "--exact"]


def test_verify_exact(tmp_path):
    """`taopt verify --exact` re-solving 24 customers without precedences (2^24 order ideals:
    the exact DP runs for minutes): Ctrl-C."""
    code, err, _ = interrupt(tmp_path, verify_exact_args(tmp_path), delay=1.0)
    assert_interrupted(code, err, "verify")


def claims_args(tmp_path: Path) -> list[str]:
    """`taopt claims` over many samples (pure Python loops; no progress bar on stderr)."""
    return ["claims", "--samples", "100000", "--quiet"]


def test_claims(tmp_path):
    """`taopt claims` over many samples (pure Python loops): Ctrl-C."""
    code, err, _ = interrupt(tmp_path, claims_args(tmp_path), delay=1.0)
    assert_interrupted(code, err, "claims")


def simulate_args(tmp_path: Path) -> list[str]:
    """`taopt simulate` of a large chapter 4 problem (the event engine)."""
    from taopt.comm import CommProblem

    rng = np.random.default_rng(1)
    targets = rng.uniform(0, 3000, size=(1500, 2)).tolist()
    vehicles = rng.uniform(0, 3000, size=(12, 2)).tolist()
    problem = CommProblem(targets, vehicles, ["a"] * 1500, ["a"] * 12, 300.0)
    path = tmp_path / "comm.json"
    problem.save(path)
    return ["simulate", str(path)]


def test_simulate(tmp_path):
    """`taopt simulate` of a large chapter 4 problem (the event engine): Ctrl-C."""
    code, err, _ = interrupt(tmp_path, simulate_args(tmp_path), delay=1.0)
    assert_interrupted(code, err, "simulate")


#: The commands above, by the name in their interrupted line.
COMMANDS = {
    "solve": solve_milp_args,
    "verify": verify_exact_args,
    "claims": claims_args,
    "simulate": simulate_args,
}


@pytest.mark.timing
@pytest.mark.parametrize("command", list(COMMANDS))
def test_ctrl_c_stops_promptly(tmp_path, command):
    """Each command above exits (130) within STOP_BOUND s of wall-clock time after Ctrl-C."""
    code, err, seconds = interrupt(tmp_path, COMMANDS[command](tmp_path), delay=1.0)
    assert_interrupted(code, err, command)
    assert seconds < STOP_BOUND, f"{seconds:.2f} s"


# ------------------------------------------------------------------ the HiGHS mechanism
def hard_mip() -> cp.Problem:
    """A multi-dimensional 0-1 knapsack HiGHS needs far more than a few seconds for."""
    rng = np.random.default_rng(0)
    n = 250
    x = cp.Variable(n, boolean=True)
    weights = rng.integers(1, 1000, size=(25, n))
    values = rng.integers(1, 1000, size=n)
    return cp.Problem(cp.Maximize(values @ x), [weights @ x <= weights.sum(axis=1) // 2])


def interrupt_when_highs_runs(solve) -> tuple[float, int]:
    """Call ``solve()`` on the main thread, send SIGINT once HiGHS runs; (seconds to stop,
    runs abandoned: not stopped by the interrupt callbacks within INTERRUPT_GRACE)."""
    sent = {}

    def fire() -> None:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if any(t.name == "highs-run" and t.is_alive() for t in threading.enumerate()):
                time.sleep(0.3)
                sent["at"] = time.monotonic()
                os.kill(os.getpid(), signal.SIGINT)
                return
            time.sleep(0.01)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Thread(target=fire, daemon=True).start()
        with pytest.raises(KeyboardInterrupt):
            solve()
        return time.monotonic() - sent["at"], runtime_interrupt.abandoned()
    finally:
        signal.signal(signal.SIGINT, previous)
        # a run left to its time limit: let it end (else the exit hook would end pytest
        # with code 130)
        runtime_interrupt.wait_abandoned(70)


def test_highs_model_run_interrupted():
    """A live HighsModel MIP stops at Ctrl-C through its interrupt callback within the grace
    (the run is not abandoned; no solver error)."""
    model = HighsModel(hard_mip())
    _, abandoned = interrupt_when_highs_runs(lambda: model.solve(time_limit=60))
    assert abandoned == 0


def test_cvxpy_highs_run_interrupted():
    """cvxpy's own HiGHS object (solve_highs) stops at Ctrl-C within the grace too (not
    abandoned), and highspy is restored."""
    import highspy

    original = highspy.Highs
    _, abandoned = interrupt_when_highs_runs(lambda: solve_highs(hard_mip(), time_limit=60))
    assert abandoned == 0
    assert highspy.Highs is original


HIGHS_RUNS = {
    "HighsModel": lambda: HighsModel(hard_mip()).solve(time_limit=60),
    "solve_highs": lambda: solve_highs(hard_mip(), time_limit=60),
}


@pytest.mark.timing
@pytest.mark.parametrize("way", list(HIGHS_RUNS))
def test_highs_run_stops_within_the_grace_on_the_clock(way):
    """Both ways to run HiGHS stop within INTERRUPT_GRACE + 1 s of wall-clock after Ctrl-C."""
    seconds, abandoned = interrupt_when_highs_runs(HIGHS_RUNS[way])
    assert abandoned == 0
    assert seconds < INTERRUPT_GRACE + 1.0, f"{seconds:.2f} s"
