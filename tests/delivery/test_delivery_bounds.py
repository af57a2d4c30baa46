"""Lower bounds stronger than Proposition 5.3, and taopt.bounds.lower (issue 16, item 2).

Every bound is checked never above an optimum computed independently (the subset DP
``optimal_plan``, brute force over orders, the references of tests/reference.py), and
never below the weaker bound it claims to improve.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from conftest import ROOT
from reference import REFERENCES, brute_force_routing
from reference_exact import sop_brute_force, sop_instance

import taopt
from taopt.delivery.bounds import (
    arborescence_bound,
    decomposition_bound,
    path_bound,
    service_gap_matrix,
)
from taopt.delivery.costs import drone_cost_matrix
from taopt.delivery.dags import layered_dag
from taopt.delivery.evaluate import timeline
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import optimal_plan
from taopt.errors import InstanceError

REL = 1e-9
DAG40_EXACT = ROOT / "docs/reproduction/data/chapter5/delivery_dag40_exact.csv"


def _random_delivery(seed: int, precedences: bool) -> DeliveryInstance:
    """3–8 customers on a 5 x 5 grid, random speeds and range, layered DAG or none."""
    rng = np.random.default_rng([2016, seed])
    n = int(rng.integers(3, 9))
    pairs = layered_dag(n, layers=3, density=0.3, seed=rng) if precedences else ()
    return DeliveryInstance.grid(
        rng.uniform(0, 800, size=(n, 2)),
        5,
        800.0,
        v_drone=float(rng.uniform(0.8, 2.0)),
        v_truck=1.0,
        flight_range=float(rng.uniform(250.0, 900.0)),
        precedences=pairs,
        service_time=float(rng.choice([0.0, 5.0])),
    )


@pytest.mark.parametrize("precedences", [False, True])
@pytest.mark.parametrize("seed", range(12))
def test_path_bound_between_prop_5_3_and_optimum(seed, precedences):
    """f_a <= path_bound <= f_o (subset DP) on small random instances."""
    inst = _random_delivery(seed, precedences)
    optimum = optimal_plan(inst).objective
    value = path_bound(inst)
    assert arborescence_bound(inst) <= value * (1 + REL)
    assert value <= optimum * (1 + REL)


@pytest.mark.parametrize("precedences", [False, True])
@pytest.mark.parametrize("seed", range(12))
def test_decomposition_bound_between_prop_5_3_and_optimum(seed, precedences):
    """f_a <= decomposition_bound <= f_o (subset DP) on small random instances."""
    inst = _random_delivery(seed, precedences)
    optimum = optimal_plan(inst).objective
    value = decomposition_bound(inst)
    assert arborescence_bound(inst) <= value * (1 + REL)
    assert value <= optimum * (1 + REL)


def test_decomposition_bound_on_pickup_delivery_pairs_beats_path_bound():
    """n = 10 pick-up/delivery pairs, v_d/v_t = 1.4: path <= decomposition <= f_o, strictly."""
    from taopt.delivery.dags import paired_precedences

    rng = np.random.default_rng([99, 1])
    inst = DeliveryInstance.grid(
        rng.uniform(0, 1000, (10, 2)), 11, 1000.0, 1.4, 1.0, 300.0,
        precedences=paired_precedences(10, seed=rng),
    )  # fmt: skip
    optimum = optimal_plan(inst).objective
    assert path_bound(inst) < decomposition_bound(inst) <= optimum * (1 + REL)


def test_path_bound_is_deterministic_and_zero_iterations_is_arborescence():
    """Same instance, same value; 0 iterations is >= the arborescence on consecutive edges."""
    inst = _random_delivery(3, True)
    assert path_bound(inst) == path_bound(inst)
    assert path_bound(inst, iterations=0) >= arborescence_bound(inst, rule="consecutive") * (
        1 - REL
    )


@pytest.mark.parametrize("seed", range(12))
def test_service_gap_is_at_least_tstar_and_below_every_real_gap(seed):
    """t* <= t** <= t_j - t_r for consecutive services of the optimal and of SMMA's plan."""
    inst = _random_delivery(seed, seed % 2 == 0)
    D, gap = drone_cost_matrix(inst), service_gap_matrix(inst)
    assert (gap >= D - 1e-9).all()
    for plan in (optimal_plan(inst).plan, taopt.solve(inst, "SMMA").plan):
        times = timeline(inst, plan).service_time
        order = list(plan.order)
        assert gap[inst.n, order[0]] <= times[0] + 1e-9
        for p in range(1, len(order)):
            assert gap[order[p - 1], order[p]] <= times[p] - times[p - 1] + 1e-9


def test_path_bound_beats_prop_5_3_on_a_pairs120_instance():
    """Strictly stronger than Proposition 5.3 on pairs120 instance 0 (L/L0 = 0.3)."""
    from taopt.orchestration.studies.delivery import study_instance

    inst = study_instance("pairs120", 0, ratio=0.3)
    assert path_bound(inst) > 1.05 * taopt.bounds.arborescence(inst)
    assert decomposition_bound(inst, iterations=60) > taopt.bounds.arborescence(inst)


