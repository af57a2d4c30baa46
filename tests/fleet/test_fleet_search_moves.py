"""The fleet searches' newer parts (issue 32): pinned drones and N6's re-pairing moves, N4's
sampled far moves, the early stop of a worse candidate, and 3P with open sorties.

Every move is decoded by :func:`taopt.heuristics.fleet.decode` (which rejects an order against
precedence) and re-scored by :func:`taopt.fleet.evaluate_fleet`; optima of the tiny instances
come from the family's certified ``"exact"`` (itself checked against brute force).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.fleet import FleetProblem, evaluate_fleet
from taopt.fleet.brute import tiny_instance
from taopt.fleet.instances import residential_fleet
from taopt.heuristics.fleet import DRONE, PINNED, TRUCK, decode, pinned
from taopt.heuristics.fleet_search import _Search, route_first
from taopt.runtime import Deadline


def _example() -> FleetProblem:
    return FleetProblem.load(Path(taopt.__file__).parent / "data/examples/fleet_problem.json")


def _search(problem: FleetProblem, open_sorties: bool = True) -> tuple[_Search, tuple]:
    """A search at its route-first start (the current decode set)."""
    search = _Search(problem, np.random.default_rng(0), Deadline(None), open_sorties=open_sorties)
    (order, trucks, modes), _, _ = route_first(search)
    search.set_current(order, trucks, modes)
    return search, (order, trucks, modes)


def test_pinned_mode_serves_by_that_drone():
    """Every customer pinned to drone 1 is served by drone 1's sorties, drone 0 idle; feasible."""
    p = residential_fleet(6, trucks=1, drones=2, capacity=2, seed=0)
    order = list(range(6))
    order.sort(key=lambda j: [j in {v for _, v in p.precedences}, j])  # roots first
    modes = np.full(6, PINNED + 1)
    for open_sorties in (False, True):
        builder = decode(
            p, order, np.zeros(6, dtype=np.int64), modes=modes, open_sorties=open_sorties
        )
        plan = builder.plan()
        assert plan.sorties[0][0] == ()
        assert sorted(j for s in plan.sorties[0][1] for j in s.customers) == list(range(6))
        assert evaluate_fleet(p, plan) == pytest.approx(builder.objective(), rel=1e-9)
        assert (builder.drone_of == 1).all()
    assert pinned(PINNED + 1) == 1 and pinned(DRONE) == -1 and pinned(TRUCK) == -1


def test_pinning_a_truck_only_customer_names_it():
    """A drone pinned for a customer only a truck may serve is an error naming the customer."""
    p = tiny_instance(3, n=3, trucks=1, drones=2, capacity=1)
    truck_only = [j for j in range(p.n) if not p.drone_servable(j)]
    if not truck_only:
        pytest.skip("no truck-only customer in this tiny instance")
    j = truck_only[0]
    modes = np.full(p.n, -1)
    modes[j] = PINNED
    with pytest.raises(InstanceError, match=f"customer {j}"):
        decode(p, list(range(p.n)), np.zeros(p.n, dtype=np.int64), modes=modes)


@pytest.mark.parametrize("open_sorties", [False, True])
def test_repair_moves_decode_feasibly_and_match_the_prefix_value(open_sorties):
    """Every N6 move on the example (2 trucks x 2 drones) and a one-truck, three-drone instance
    keeps precedence, decodes feasibly, and the search's prefix value equals a full decode."""
    for p in (_example(), residential_fleet(8, trucks=1, drones=3, capacity=2, seed=1)):
        search, (order, trucks, modes) = _search(p, open_sorties)
        assert search.repairs
        moves = search.repairs_of(order, trucks, modes, limit=10_000)
        assert moves
        assert any((m[2] >= PINNED).sum() == 2 and m[0] != order for m in moves)  # joins
        for new_order, new_trucks, new_modes in moves:
            builder = decode(p, new_order, new_trucks, modes=new_modes, open_sorties=open_sorties)
            assert evaluate_fleet(p, builder.plan()) == pytest.approx(builder.objective(), rel=1e-9)
            assert search.value(new_order, new_trucks, new_modes) == pytest.approx(
                builder.objective(), rel=1e-12
            )
            for j in np.flatnonzero(new_modes >= PINNED):
                assert builder.drone_of[j] == pinned(int(new_modes[j]))


