"""The fleet family's heuristics (NIA, MMA, SMMA, 3P, ILS), its lower bound and teaching MILP.

Optima come from the certified ``"exact"`` method (itself checked against brute force in
``tests/fleet/test_fleet*.py``) and, for a few, from :func:`taopt.fleet.brute.brute_force` directly.
"""

from __future__ import annotations

import math

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.delivery import example_instance
from taopt.fleet import FleetProblem, evaluate_fleet
from taopt.fleet.bounds import chapter5_bound, fleet_lower, reach_bound, work_bound
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.instances import residential_fleet
from taopt.heuristics.fleet import construct, decode
from taopt.heuristics.fleet_search import truck_routes

HEURISTICS = {
    "NIA": {},
    "MMA": {},
    "SMMA": {},
    "3P": {"iterations": 2, "sample": 10},
    "ILS": {"iterations": 3, "sample": 10},
}


def _tiny(seed: int) -> FleetProblem:
    """Tiny instance ``seed``: n 2–4, K 1–2, D 1–2, c 1–2, precedence on 2 of 3, both objectives."""
    return tiny_instance(
        seed,
        n=2 + seed % 3,
        trucks=1 + seed % 2,
        drones=1 + (seed // 2) % 2,
        capacity=1 + (seed // 4) % 2,
        precedence=bool(seed % 3),
        objective="return" if seed % 5 == 0 else "last_service",
        stops=3,
    )


TINY = [p for p in (_tiny(seed) for seed in range(24)) if not p.unservable()]


@pytest.fixture(scope="module")
def optima() -> dict[str, float]:
    """Certified optima of the tiny instances by the family's exact method."""
    out = {}
    for p in TINY:
        s = taopt.solve(p, "exact")
        assert s.status == "optimal"
        out[p.name] = s.objective
    return out


@pytest.mark.parametrize("method", sorted(HEURISTICS))
def test_heuristics_feasible_and_never_below_the_optimum(method, optima):
    """Every heuristic's plan is feasible (re-scored by evaluate) and >= the certified optimum."""
    for p in TINY:
        s = taopt.solve(p, method, **HEURISTICS[method])
        assert s.status == "feasible"
        assert evaluate_fleet(p, s.solution) == pytest.approx(s.objective, rel=1e-9)
        assert s.objective >= optima[p.name] * (1 - 1e-9), p.name


def test_builder_times_are_the_earliest_schedule():
    """The builder's own objective equals evaluate's on every rule and many instances."""
    for seed in range(60):
        p = tiny_instance(
            seed,
            n=2 + seed % 5,
            trucks=1 + seed % 3,
            drones=seed % 3,
            capacity=1 + seed % 3,
            precedence=bool(seed % 2),
            objective="return" if seed % 4 == 0 else "last_service",
            stops=4,
        )
        if p.unservable():
            continue
        for rule in ("NIA", "MMA", "SMMA"):
            b = construct(p, rule)
            assert evaluate_fleet(p, b.plan()) == pytest.approx(b.objective(), rel=1e-9), (
                seed,
                rule,
            )


def test_heuristics_match_brute_force_bound_on_two_customers():
    """On n = 2 instances every heuristic is >= brute force's optimum and the bound <= it."""
    for seed in (0, 3, 6, 9):
        p = tiny_instance(seed, n=2, trucks=1, drones=1, capacity=2, precedence=True, stops=3)
        value, _, _ = brute_force(p)
        assert fleet_lower(p) <= value * (1 + 1e-9)
        for method, options in HEURISTICS.items():
            assert taopt.solve(p, method, **options).objective >= value * (1 - 1e-9)


def test_lower_bound_never_above_the_optimum(optima):
    """taopt.lower (reach, return reach, work, chapter 5's) <= the certified optimum; >= reach."""
    for p in TINY:
        lb = taopt.lower(p)
        assert reach_bound(p) <= lb <= optima[p.name] * (1 + 1e-9), p.name
        assert work_bound(p) <= lb


def test_lower_bound_on_chapter5_reduction():
    """The K = D = c = 1 reduction of the Fig. 5.6 stand-in: the bound is at least chapter 5's
    own and at most chapter 5's optimum 1793.7145."""
    instance = example_instance(250.0)
    p = FleetProblem.from_delivery(instance)
    own = chapter5_bound(p, "fast")
    assert own == pytest.approx(taopt.lower(instance, "fast"))
    assert max(own, fleet_lower(p, "fast")) <= 1793.7145 + 1e-3
    assert chapter5_bound(p.replace(capacity=2), "fast") == 0.0  # not chapter 5's shape


def test_same_seed_same_result():
    """3P and ILS: the same seed gives the same plan and objective."""
    p = residential_fleet(12, trucks=2, drones=2, capacity=2, seed=3)
    for method in ("3P", "ILS"):
        options = HEURISTICS[method]
        a = taopt.solve(p, method, seed=5, **options)
        b = taopt.solve(p, method, seed=5, **options)
        assert a.objective == b.objective
        assert a.solution == b.solution


def test_ils_never_worse_than_its_start():
    """ILS returns a plan no worse than the better of MMA and SMMA."""
    p = residential_fleet(15, trucks=2, drones=2, capacity=2, seed=4)
    start = min(taopt.solve(p, m).objective for m in ("MMA", "SMMA"))
    s = taopt.solve(p, "ILS", iterations=3, sample=10)
    assert s.objective <= start * (1 + 1e-12)
    # <=: under last_service ILS decodes the rules' encodings with open sorties too
    assert s.info["start_objective"] <= start * (1 + 1e-12)


def test_truck_routes_respect_precedence_and_servers():
    """3P's phase 1: a topological order, each customer on a truck able to serve it."""
    p = residential_fleet(20, trucks=3, drones=1, capacity=2, seed=2).replace(drones=[1, 0, 1])
    order, trucks = truck_routes(p)
    position = {j: i for i, j in enumerate(order)}
    assert sorted(order) == list(range(p.n))
    assert all(position[r] < position[j] for r, j in p.precedences)
    assert all(p.drones[trucks[j]] > 0 for j in range(p.n) if not p.truck_servable(j))
    decoded = decode(p, order, trucks)
    assert evaluate_fleet(p, decoded.plan()) == pytest.approx(decoded.objective())


def test_decode_rejects_an_order_against_precedence():
    """decode names the customer placed before its predecessor."""
    p = residential_fleet(6, trucks=1, drones=1, capacity=1, seed=1)
    r, j = p.precedences[0]
    order = [j, r] + [x for x in range(p.n) if x not in (r, j)]
    with pytest.raises(
        taopt.errors.InstanceError, match=f"customer {j} before its predecessor {r}"
    ):
        decode(p, order)


def test_infeasible_instance_is_reported_by_every_heuristic():
    """A drone-only customer out of range: status infeasible naming the customer, no plan."""
    g = nx.Graph()
    g.add_edge(0, 1, length=100.0)
    p = FleetProblem([[50, 10], [50, 900]], [[0, 0], [100, 0]], g, depot=0, flight_range=300)
    for method, options in HEURISTICS.items():
        s = taopt.solve(p, method, **options)
        assert s.status == "infeasible"
        assert "customer 1" in s.info["reason"]
        assert s.solution is None and math.isinf(s.objective)


def test_milp_equals_the_optimum_on_tiny_instances():
    """The teaching MILP certifies the exact optimum on two 2-customer instances (one per
    objective)."""
    for seed in (4, 5):
        p = tiny_instance(
            seed,
            n=2,
            trucks=1,
            drones=1,
            capacity=1 + seed % 2,
            precedence=True,
            stops=3,
            objective=["last_service", "return"][seed % 2],
        )
        s = taopt.solve(p, "milp")
        assert s.status == "optimal"
        assert s.objective == pytest.approx(taopt.solve(p, "exact").objective, rel=1e-6)


@pytest.mark.slow
def test_milp_equals_brute_force_more():
    """Slow: the MILP equals brute force on n = 3 instances of both objectives, K, D in {1, 2}."""
    for seed in range(12):
        rng = np.random.default_rng(seed)
        p = tiny_instance(
            seed,
            n=3,
            trucks=int(rng.integers(1, 3)),
            drones=int(rng.integers(0, 2)),
            capacity=int(rng.integers(1, 3)),
            precedence=bool(seed % 2),
            objective="return" if seed % 3 == 0 else "last_service",
            stops=3,
        )
        if p.unservable():
            continue
        value, _, _ = brute_force(p)
        s = taopt.solve(p, "milp")
        assert s.status == "optimal"
        assert s.objective == pytest.approx(value, rel=1e-6)


def test_milp_labels_its_rows():
    """Every row family of the MILP carries its (F..) label."""
    from taopt.models.fleet_milp import describe

    families = describe(TINY[0])
    assert families and all(f["label"].startswith("(F") for f in families)
    assert any("precedence" in f["label"] for f in describe(residential_fleet(3, seed=1)))


def test_plot_writes_map_and_gantt(tmp_path):
    """The registered plot writes a PNG of the plan (map and Gantt); a gantt plot exists."""
    from taopt.registry import family_of

    p = residential_fleet(8, trucks=2, drones=2, capacity=2, seed=1)
    s = taopt.solve(p, "MMA")
    plots = family_of(p).plots
    path = tmp_path / "plan.png"
    plots["plan"](p, s.solution, str(path), method="MMA")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "gantt" in plots


def test_search_value_from_snapshots_equals_a_full_decode():
    """The searches' prefix re-decode gives decode()'s objective for random moves and flips."""
    from taopt.fleet.tspd import TSPD_FOLDER
    from taopt.heuristics.fleet_search import _Search, route_first
    from taopt.runtime import Deadline

    problems = [
        residential_fleet(30, trucks=2, drones=2, capacity=2, seed=7),
        FleetProblem.from_tspd(TSPD_FOLDER / "uniform-3-n13.txt"),
    ]
    for p in problems:
        search = _Search(p, np.random.default_rng(0), Deadline(None))
        (order, trucks, modes), _, _ = route_first(search)
        search.set_current(order, trucks, modes)
        flips = search.flips(order, trucks, modes)
        for step in range(40):
            new_order = search.shift(order) or order
            moved = search.reassign(trucks, modes)
            new_trucks, new_modes = (trucks, modes) if moved is None else moved[1:]
            if flips and step % 2:
                new_order, new_trucks, new_modes = flips[step % len(flips)]
            full = decode(p, new_order, new_trucks, modes=new_modes).objective()
            value = search.value(new_order, new_trucks, new_modes)
            assert value == pytest.approx(full, rel=1e-12)


@pytest.mark.slow
def test_solve_command_plots_and_prints_a_fleet_plan(tmp_path, capsys):
    """`taopt solve FILE --methods MMA --plot` on the fleet example writes the PNG and prints
    each truck's walk and each drone's sorties (it raised AttributeError n_targets before)."""
    from pathlib import Path

    from taopt.orchestration.cli import main

    example = Path(taopt.__file__).parent / "data" / "examples" / "fleet_problem.json"
    png = tmp_path / "fleet.png"
    assert main(["solve", str(example), "--methods", "MMA", "--quiet", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "truck 0: s0" in out and "drone (1, 1) [positions]" in out
    assert png.read_bytes()[:4] == b"\x89PNG"
