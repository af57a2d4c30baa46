"""Chapter 3 exact models: corrected = independent exact methods, printed <= corrected, joint."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from conftest import ROOT
from hypothesis import given, settings
from hypothesis import strategies as st

import taopt
from taopt import Instance
from taopt.bounds import arborescence
from taopt.capability import CapabilityProblem
from taopt.capability.instances import capability_problem_from_instance, thesis_scenario
from taopt.errors import InstanceError
from taopt.models import solve_capability
from taopt.models.capability import build_printed, decode_printed, describe
from taopt.orchestration.studies.capability_claims import exact_optimum, random_problem
from taopt.runtime.workers import kept_pool

EXAMPLE = ROOT / "docs" / "reproduction" / "data" / "chapter3" / "printed_vs_corrected.json"


def brute_force(problem: CapabilityProblem) -> float:
    """Optimum by enumerating every vehicle's ordered subset of servable targets (tiny n).

    Independent of the class split: each vehicle picks any ordered subset of the targets
    demanding its capability, and a combination counts when every (target, capability)
    demand is served exactly once.
    """
    n = problem.n
    options = []
    for cap in problem.vehicle_capability:
        servable = [j for j in range(n) if cap in problem.demands[j]]
        mine = [()]
        for size in range(1, len(servable) + 1):
            mine += list(itertools.permutations(servable, size))
        options.append(mine)
    wanted = sorted((j, c) for j in range(n) for c in problem.demands[j])
    best = np.inf
    for combo in itertools.product(*options):
        served = sorted((j, problem.vehicle_capability[k]) for k, r in enumerate(combo) for j in r)
        if served != wanted:
            continue
        total = 0.0
        for k, route in enumerate(combo):
            cost = problem.cost_for(problem.vehicle_capability[k])
            nodes = [n + k, *route]
            total += sum(cost[a, b] for a, b in zip(nodes[:-1], nodes[1:], strict=True))
        best = min(best, total)
    return float(best)


@pytest.mark.parametrize("seed", range(6))
def test_corrected_equals_brute_force_on_tiny_instances(seed):
    """n <= 3, m <= 3: the certified optimum equals whole-problem enumeration."""
    rng = np.random.default_rng(seed)
    kind = ("metric", "euclidean")[seed % 2]
    problem = random_problem(kind, int(rng.integers(1, 4)), int(rng.integers(1, 4)), 1, rng)
    if seed >= 2:
        problem = random_problem(kind, 3, 3, int(rng.integers(2, 4)), rng)
    exact = solve_capability(problem)
    assert exact.status == "optimal"
    assert exact.objective == pytest.approx(brute_force(problem), rel=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_exact_on_obstacle_scenarios(seed):
    """§3.7 scenarios (n <= 9, m <= 4, |A| <= 3, obstacles): every must-show property."""
    rng = np.random.default_rng(100 + seed)
    n, m = int(rng.integers(4, 10)), int(rng.integers(1, 5))
    k = int(rng.integers(1, min(3, m) + 1))
    problem = thesis_scenario(n, m, k, seed=seed).problem
    exact = taopt.solve(problem, "exact")
    dp = exact_optimum(problem)[0]
    assert exact.status == "optimal"
    assert exact.objective == pytest.approx(dp, rel=1e-6)
    assert taopt.evaluate(problem, exact.routes) == pytest.approx(exact.objective, rel=1e-6)
    assert exact.bound <= exact.objective * (1 + 1e-9)
    assert solve_capability(problem, "printed").objective <= exact.objective * (1 + 1e-9)
    assert arborescence(problem) <= exact.objective * (1 + 1e-9)
    for method in ("DTAA", "GA", "MC"):
        heuristic = taopt.solve(
            problem, method, seed=seed, **({"generations": 60} if method == "GA" else {})
        )
        assert taopt.evaluate(problem, heuristic.routes) == pytest.approx(heuristic.objective)
        assert heuristic.objective >= exact.objective * (1 - 1e-9)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(1, 7),
    m=st.integers(1, 4),
    k=st.integers(1, 3),
    kind=st.sampled_from(["metric", "euclidean"]),
)
def test_three_formulations_agree(seed, n, m, k, kind):
    """corrected = joint (DFJ and MTZ) = subset DP; printed is never above them."""
    problem = random_problem(kind, n, m, min(k, m), np.random.default_rng(seed))
    dp = exact_optimum(problem)[0]
    corrected = solve_capability(problem, "corrected")
    assert corrected.status == "optimal"
    assert corrected.objective == pytest.approx(dp, rel=1e-6, abs=1e-9)
    for sec in ("dfj", "mtz"):
        joint = solve_capability(problem, "joint", sec=sec)
        assert joint.status == "optimal"
        assert joint.objective == pytest.approx(dp, rel=1e-6, abs=1e-9)
    printed = solve_capability(problem, "printed")
    assert printed.objective <= dp * (1 + 1e-9) + 1e-9
    if printed.status == "optimal":  # its arcs happened to be routes
        assert printed.objective == pytest.approx(dp, rel=1e-6, abs=1e-9)


def test_shipped_example_printed_strictly_below():
    """The shipped example: the printed model closes a subtour and switches vehicles."""
    instance = Instance.load(EXAMPLE)
    problem = capability_problem_from_instance(instance)
    printed = solve_capability(problem, "printed")
    corrected = solve_capability(problem, "corrected")
    assert printed.status == "relaxation" and printed.routes is None
    # cycle t0 <-> t1 (2 sqrt(500)), t2 entered from B's start for a and for b (15 + 15)
    assert printed.objective == pytest.approx(2 * np.sqrt(500) + 30)
    assert corrected.objective == pytest.approx(exact_optimum(problem)[0])
    assert corrected.objective == pytest.approx(np.hypot(50, 40) + 50 + np.sqrt(500) + 15)
    assert corrected.routes == [[2, 0, 1], [2]]
    assert printed.info["subtours"] == [["a", [0, 1]]]
    # vehicle A's class enters t2 from vehicle B's start: not its own point, not its label
    assert printed.info["foreign_tails"] == [[4, 2, 0]]
    assert printed.info["vehicle_switches"] == [[4, 2, 0, 1]]


def test_printed_optimal_when_its_arcs_are_routes():
    """One vehicle, targets in a row from it: the relaxation's arcs are the optimal route."""
    x = np.array([1.0, 2.0, 3.0, 0.0])
    cost = abs(x[:, None] - x[None, :]) + np.where(x[:, None] > x[None, :], 10.0, 0.0)
    np.fill_diagonal(cost, 0)
    p = CapabilityProblem(cost, 3, ["a"], [{"a"}] * 3)
    printed = solve_capability(p, "printed")
    assert printed.status == "optimal" and printed.routes == [[0, 1, 2]]
    assert printed.objective == pytest.approx(3.0)


