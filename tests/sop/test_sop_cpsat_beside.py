"""CP-SAT beside the SOP portfolio (issue 33): the combined result equals brute force with
CP-SAT on and off, CP-SAT's proof stops the portfolio's stages, a run cut short keeps a
valid bound, and a cancelled CP-SAT leaves no worker process behind."""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest

import taopt
import taopt.heuristics  # noqa: F401  (registers the CP-SAT peer the portfolio looks up)
from taopt.heuristics import peers
from taopt.models import sop as sop_model
from taopt.models.sop import solve_sop_problem
from taopt.result import OPTIMAL, TIME_LIMIT, Order, finish
from taopt.runtime import Deadline
from taopt.sop.generate import random_sop
from taopt.sop.problem import SopProblem, evaluate_order

pytest.importorskip("ortools")


@pytest.fixture(scope="module", autouse=True)
def stop_workers():
    """Stop the peer workers after this module, so no test leaves processes behind."""
    yield
    peers.shutdown()


def _brute(problem: SopProblem) -> float:
    """The optimum by enumeration of every feasible order."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    best = np.inf
    for perm in itertools.permutations(inner):
        order = [problem.start, *perm, problem.end]
        where = {v: k for k, v in enumerate(order)}
        if all(where[a] < where[b] for a, b in problem.closure.edges()):
            best = min(best, float(problem.cost[order[:-1], order[1:]].sum()))
    return best


def _slow_stages(problem: SopProblem, time_limit: float | None, **options: object):
    """Stand-in stages: a poor order (the identity path, if feasible; else none) and no
    bound, kept until the run's deadline expires or is cancelled."""
    deadline = Deadline(time_limit)
    while not (deadline.limited and deadline.expired()):
        time.sleep(0.005)
    order = list(range(problem.n))
    try:
        evaluate_order(problem, order)
    except Exception:
        order = None
    payload = None if order is None else Order(order)
    result = finish(problem, payload, method="exact-sop", stop=deadline.reason, bound=0.0)
    return result.replace(info={**result.info, "engine": "slow", "cancelled": deadline.cancelled})


@pytest.mark.parametrize("cpsat", [True, False])
@pytest.mark.parametrize("seed", range(4))
def test_combined_equals_brute_force(seed, cpsat):
    """With CP-SAT on or off the portfolio's optimum equals brute force, order feasible."""
    problem = random_sop(7 + seed % 2, 0.2, seed)
    result = solve_sop_problem(problem, cpsat=cpsat)
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(_brute(problem))
    assert evaluate_order(problem, result.order) == pytest.approx(result.objective)
    if cpsat:
        assert isinstance(result.info["cpsat"], dict) and result.info["proved_by"]
    else:
        assert result.info["cpsat"] == "off"


@pytest.mark.parametrize("seed", range(3))
def test_cpsat_proof_stops_the_stages(monkeypatch, seed):
    """When the stages cannot close, CP-SAT's re-scored proof cancels them and is returned."""
    monkeypatch.setattr(sop_model, "_stages", _slow_stages)
    problem = random_sop(8, 0.3, seed)
    result = solve_sop_problem(problem, cpsat=True)  # no limit: only the proof ends the stages
    assert result.status == OPTIMAL and result.info["proved_by"] == "cpsat"
    assert result.info["cancelled"] and "+cpsat" in result.info["engine"]
    assert result.objective == pytest.approx(_brute(problem)) == result.bound
    assert evaluate_order(problem, result.order) == pytest.approx(result.objective)


def test_tiny_limit_keeps_a_valid_bound():
    """CP-SAT cut short by a tiny limit: the result's bound stays at most the optimum and its
    order (if any) is feasible; the status is never a false optimal."""
    problem = random_sop(9, 0.25, 7)
    optimum = _brute(problem)
    for limit in (0.05, 0.3):
        result = solve_sop_problem(problem, time_limit=limit, cpsat=True)
        assert result.bound is None or result.bound <= optimum + 1e-9
        if result.solution is not None:
            assert evaluate_order(problem, result.order) == pytest.approx(result.objective)
        if result.status == OPTIMAL:
            assert result.objective == pytest.approx(optimum)
        else:
            assert result.status == TIME_LIMIT


