"""Our branch-and-cut over the SOP cut model (issue 33 item 4): its optimum equals brute force
on random tiny SOPs (sparse and dense precedence, both branching rules), its bound is never
above the optimum when stopped early, and a time-limited run returns a proven bound."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest

from taopt.models import sop_bc
from taopt.models.sop_bc import TREE_MIN_GAP, node_bound, solve_sop_bc, wants_tree
from taopt.models.sop_cuts import SopCutModel
from taopt.result import OPTIMAL, TIME_LIMIT
from taopt.sop.problem import SopProblem, evaluate_order, load_sop
from tests.reference_exact import sop_brute_force


def _instance(seed: int) -> SopProblem:
    """7-9 nodes, start 0 and end n-1, uniform or small-integer costs, sparse (0.1) or dense
    (0.4) random precedences among the inner nodes: fractional root LPs, so the tree
    branches."""
    rng = np.random.default_rng([41, seed])
    n = int(rng.integers(7, 10))
    if seed % 2:
        cost = rng.integers(0, 20, size=(n, n)).astype(float)
    else:
        cost = rng.uniform(0.0, 100.0, size=(n, n))
    density = 0.1 if seed % 4 < 2 else 0.4
    pairs = [
        (a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < density
    ]
    return SopProblem(cost, pairs, 0, n - 1, name=f"bc-{seed}")


@pytest.mark.parametrize("strong", [1, 8])
@pytest.mark.parametrize("branching", ["split", "arc"])
def test_tree_matches_brute_force(branching, strong, monkeypatch):
    """The tree's optimum equals brute force on 24 random SOPs (with and without strong
    branching); the tree, not the root stage, closes some of them."""
    monkeypatch.setattr(sop_bc, "STRONG_CANDIDATES", strong)
    in_tree = 0
    for seed in range(24):
        problem = _instance(seed)
        optimum = sop_brute_force(problem)
        result = solve_sop_bc(problem, branching=branching)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)
        in_tree += result.info["nodes"] > 0
    assert in_tree >= 3  # the tree is exercised, not only the root


@pytest.mark.parametrize("limit", [1, 2, 3])
def test_bound_below_optimum_when_stopped(limit):
    """Stopped after 1-3 nodes, the proven bound is at most the brute-force optimum."""
    for seed in range(16):
        problem = _instance(seed)
        optimum = sop_brute_force(problem)
        result = solve_sop_bc(problem, node_limit=limit)
        assert result.bound <= optimum + 1e-6
        if result.status == TIME_LIMIT:
            assert result.bound <= result.objective + 1e-9


def test_node_bound_holds_on_the_box():
    """The node bound of a box (some arcs fixed) is at most the cost of every order in it."""
    problem = _instance(5)
    model = SopCutModel(problem)
    model.root()
    rng = np.random.default_rng(5)
    for _ in range(10):
        lower = np.zeros(model.n_arcs)
        upper = np.ones(model.n_arcs)
        upper[rng.random(model.n_arcs) < 0.2] = 0.0
        model.highs.changeColsBounds(
            model.n_arcs, np.arange(model.n_arcs, dtype=np.int32), lower, upper
        )
        model.highs.run()
        bound, _ = node_bound(model, lower, upper)
        for cost in _box_costs(problem, model, lower, upper):
            assert bound <= cost + 1e-6


def _box_costs(
    problem: SopProblem, model: SopCutModel, lower: np.ndarray, upper: np.ndarray
) -> list[float]:
    """The costs of every order (brute force) whose arcs lie in the box: each of its arcs of
    upper bound 1, each arc of lower bound 1 among its arcs."""
    costs = []
    for order in itertools.permutations(range(1, problem.n - 1)):
        path = [0, *order, problem.n - 1]
        arcs = model.arc_index[path[:-1], path[1:]]
        if (arcs < 0).any() or (upper[arcs] < 0.5).any():
            continue
        if not set(np.flatnonzero(lower > 0.5).tolist()) <= set(arcs.tolist()):
            continue
        if not all(path.index(a) < path.index(b) for a, b in problem.closure.edges()):
            continue
        costs.append(float(problem.cost[path[:-1], path[1:]].sum()))
    return costs


def test_stopped_child_bound_holds_on_the_box():
    """A child LP stopped after 1-3 dual simplex iterations (HiGHS's iteration limit) or at an
    objective bound just above the root's LP value still gives a node bound at most the
    cost of every order in the child's box (weak duality with any clipped duals), on 8 random
    SOPs and random boxes (an arc fixed to 1 or 0, and some arcs to 0); both stops occur."""
    statuses: set[str] = set()
    for seed in range(8):
        problem = _instance(seed)
        model = SopCutModel(problem)
        model.root()
        model.highs.run()
        root = model.highs.getBasis()
        value = float(model.highs.getInfo().objective_function_value)
        rng = np.random.default_rng([7, seed])
        for trial in range(6):
            lower = np.zeros(model.n_arcs)
            upper = np.where(model.fixed, 0.0, 1.0)
            upper[rng.random(model.n_arcs) < 0.1] = 0.0
            arc = int(rng.integers(model.n_arcs))
            if trial % 2:
                lower[arc] = upper[arc]  # fixed to 1 (where still open)
            else:
                upper[arc] = 0.0
            columns = np.arange(model.n_arcs, dtype=np.int32)
            model.highs.changeColsBounds(model.n_arcs, columns, lower, upper)
            model.highs.setBasis(root)
            if trial < 3:
                model.highs.setOptionValue("simplex_iteration_limit", trial + 1)
            else:
                model.highs.setOptionValue("objective_bound", value + 0.01 * abs(value))
            model.highs.run()
            model.highs.setOptionValue("simplex_iteration_limit", sop_bc.ITERATIONS_UNLIMITED)
            model.highs.setOptionValue("objective_bound", sop_bc.highspy.kHighsInf)
            status = model.highs.getModelStatus()
            statuses.add(status.name)
            if status == sop_bc.highspy.HighsModelStatus.kInfeasible:
                assert not _box_costs(problem, model, lower, upper)
                continue
            bound, _ = node_bound(model, lower, upper)
            for cost in _box_costs(problem, model, lower, upper):
                assert bound <= cost + 1e-6
        model.highs.changeColsBounds(
            model.n_arcs, columns, np.zeros(model.n_arcs), np.where(model.fixed, 0.0, 1.0)
        )
    assert {"kIterationLimit", "kObjectiveBound"} <= statuses


_RULES = ["STRONG_STOPPED", "STRONG_FIXING", "STRONG_CUTOFF", "STRONG_BASES", "STRONG_FLOOR"]


@pytest.mark.parametrize("off", [None, *_RULES])
def test_strong_rules_match_brute_force(off, monkeypatch):
    """With child LPs stopped after 2 iterations (most strong-branching children stop early)
    and each of the strong-branching rules off in turn (none off: all on), the tree's optimum
    equals brute force on 12 random SOPs, from no order and from the optimal order (a tight
    cutoff: children above it, fixings); stopped after 2 nodes its bound is at most the
    optimum. Rules on are exercised: stopped children bound, nodes fixed."""
    monkeypatch.setattr(sop_bc, "STRONG_ITERATIONS", 2)
    monkeypatch.setattr(sop_bc, "RELIABLE", 8)  # strong branching at every node
    if off is not None:
        monkeypatch.setattr(sop_bc, off, False)
    stopped = fixings = floors = 0
    for seed in range(12):
        problem = _instance(seed)
        optimum = sop_brute_force(problem)
        result = solve_sop_bc(problem)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        warm = solve_sop_bc(problem, incumbent=result.order)
        assert warm.status == OPTIMAL and warm.objective == pytest.approx(optimum)
        assert solve_sop_bc(problem, node_limit=2).bound <= optimum + 1e-6
        for info in (result.info, warm.info):
            stopped += info["strong_stopped"]
            fixings += info["strong_fixings"]
            floors += info["strong_floors"]
    assert (stopped > 0) == (off != "STRONG_STOPPED")
    assert (fixings > 0) == (off != "STRONG_FIXING")
    assert floors == 0 or off != "STRONG_FLOOR"  # too few branchings here to raise one


@pytest.mark.slow
def test_strong_floor_on_esc47():
    """ESC47 (optimum 1288) solved by the tree: children's bounds raised by other candidates'
    strong branching (STRONG_FLOOR; the tiny SOPs above branch too little to raise one), and
    every proven bound of its trace at most the optimum. Some 5-15 s (the root stage)."""
    cost, precedences, start, end, name = load_sop("ESC47")
    result = solve_sop_bc(SopProblem(cost, precedences, start, end, name=name))
    assert result.status == OPTIMAL and result.objective == pytest.approx(1288)
    assert result.info["strong_floors"] > 0
    assert all(bound <= 1288 + 1e-9 for _, bound in result.info["trace"])


def test_time_limited_run_returns_a_proven_bound():
    """ESC47 stopped after 2 s: an order that scores as reported and a bound below it and
    below the known optimum 1288."""
    cost, precedences, start, end, name = load_sop("ESC47")
    problem = SopProblem(cost, precedences, start, end, name=name)
    result = solve_sop_bc(problem, time_limit=2.0)
    assert result.status in (OPTIMAL, TIME_LIMIT)
    assert math.isfinite(result.bound) and result.bound <= 1288 + 1e-9
    assert result.bound <= result.objective
    assert evaluate_order(problem, result.order) == pytest.approx(result.objective)


def test_tree_counts(monkeypatch):
    """On the first random SOP that branches (no strong branching), the tree reports its LPs
    (one per node at least) and a bound trace that never falls."""
    monkeypatch.setattr(sop_bc, "STRONG_CANDIDATES", 1)
    for seed in range(24):
        info = solve_sop_bc(_instance(seed)).info
        if info["nodes"] > 1:
            break
    assert info["lps"] >= info["nodes"] > 1
    bounds = [b for _, b in info["trace"]]
    assert bounds == sorted(bounds)


def test_wants_tree_reads_the_gap():
    """The portfolio's rule: the tree for a gap above TREE_MIN_GAP or an unknown one, the MIP
    rounds below it."""
    assert wants_tree(100.0, 100.0 * (1 - 2 * TREE_MIN_GAP))
    assert not wants_tree(100.0, 100.0 * (1 - TREE_MIN_GAP / 2))
    assert wants_tree(math.inf, 5.0) and wants_tree(10.0, -math.inf)


@pytest.mark.parametrize("reliable", [0, 1])
def test_reliability_branching_matches_brute_force(reliable, monkeypatch):
    """With every key reliable from the start (every branching taken on pseudo-costs alone)
    or after one observation (strong branching and pseudo-costs mixed), the tree's optimum
    still equals brute force on 48 random SOPs; from the start, some nodes were branched on
    pseudo-costs."""
    monkeypatch.setattr(sop_bc, "RELIABLE", reliable)
    monkeypatch.setattr(sop_bc, "LOOKAHEAD", 1)
    on_pseudo = 0
    for seed in range(48):
        problem = _instance(seed)
        result = solve_sop_bc(problem)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(sop_brute_force(problem))
        on_pseudo += result.info["pseudo_branchings"]
    assert on_pseudo >= 1 or reliable


def test_pseudo_costs_estimate():
    """A key's estimate is its own mean gain per unit share times the share; a key without
    observations gets the mean over every key, 1 with none at all; reliability counts each
    child's observations."""
    costs = sop_bc.PseudoCosts()
    assert list(costs.estimate(("out", 1), (0.5, 0.5))) == [0.5, 0.5]
    costs.observe(("out", 1), 0, 3.0, 0.5)  # 6 per unit
    costs.observe(("out", 1), 1, -1.0, 0.5)  # a fall counts as 0
    costs.observe(("in", 2), 0, 2.0, 0.25)  # 8 per unit
    assert list(costs.estimate(("out", 1), (0.25, 0.75))) == [1.5, 0.0]
    assert list(costs.estimate(("in", 3), (1.0, 1.0))) == [7.0, 0.0]
    assert not costs.reliable(("in", 2))
    for _ in range(sop_bc.RELIABLE):
        costs.observe(("in", 2), 0, 1.0, 0.5)
        costs.observe(("in", 2), 1, 1.0, 0.5)
    assert costs.reliable(("in", 2))


def test_rows_grown_equal_rows_read_whole():
    """Rows read once and grown by the rows added since (``Rows.now``) equal the rows read
    whole from HiGHS, and give the same node bound."""
    problem = _instance(9)
    model = SopCutModel(problem)
    early = sop_bc.Rows.of(model)
    model.root()
    assert model.highs.getNumRow() > early.count
    grown, whole = early.now(model), sop_bc.Rows.of(model)
    assert grown.count == whole.count
    assert (grown.matrix != whole.matrix).nnz == 0
    assert np.array_equal(grown.lower, whole.lower) and np.array_equal(grown.upper, whole.upper)
    lower, upper = np.zeros(model.n_arcs), np.where(model.fixed, 0.0, 1.0)
    assert node_bound(model, lower, upper, grown)[0] == node_bound(model, lower, upper, whole)[0]


@pytest.mark.parametrize("age", [1, 2])
def test_cut_pool_matches_brute_force(age, monkeypatch):
    """With a tiny aging threshold (rows leave the LP after 1 or 2 slack node LPs) the tree's
    optimum equals brute force on 24 random SOPs, every bound when stopped after 3 nodes is
    at most the optimum, rows do leave and come back, and after the tree the model holds
    every row again in its order (the LP read whole equals the rows kept by the model)."""
    monkeypatch.setattr(sop_bc, "POOL_AGE", age)
    monkeypatch.setattr(sop_bc, "STRONG_CANDIDATES", 1 + age % 2 * 7)
    retired = restored = 0
    for seed in range(24):
        problem = _instance(seed)
        optimum = sop_brute_force(problem)
        model = SopCutModel(problem)
        result = solve_sop_bc(problem, model=model)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        pool = result.info["pool"]
        if pool is not None:
            retired, restored = retired + pool["retired"], restored + pool["restored"]
        # every row back, in the model's order: the cut rows by position
        rows = sop_bc.Rows.of(model)
        assert rows.count == model.degree_rows + len(model.cut_rows) + model.pool_rows
        for k, arcs in enumerate(model.cut_rows):
            assert set(rows.matrix[model.degree_rows + k].indices) == set(arcs.tolist())
        stopped = solve_sop_bc(problem, node_limit=3)
        assert stopped.bound <= optimum + 1e-6
    assert retired > 0


def _random_sop(key: list[int], n: int, density: float) -> SopProblem:
    """A random n-node SOP (costs 0-99, start 0, end n - 1), each pair of inner nodes a
    precedence with probability ``density``, drawn from ``default_rng(key)``."""
    rng = np.random.default_rng(key)
    cost = rng.integers(0, 100, size=(n, n)).astype(float)
    pairs = [
        (a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < density
    ]
    return SopProblem(cost, pairs, 0, n - 1)


def test_cut_pool_rows_come_back(monkeypatch):
    """On 6 random 13-node SOPs, the tree with rows leaving after one slack LP ends at the
    optimum of the tree without the pool, its bound after 2 nodes is at most that optimum, and
    some pooled rows came back at a node's point (the pool is exercised both ways)."""
    monkeypatch.setattr(sop_bc, "POOL_AGE", 1)
    restored = 0
    for seed in range(6):
        problem = _random_sop([43, seed], 13, 0.1)
        monkeypatch.setattr(sop_bc, "POOL", False)
        plain = solve_sop_bc(problem)
        monkeypatch.setattr(sop_bc, "POOL", True)
        pooled = solve_sop_bc(problem)
        assert plain.status == pooled.status == OPTIMAL
        assert pooled.objective == pytest.approx(plain.objective)
        assert evaluate_order(problem, pooled.order) == pytest.approx(plain.objective)
        assert solve_sop_bc(problem, node_limit=2).bound <= plain.objective + 1e-6
        restored += (pooled.info["pool"] or {}).get("restored", 0)
    assert restored > 0


def _root_pool() -> tuple[SopCutModel, Any, Any, np.ndarray, np.ndarray]:
    """Instance 9's root LP, its rows, a pool that observed its point, the point, and the
    cut rows slack there (asserted some: a root LP with slack cut rows)."""
    model = SopCutModel(_instance(9))
    model.root()
    model.highs.run()
    rows = sop_bc.Rows.of(model)
    pool = sop_bc.CutPool.of(model, rows)
    values = model.lp_values()
    pool.observe(rows, values)
    slack = np.flatnonzero(pool.age[pool.kept :] > 0) + pool.kept
    assert len(slack)
    return model, rows, pool, values, slack


def test_cut_pool_rows_round_trip():
    """Rows retired from the LP and restored come back with their coefficients and sides; a
    stored basis maps by row identity (rows it does not know: basic) or is refused when it
    lost a nonbasic row."""
    model, rows, pool, values, slack = _root_pool()
    pool.age[slack] = sop_bc.POOL_AGE
    basis = model.highs.getBasis()
    stored = (
        sop_bc._packed(basis.col_status),
        sop_bc._packed(basis.row_status),
        pool.ids,
    )
    fewer = pool.retire(model, rows)
    assert fewer.count == rows.count - len(slack) == model.highs.getNumRow()
    assert not len(pool.violated(values))  # slack at this point
    mapped = pool.statuses(stored)  # the retired rows were basic: still one basic per row
    assert mapped is not None and len(mapped) == fewer.count
    assert pool.restore(model) == len(slack)
    back = sop_bc.Rows.of(model)
    assert back.count == rows.count
    moved = np.concatenate([np.setdiff1d(np.arange(rows.count), slack), slack])
    assert (back.matrix != rows.matrix[moved]).nnz == 0
    assert np.array_equal(back.lower, rows.lower[moved])
    assert np.array_equal(np.sort(pool.ids), np.arange(rows.count))
    basic = int(sop_bc.highspy.HighsBasisStatus.kBasic)
    tight = np.flatnonzero(stored[1] != basic)
    tight = tight[tight >= pool.kept]
    assert len(tight)  # a tight cut row at the root
    without = sop_bc.CutPool(pool.kept, np.delete(stored[2], tight[0]), pool.age[:-1], 0)
    assert without.statuses(stored) is None and without.stale == 1


def test_cut_pool_repair_and_backoff(monkeypatch):
    """A stored basis that holds a row tight which has since left the LP is refused as it is,
    and maps once ``missing`` names that row and it comes back (a repair, not a return: its
    limit stays POOL_AGE); a row that came back violated retires after twice POOL_AGE, four
    times after a second return, never more than the cap."""
    model, rows, pool, _, slack = _root_pool()
    basis = model.highs.getBasis()
    col_status, row_status = sop_bc._packed(basis.col_status), sop_bc._packed(basis.row_status)
    basic = int(sop_bc.highspy.HighsBasisStatus.kBasic)
    # a stored basis in which the first slack row was tight (a column basic in its place)
    row_status[slack[0]] = int(sop_bc.highspy.HighsBasisStatus.kLower)
    col_status[np.flatnonzero(col_status != basic)[0]] = basic
    stored = (col_status, row_status, pool.ids.copy())
    pool.age[slack] = sop_bc.POOL_AGE
    pool.retire(model, rows)
    assert pool.statuses(stored) is None and pool.stale == 1
    missing = pool.missing(stored)
    assert pool.pooled[missing].tolist() == [stored[2][slack[0]]]
    assert pool.restore(model, missing, returned=False) == 1
    assert (pool.repaired, pool.restored) == (1, 0)
    mapped = pool.statuses(stored)
    assert mapped is not None and pool.stale == 1
    assert mapped[pool.ids == stored[2][slack[0]]][0] == row_status[slack[0]]
    monkeypatch.setattr(sop_bc, "POOL_BACKOFF", True)
    assert pool.limits()[-1] == sop_bc.POOL_AGE  # a repair is no return
    # returns double the age limit, up to the cap
    for k in range(1, sop_bc.POOL_BACKOFF_CAP + 3):
        rows = sop_bc.Rows.of(model)
        pool.age[-1] = pool.limits()[-1]
        pool.retire(model, rows)
        identity = pool.pooled[-1]
        pool.restore(model, np.array([len(pool.pooled) - 1]))
        assert pool.ids[-1] == identity
        expected = sop_bc.POOL_AGE * 2 ** min(k, sop_bc.POOL_BACKOFF_CAP)
        assert pool.limits()[-1] == expected
        assert pool.age[-1] == 0 and pool.age[-1] < pool.limits()[-1]
    assert pool.restored == sop_bc.POOL_BACKOFF_CAP + 2


def test_pool_backoff_and_repair_equal_the_plain_tree(monkeypatch):
    """On a random 18-node SOP that branches (no strong branching, rows leaving after one
    slack LP), the tree with the retirement doubling per return and the stored bases repaired
    from the pool, and the tree with neither, end at the optimum of the tree without a pool;
    with the repair no basis is dropped and some are repaired, without it some are dropped
    (both paths exercised). The 7-9-node brute
    force, and its bound stopped after 3 nodes, run with the repair on by default
    (``test_cut_pool_matches_brute_force``)."""
    monkeypatch.setattr(sop_bc, "POOL_AGE", 1)
    monkeypatch.setattr(sop_bc, "STRONG_CANDIDATES", 1)
    counts = {False: [0, 0], True: [0, 0]}
    for seed in (0,):
        problem = _random_sop([47, seed], 18, 0.05)
        monkeypatch.setattr(sop_bc, "POOL", False)
        plain = solve_sop_bc(problem)
        assert plain.status == OPTIMAL
        monkeypatch.setattr(sop_bc, "POOL", True)
        for on in (False, True):
            monkeypatch.setattr(sop_bc, "POOL_BACKOFF", on)
            monkeypatch.setattr(sop_bc, "POOL_REPAIR", on)
            result = solve_sop_bc(problem)
            assert result.status == OPTIMAL
            assert result.objective == pytest.approx(plain.objective)
            assert evaluate_order(problem, result.order) == pytest.approx(plain.objective)
            pool = result.info["pool"]
            counts[on][0] += pool["stale"]
            counts[on][1] += pool["repaired"]
    assert counts[True][0] == 0 and counts[True][1] > 0
    assert counts[False][0] > 0 and counts[False][1] == 0