def test_decode_printed_by_hand():
    """decode_printed names a subtour, a foreign tail and a vehicle switch from given arcs."""
    x = np.array([10.0, 11.0, 0.0, 20.0])
    p = CapabilityProblem(abs(x[:, None] - x[None, :]), 2, ["a", "b"], [{"a"}, {"a"}])
    model = build_printed(p)
    values = np.zeros(len(model.tails))
    for i, j, k in [(0, 1, 0), (1, 0, 0)]:
        values[(model.tails == i) & (model.heads == j) & (model.labels == k)] = 1
    decoded = decode_printed(p, model, values)
    assert decoded.subtours == [("a", [0, 1])] and decoded.routes is None
    values[:] = 0
    for i, j, k in [(2, 0, 0), (0, 1, 0)]:
        values[(model.tails == i) & (model.heads == j) & (model.labels == k)] = 1
    decoded = decode_printed(p, model, values)
    assert decoded.routes == [[0, 1], []] and not decoded.vehicle_switches


def test_time_limit_and_incumbent():
    """A time-limited solve keeps a proven bound; an incumbent is accepted and checked."""
    problem = thesis_scenario(9, 2, 1, seed=4).problem
    dtaa = taopt.solve(problem, "DTAA")
    exact = taopt.solve(problem, "exact")
    assert exact.info["warm_start"]["method"] == "DTAA"
    again = solve_capability(problem, incumbent=dtaa)
    assert again.objective == pytest.approx(exact.objective)
    joint = solve_capability(problem, "joint", incumbent=dtaa.routes)
    assert joint.objective == pytest.approx(exact.objective)
    limited = solve_capability(problem, time_limit=0.05)
    assert limited.status in ("optimal", "time_limit")
    assert limited.bound <= limited.objective * (1 + 1e-9)
    with pytest.raises(taopt.FeasibilityError):
        solve_capability(problem, incumbent=[[0]] * problem.m)
    with pytest.raises(InstanceError, match="formulation"):
        solve_capability(problem, "dual")


def test_describe_lists_labelled_constraints():
    """describe() reads like the thesis: (3.2), (3.3) and (2.5) rows with their counts."""
    problem = thesis_scenario(5, 3, 2, seed=1).problem
    printed = describe(problem, "printed", show=False)
    assert [f["equation"] for f in printed] == ["(3.1)", "(3.2)", "(3.3)"]
    assert printed[1]["rows"] == problem.demand_pairs()
    joint = describe(problem, "joint", sec="mtz", show=False)
    assert "(2.5)" in [f["equation"] for f in joint]