def test_cpsat_cut_short_beside_slow_stages(monkeypatch):
    """CP-SAT stopped by its share of a 1 s limit on ESC47 (optimum 1288) beside stages that
    find nothing: its bound is at most the optimum, its order feasible, status time_limit."""
    monkeypatch.setattr(sop_model, "_stages", _slow_stages)
    peers._worker("cpsat").wait_ready(None)  # started: the limit goes to the search
    problem = SopProblem.load("ESC47")
    result = solve_sop_problem(problem, time_limit=1.0, cpsat=True)
    assert result.status == TIME_LIMIT and result.bound <= 1288.0
    assert result.info["cpsat"]["status"] == TIME_LIMIT
    if result.solution is not None:
        assert evaluate_order(problem, result.order) == pytest.approx(result.objective)
        assert result.objective >= 1288.0


@pytest.mark.slow
def test_cancel_leaves_no_worker_behind(monkeypatch):
    """The stages prove the optimum while CP-SAT searches: its worker is stopped and reaped
    before the call returns, and the next call starts a fresh one."""
    problem = SopProblem.load("ESC47")  # CP-SAT does not close it in seconds
    seen: dict[str, int] = {}
    heuristic = taopt.solve(problem, "NIA")
    order, value = heuristic.solution, heuristic.objective

    def stages(problem: SopProblem, time_limit: float | None, **options: object):
        end = time.monotonic() + 60
        while time.monotonic() < end:  # until CP-SAT's worker holds a request
            worker = peers._WORKERS.get("cpsat")
            if worker is not None and worker.ready and worker.lock.locked():
                seen["pid"] = worker.process.pid
                break
            time.sleep(0.01)
        time.sleep(0.2)  # a stand-in proof: a heuristic order whose bound is its value
        return finish(problem, order, method="exact-sop", stop="optimal", bound=value)

    monkeypatch.setattr(sop_model, "_stages", stages)
    result = solve_sop_problem(problem, cpsat=True)
    assert "pid" in seen
    worker = peers._WORKERS["cpsat"]
    assert worker.process.pid == seen["pid"] and worker.process.poll() is not None
    assert result.info["cpsat"]["worker"] == "cancelled; stopped its worker"
    assert result.status == OPTIMAL and result.info["proved_by"] == "portfolio"


def test_cpsat_true_without_the_peer_is_an_error(monkeypatch):
    """cpsat=True with OR-Tools missing says what to install; None runs without it."""
    from taopt import registry

    monkeypatch.setattr(registry, "_installed", lambda package: package != "ortools")
    problem = random_sop(6, 0.2, 1)
    with pytest.raises(taopt.SolverError, match="ortools"):
        solve_sop_problem(problem, cpsat=True)
    result = solve_sop_problem(problem)
    assert result.status == OPTIMAL and result.info["cpsat"].startswith("not available")


def test_default_rule_skips_small_instances_and_short_limits():
    """cpsat=None leaves CP-SAT off below CPSAT_MIN_NODES nodes and CPSAT_MIN_LIMIT seconds."""
    small = random_sop(6, 0.2, 2)
    assert solve_sop_problem(small).info["cpsat"].startswith("off: 6 nodes")
    runner, why = sop_model._cpsat_peer(SopProblem.load("ESC47"), None, "auto", 1.0)
    assert runner is None and why.startswith("off: time_limit")
    runner, why = sop_model._cpsat_peer(SopProblem.load("ESC47"), None, "dp", None)
    assert runner is None and why.startswith("off: engine")
    runner, _ = sop_model._cpsat_peer(SopProblem.load("ESC47"), None, "auto", 60.0)
    assert runner is not None


