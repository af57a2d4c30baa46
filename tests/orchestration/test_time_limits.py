"""Wall-clock time limits and size guards (issue 15 items 2, 6; docs/architecture.md, invariant 4).

Every exact method of every family, called through ``taopt.solve`` with a tiny ``time_limit``
on an instance large for it, returns (no exception) with status "time_limit" and a proven
bound not above the objective, or a certified optimum. The unit tests assert no wall-clock
time; that the calls *return on time* (T + 3 s, loosely: CI machines are noisy) and that
refusals are fast is checked by the ``timing`` group at the end of this file
(``pytest -m timing -n 0``, docs/architecture.md "Tests"); the precise figures are in
``benchmarks/bench_time_limits.py``.
"""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.result import OPTIMAL, TIME_LIMIT
from taopt.runtime import (
    DEFAULT_MAX_MEMORY_GB,
    MEMORY_ENV,
    MIN_SHARE,
    Deadline,
    check_footprint,
    check_memory,
    max_memory_gb,
)

LIMIT = 0.2
SLACK = 3.0


def euclidean(n: int, m: int = 3, seed: int = 0) -> taopt.AssignmentProblem:
    points = np.random.default_rng(seed).random((n + m, 2))
    cost = np.linalg.norm(points[:, None] - points[None], axis=-1)
    return taopt.AssignmentProblem(cost, n, name=f"euclid-{n}")


def delivery(n: int, seed: int = 7):
    """The residential example's generator with n customers."""
    from taopt.delivery import build_example_instance

    return build_example_instance(seed=seed, n=n)


@pytest.fixture(autouse=True, scope="module")
def imports_paid():
    """Import the methods (cvxpy, HiGHS: seconds on a loaded machine) before any clock runs,
    as a CLI or a study pays them once."""
    taopt.solve(euclidean(3), "exact")


def timed(problem, method: str, time_limit: float = LIMIT, **options):
    began = time.perf_counter()
    result = taopt.solve(problem, method, time_limit=time_limit, **options)
    return result, time.perf_counter() - began


def assert_contract(problem, result) -> None:
    """Status time_limit (or a proven optimum), a bound not above the objective (on time:
    :func:`test_limited_calls_return_on_time`)."""
    assert result.status in (TIME_LIMIT, OPTIMAL)
    assert result.bound is not None and math.isfinite(result.bound)
    assert result.bound <= result.objective + 1e-9 * max(1.0, abs(result.bound))
    if result.status == OPTIMAL:
        assert result.bound == pytest.approx(result.objective, rel=1e-6)
    if result.solution is None:
        assert result.objective == math.inf
    else:
        assert taopt.evaluate(problem, result) == pytest.approx(result.objective)


def run(problem, method: str, time_limit: float = LIMIT, **options):
    result, elapsed = timed(problem, method, time_limit, **options)
    assert_contract(problem, result)
    return result, elapsed


# -- the clock ---------------------------------------------------------------------------------


class StandInClock:
    """A ``time`` module whose ``perf_counter`` moves only when told (no wall-clock)."""

    def __init__(self) -> None:
        self.now = 100.0

    def perf_counter(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch) -> StandInClock:
    """The clock every Deadline reads, advanced by hand."""
    import taopt.runtime.deadline as deadline_module

    stand_in = StandInClock()
    monkeypatch.setattr(deadline_module, "time", stand_in)
    return stand_in


def test_deadline_counts_down_and_none_is_unlimited(clock):
    """A Deadline's remaining time shrinks to 0 and expires; None never expires."""
    d = Deadline(0.05)
    assert d.remaining() == pytest.approx(0.05) and not d.expired()
    clock.now += 0.03
    assert d.remaining() == pytest.approx(0.02) and not d.expired() and d.expired(margin=0.03)
    clock.now += 0.03
    assert d.remaining() == 0.0 and d.expired()
    unlimited = Deadline(None)
    clock.now += 1e6
    assert unlimited.remaining() is None and not unlimited.expired() and not unlimited.limited