# ------------------------------------------------------- classes in worker processes (issue 18)
@pytest.mark.parametrize("seed", range(3))
def test_workers_give_the_serial_optimum(seed):
    """Classes solved in 2 worker processes: the same certified optimum as workers=1."""
    rng = np.random.default_rng(300 + seed)
    kind = ("metric", "euclidean", "grid-drift")[seed]
    problem = random_problem(kind, 14, 4, 3, rng)
    serial = solve_capability(problem, workers=1)
    parallel = solve_capability(problem, workers=2)
    assert serial.status == parallel.status == "optimal"
    assert parallel.objective == pytest.approx(serial.objective, rel=1e-9)
    assert parallel.objective == pytest.approx(taopt.evaluate(problem, parallel.routes), rel=1e-12)
    assert [c["objective"] for c in parallel.info["classes"]] == pytest.approx(
        [c["objective"] for c in serial.info["classes"]], rel=1e-9
    )


def limited_in_workers():
    """The 60-target scenario, its DTAA plan, and the capability model on it in 2 workers
    with a 0.3 s limit (the pool started beforehand)."""
    problem = thesis_scenario(60, 6, 3, seed=7).problem
    dtaa = taopt.solve(problem, "DTAA")
    solve_capability(thesis_scenario(9, 2, 2, seed=1).problem, workers=2)  # pool started
    return problem, dtaa, solve_capability(problem, time_limit=0.3, incumbent=dtaa, workers=2)


def test_workers_respect_the_time_limit():
    """In workers, a short limit gives a certified or time_limit result, bound <= f."""
    _, dtaa, limited = limited_in_workers()
    assert limited.status in ("optimal", "time_limit")
    assert limited.bound <= limited.objective * (1 + 1e-9)
    assert limited.objective <= dtaa.objective * (1 + 1e-9)


@pytest.mark.timing
def test_workers_keep_the_time_limit_on_the_clock():
    """In workers, a 0.3 s limit returns within 0.3 + 1.5 s of wall-clock time."""
    assert limited_in_workers()[2].runtime < 0.3 + 1.5


def test_workers_option_checked(capability_9x2):
    """workers must be a positive integer; 1 is the serial path."""
    problem = capability_9x2
    for bad in (0, -1, 1.5, True):
        with pytest.raises(InstanceError, match="workers"):
            solve_capability(problem, workers=bad)


def test_killed_worker_is_a_clear_error(monkeypatch, capability_9x2):
    """A worker process killed mid-solve raises SolverError naming its class, never hangs;
    the broken pool is dropped and the next call starts anew."""
    import runtime_tasks

    from taopt.errors import SolverError
    from taopt.models import capability

    problem = capability_9x2
    with monkeypatch.context() as patch:
        patch.setattr(capability, "_solve_class", runtime_tasks.die)  # the worker dies in it
        with pytest.raises(SolverError, match="worker process solving capability class"):
            solve_capability(problem, workers=2)
    assert kept_pool(("capability", 2)) is None
    assert solve_capability(problem, workers=2).objective == pytest.approx(
        solve_capability(problem, workers=1).objective
    )


CTRL_C_SCRIPT = """
import os, sys, time
sys.path.insert(0, {tests!r})  # the workers inherit it and import runtime_tasks
import runtime_tasks
from taopt.capability.instances import thesis_scenario
from taopt.models import capability, solve_capability
from taopt.runtime.workers import kept_pool

capability._solve_class = runtime_tasks.busy  # every class keeps its worker busy
problem = thesis_scenario(9, 2, 2, seed=4).problem
pids = []
def note():
    while len(pids) < 2:
        time.sleep(0.05)
        pool = kept_pool(("capability", 2))
        pids[:] = pool.pids() if pool is not None else []
    print("ready", flush=True)  # both workers are at work
import threading
threading.Thread(target=note, daemon=True).start()
try:
    solve_capability(problem, workers=2)
except KeyboardInterrupt:
    alive = []
    for pid in pids:
        try:
            os.kill(pid, 0)
            alive.append(pid)
        except ProcessLookupError:
            pass
    print("interrupted", len(pids), "alive", alive, flush=True)
    sys.exit(130)
print("finished", flush=True)
"""


