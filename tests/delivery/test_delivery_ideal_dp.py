"""The exact DP over order ideals (taopt.delivery.ideal_dp): equal to the subset DP and the
MILP, valid completion bounds, incumbents, time limits and degenerate input."""

from __future__ import annotations

import math

import numpy as np
import pytest

import taopt
from taopt.delivery.bounds import arborescence_bound
from taopt.delivery.dags import layered_dag
from taopt.delivery.evaluate import evaluate_plan
from taopt.delivery.ideal_dp import completion_bound, count_ideals, ideal_dp
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import _sortie_data, _sortie_step, optimal_plan
from taopt.errors import InstanceError
from taopt.models.delivery import solve_delivery
from taopt.orchestration.pipeline import certifying_method, default_methods

REL = 1e-9


def random_instance(seed: int, n: int, precedences: bool = True, tau: float = 0.0):
    """n random customers on a k x k grid, random speeds and range, optional layered DAG."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(3, 5))
    side = 300.0
    h = side / (k - 1)
    customers = rng.uniform(0, side, (n, 2))
    pairs = (
        layered_dag(n, layers=int(rng.integers(1, 4)), density=0.4, seed=rng) if precedences else ()
    )
    return DeliveryInstance.grid(
        customers, k, side, rng.uniform(0.7, 2.0), 1.0, rng.uniform(1.45, 4.0) * h, pairs, tau
    )


def plain_ideal_dp(inst) -> float:
    """Independent reference: every ideal, every landing stop, one _sortie_step per
    (ideal, added customer), no min-plus tables, dominance, bound or incumbent."""
    n, s = inst.n, inst.s
    data = _sortie_data(inst)
    need = [0] * n
    for r, j in inst.precedences:
        need[j] |= 1 << r
    start = np.full(s, np.inf)
    start[inst.depot] = 0.0
    layer, best = {0: start}, math.inf
    for size in range(n):
        following: dict[int, np.ndarray] = {}
        for served, ready in layer.items():
            alive = np.flatnonzero(np.isfinite(ready))
            for j in range(n):
                if served >> j & 1 or need[j] & ~served:
                    continue
                sortie = data.get(j)
                if size == n - 1:
                    _, times, i_pos, _ = _sortie_step(
                        inst.truck_time, inst.service_time, ready[alive], alive, sortie, True
                    )
                    best = min(best, float(times[i_pos]))
                    continue
                _, _, _, value = _sortie_step(
                    inst.truck_time, inst.service_time, ready[alive], alive, sortie
                )
                row = following.setdefault(served | 1 << j, np.full(s, np.inf))
                row[sortie[0]] = np.minimum(row[sortie[0]], value)
        layer = following
    return best


def test_counts_ideals_of_a_chain_and_an_antichain():
    """A chain of n customers has n + 1 ideals, an antichain 2^n."""
    chain = random_instance(0, 6, precedences=False)
    free = count_ideals(chain)
    assert free == 2**6
    linked = DeliveryInstance.grid(
        chain.customers, 3, 300.0, 1.0, 1.0, 400.0, [(i, i + 1) for i in range(5)]
    )
    assert count_ideals(linked) == 7
    assert count_ideals(chain, cap=10) is None


@pytest.mark.parametrize("seed", range(16))
def test_equals_the_subset_dp(seed):
    """Same optimum as the subset DP on random instances with and without precedences."""
    n = 4 + seed % 6
    inst = random_instance(seed, n, precedences=seed % 3 != 0, tau=5.0 * (seed % 2))
    reference = optimal_plan(inst)
    sol = ideal_dp(inst)
    assert sol.status == "optimal" and sol.bound == sol.objective
    assert sol.objective == pytest.approx(reference.objective, rel=REL)
    assert plain_ideal_dp(inst) == pytest.approx(reference.objective, rel=REL)
    assert evaluate_plan(inst, sol.plan) == sol.objective


@pytest.mark.parametrize("seed", range(6))
def test_without_beam_dominance_or_pruning_same_optimum(seed):
    """Each speed-up (beam incumbent, dominance, bound pruning) leaves the optimum unchanged."""
    inst = random_instance(100 + seed, 7)
    plain = ideal_dp(inst, beam=0, dominance=False, prune=False, relaxation=False)
    for options in ({"beam": 0}, {"beam": 3}, {"dominance": False}, {"relaxation": False}):
        assert ideal_dp(inst, **options).objective == pytest.approx(plain.objective, rel=REL)


@pytest.mark.parametrize("seed", range(2))
def test_equals_the_milp_on_tiny_instances(seed):
    """Same optimum as the MILP (5.1)-(5.7) on 3-4 customers."""
    inst = random_instance(200 + seed, 3 + seed)
    milp = solve_delivery(inst, time_limit=60)
    assert milp.status == "optimal"
    assert ideal_dp(inst).objective == pytest.approx(milp.objective, rel=1e-6)


@pytest.mark.parametrize("seed", range(8))
def test_completion_bound_never_exceeds_the_true_remaining_time(seed):
    """B(I, k) (weak terms <= with the relaxation) <= the optimum from (I, k, R) minus R."""
    rng = np.random.default_rng(seed)
    inst = random_instance(300 + seed, 7, tau=3.0 * (seed % 2))
    order = list(taopt.solve(inst, "NIA").plan.order)
    for _ in range(4):
        served = order[: int(rng.integers(0, inst.n))]
        mask = sum(1 << j for j in served)
        stop = int(rng.integers(0, inst.s))
        ready = float(rng.uniform(0, 100))
        remaining = ideal_dp(inst, _start=(mask, stop, ready), beam=0).objective - ready
        weak = completion_bound(inst, served, stop, relaxation=False)
        strong = completion_bound(inst, served, stop)
        assert weak <= strong * (1 + 1e-12) and strong <= remaining * (1 + 1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_incumbent_does_not_change_the_optimum(seed):
    """A heuristic or an optimal incumbent prunes, the optimum stays the same."""
    inst = random_instance(400 + seed, 8)
    opt = ideal_dp(inst, beam=0)
    for incumbent in (taopt.solve(inst, "NIA"), opt.plan):
        sol = ideal_dp(inst, incumbent=incumbent, beam=0)
        assert sol.status == "optimal"
        assert sol.objective == pytest.approx(opt.objective, rel=REL)
    assert ideal_dp(inst, incumbent=opt.plan, beam=0).info["states_pruned"] > 0


def test_time_limit_returns_a_proven_bound_without_raising():
    """A tiny limit: status time_limit, bound <= optimum, the incumbent or no plan (inf)."""
    inst = random_instance(7, 9)
    opt = ideal_dp(inst).objective
    alone = ideal_dp(inst, time_limit=1e-9)
    assert alone.status == "time_limit" and alone.plan is None and math.isinf(alone.objective)
    assert arborescence_bound(inst) <= alone.bound <= opt * (1 + REL)
    nia = taopt.solve(inst, "NIA")
    kept = ideal_dp(inst, time_limit=1e-9, incumbent=nia)
    assert kept.status == "time_limit" and kept.objective == evaluate_plan(inst, kept.plan)
    assert kept.bound <= opt * (1 + REL) <= kept.objective * (1 + REL)


def test_size_guard_stops_like_a_time_limit():
    """Past max_states the run stops with status time_limit and a valid bound."""
    inst = random_instance(8, 9, precedences=False)
    opt = ideal_dp(inst).objective
    sol = ideal_dp(inst, max_states=50, beam=0)
    assert sol.status == "time_limit" and sol.info["stopped_by"] == "size"
    assert sol.bound <= opt * (1 + REL)
    for cells in (20, 60, 100):  # stops after a few layers, or not at all
        later = ideal_dp(inst, max_states=cells * inst.s, beam=0, relaxation=False)
        assert later.status in ("time_limit", "optimal")
        assert later.bound <= opt * (1 + REL)
        if later.status == "time_limit":
            assert later.info["stopped_by"] == "size" and later.info["ideals_expanded"] > 1


def test_degenerate_input():
    """One customer is solved; more than 63 customers are refused with a clear error."""
    one = random_instance(9, 1)
    assert ideal_dp(one).objective == pytest.approx(optimal_plan(one).objective, rel=REL)
    rng = np.random.default_rng(0)
    big = DeliveryInstance.grid(rng.uniform(0, 300, (64, 2)), 3, 300.0, 1.0, 1.0, 400.0)
    with pytest.raises(InstanceError, match="63"):
        ideal_dp(big)
    assert count_ideals(big) is None


def test_registered_as_exact_and_certifying():
    """'exact' is the ideal DP, default and certifying while affordable; MILP is 'milp'."""
    inst = random_instance(10, 6)
    assert certifying_method(inst) == "exact"
    assert "exact" in default_methods(inst) and "milp" not in default_methods(inst)
    sol = taopt.solve(inst, "exact")
    assert sol.status == "optimal"
    assert sol.objective == pytest.approx(taopt.solve(inst, "subset-dp").objective, rel=REL)


def test_example_instance_is_certified_and_below_every_heuristic(delivery_example):
    """Fig. 5.6's setup: optimal, equal to an independent plain DP over ideals, <= NIA, MMA,
    SMMA, above Proposition 5.3's bound."""
    inst = delivery_example
    sol = taopt.solve(inst, "exact")
    assert sol.status == "optimal" and evaluate_plan(inst, sol.plan) == sol.objective
    assert sol.objective == pytest.approx(plain_ideal_dp(inst), rel=REL)
    for name in ("NIA", "MMA", "SMMA"):
        assert taopt.solve(inst, name).objective >= sol.objective * (1 - REL)
    assert arborescence_bound(inst) <= sol.objective


def test_study_takes_the_optimum_from_exact_rows(tmp_path):
    """Beyond exact_max_n the study's optimum comes from the certified 'exact' rows."""
    from taopt.orchestration.studies.delivery import delivery_study

    df = delivery_study(
        "small",
        instances=1,
        ratios=(0.6,),
        methods=("NIA", "exact"),
        exact_max_n=0,
        out_dir=tmp_path,
        progress=False,
    )
    exact = df[df.method == "exact"].set_index("ratio")
    assert (exact.status == "optimal").all()
    assert df.optimum.notna().all() and (df.gap_to_optimum >= -1e-12).all()
    nia = df[df.method == "NIA"].set_index("ratio")
    assert (nia.optimum == exact.objective).all()