def test_a_share_of_a_spent_deadline_is_still_a_valid_limit(clock):
    """Once the time is spent a share is MIN_SHARE, which every solver takes as a limit."""
    d = Deadline(0.01)
    assert d.share(0.5) == pytest.approx(0.005)
    clock.now += 0.02
    assert d.share(0.2) == MIN_SHARE > 0 and Deadline(None).share(0.5) is None


@pytest.mark.parametrize("time_limit", [0.001, 0.01, 0.05])
def test_budgeted_exact_under_a_spent_limit(time_limit):
    """The budgeted model's sub-solves get a positive share when the warm start and the
    bounds have used the whole limit (60 targets: it raised "time_limit must be positive,
    got 0.0" before)."""
    from taopt.budgeted import BudgetedProblem

    n, m = 60, 5
    cost = np.random.default_rng(103).uniform(0.0, 100.0, size=(n + m, n + m))
    problem = BudgetedProblem(cost, n, capacity=[15] * m, max_time=[900.0] * (m - 1) + [None])
    result, _ = timed(problem, "exact", time_limit)
    assert result.status in (TIME_LIMIT, OPTIMAL)
    if result.solution is not None:
        assert taopt.evaluate(problem, result) == pytest.approx(result.objective)
        assert result.bound is None or result.bound <= result.objective + 1e-9


def test_solve_rejects_a_bad_time_limit():
    """A zero, negative, boolean or infinite time_limit is an InstanceError."""
    p = euclidean(4)
    for bad in (0, -1.0, True, math.inf):
        with pytest.raises(InstanceError, match="time_limit"):
            taopt.solve(p, "MC", time_limit=bad)


# -- heuristics stop on their limit ------------------------------------------------------------


def test_mc_stops_on_its_limit_with_complete_routes():
    """MC under a tiny limit still returns every target once, scored by the one scorer."""
    p = euclidean(400, 2)
    result, _ = timed(p, "MC", time_limit=0.01)
    assert sorted(k for route in result.routes for k in route) == list(range(p.n))
    assert taopt.evaluate(p, result) == pytest.approx(result.objective)
    assert result.info.get("stopped_by") == "time_limit"
    unlimited = taopt.solve(p, "MC")
    assert "stopped_by" not in unlimited.info
    assert unlimited.objective <= result.objective + 1e-9  # the completion is a fallback


def test_simulation_stopped_by_its_limit_has_no_plan():
    """DAA stopped before every target is visited: status time_limit, objective inf, no plan."""
    from taopt.comm.problem import random_problem

    p = random_problem(300, 10, 3, 200.0, seed=0)
    result, _ = timed(p, "DAA", time_limit=0.001)
    assert result.status == TIME_LIMIT and result.objective == math.inf
    assert result.solution is None


# -- every exact method of every family --------------------------------------------------------


def test_assignment_exact_under_a_tiny_limit():
    """Routing (2.2)-(2.5) with 300 targets at T = 0.2: time_limit with a bound, warm-started."""
    result, _ = run(euclidean(300), "exact")
    assert result.info["warm_start"]["method"] == "MC"


def test_sop_exact_returns_a_bound_not_an_error(sop_esc25):
    """SOP exact on ESC25 at T = 0.2: time_limit with SMMA's order and a bound, no SolverError."""
    result, _ = run(sop_esc25, "exact")
    assert result.status == TIME_LIMIT and result.solution is not None


def test_sop_exact_without_incumbent_stops_with_a_bound(sop_esc47):
    """Without a warm start and with almost no time, SOP exact stops with a bound and either
    no plan (objective inf) or a feasible one, never a raise."""
    from taopt.sop.problem import evaluate_order

    problem = sop_esc47  # 2-5 s to prove: 10 ms cannot
    result, _ = run(problem, "exact", time_limit=0.01, incumbent=None)
    assert result.status == TIME_LIMIT and result.bound is not None
    if result.solution is None:
        assert result.objective == math.inf
    else:
        assert result.objective == pytest.approx(evaluate_order(problem, result.solution))


def test_delivery_milp_under_a_tiny_limit():
    """The delivery MILP on 20 customers at T = 0.2: time_limit, the incumbent and a bound."""
    run(delivery(20), "milp")