def ctrl_c_the_workers() -> tuple[int, str, str, float]:
    """Run CTRL_C_SCRIPT, send SIGINT once both workers are busy: (code, stdout, stderr,
    seconds from the signal to the exit)."""
    import signal
    import subprocess
    import sys
    import time

    tests = str(ROOT / "tests")
    process = subprocess.Popen(
        [sys.executable, "-c", CTRL_C_SCRIPT.format(tests=tests)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        assert process.stdout.readline().strip() == "ready", process.communicate()
        assert process.poll() is None, process.communicate()
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    return process.returncode, out, err, time.monotonic() - sent


def test_ctrl_c_stops_the_workers():
    """Ctrl-C during a solve in workers: KeyboardInterrupt, every worker gone (within the
    60 s hang guard; how fast: test_ctrl_c_stops_the_workers_at_once)."""
    code, out, err, _ = ctrl_c_the_workers()
    assert code == 130, err
    assert out.split() == ["interrupted", "2", "alive", "[]"], (out, err)


@pytest.mark.timing
def test_ctrl_c_stops_the_workers_at_once():
    """Ctrl-C during a solve in workers ends the process within 6 s of wall-clock time."""
    code, out, err, seconds = ctrl_c_the_workers()
    assert code == 130, err
    assert seconds < 6.0, f"{seconds:.2f} s"


def test_default_workers(monkeypatch, capability_9x2):
    """Default workers: 1 for small classes or inside a study's task, else one per core."""
    from taopt.models import capability

    small = capability_9x2
    assert solve_capability(small).info["workers"] == 1
    large = thesis_scenario(60, 6, 2, seed=7).problem
    classes = [c for c in large.classes if c.problem]
    assert min(len(c.targets) for c in classes) >= capability.PARALLEL_MIN_TARGETS
    monkeypatch.setattr(capability, "available_cores", lambda: 8)
    monkeypatch.delenv("TAOPT_SOLVER_THREADS", raising=False)
    assert capability._auto_workers(classes) == 2  # at most one per class
    monkeypatch.setattr(capability, "available_cores", lambda: 1)
    assert capability._auto_workers(classes) == 1
    monkeypatch.setattr(capability, "available_cores", lambda: 8)
    monkeypatch.setenv("TAOPT_SOLVER_THREADS", "1")
    assert capability._auto_workers(classes) == 1


def past_its_limit(monkeypatch):
    """The 90-target study scenario, its DTAA plan, and the capability model on it in 2
    workers with a 30 s limit and a grace of -29 s (the workers are "past" it after 1 s)."""
    from taopt.capability.instances import STUDY_CELL
    from taopt.models import capability
    from taopt.orchestration.studies.capability import make_scenario

    settings = {"seed": 1, "cell": STUDY_CELL, "neighbours": 16}
    problem = make_scenario({"n": 90, "m": 10, "A": 5, "scenario": 0}, settings).problem
    dtaa = taopt.solve(problem, "DTAA")
    solve_capability(thesis_scenario(9, 2, 2, seed=1).problem, workers=2)  # pool started
    monkeypatch.setattr(capability, "WORKER_GRACE", -29.0)  # "past" 1 s into a 30 s limit
    return problem, dtaa, solve_capability(problem, time_limit=30.0, incumbent=dtaa, workers=2)


def test_worker_past_its_limit_is_killed(monkeypatch):
    """A worker past limit + grace is killed: time_limit, the incumbent's routes, bound <= f."""
    problem, dtaa, result = past_its_limit(monkeypatch)
    assert result.status == "time_limit"
    assert kept_pool(("capability", 2)) is None
    killed = [c for c in result.info["classes"] if c["status"] == "time_limit"]
    assert killed
    assert result.objective == pytest.approx(taopt.evaluate(problem, result.routes), rel=1e-12)
    assert result.objective <= dtaa.objective * (1 + 1e-9)
    assert result.bound <= result.objective


@pytest.mark.timing
def test_worker_past_its_limit_is_killed_at_once(monkeypatch):
    """Workers past limit + grace (1 s into a 30 s limit) are killed within 10 s of wall-clock."""
    assert past_its_limit(monkeypatch)[2].runtime < 10.0


def test_corrected_model_hands_the_improver_to_every_class():
    """``improve`` reaches each class's DFJ loop (serially here, so a closure will do) and
    the certified optimum is the same as without it."""
    from taopt.heuristics.ga_routing import improve_routes

    problem = random_problem("grid-drift", 14, 4, 2, np.random.default_rng(7))
    seen = []

    def improve(class_problem, routes):
        seen.append(class_problem.n)
        return improve_routes(class_problem, routes)

    with_it = solve_capability(problem, workers=1, improve=improve)
    without = solve_capability(problem, workers=1)
    assert with_it.status == without.status == "optimal"
    assert with_it.objective == pytest.approx(without.objective, rel=1e-9)
    solvable = {c.problem.n for c in problem.classes if c.problem is not None}
    assert set(seen) == solvable