def test_dp_started_under_a_cancelled_token_stops_cleanly():
    """The DP set up while the run's token is already cancelled (CP-SAT proved first) ends
    with status time_limit and a valid bound, not an error."""
    from taopt.models.sop_dp import solve_sop_dp
    from taopt.runtime import CancelToken, cancel_scope

    problem = random_sop(9, 0.2, 5)
    token = CancelToken()
    token.cancel()
    with cancel_scope(token):
        result = solve_sop_dp(problem, None)
    assert result.status in (TIME_LIMIT, OPTIMAL)
    assert result.bound is None or result.bound <= _brute(problem) + 1e-9


def _root_then_slow(problem: SopProblem, time_limit: float | None, **options: object):
    """Stand-in stages whose root stage chose the cut engine first (``on_root(True)``), then
    nothing better than :func:`_slow_stages` until the deadline."""
    on_root = options.get("on_root")
    assert callable(on_root)
    on_root(True)
    return _slow_stages(problem, time_limit)


def test_cpsat_stopped_by_the_probe_rule_keeps_its_order(monkeypatch):
    """After the root chose the cut engine first, CP-SAT is stopped by the rule once its
    share of the limit passed; its order is kept (feasible), the bound stays valid."""
    monkeypatch.setattr(sop_model, "_stages", _root_then_slow)
    monkeypatch.setattr(sop_model, "CPSAT_PROBE_SHARE", 0.3)
    peers._worker("cpsat").wait_ready(None)  # started: its share goes to the search
    problem = SopProblem.load("ESC47")
    result = solve_sop_problem(problem, time_limit=1.2, cpsat=True)
    assert "by the rule" in result.info["cpsat"]["stopped"]
    assert result.bound is None or result.bound <= 1288.0
    if result.solution is not None:
        assert evaluate_order(problem, result.order) == pytest.approx(result.objective)
        assert result.objective >= 1288.0


def test_probe_rule_on_and_off_give_the_same_optimum(monkeypatch):
    """The real stages with the cut engine first and CP-SAT stopped at once (shares 0), and
    with neither rule, give the brute-force optimum with a feasible order."""
    problem = random_sop(8, 0.2, 3)
    optimum = _brute(problem)
    for share in (0.0, 2.0):
        monkeypatch.setattr(sop_model, "CUTS_FIRST_SHARE", share)
        monkeypatch.setattr(sop_model, "CPSAT_PROBE_SHARE", share)
        result = solve_sop_problem(problem, time_limit=5.0, ideal_cap=1, cpsat=True)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)


def test_cpsat_stays_off_when_the_dp_runs_alone_on_counted_ideals():
    """With cpsat=None, a 40-node SOP of few ideals (dense random precedence) is solved
    by the DP alone: CP-SAT is not started, the reason names the ideals, the memory guard
    does not count its worker, and the order is optimal (the forward-only DP agrees)."""
    from taopt.models import sop_dp

    problem = random_sop(40, 0.9, 3)
    ideals, capped = sop_dp.count_ideals(problem)
    assert not capped and ideals < 10_000
    result = solve_sop_problem(problem, time_limit=20)
    assert "ideals" in result.info["cpsat"] and result.info["cpsat"].startswith("off")
    assert result.status == OPTIMAL
    assert evaluate_order(problem, result.order) == result.objective
    again = sop_dp.solve_sop_dp(problem, beam_width=0, both=False)
    assert again.status == OPTIMAL and again.objective == result.objective
    off = sop_model._footprint(problem, {"time_limit": 20.0, "cpsat": False})[0]
    assert sop_model._footprint(problem, {"time_limit": 20.0, "cpsat": None})[0] == off
    forced = solve_sop_problem(problem, time_limit=20, cpsat=True)  # cpsat=True still runs it
    assert isinstance(forced.info["cpsat"], dict) and forced.objective == result.objective