def test_delivery_exact_under_a_tiny_limit():
    """The ideal DP on 20 customers at T = 0.01: the incumbent and a bound, never a raise."""
    result, _ = run(delivery(20), "exact", time_limit=0.01)
    assert result.solution is not None


def test_delivery_dp_under_a_tiny_limit():
    """The subset DP on 14 customers (2^14 states) at T = 0.05 stops with the incumbent."""
    result, _ = run(delivery(14), "subset-dp", time_limit=0.05)
    assert result.status == TIME_LIMIT and result.solution is not None


def test_delivery_dp_refuses_too_many_customers():
    """Above max_customers the DP is refused by an InstanceError naming n and the limit."""
    with pytest.raises(InstanceError, match="n = 16 customers > max_customers = 14"):
        taopt.solve(delivery(16), "subset-dp")


@pytest.mark.parametrize("method", ["exact", "joint"])
def test_capability_exact_under_a_tiny_limit(method):
    """Chapter 3's corrected and joint models on 50 targets at T = 0.2."""
    from taopt.capability.instances import thesis_scenario

    run(thesis_scenario(50, 10, 3, 0).problem, method)


def test_comm_exact_under_a_tiny_limit():
    """Chapter 4's f_o on 300 targets at T = 0.2 (DAA's warm start is stopped too)."""
    from taopt.comm.problem import random_problem

    run(random_problem(300, 10, 3, 200.0, seed=0), "exact")


def test_failing_warm_start_is_skipped():
    """A warm-start heuristic that fails is skipped; the exact method still certifies."""
    from taopt.sop.problem import SopProblem

    cost = [
        [0, 3, 5, 9, -1],
        [-1, 0, 4, 6, -1],
        [-1, 2, 0, 3, 7],
        [-1, 4, 1, 0, 3],
        [2, -1, -1, -1, 0],
    ]
    cost = np.where(np.array(cost) == -1, np.inf, np.array(cost, dtype=float))
    p = SopProblem(cost, ((2, 1),), 0, 4)
    result = taopt.solve(p, "exact")
    assert result.status == OPTIMAL and result.objective == 16


# -- size guards -------------------------------------------------------------------------------


def test_memory_limit_from_option_environment_and_default(monkeypatch):
    """The limit is the option, else TAOPT_MAX_MEMORY_GB, else the documented default."""
    monkeypatch.delenv(MEMORY_ENV, raising=False)
    assert max_memory_gb() == DEFAULT_MAX_MEMORY_GB
    monkeypatch.setenv(MEMORY_ENV, "0.5")
    assert max_memory_gb() == 0.5 and max_memory_gb(8) == 8.0
    monkeypatch.setenv(MEMORY_ENV, "lots")
    with pytest.raises(InstanceError, match=MEMORY_ENV):
        max_memory_gb()
    with pytest.raises(InstanceError, match="positive"):
        check_memory(1.0, "x", max_memory_gb=0)


def test_large_assignment_exact_is_refused_fast(monkeypatch):
    """3,000 targets: the exact model is refused before building, naming size and limit."""
    from taopt.models.routing import compact, dfj

    p = euclidean(3000)

    def never(*args, **kwargs):  # refused fast: before anything is built or started
        raise AssertionError("the model was built before the size guard refused it")

    with monkeypatch.context() as patch:
        for module, name in [(dfj, "DfjModel"), (dfj, "HighsModel"), (compact, "build")]:
            patch.setattr(module, name, never)
        patch.setattr(compact, "HighsModel", never)
        with pytest.raises(InstanceError, match=r"3,000 targets.*GB.*limit of 4 GB"):
            taopt.solve(p, "exact", time_limit=30, max_memory_gb=4)
    check_footprint(p, "exact", max_memory_gb=math.inf)  # the override lifts the guard
    assert taopt.solve(p, "MC", time_limit=0.05, max_memory_gb=4).routes is not None


