"""The fleet family (§6.2): data, scorer, readers, brute force and the certified exact method."""

from __future__ import annotations

import json

import networkx as nx
import numpy as np
import pytest
from conftest import ROOT

import taopt
from taopt.errors import FeasibilityError, InstanceError
from taopt.fleet import FleetPlan, FleetProblem, schedule

EXAMPLE = ROOT / "taopt/data/examples/fleet_problem.json"


def line(length: float = 100.0, stops: int = 2) -> nx.Graph:
    """A street path 0 - 1 - ... along the x axis, ``length`` apart."""
    g = nx.Graph()
    for a in range(stops - 1):
        g.add_edge(a, a + 1, length=length)
    return g


def two_stops(**kw):
    """Stops (0, 0) and (100, 0) joined by a 100 m street; customers given in ``kw``."""
    fields = dict(stops=[[0, 0], [100, 0]], graph=line(), depot=0, v_truck=10, v_drone=10)
    fields.update(kw)
    return FleetProblem(**fields)


# -- data ------------------------------------------------------------------------------------------
def test_example_round_trips_and_is_the_spec_fleet():
    """The shipped example loads, has 2 trucks x 2 drones, c = 2, a DAG, and saves back equal."""
    p = FleetProblem.load(EXAMPLE)
    assert (p.K, p.drones, p.capacity) == (2, (2, 2), 2)
    assert 8 <= p.n <= 12 and p.precedences
    assert FleetProblem.from_dict(json.loads(json.dumps(p.to_dict()))).to_dict() == p.to_dict()


def test_bad_input_names_the_item(tmp_path):
    """Constructor and loader errors name the offending item."""
    with pytest.raises(InstanceError, match=r"customer_stop\[0\] is None"):
        two_stops(customers=[[5, 5]], service=["both"])
    with pytest.raises(InstanceError, match=r"service\[1\] = 'boat'"):
        two_stops(customers=[[5, 5], [6, 6]], service=["drone", "boat"])
    with pytest.raises(InstanceError, match=r"precedence cycle"):
        two_stops(customers=[[5, 5], [6, 6]], precedences=[(0, 1), (1, 0)])
    with pytest.raises(InstanceError, match=r"drones\[1\] = -1"):
        two_stops(customers=[[5, 5]], drones=[1, -1])
    with pytest.raises(InstanceError, match="capacity = 0"):
        two_stops(customers=[[5, 5]], capacity=0)
    data = FleetProblem.load(EXAMPLE).to_dict()
    data["objective"] = "fastest"
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(InstanceError, match=r"bad.json: objective"):
        FleetProblem.load(bad)


def test_unservable_names_the_out_of_range_drone_customer():
    """A drone-only customer beyond half the range of every stop is reported unservable."""
    p = two_stops(customers=[[50, 10], [50, 400]], flight_range=300)
    assert p.unservable() == [1]
    assert two_stops(customers=[[50, 10]], drones=0).unservable() == [0]


# -- the scorer on hand-made plans ----------------------------------------------------------------
def test_sortie_of_two_customers_with_tau_and_truck_wait():
    """Launch at the depot, serve two customers (τ each), recover at stop 1 (τ): hand times."""
    p = two_stops(customers=[[0, 30], [100, 30]], capacity=2, service_time=2, flight_range=1e3)
    plan = FleetPlan([[0, 1]], [[]], [[[[0, [0, 1], 1]]]])
    sched = schedule(p, plan)
    # t0 = 3 + 2 = 5, t1 = 5 + 10 + 2 = 17, back at 17 + 3 = 20, truck at 10, R = 22
    assert sched.service.tolist() == [5.0, 17.0]
    assert sched.sorties[0][3:] == (0.0, 20.0, 22.0)
    assert taopt.evaluate(p, plan) == 17.0
    p_ret = p.replace(objective="return")
    assert taopt.evaluate(p_ret, plan) == 22.0 + 10.0  # leave stop 1 at 22, drive home


