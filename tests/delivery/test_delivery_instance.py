"""DeliveryInstance validation, JSON round trip, and the evaluator's constraint checks."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.delivery.evaluate import evaluate_plan, timeline
from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.errors import FeasibilityError, InstanceError

CUSTOMERS = [[10.0, 10.0], [50.0, 60.0], [90.0, 20.0]]


def small(**changes):
    """3 customers on a 3x3 grid over [0, 100]^2 (50 m streets), unit speeds, L = 100."""
    base = DeliveryInstance.grid(CUSTOMERS, 3, 100, 1.0, 1.0, 100, precedences=[(2, 0)])
    return base.replace(**changes) if changes else base


def test_grid_layout():
    inst = small()
    assert (inst.n, inst.s, inst.depot) == (3, 9, 0)
    assert inst.stops[1].tolist() == [50.0, 0.0] and inst.stops[3].tolist() == [0.0, 50.0]
    assert inst.truck_distance[0, 8] == pytest.approx(200.0)  # Manhattan on the grid
    assert inst.flight_distance[0, 0] == pytest.approx(np.hypot(10, 10))
    assert list(inst.precedence_graph.edges) == [(2, 0)]


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"precedences": [(0, 1), (1, 2), (2, 0)]}, r"precedence cycle 0 -> 1 -> 2 -> 0"),
        ({"precedences": [(1, 1)]}, r"customer 1 cannot precede itself"),
        ({"precedences": [(0, 5)]}, r"precedence \(0, 5\) = 5 is not a customer"),
        ({"flight_range": 25.0}, r"customer 0 cannot be served: its nearest stop 0 is 14.1421"),
        ({"depot": 9}, r"depot = 9 is not a stop"),
        ({"v_drone": -1.0}, r"v_drone = -1.0 must be > 0"),
        ({"v_truck": float("nan")}, r"v_truck = nan is not finite"),
        ({"service_time": -2}, r"service_time = -2.0 must be >= 0"),
        ({"customers": [[0, 0], [np.nan, 1]]}, r"customers\[1\] = \[nan, 1.0\] is not finite"),
        ({"customers": np.zeros((0, 2))}, r"at least one customer"),
    ],
)
def test_bad_input_is_named(changes, message):
    with pytest.raises(InstanceError, match=message):
        small(**changes)


def test_disconnected_network_and_bad_edges():
    base = small()
    graph = nx.Graph(base.graph)
    graph.remove_edges_from([(7, 8), (5, 8)])  # stop 8 cut off
    with pytest.raises(InstanceError, match=r"disconnected.*stop 8"):
        base.replace(graph=graph)
    graph = nx.Graph(base.graph)
    graph.edges[0, 1]["length"] = -3.0
    with pytest.raises(InstanceError, match=r"edge \(0, 1\) length = -3.0"):
        base.replace(graph=graph)
    graph = nx.Graph(base.graph)
    del graph.edges[0, 1]["length"]
    with pytest.raises(InstanceError, match=r"edge \(0, 1\) has no 'length'"):
        base.replace(graph=graph)
    graph = nx.Graph(base.graph)
    graph.add_edge(8, 12, length=1.0)
    with pytest.raises(InstanceError, match=r"12 is not a stop"):
        base.replace(graph=graph)


def test_street_shorter_than_straight_line_is_refused():
    """A Python-built street shorter than the straight line between its stops is named, with
    both lengths; equal to it (within 1e-9 relative) is fine."""
    base = small()
    graph = nx.Graph(base.graph)
    graph.edges[0, 1]["length"] = 49.0  # stops 0 and 1 are 50 m apart
    with pytest.raises(InstanceError, match=r"street edge \(0, 1\) has length 49, .* line 50 "):
        base.replace(graph=graph)
    graph.edges[0, 1]["length"] = 50.0 * (1 - 1e-12)
    assert base.replace(graph=graph).truck_distance[0, 1] == pytest.approx(50.0)
    stops = base.stops.copy()
    stops[4] = [5000.0, 50.0]  # the centre stop moved 5 km away from its 50 m streets
    with pytest.raises(InstanceError, match=r"street edge \(1, 4\) .* shorter than the straight"):
        base.replace(stops=stops)


def test_immutable_and_validated_copies():
    inst = small()
    with pytest.raises(ValueError):
        inst.truck_time[0, 1] = 5.0
    with pytest.raises(ValueError):
        inst.customers[0, 0] = 5.0
    with pytest.raises(nx.NetworkXError):
        inst.graph.add_edge(0, 8, length=1.0)
    with pytest.raises(AttributeError):
        inst.flight_range = 3.0
    longer = inst.replace(flight_range=300.0)
    assert longer.flight_range == 300.0 and inst.flight_range == 100.0


def test_json_round_trip(tmp_path):
    inst = small(service_time=30.0, name="three")
    path = tmp_path / "inst.json"
    inst.save(path)
    back = DeliveryInstance.load(path)
    assert back.to_dict() == inst.to_dict()
    assert np.array_equal(back.truck_time, inst.truck_time)
    plan = taopt.schedule(inst, [1, 2, 0]).plan
    assert evaluate_plan(back, plan) == evaluate_plan(inst, plan)
    with pytest.raises(InstanceError, match="schema_version"):
        DeliveryInstance.from_dict({**inst.to_dict(), "schema_version": 7})


def test_evaluate_names_each_violated_constraint():
    inst = small()
    good = taopt.schedule(inst, [2, 0, 1]).plan
    assert taopt.evaluate(inst, good) == pytest.approx(evaluate_plan(inst, good))
    cases = [
        (Plan((2, 0), good.launch[:2], good.landing[:2]), r"\(5.2\) customer 1 is never served"),
        (Plan((2, 0, 0), good.launch, good.landing), r"\(5.2\) customer 0 is served 2 times"),
        (Plan((2, 0, 1), good.launch, (9,) + good.landing[1:]), r"landing stop 9 is not a stop"),
        (Plan((2, 0, 1), (0, 0, 0), (8, 8, 8)), r"\(5.6\) sortie 0 to customer 2"),
        (Plan((0, 2, 1), good.launch, good.landing), r"\(5.7\) precedence \(2, 0\)"),
    ]
    for plan, message in cases:
        with pytest.raises(FeasibilityError, match=message):
            evaluate_plan(inst, plan)
    with pytest.raises(FeasibilityError, match="plan has 2 customers"):
        Plan((1, 2), (0,), (0, 1))


def test_timeline_semantics_by_hand():
    """One customer at (0, 100), stops of a 2x2 grid; drone 10 m/s, truck 5 m/s, τ = 3 s."""
    inst = DeliveryInstance.grid([[0, 100]], 2, 100, 10.0, 5.0, 150, service_time=3.0)
    # launch at the depot, fly 100 m (10 s) + τ: served at 13; truck drives 0 -> 2 (20 s)
    line = timeline(inst, Plan((0,), (0,), (2,)))
    assert line.service_time.tolist() == [13.0]
    assert line.recovery_time.tolist() == [23.0]  # max(13 + 0, 20) + 3
    assert line.makespan == 13.0
    # drive first, then a zero-length sortie: 20 + 0 + 3
    assert evaluate_plan(inst, Plan((0,), (2,), (2,))) == 23.0