def test_instance_of_ten_thousand_targets_is_refused_fast(tmp_path, monkeypatch):
    """An instance file of 10,000 targets is refused before validation and navigation."""
    from taopt.orchestration.solving import load_problem_file

    monkeypatch.delenv(MEMORY_ENV, raising=False)
    data = {
        "schema_version": 1,
        "kind": "instance",
        "region": [0.0, 1000.0],
        "vehicles": [{"id": "v0", "start": [0.0, 0.0], "speed": 1.0, "capability": "any"}],
        "targets": [
            {"id": f"t{k}", "position": [float(k % 1000), float(k // 10)], "demands": ["any"]}
            for k in range(10_000)
        ],
    }
    path = tmp_path / "big.json"
    path.write_text(json.dumps(data))
    import taopt.orchestration.solving as solving

    def never(*args, **kwargs):  # validation and navigation must not start
        raise AssertionError("the instance was validated or navigated before being refused")

    monkeypatch.setattr(solving.Instance, "from_dict", never)
    monkeypatch.setattr(solving, "problem_from_instance", never)
    with pytest.raises(InstanceError, match=r"big.json.*10,000 targets.*limit of 4 GB"):
        load_problem_file(path, progress=False)


def test_matrix_of_numeric_strings_is_refused_fast(tmp_path):
    """A 400 x 400 cost matrix of numeric strings is refused in well under a second or two."""
    from taopt.orchestration.solving import load_problem_file

    n = 400
    cost = [[str(float(i + j)) for j in range(n)] for i in range(n)]
    path = tmp_path / "strings.json"
    data = {"schema_version": 1, "kind": "assignment_problem", "n_targets": n - 1, "cost": cost}
    path.write_text(json.dumps(data))
    with pytest.raises(InstanceError, match=r"strings.json.*cost\[0\]\[\d+\].*expected a number"):
        load_problem_file(path, progress=False)


@pytest.mark.parametrize("family", ["assignment", "sop", "delivery"])
def test_genetic_algorithms_stop_on_their_limit(family):
    """Each GA stops on a tiny time_limit with its best so far, feasible and scored."""
    from taopt.sop.problem import SopProblem

    problem = {
        "assignment": lambda: euclidean(200),
        "sop": lambda: SopProblem.load("ESC25"),
        "delivery": lambda: delivery(20),
    }[family]()
    result, _ = timed(problem, "GA", time_limit=0.05)
    assert taopt.evaluate(problem, result) == pytest.approx(result.objective)
    history = result.info["history"]
    full = 350 if family == "assignment" else 2000
    assert len(history) < full + 1  # stopped before the last generation


def test_sop_assignment_bound_is_valid_and_beats_the_tree_on_esc():
    """The assignment relaxation never exceeds the optimum of the shipped SOP files."""
    from taopt.models.sop import assignment_bound
    from taopt.sop.problem import KNOWN_OPTIMA, SopProblem, shipped_sop, sop_arborescence_bound

    for name in shipped_sop():
        p = SopProblem.load(name)
        bound = assignment_bound(p.cost, p.closure, p.start, p.end)
        assert 0 <= bound <= KNOWN_OPTIMA[name] + 1e-9
    esc = SopProblem.load("ESC25")
    assert assignment_bound(esc.cost, esc.closure, esc.start, esc.end) > sop_arborescence_bound(esc)


def test_sop_under_a_generous_limit_still_certifies():
    """With time to spare, the limited path (compiled apart, then solved) proves the optimum."""
    from taopt.sop.problem import KNOWN_OPTIMA, SopProblem

    for name in ("ESC07", "ESC11", "ESC12"):
        result = taopt.solve(SopProblem.load(name), "exact", time_limit=60)
        assert result.status == OPTIMAL and result.objective == KNOWN_OPTIMA[name]


# -- issue 30 item 4: the clock is looked at inside the memetic steps too -----------------------


class ExpiresAfter:
    """A stand-in Deadline that is limited and expires after ``checks`` queries (no clock):
    it tells which steps look at the deadline, whatever the machine's speed."""

    def __init__(self, checks: int) -> None:
        self.checks, self.asked = checks, 0
        self.limited, self.seconds = True, 1.0

    def expired(self, margin: float = 0.0) -> bool:
        self.asked += 1
        return self.asked > self.checks

    def remaining(self) -> float:
        return 0.0 if self.asked >= self.checks else 1.0

    def elapsed(self) -> float:
        return 0.0


def test_local_searches_stop_at_an_expired_deadline():
    """Each memetic descent makes no move once its deadline has expired (and some without)."""
    from taopt.budgeted import BudgetedProblem
    from taopt.heuristics.budgeted import LimitedDescent
    from taopt.heuristics.ga_local_search import local_search
    from taopt.heuristics.ga_penalised_search import PenalisedSearch
    from taopt.heuristics.ga_routing import decode, path_matrix, path_nodes

    problem = euclidean(40, 3, seed=4)
    genes = np.random.default_rng(1).permutation(problem.n + problem.m - 1)
    matrix, path = path_matrix(problem), path_nodes(problem, genes)[0]
    spent = Deadline(1e-9)
    assert local_search(matrix, path, deadline=spent)[1] == 0 < local_search(matrix, path)[1]
    budgeted = BudgetedProblem(problem.cost, problem.n, capacity=[20, 20, 20])
    search = PenalisedSearch(budgeted, 1.0, 0.1)
    assert search.run(matrix, path, deadline=spent)[1] == 0 < search.run(matrix, path)[1]
    routes = decode(problem, genes, "vehicle")
    descent = LimitedDescent(budgeted)
    assert descent.run(routes, deadline=spent)[1] == 0 < descent.run(routes)[1]


@pytest.mark.parametrize("family", ["assignment", "budgeted"])
def test_memetic_step_looks_at_the_deadline(family, monkeypatch):
    """A deadline that expires once the first generation has begun stops the GA inside that
    generation's local search (no move made, one generation, the best so far, scored): a
    generation's polish on n = 200 took 15 s past a 1 s limit under load before."""
    from taopt.budgeted import BudgetedProblem
    from taopt.heuristics import ga_routing
    from taopt.heuristics.budgeted import ga as budgeted

    problem = euclidean(60, 3, seed=2)
    module, ga = ga_routing, ga_routing.genetic_algorithm
    if family == "budgeted":
        problem = BudgetedProblem(problem.cost, problem.n, capacity=[25, 25, 25])
        module, ga = budgeted, budgeted.genetic_algorithm
    monkeypatch.setattr(module, "Deadline", lambda seconds: ExpiresAfter(1))
    result = ga(problem, seed=0, time_limit=1.0)
    assert result.info["generations_done"] == 1 and result.info["stopped_by"] == "time_limit"
    assert result.info["moves"] == 0
    assert taopt.evaluate(problem, result.solution) == pytest.approx(result.objective)


def test_delivery_milp_with_a_spent_limit_builds_nothing():
    """Given a limit already spent, the delivery MILP returns the incumbent with status
    time_limit and a valid bound without building its model (it built it before)."""
    from taopt.heuristics.sequencing import smma_delivery
    from taopt.models.delivery import solve_delivery

    instance = delivery(12)
    incumbent = smma_delivery(instance)
    result = solve_delivery(instance, time_limit=1e-9, incumbent=incumbent.solution)
    assert result.info["model"] == "not built"
    assert result.status == TIME_LIMIT and result.objective == pytest.approx(incumbent.objective)
    assert result.bound is not None and result.bound <= result.objective


def test_delivery_milp_skips_a_compile_that_cannot_fit(monkeypatch):
    """The compile-and-presolve estimate follows the build's measured time (so it grows with
    the machine's load): when it exceeds what is left, HiGHS is not started and the answer is
    the incumbent with a bound (a 1 s limit took 2.4 s under load before)."""
    from taopt.models import delivery as model

    monkeypatch.setattr(model, "COMPILE_PER_BUILD_PER_CUSTOMER", 1e9)
    instance = delivery(10)
    result = taopt.solve(instance, "milp", time_limit=60.0)
    assert result.info["model"] == "built, not compiled" and result.info["estimate"] > 60
    assert result.status == TIME_LIMIT and result.solution is not None
    assert taopt.evaluate(instance, result) == pytest.approx(result.objective)
    assert result.bound is not None and result.bound <= result.objective


def test_budgeted_warm_start_and_starts_keep_to_a_spent_limit(monkeypatch):
    """Budgeted EVM (the exact model's warm start) stops at its limit with the targets not yet
    placed reported (no_solution), and the exact model builds no further start once its limit
    is spent (n = 100 at T = 0.5 took 1.5 s under load: EVM and the repair ignored the clock)."""
    from taopt.budgeted import BudgetedProblem
    from taopt.heuristics.budgeted import evm
    from taopt.models.budgeted import solve as model

    problem = BudgetedProblem(euclidean(30, 3).cost, 30, capacity=[12, 12, 12])
    stopped = evm(problem, time_limit=1e-9)
    assert stopped.status == "no_solution" and stopped.info["stopped_by"] == "time_limit"
    assert stopped.info["unassigned"] == 30 and math.isinf(stopped.objective)
    assert evm(problem).status == "feasible"  # without a limit it places them all

    def never(*args, **kwargs):
        raise AssertionError("a start was built after the limit")

    monkeypatch.setattr(model, "greedy_budgeted", never)
    monkeypatch.setattr(model, "repaired_routes", never)
    result = model.solve_budgeted(problem, time_limit=1e-9)
    assert result.status == TIME_LIMIT and result.bound is not None


def test_sop_portfolio_skips_a_second_stage_it_cannot_set_up(monkeypatch, sop_esc47):
    """The SOP portfolio starts its second DP stage only when its share covers twice the first
    stage's measured setup (ESC47 at T = 0.5 took 2 s under load: each stage's setup is
    outside the DP's clock); the answer still carries the first stage's order and bound."""
    from taopt.models import sop_dp

    real, calls = sop_dp.solve_sop_dp, []

    def first_stage_slow_to_set_up(problem, time_limit=None, **options):
        calls.append(options)
        result = real(problem, 1e-3, **options)
        return result.replace(info={**result.info, "setup_seconds": 1e6})

    monkeypatch.setattr(sop_dp, "solve_sop_dp", first_stage_slow_to_set_up)
    problem = sop_esc47
    result = taopt.solve(problem, "exact", time_limit=1.0)
    assert len(calls) == 1 and result.info["second_stage"].startswith("skipped")
    assert result.status == TIME_LIMIT and result.bound <= result.objective
    assert taopt.evaluate(problem, result) == pytest.approx(result.objective)


def test_sop_portfolio_without_the_milp_skips_a_dp_stage_it_cannot_set_up(monkeypatch, sop_esc47):
    """Above the memory limit (no MILP) the portfolio's extra DP stage is not started either
    when the time left is under twice the measured setup: one DP run, its order and bound."""
    from taopt.models import sop_dp

    real, calls = sop_dp.solve_sop_dp, []

    def first_stage_slow_to_set_up(problem, time_limit=None, **options):
        calls.append(options)
        result = real(problem, 1e-3, **options)
        return result.replace(info={**result.info, "setup_seconds": 1e6})

    from taopt.models.sop import BASE_BYTES, dp_bytes

    monkeypatch.setattr(sop_dp, "solve_sop_dp", first_stage_slow_to_set_up)
    problem = sop_esc47
    room_for_the_dp = (BASE_BYTES + dp_bytes(problem.n, 50_000)) / 1e9  # not for the MILP
    result = taopt.solve(problem, "exact", time_limit=1.0, max_memory_gb=room_for_the_dp)
    assert result.info["memory_plan"] == "dp" and result.info["milp"].startswith("skipped")
    assert len(calls) == 1 and result.info["more_dp"].startswith("skipped")
    assert result.status == TIME_LIMIT and result.bound <= result.objective
    assert taopt.evaluate(problem, result) == pytest.approx(result.objective)


def test_delivery_milp_limited_runs_leave_out_the_clockless_highs_phases(monkeypatch):
    """A time-limited delivery MILP asks HiGHS for no probing and no restart (both ignore
    its clock: 6 s took up to 13 s); the answer is still certified on a small instance."""
    from taopt.models import delivery as model

    seen = []
    real = model.HighsModel.solve

    def recording(self, time_limit=None, mip_rel_gap=None, on_solution=None, options=None, **kw):
        seen.append(dict(options or {}))
        return real(self, time_limit, mip_rel_gap, on_solution, options, **kw)

    monkeypatch.setattr(model.HighsModel, "solve", recording)
    instance = delivery(6)
    result = taopt.solve(instance, "milp", time_limit=60.0)
    assert seen and all(
        o["presolve_rule_off"] == 2**15 and o["mip_allow_restart"] is False for o in seen
    )
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(taopt.solve(instance, "exact").objective)


def test_sop_portfolio_starts_no_dp_stage_it_cannot_set_up(monkeypatch, sop_esc47):
    """The portfolio starts a DP stage only when its share covers the ideal count just
    measured (a stage sets up about as long, outside its clock: under load ESC47 at T = 1
    took 2.8 s); otherwise it answers at once with the warm start's order and a bound."""
    from taopt.models import sop as model

    monkeypatch.setattr(model, "DP_SHARE", 1e-9)  # a first stage's share below any count
    problem = sop_esc47
    result = taopt.solve(problem, "exact", time_limit=2.0)
    assert result.info["model"] == "not run" and result.info["engine"] == "none"
    assert result.status == TIME_LIMIT and result.bound <= result.objective
    assert taopt.evaluate(problem, result) == pytest.approx(result.objective)


def test_limited_mip_runs_leave_out_highs_clockless_phases():
    """Every time-limited MIP run of a HighsModel (all exact models) turns off HiGHS's probing
    and restarts, which ignore its clock (the budgeted model's 5 s took 6.3 s, routing's
    5.7 s); a run without a limit turns them back on."""
    import cvxpy as cp

    from taopt.models.highs import CLOCKLESS_MIP_PHASES, HighsModel

    x = cp.Variable(3, integer=True)
    model = HighsModel(cp.Problem(cp.Minimize(cp.sum(x)), [x >= 0.5, x[0] + x[1] >= 3]))

    def phases():
        return {name: model.highs.getOptionValue(name)[1] for name in CLOCKLESS_MIP_PHASES}

    assert model.solve(time_limit=10.0).objective == 4.0
    assert phases() == {"presolve_rule_off": 2**15, "mip_allow_restart": False}
    assert model.solve().objective == 4.0
    assert phases() == {"presolve_rule_off": 0, "mip_allow_restart": True}


def test_ideal_count_under_a_deadline_stops_early_and_stays_a_lower_bound():
    """count_ideals with a deadline returns "capped" with a lower bound on the count, either
    because the deadline passed or because a layer's candidates prove the cap is passed
    (each ideal has at most as many parents as removable nodes), never above the true count."""
    from taopt.models.sop_dp import count_ideals

    n = 16
    cost = np.random.default_rng(5).integers(1, 40, (n, n)).astype(float)
    problem = taopt.SopProblem(cost, ((1, 2), (3, 4), (5, 6)), 0, n - 1)
    exact, capped = count_ideals(problem, cap=10**6)
    assert not capped and exact > 1000
    for deadline in (Deadline(1e-9), Deadline(60.0)):
        found, capped = count_ideals(problem, cap=1000, deadline=deadline)
        assert capped and found <= exact
    assert count_ideals(problem, cap=1000, deadline=Deadline(60.0))[0] > 1000
    assert count_ideals(problem, cap=1000) == (count_ideals(problem, cap=1000)[0], True)


# -- on time: the timing group (pytest -m timing -n 0; docs/architecture.md "Tests") -----------


def _budgeted_60():
    from taopt.budgeted import BudgetedProblem

    n, m = 60, 5
    cost = np.random.default_rng(103).uniform(0.0, 100.0, size=(n + m, n + m))
    return BudgetedProblem(cost, n, capacity=[15] * m, max_time=[900.0] * (m - 1) + [None])


def _esc(name: str):
    from taopt.sop.problem import SopProblem

    return SopProblem.load(name)


def _capability_50():
    from taopt.capability.instances import thesis_scenario

    return thesis_scenario(50, 10, 3, 0).problem


def _comm(n: int):
    from taopt.comm.problem import random_problem

    return random_problem(n, 10, 3, 200.0, seed=0)


#: (problem, method, time_limit, options): every limited call of the unit tests above.
ON_TIME = {
    "budgeted-exact-0.001": (_budgeted_60, "exact", 0.001, {}),
    "budgeted-exact-0.01": (_budgeted_60, "exact", 0.01, {}),
    "budgeted-exact-0.05": (_budgeted_60, "exact", 0.05, {}),
    "assignment-MC": (lambda: euclidean(400, 2), "MC", 0.01, {}),
    "comm-DAA": (lambda: _comm(300), "DAA", 0.001, {}),
    "assignment-exact": (lambda: euclidean(300), "exact", LIMIT, {}),
    "sop-exact": (lambda: _esc("ESC25"), "exact", LIMIT, {}),
    "sop-exact-cold": (lambda: _esc("ESC47"), "exact", 0.01, {"incumbent": None}),
    "delivery-milp": (lambda: delivery(20), "milp", LIMIT, {}),
    "delivery-exact": (lambda: delivery(20), "exact", 0.01, {}),
    "delivery-subset-dp": (lambda: delivery(14), "subset-dp", 0.05, {}),
    "capability-exact": (_capability_50, "exact", LIMIT, {}),
    "capability-joint": (_capability_50, "joint", LIMIT, {}),
    "comm-exact": (lambda: _comm(300), "exact", LIMIT, {}),
    "assignment-GA": (lambda: euclidean(200), "GA", 0.05, {}),
    "sop-GA": (lambda: _esc("ESC25"), "GA", 0.05, {}),
    "delivery-GA": (lambda: delivery(20), "GA", 0.05, {}),
}


@pytest.mark.timing
@pytest.mark.parametrize("case", list(ON_TIME))
def test_limited_calls_return_on_time(case):
    """Each limited call of this file returns within T + SLACK of wall-clock time."""
    build, method, time_limit, options = ON_TIME[case]
    problem = build()
    _, elapsed = timed(problem, method, time_limit, **options)
    assert elapsed < time_limit + SLACK, f"{case}: {elapsed:.2f} s"


@pytest.mark.timing
def test_large_assignment_is_refused_within_two_seconds():
    """3,000 targets: the exact model's refusal takes under 2 s (nothing is built)."""
    p = euclidean(3000)
    began = time.perf_counter()
    with pytest.raises(InstanceError, match=r"3,000 targets"):
        taopt.solve(p, "exact", time_limit=30, max_memory_gb=4)
    assert time.perf_counter() - began < 2.0


@pytest.mark.timing
def test_matrix_of_numeric_strings_is_refused_within_three_seconds(tmp_path):
    """A 400 x 400 cost matrix of numeric strings is refused in under 3 s."""
    from taopt.orchestration.solving import load_problem_file

    n = 400
    cost = [[str(float(i + j)) for j in range(n)] for i in range(n)]
    path = tmp_path / "strings.json"
    data = {"schema_version": 1, "kind": "assignment_problem", "n_targets": n - 1, "cost": cost}
    path.write_text(json.dumps(data))
    began = time.perf_counter()
    with pytest.raises(InstanceError, match="expected a number"):
        load_problem_file(path, progress=False)
    assert time.perf_counter() - began < 3.0


def test_first_solve_imports_its_methods_on_its_own_clock():
    """Reaching ``taopt.solve`` imports no method package: a first call imports them after its
    deadline starts (they took 1.6-2.2 s, past the limit), and the call still finds them."""
    import subprocess
    import sys

    code = (
        "import sys, taopt\n"
        "solve = taopt.solve\n"
        "print(sorted(m for m in ('taopt.models', 'taopt.heuristics') if m in sys.modules))\n"
        "import numpy as np\n"
        "p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), n_targets=2)\n"
        "print(solve(p, 'exact', time_limit=30).objective)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["[]", "4.0"]
