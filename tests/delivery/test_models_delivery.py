"""Tests of the exact truck–drone MILP (helper-6), checked without trusting the solver.

Independent check: enumerate every precedence-feasible customer order, schedule each
with the exact fixed-order DP :func:`taopt.schedule`, and take the best; the MILP must
match it. The decoded plan is re-scored by :func:`taopt.evaluate`.
"""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError
from taopt.models import solve_delivery
from taopt.models.delivery import describe, feasible_triples

REL = 1e-6


def random_instance(seed: int, n: int = 6, k: int = 3, service_time: float = 0.0):
    """n customers uniform in [0, 1000]^2, a k×k street grid, random precedences.

    Speeds and range vary with the seed (v_d/v_t in [0.8, 1.6], L in [750, 1100]) so
    the truck or the drone can be the bottleneck.
    """
    rng = np.random.default_rng([7, seed])
    customers = rng.uniform(0, 1000, size=(n, 2))
    ranks = rng.permutation(n)
    precedences = [
        (int(ranks[a]), int(ranks[b]))
        for a, b in itertools.combinations(range(n), 2)
        if rng.random() < 0.2
    ]
    return DeliveryInstance.grid(
        customers,
        k,
        1000.0,
        v_drone=float(rng.uniform(0.8, 1.6)),
        v_truck=1.0,
        flight_range=float(rng.uniform(750, 1100)),
        precedences=precedences,
        service_time=service_time,
        name=f"random-{seed}",
    )


def enumerate_optimum(instance: DeliveryInstance) -> float:
    """Best makespan over all precedence-feasible orders, each scheduled exactly."""
    orders = nx.all_topological_sorts(instance.precedence_graph)
    return min(taopt.schedule(instance, list(order)).objective for order in orders)


def check_exact(instance: DeliveryInstance, heuristics: bool = True) -> None:
    sol = solve_delivery(instance)
    assert sol.status == "optimal"
    # the one scorer agrees with the model, and the fixed-order DP reproduces it
    assert taopt.evaluate(instance, sol.plan) == pytest.approx(sol.objective, rel=REL)
    assert sol.info["model_objective"] == pytest.approx(sol.objective, rel=REL)
    assert taopt.schedule(instance, sol.plan.order).objective == pytest.approx(
        sol.objective, rel=REL
    )
    # independent enumeration
    assert sol.objective == pytest.approx(enumerate_optimum(instance), rel=REL)
    # bounds never above the optimum
    assert sol.bound <= sol.objective * (1 + REL)
    assert taopt.bounds.arborescence(instance) <= sol.objective * (1 + REL)
    if heuristics:
        for name in ("NIA", "MMA", "SMMA", "GA"):
            options = {"population": 6, "generations": 5} if name == "GA" else {}
            heur = taopt.heuristics.run(name, instance, seed=0, **options)
            assert heur.objective >= sol.objective * (1 - REL), name


@pytest.mark.parametrize("seed", range(5))
def test_exact_matches_enumeration_small(seed):
    """The MILP optimum equals brute-force enumeration on small random instances."""
    check_exact(random_instance(seed))


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(5, 20))
def test_exact_matches_enumeration_sweep(seed):
    """The same check on 15 more random instances."""
    check_exact(random_instance(seed))


def test_service_time_tau_is_modelled():
    """τ = 30 s paid at the customer and at the truck: still equal to enumeration."""
    check_exact(random_instance(101, n=5, service_time=30.0), heuristics=False)


def test_dominance_reduction_is_safe():
    """The reduced model (dominated triples removed) has the full model's optimum."""
    for seed in (0, 3):
        inst = random_instance(seed, n=5)
        full = feasible_triples(inst, reduce=False)
        reduced = feasible_triples(inst)
        assert len(reduced.middle) <= len(full.middle)
        from taopt.models.delivery import build

        values = []
        for reduce in (False, True):
            model = build(inst, reduce=reduce)
            model.problem.solve(solver="HIGHS", mip_rel_gap=1e-9)
            values.append(model.problem.value)
        assert values[0] == pytest.approx(values[1], rel=REL)


def test_without_incumbent_cutoff_and_with_a_given_plan():
    """No cut-off and an optimal given plan both give the enumerated optimum."""
    inst = random_instance(4)
    expected = enumerate_optimum(inst)
    plain = solve_delivery(inst, incumbent=None)
    assert plain.info["cutoff"] is None
    assert plain.objective == pytest.approx(expected, rel=REL)
    # an optimal incumbent: HiGHS must still find (and prove) a plan of that value
    given = solve_delivery(inst, incumbent=plain.plan)
    assert given.status == "optimal"
    assert given.objective == pytest.approx(expected, rel=REL)