def test_precedence_across_trucks_makes_the_drone_wait():
    """r served by truck 1 at stop 1 (t = 10) precedes j, whose drone would arrive at 3: t_j = 10."""
    p = two_stops(
        customers=[[100, 0], [0, 30]],
        drones=[1, 0],
        service=["truck", "drone"],
        customer_stop=[1, None],
        precedences=[(0, 1)],
        flight_range=1e3,
    )
    plan = FleetPlan([[0], [0, 1]], [[], [(1, 0)]], [[[[0, [1], 0]]], []])
    sched = schedule(p, plan)
    assert sched.service.tolist() == [10.0, 10.0]
    assert sched.sorties[0][3:] == (0.0, 13.0, 13.0)


def test_deadlock_names_the_precedence_pair():
    """A drone must serve 1 then 0 in one sortie while (0, 1) is required: a named deadlock."""
    p = two_stops(customers=[[0, 30], [100, 30]], capacity=2, precedences=[(0, 1)])
    plan = FleetPlan([[0]], [[]], [[[[0, [1, 0], 0]]]])
    with pytest.raises(FeasibilityError, match=r"deadlocks: precedence pair\(s\) \(0, 1\)"):
        taopt.evaluate(p, plan)


@pytest.mark.parametrize(
    ("plan", "message"),
    [
        (FleetPlan([[0, 1]], [[]], [[[[0, [0], 1]]]]), r"customer 1 is never served"),
        (FleetPlan([[0, 1]], [[]], [[[[0, [0, 1, 0], 1]]]]), r"customer 0 is served twice"),
        (FleetPlan([[0, 1]], [[]], [[[[1, [0], 0], [1, [1], 1]]]]), r"recovered at position 0"),
        (FleetPlan([[0, 1]], [[]], [[[[0, [0], 1], [0, [1], 1]]]]), r"sortie 1 of drone \(0, 0\)"),
        (FleetPlan([[0, 1]], [[(0, 1)]], [[[[0, [0], 1]]]]), r"only be served by a drone"),
        (FleetPlan([[1, 0]], [[]], [[[[0, [0, 1], 1]]]]), r"start at the depot"),
        (FleetPlan([[0, 1]], [[]], [[[[0, [0, 1], 1]], []]]), r"carries 1 drones"),
    ],
)
def test_violations_are_named(plan, message):
    """Each structural violation raises a FeasibilityError naming the item."""
    p = two_stops(customers=[[0, 30], [100, 30]], capacity=3, flight_range=1e3)
    with pytest.raises(FeasibilityError, match=message):
        taopt.evaluate(p, plan)


def test_range_and_capacity_limits_are_named():
    """A sortie over the flight range or over c customers names the sortie and the limit."""
    p = two_stops(customers=[[0, 30], [100, 30]], capacity=1, flight_range=70)
    with pytest.raises(FeasibilityError, match=r"serves 2 customers; a sortie serves 1 to c = 1"):
        taopt.evaluate(p, FleetPlan([[0]], [[]], [[[[0, [0, 1], 0]]]]))
    with pytest.raises(
        FeasibilityError, match=r"sortie 1 of drone \(0, 0\): flies 208.806 .*> flight range 70"
    ):
        taopt.evaluate(p, FleetPlan([[0, 1]], [[]], [[[[0, [0], 0], [0, [1], 0]]]]))


def test_payload_round_trips_through_a_solution():
    """A fleet plan survives Solution.to_dict / from_dict."""
    plan = FleetPlan([[0, 1], [0]], [[(1, 2)], []], [[[[0, [0, 1], 1]]], [[], []]])
    sol = taopt.Solution(1.0, "feasible", plan, method="x")
    assert taopt.Solution.from_dict(json.loads(json.dumps(sol.to_dict()))).solution == plan


# -- readers ----------------------------------------------------------------------------------------
def test_delivery_reduction_scores_like_chapter_5():
    """Chapter 5's optimal plan of the Fig. 5.6 stand-in scores 1793.7145 as a fleet plan."""
    from taopt.delivery import example_instance
    from taopt.delivery.evaluate import evaluate_plan

    inst = example_instance(250.0)
    fleet = FleetProblem.from_delivery(inst)
    assert (fleet.K, fleet.D, fleet.capacity, fleet.objective) == (1, 1, 1, "last_service")
    plan = taopt.solve(inst, "NIA").solution
    fleet_plan = FleetPlan.from_delivery_plan(plan, inst.depot)
    assert taopt.evaluate(fleet, fleet_plan) == pytest.approx(evaluate_plan(inst, plan), rel=1e-12)


