"""The fleet family (§6.2): data, scorer, readers, brute force and the certified exact method."""

from __future__ import annotations

import json
from pathlib import Path

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.errors import FeasibilityError, InstanceError
from taopt.fleet import FleetPlan, FleetProblem, schedule

ROOT = Path(__file__).resolve().parents[1]
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