def test_repair_moves_are_sampled_past_the_limit():
    """N6 builds at most ``limit`` moves."""
    p = residential_fleet(12, trucks=1, drones=2, capacity=2, seed=2)
    search, (order, trucks, modes) = _search(p)
    assert len(search.repairs_of(order, trucks, modes, limit=7)) <= 7


def test_repairs_idle_with_one_single_parcel_drone():
    """N6 is idle on a TSP-D instance (one drone, c = 1): its moves there are N4's."""
    from taopt.fleet.tspd import TSPD_FOLDER

    search, _ = _search(FleetProblem.from_tspd(TSPD_FOLDER / "uniform-3-n13.txt"), False)
    assert not search.repairs


def test_far_moves_are_sampled_past_the_limit():
    """N4 with a limit builds its near flips and at most ``limit`` far moves, each feasible."""
    p = _example()
    search, (order, trucks, modes) = _search(p, False)
    near = search.flips(order, trucks, modes)
    complete = search.flips(order, trucks, modes, far=True)
    sampled = search.flips(order, trucks, modes, far=True, limit=5)
    assert len(complete) > len(near) + 5
    assert len(near) < len(sampled) <= len(near) + 5
    for new_order, new_trucks, new_modes in sampled:
        builder = decode(p, new_order, new_trucks, modes=new_modes)
        assert evaluate_fleet(p, builder.plan()) == pytest.approx(builder.objective(), rel=1e-9)


def test_value_stops_early_only_above_the_bar():
    """value(above=bar) is the full value when that is below the bar, and >= bar otherwise."""
    p = residential_fleet(20, trucks=2, drones=2, capacity=2, seed=5)
    search, (order, trucks, modes) = _search(p)
    rng = np.random.default_rng(1)
    for _ in range(30):
        new_order = search.shift(order) or order
        moved = search.reassign(trucks, modes)
        new_trucks, new_modes = (trucks, modes) if moved is None else moved[1:]
        full = decode(p, new_order, new_trucks, modes=new_modes, open_sorties=True).objective()
        bar = full * float(rng.uniform(0.8, 1.2))
        got = search.value(new_order, new_trucks, new_modes, above=bar)
        if full < bar:
            assert got == pytest.approx(full, rel=1e-12)
        else:
            assert got >= bar


def test_three_phase_decodes_with_open_sorties_on_the_example():
    """3P under last_service (open sorties) beats its closed decoder's plan on the example at
    seed 0 after one pass (202.70 closed, 167.06 open), the plan feasible."""
    p = _example()
    closed = taopt.solve(p, "3P", seed=0, iterations=1, open_sorties=False)
    opened = taopt.solve(p, "3P", seed=0, iterations=1)
    assert opened.objective < closed.objective
    assert evaluate_fleet(p, opened.solution) == pytest.approx(opened.objective, rel=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_searches_never_below_the_optimum_with_two_drones(seed):
    """3P and ILS (iteration-bounded) on tiny one-truck, two-drone, c = 2 instances: feasible,
    never below the certified optimum, the same plan for the same seed."""
    p = tiny_instance(
        100 + seed, n=4, trucks=1, drones=2, capacity=2, precedence=bool(seed % 2), stops=3
    )
    if p.unservable():
        pytest.skip("unservable draw")
    exact = taopt.solve(p, "exact")
    assert exact.status == "optimal"
    optimum = exact.objective
    for method, options in (("3P", {"iterations": 2}), ("ILS", {"iterations": 3})):
        a = taopt.solve(p, method, seed=seed, **options)
        b = taopt.solve(p, method, seed=seed, **options)
        assert a.solution == b.solution
        assert evaluate_fleet(p, a.solution) == pytest.approx(a.objective, rel=1e-9)
        assert a.objective >= optimum * (1 - 1e-9)


def test_default_sample_is_capped():
    """The default sample is 2 n up to n = 32 and SAMPLE_CAP past it (a pass stays O(n^2))."""
    from taopt.heuristics.fleet_search import SAMPLE_CAP, default_sample

    assert default_sample(10) == 20
    assert default_sample(32) == 64 == SAMPLE_CAP
    assert default_sample(120) == SAMPLE_CAP