def test_tspd_reader_scores_the_published_solution():
    """uniform-1-n11's published operations, as a fleet plan, score its published optimum."""
    p = FleetProblem.from_tspd(ROOT / "taopt/data/tspd/uniform-1-n11.txt")
    assert (p.n, p.s, p.objective, p.v_drone) == (10, 11, "return", 2.0)
    route = [0, 9, 9, 3, 7, 2, 5, 0]
    truck = [(1, 8), (3, 2), (4, 6), (5, 1), (6, 4)]
    flights = [[0, [7], 1], [1, [5], 2], [2, [9], 4], [4, [0], 5], [5, [3], 7]]
    value = taopt.evaluate(p, FleetPlan([route], [truck], [[flights]]))
    assert value == pytest.approx(221.18876576478925, rel=1e-12)
    assert np.isinf(p.flight_range)


# -- exact methods against the brute force -------------------------------------------------------
FAST_TINY = [
    # (seed, n, K, D, c, precedence, objective, stops)
    (1, 3, 1, 1, 1, False, "return", 2),
    (1, 3, 1, 1, 2, True, "last_service", 2),
    (2, 3, 2, 1, 1, False, "last_service", 2),
    (2, 3, 2, 1, 2, True, "return", 2),
    (3, 3, 1, 1, 1, True, "return", 3),
    (4, 2, 1, 2, 2, True, "last_service", 3),
    (5, 2, 2, 2, 1, False, "return", 3),
]


@pytest.mark.parametrize("case", FAST_TINY)
def test_exact_equals_brute_force_on_tiny_instances(case):
    """taopt.solve(..., "exact") is optimal and equals the brute-force optimum."""
    from taopt.fleet.brute import brute_force, tiny_instance

    problem = tiny_instance(*case[:7], stops=case[7])
    value, plan, count = brute_force(problem)
    assert count > 0 and plan is not None
    solution = taopt.solve(problem, "exact")
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(value, rel=1e-9, abs=1e-9)
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)


@pytest.mark.parametrize("objective", ["return", "last_service"])
@pytest.mark.parametrize("trucks", [1, 2])
def test_operations_dp_equals_label_search(objective, trucks):
    """One drone per truck, c = 1, no precedence: the subset DP and the label search agree."""
    from taopt.fleet.brute import tiny_instance
    from taopt.models.fleet import solve_fleet

    problem = tiny_instance(11, 4, trucks, 1, 1, False, objective, stops=3)
    ops = solve_fleet(problem, algorithm="operations")
    search = solve_fleet(problem, algorithm="search")
    assert ops.info["algorithm"] == "operations" and search.info["algorithm"] == "search"
    assert ops.status == search.status == "optimal"
    assert ops.objective == pytest.approx(search.objective, rel=1e-9)


def test_chapter5_reduction_small_dag_instance():
    """The K = D = c = 1 reduction of a 4-customer dag instance: chapter 5's exact optimum, by
    the dispatched ideal DP and by the fleet label search."""
    from taopt.delivery import build_example_instance
    from taopt.models.fleet import solve_fleet

    inst = build_example_instance(seed=3, n=4)
    chapter5 = taopt.solve(inst, "exact")
    fleet = FleetProblem.from_delivery(inst)
    dispatched = taopt.solve(fleet, "exact")
    assert dispatched.info["algorithm"] == "ideal_dp" and dispatched.status == "optimal"
    assert dispatched.objective == pytest.approx(chapter5.objective, rel=1e-9)
    search = solve_fleet(fleet, algorithm="search")
    assert search.status == "optimal"
    assert search.objective == pytest.approx(chapter5.objective, rel=1e-9)


@pytest.mark.slow
def test_chapter5_reduction_of_the_fig_5_6_stand_in():
    """example_instance(250) as a fleet problem: chapter 5's optimum 1793.7145."""
    from taopt.delivery import example_instance

    solution = taopt.solve(FleetProblem.from_delivery(example_instance(250.0)), "exact")
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(1793.7145315257808, rel=1e-9)