@pytest.mark.slow
@pytest.mark.parametrize("vd_ratio", [None, 1.0])
def test_path_bound_beats_prop_5_3_on_every_pairs120_instance(vd_ratio):
    """lower() > Proposition 5.3 on all 10 pairs120 instances x 6 ratios (both v_d / v_t)."""
    from taopt.orchestration.studies.delivery import DEFAULT_RATIOS, study_instance

    for i, ratio in itertools.product(range(10), DEFAULT_RATIOS):
        inst = study_instance("pairs120", i, ratio=ratio, vd_ratio=vd_ratio)
        assert taopt.bounds.lower(inst) > taopt.bounds.arborescence(inst)


@pytest.mark.slow
def test_lower_below_every_certified_dag40_optimum():
    """lower() never exceeds a certified dag40 optimum (the exact-DP helper's CSV, shipped)."""
    import pandas as pd

    assert DAG40_EXACT.exists(), f"{DAG40_EXACT} is shipped with the reproduction data"

    from taopt.orchestration.studies.delivery import study_instance

    table = pd.read_csv(DAG40_EXACT)
    certified = table["optimum"] if "optimum" in table else pd.Series(np.nan, table.index)
    if "status" in table:  # rows of the exact method: its objective when proven optimal
        proven = table["objective"].where(table["status"] == "optimal")
        certified = certified.fillna(proven)
    table = table.assign(certified=certified).dropna(subset=["certified"])
    table = table.drop_duplicates(["instance", "ratio"])
    assert len(table) > 0
    for row in table.itertuples():
        inst = study_instance("dag40", int(row.instance), ratio=float(row.ratio))
        assert taopt.bounds.lower(inst) <= row.certified * (1 + REL)


@pytest.mark.parametrize("seed", range(20))
def test_sop_lower_between_arborescence_and_brute_force(seed):
    """SOP: arborescence <= lower(auto) <= brute-force optimum on 4-7 nodes."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    value = taopt.bounds.lower(problem)
    assert taopt.bounds.arborescence(problem) <= value * (1 + REL) + 1e-9
    assert value <= optimum * (1 + REL) + 1e-9


@pytest.mark.parametrize("seed", range(15))
def test_routing_lower_between_arborescence_and_brute_force(seed):
    """Chapter 2: arborescence <= lower(auto) <= brute-force optimum (asymmetric costs)."""
    rng = np.random.default_rng([5, seed])
    n, m = int(rng.integers(1, 6)), int(rng.integers(1, 4))
    cost = rng.uniform(1.0, 30.0, size=(n + m, n + m))
    problem = taopt.AssignmentProblem(cost, n_targets=n)
    optimum = brute_force_routing(problem.cost, n)
    value = taopt.bounds.lower(problem)
    assert taopt.bounds.arborescence(problem) <= value * (1 + REL)
    assert value <= optimum * (1 + REL)


@pytest.mark.parametrize("make", REFERENCES, ids=lambda make: make.__name__)
@pytest.mark.parametrize("strength", ["fast", "auto"])
def test_lower_never_above_the_reference_optimum(make, strength):
    """Every family: lower(p) <= the independently known optimum, and fast <= auto."""
    reference = make()
    value = taopt.lower(reference.problem, strength=strength)
    assert math.isfinite(value)
    assert value <= reference.optimum * (1 + 1e-6)
    assert taopt.bounds.lower(reference.problem, "fast") <= taopt.bounds.lower(
        reference.problem
    ) * (1 + REL)


def test_lower_strong_routing_includes_the_lp(ref_routing_asymmetric):
    """strength="strong" on chapter 2 is >= the DFJ LP bound and <= the optimum."""
    reference = ref_routing_asymmetric  # cvxpy is a core dependency: no skip when it is missing
    value = taopt.bounds.lower(reference.problem, "strong")
    assert value >= taopt.models.lp_bound(reference.problem) * (1 - 1e-6)
    assert value <= reference.optimum * (1 + 1e-6)


def test_lower_rejects_unknown_inputs(ref_routing_small):
    """An unknown strength or problem type raises InstanceError."""
    with pytest.raises(InstanceError, match="strength"):
        taopt.bounds.lower(ref_routing_small.problem, "best")
    with pytest.raises(InstanceError, match="not a registered problem type"):
        taopt.bounds.lower(object())


def test_study_reports_strong_bound_between_prop_5_3_and_optimum(delivery_tiny_study):
    """The delivery study's strong_bound column: valid_bound <= strong_bound <= optimum."""
    df = delivery_tiny_study[1]
    assert (df.valid_bound <= df.strong_bound * (1 + REL)).all()
    assert (df.strong_bound <= df.optimum * (1 + REL)).all()
    assert np.allclose(df.q_strong, df.objective / df.strong_bound)


@pytest.mark.parametrize("flight_range", [250.0, 300.0])
def test_path_bound_on_the_fig_5_6_example(flight_range):
    """The 20-customer example: Prop. 5.3 < lower() <= every heuristic's makespan."""
    from taopt.delivery import example_instance

    inst = example_instance(flight_range)
    value = taopt.bounds.lower(inst)
    assert value > arborescence_bound(inst)
    for method in ("NIA", "MMA", "SMMA"):
        assert value <= taopt.solve(inst, method).objective