def test_time_limit_keeps_a_certified_gap():
    """A tiny limit: never a fake optimum; the bound stays below the true optimum (the
    registry's warm start gives the MILP its incumbent)."""
    inst = random_instance(1, n=7)
    expected = enumerate_optimum(inst)
    sol = taopt.solve(inst, "milp", time_limit=0.05)
    assert sol.status in ("time_limit", "optimal")
    assert taopt.evaluate(inst, sol.plan) == pytest.approx(sol.objective, rel=REL)
    assert sol.objective >= expected * (1 - REL)
    assert sol.bound <= expected * (1 + REL)


@pytest.mark.parametrize("incumbent", [None, "heuristic"])
def test_loose_mip_gap_is_not_called_optimal(incumbent):
    """mip_gap=0.5 stops HiGHS early (review item 4): "optimal" only within 1e-6, else
    "feasible" with a proven bound, and never worse than the incumbent."""
    from taopt.models.highs import OPTIMALITY_TOLERANCE

    inst = random_instance(2, n=6)
    optimum = enumerate_optimum(inst)
    if incumbent == "heuristic":  # taopt.solve passes the best of NIA, MMA and SMMA
        sol = taopt.solve(inst, "milp", mip_gap=0.5)
    else:
        sol = solve_delivery(inst, mip_gap=0.5, incumbent=None)
    assert taopt.evaluate(inst, sol.plan) == pytest.approx(sol.objective, rel=1e-9)
    assert sol.bound <= optimum * (1 + REL) and sol.objective >= optimum * (1 - REL)
    if sol.status == "optimal":
        assert sol.gap <= OPTIMALITY_TOLERANCE
    else:
        assert sol.status == "feasible" and sol.info["stopped_by"] == "mip_gap"
        assert OPTIMALITY_TOLERANCE < sol.gap <= 0.5 + 1e-9
    if sol.info["cutoff"] is not None:
        assert sol.objective <= sol.info["cutoff"] * (1 + 1e-9)


def test_customer_leg_cuts_keep_the_optimum():
    """The customer-pair valid inequalities do not change the optimum."""
    inst = random_instance(2, n=5)
    plain = solve_delivery(inst)
    strong = solve_delivery(inst, customer_legs=True)
    assert strong.objective == pytest.approx(plain.objective, rel=REL)


def test_single_customer_and_no_precedences():
    """One customer: the MILP equals enumeration and the one scorer."""
    inst = DeliveryInstance.grid(
        [[100, 300]], k=2, side=400, v_drone=2.0, v_truck=1.0, flight_range=700
    )
    sol = solve_delivery(inst)
    assert sol.objective == pytest.approx(enumerate_optimum(inst), rel=REL)
    assert taopt.evaluate(inst, sol) == pytest.approx(sol.objective, rel=REL)


def test_describe_maps_families_to_printed_equations():
    """describe() maps the families to every printed equation (5.1)-(5.7)."""
    table = describe(random_instance(0), show=False)
    text = " ".join(row["label"] + " " + row["implements"] for row in table)
    for eq in ("(5.1)", "(5.2)", "(5.3)", "(5.4)", "(5.5)", "(5.6)", "(5.7)"):
        assert eq in text
    assert all(row["rows"] > 0 for row in table if not row["label"].startswith(("(5.4)", "(5.6)")))


def test_bad_input():
    """A non-instance and a negative time limit raise InstanceError."""
    with pytest.raises(InstanceError):
        solve_delivery("not an instance")
    with pytest.raises(InstanceError, match="time_limit"):
        solve_delivery(random_instance(0), time_limit=-1)


def test_time_limited_run_on_many_stops_is_no_worse_than_the_heuristics():
    """121 stops make the MILP large: stopped by the limit it must still return the best known
    plan (never worse than NIA/MMA/SMMA) with a bound below the subset-DP optimum."""
    import taopt.heuristics
    from taopt.delivery.schedule import optimal_plan
    from taopt.orchestration.studies.delivery import study_instance

    inst = study_instance("small", 0, seed=3, ratio=0.3)
    sol = taopt.solve(inst, "milp", time_limit=2.0)
    best_heuristic = min(
        taopt.heuristics.run(name, inst).objective for name in ("NIA", "MMA", "SMMA")
    )
    optimum = optimal_plan(inst).objective
    assert sol.objective <= best_heuristic * (1 + 1e-9)
    assert sol.objective == pytest.approx(taopt.evaluate(inst, sol.plan), rel=1e-9)
    assert sol.bound is not None and sol.bound <= optimum * (1 + 1e-9)
    if sol.status == "optimal":
        assert sol.objective == pytest.approx(optimum, rel=1e-6)
    else:
        assert sol.status == "time_limit" and sol.gap is not None