@pytest.mark.parametrize("name", ["uniform-1-n5", "uniform-11-n6", "uniform-31-n8"])
def test_tspd_published_optimum(name):
    """The exact method equals the published TSP-D optimum (relative 1e-6)."""
    from taopt.fleet.tspd import TSPD_FOLDER, published_optimum

    path = TSPD_FOLDER / f"{name}.txt"
    solution = taopt.solve(FleetProblem.from_tspd(path), "exact")
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(published_optimum(path), rel=1e-6)


def test_infeasible_instance_is_proven_and_names_the_customer():
    """A drone-only customer out of range: status infeasible, the reason names it."""
    p = two_stops(customers=[[50, 10], [50, 400]], flight_range=300)
    solution = taopt.solve(p, "exact")
    assert solution.status == "infeasible"
    assert "customer 1" in solution.info["reason"]


def test_time_limit_returns_a_feasible_plan_and_a_proven_bound():
    """A tight wall-clock limit: status time_limit, a feasible incumbent, bound <= objective."""
    from taopt.fleet.instances import residential_fleet
    from taopt.models.fleet import solve_fleet

    problem = residential_fleet(6, 2, 2, 2, seed=1)
    solution = solve_fleet(problem, time_limit=0.3)
    assert solution.status in ("time_limit", "optimal")
    assert solution.bound <= solution.objective + 1e-9
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)


def test_size_guard_stops_like_a_time_limit():
    """max_labels reached: stopped_by "size", a feasible plan and a proven bound."""
    from taopt.fleet.instances import residential_fleet
    from taopt.models.fleet import solve_fleet

    problem = residential_fleet(5, 2, 2, 2, seed=2)
    solution = solve_fleet(problem, max_labels=200)
    assert solution.info["stopped_by"] == "size"
    assert solution.bound <= solution.objective


# -- slow: the whole sets --------------------------------------------------------------------------
def _tiny_grid() -> list[tuple]:
    import itertools

    cases = []
    for seed in range(10):
        for K, D, c in itertools.product((1, 2), (1, 2), (1, 2)):
            for prec in (False, True):
                for objective in ("last_service", "return"):
                    cases.append((100 + seed, 3, K, D, c, prec, objective, 3 if D == 1 else 2))
    return cases


@pytest.mark.slow
def test_exact_equals_brute_force_on_320_tiny_instances():
    """Every combination of K, D, c in {1, 2}, with and without precedence, both objectives,
    ten seeds: the exact method equals the brute force on all 320."""
    from taopt.fleet.brute import brute_force, tiny_instance

    checked = 0
    for case in _tiny_grid():
        problem = tiny_instance(*case[:7], stops=case[7])
        value, _, _ = brute_force(problem)
        solution = taopt.solve(problem, "exact")
        assert solution.status == "optimal", case
        assert solution.objective == pytest.approx(value, rel=1e-9, abs=1e-9), case
        checked += 1
    assert checked >= 300


@pytest.mark.slow
def test_all_80_tspd_instances_reach_the_published_optimum():
    """All 80 shipped TSP-D instances: exact equals the published optimum (relative 1e-6)."""
    from taopt.fleet.tspd import published_optimum, tspd_instances

    paths = tspd_instances()
    assert len(paths) == 80
    for path in paths:
        solution = taopt.solve(FleetProblem.from_tspd(path), "exact")
        assert solution.status == "optimal", path.name
        assert solution.objective == pytest.approx(published_optimum(path), rel=1e-6), path.name


@pytest.mark.parametrize("which", ["operations", "search", "split", "ideal_dp"])
def test_every_exact_algorithm_stops_on_a_tiny_limit_with_a_plan_and_a_bound(which):
    """time_limit = 0.01 s: status time_limit (never a raise), a feasible plan, bound <= f."""
    from taopt.delivery import example_instance
    from taopt.fleet.instances import residential_fleet
    from taopt.fleet.tspd import TSPD_FOLDER

    problem = {
        "operations": lambda: FleetProblem.from_tspd(TSPD_FOLDER / "uniform-1-n13.txt"),
        "search": lambda: residential_fleet(8, 1, 2, 2),
        "split": lambda: residential_fleet(8, 2, 2, 2),
        "ideal_dp": lambda: FleetProblem.from_delivery(example_instance(250.0)),
    }[which]()
    solution = taopt.solve(problem, "exact", time_limit=0.01)
    assert solution.info["algorithm"] == which
    assert solution.status == "time_limit" and solution.bound <= solution.objective
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)
