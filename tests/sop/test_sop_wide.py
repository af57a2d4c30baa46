"""Order ideals beyond 64 nodes (issue 33 item 1): multi-word masks in the core and the SOP DP.

Checked without trusting the wide code: counts against a subset enumeration and the one-word
masks, the DP on wide masks against brute force and against the one-word DP (forcing wide
masks on small instances by lowering ``taopt.ideals.MAX_BITS``), and a DP certificate on
more than 64 nodes against an optimum known by construction.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import taopt.ideals as ideals_module
from taopt.ideals import count_ideals, ideal_layers, predecessor_masks, to_int
from taopt.models.sop import solve_sop_problem
from taopt.models.sop_dp import completion_bound, solve_sop_dp
from taopt.models.sop_dp import count_ideals as sop_count
from taopt.result import OPTIMAL
from taopt.sop.generate import atsp_sop, chain_sop, random_sop
from taopt.sop.problem import SopProblem, evaluate_order, path_cost


@pytest.fixture
def wide(monkeypatch):
    """Masks of more than 2 nodes are rows of words (as beyond 64 nodes)."""
    monkeypatch.setattr(ideals_module, "MAX_BITS", 2)


def _random_pairs(n: int, density: float, seed: int) -> list[tuple[int, int]]:
    rng = np.random.default_rng([33, seed])
    order = rng.permutation(n)
    return [
        (int(order[a]), int(order[b]))
        for a, b in itertools.combinations(range(n), 2)
        if rng.random() < density
    ]


def _subset_ideals(n: int, pairs: list[tuple[int, int]]) -> int:
    return sum(all((m >> j) & 1 == 0 or (m >> r) & 1 for r, j in pairs) for m in range(1 << n))


@pytest.mark.parametrize("seed", range(4))
def test_wide_ideal_count_equals_a_subset_enumeration(seed, wide):
    """Wide masks count the same ideals as enumerating all 2^n subsets."""
    n = 9
    pairs = _random_pairs(n, 0.25, seed)
    need = predecessor_masks(n, pairs)
    assert need.ndim == 2
    assert count_ideals(need, n) == (_subset_ideals(n, pairs), False)


def test_wide_layers_hold_the_same_sets_as_one_word_layers(monkeypatch):
    """The layers on wide masks are the one-word layers, set for set."""
    n, pairs = 10, _random_pairs(10, 0.2, 7)
    narrow = ideal_layers(predecessor_masks(n, pairs), n, cap=10_000)
    monkeypatch.setattr(ideals_module, "MAX_BITS", 3)
    spread = ideal_layers(predecessor_masks(n, pairs), n, cap=10_000)
    assert narrow is not None and spread is not None
    assert [sorted(int(m) for m in a) for a in narrow] == [
        sorted(to_int(row) for row in b) for b in spread
    ]


def test_count_beyond_64_nodes_equals_the_chain_formula():
    """Three chains of 40, 40, 41 nodes (123 in all) have 41 * 41 * 42 ideals."""
    sizes = [40, 40, 41]
    pairs, at = [], 0
    for size in sizes:
        pairs += [(at + i, at + i + 1) for i in range(size - 1)]
        at += size
    n = sum(sizes)
    assert count_ideals(predecessor_masks(n, pairs), n, cap=100_000) == (41 * 41 * 42, False)


def _brute_force(problem: SopProblem) -> float:
    rest = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    best = np.inf
    for perm in itertools.permutations(rest):
        order = [problem.start, *perm, problem.end]
        where = {v: k for k, v in enumerate(order)}
        if all(where[r] < where[j] for r, j in problem.precedences):
            best = min(best, path_cost(problem.cost, order))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_wide_dp_equals_brute_force(seed, wide):
    """On wide masks the DP's optimum is brute force's (n = 8, densities 0 to 0.5)."""
    problem = random_sop(8, 0.1 * seed, seed)
    result = solve_sop_dp(problem)
    assert result.status == OPTIMAL
    assert result.objective == _brute_force(problem)
    assert evaluate_order(problem, result.order) == result.objective


@pytest.mark.parametrize(
    "name",
    [
        "ESC07",
        "ESC11",
        "ESC12",
        pytest.param("br17.10", marks=pytest.mark.slow),
        pytest.param("br17.12", marks=pytest.mark.slow),
        pytest.param("rbg048a", marks=pytest.mark.slow),
    ],
)
def test_wide_dp_equals_the_one_word_dp_on_shipped_files(name, monkeypatch):
    """Forcing wide masks leaves the answer, bound and states of the DP unchanged."""
    problem = SopProblem.load(name)
    narrow = solve_sop_dp(problem)
    monkeypatch.setattr(ideals_module, "MAX_BITS", 4)
    spread = solve_sop_dp(problem)
    assert (spread.status, spread.objective, spread.bound) == (
        narrow.status,
        narrow.objective,
        narrow.bound,
    )
    assert spread.info["states"] == narrow.info["states"]


def test_wide_completion_bound_equals_the_one_word_bound(monkeypatch):
    """The completion bound of a state does not depend on the mask's width."""
    problem = random_sop(9, 0.2, 3)
    states = [({0}, 0), ({0, 2, 5}, 5), (set(range(8)), 7)]
    states = [(s, v) for s, v in states if all(r in s for r, j in problem.precedences if j in s)]
    narrow = [completion_bound(problem, s, v) for s, v in states]
    monkeypatch.setattr(ideals_module, "MAX_BITS", 3)
    assert [completion_bound(problem, s, v) for s, v in states] == narrow


def padded(base: SopProblem, tail: int, seed: int) -> tuple[SopProblem, float]:
    """``base`` followed by a forced chain of ``tail`` nodes, node labels shuffled.

    Every inner node of ``base`` precedes the chain, entering the chain's head from ``v``
    costs ``base.cost[v, base.end]``: the optimum is ``base``'s plus the chain's arcs.
    """
    rng = np.random.default_rng([33, 1, seed])
    m = base.n
    n = m - 1 + tail + 1  # base without its end, the chain, a new end
    inner = [v for v in range(m) if v not in (base.start, base.end)]
    cost = rng.integers(1, 100, size=(n, n)).astype(float)
    keep = [v for v in range(m) if v != base.end]
    cost[np.ix_(keep, keep)] = base.cost[np.ix_(keep, keep)]
    chain = list(range(m - 1, m - 1 + tail))
    for v in keep:
        cost[v, chain[0]] = base.cost[v, base.end]
    links = [float(cost[a, b]) for a, b in itertools.pairwise(chain)]
    cost[chain[-1], n - 1] = 0.0
    pairs = [p for p in base.precedences if base.end not in p]
    pairs += [(v, chain[0]) for v in inner] + list(itertools.pairwise(chain))
    relabel = rng.permutation(n)
    shuffled = np.empty_like(cost)
    shuffled[np.ix_(relabel, relabel)] = cost
    problem = SopProblem(
        shuffled,
        tuple((int(relabel[a]), int(relabel[b])) for a, b in pairs),
        int(relabel[base.start]),
        int(relabel[n - 1]),
        f"padded-{base.name}",
    )
    return problem, sum(links)


def test_dp_certifies_a_problem_of_more_than_64_nodes_at_its_known_optimum():
    """A 10-node problem padded by a forced chain to 67 nodes (two words a mask): the DP
    proves the base optimum plus the chain."""
    base = random_sop(10, 0.2, 5)
    problem, extra = padded(base, 57, 5)
    assert problem.n == 67
    expected = _brute_force(base) + extra
    result = solve_sop_dp(problem, beam_width=0)
    assert result.status == OPTIMAL and result.objective == expected
    assert evaluate_order(problem, result.order) == expected


@pytest.mark.slow
def test_portfolio_picks_the_dp_beyond_64_nodes_by_the_ideal_count():
    """The portfolio runs the DP on 80 nodes with few ideals and proves the known optimum."""
    base = random_sop(10, 0.2, 5)
    problem, extra = padded(base, 70, 5)
    expected = _brute_force(base) + extra
    portfolio = solve_sop_problem(problem, cpsat=False)  # the rule's own choice, CP-SAT aside
    assert portfolio.status == OPTIMAL and portfolio.objective == expected
    assert portfolio.info["engine"] == "dp" and not portfolio.info["ideals_capped"]


def test_generated_instances_are_valid():
    """The generators make valid SOPs of the asked size (chains: few ideals)."""
    assert chain_sop(90, 3, 0).n == 90
    assert sop_count(chain_sop(90, 3, 0), cap=100_000)[0] <= 31**3
    ftv = np.random.default_rng(0).integers(1, 50, size=(12, 12)).astype(float)
    problem = atsp_sop(ftv, 0.2, 0)
    assert problem.n == 13 and problem.start == 0 and problem.end == 12
    assert solve_sop_dp(problem).status == OPTIMAL


def test_above_the_memory_limit_the_portfolio_degrades_instead_of_refusing():
    """A MILP above the memory limit is skipped, not refused: time_limit (or optimal) with
    a feasible order and a bound no higher than its cost (was an InstanceError)."""
    import taopt

    problem = random_sop(40, 0.05, 3)
    result = taopt.solve(problem, "exact", time_limit=1.0, max_memory_gb=0.08)
    assert str(result.status) in ("time_limit", "optimal")
    assert evaluate_order(problem, result.order) == result.objective
    assert 0 < result.bound <= result.objective
    assert result.info["milp"].startswith("skipped")


def test_building_the_flow_model_stops_at_the_deadline():
    """An expired deadline stops the flow model's construction (BuildStopped), none builds."""
    from taopt.models.sop import BuildStopped, build
    from taopt.runtime import Deadline

    problem = random_sop(12, 0.2, 1)
    args = (problem.cost, problem.precedences, problem.start, problem.end)
    with pytest.raises(BuildStopped):
        build(*args, deadline=Deadline(1e-9))
    assert build(*args, deadline=Deadline(None)).flow is not None


@pytest.mark.parametrize("n, density", [(9, 0.0), (20, 0.1), (40, 0.3), (70, 0.05), (120, 0.2)])
def test_matching_prices_are_optimal_assignment_duals(n, density):
    """The prices from the matching (used beyond 64 nodes) leave no negative reduced cost
    and sum to the assignment bound, as the LP's do."""
    from taopt.models.sop import assignment_bound, usable_arcs
    from taopt.models.sop_dp import _matching_potentials

    problem = random_sop(n, density, 4)
    tails, heads = usable_arcs(problem.cost, problem.closure)
    usable = np.full((n, n), np.inf)
    usable[tails, heads] = problem.cost[tails, heads]
    prices = _matching_potentials(usable, problem.start, problem.end)
    assert prices is not None
    alpha, beta = prices
    reduced = usable - alpha[:, None] - beta[None, :]
    assert reduced[np.isfinite(reduced)].min() >= 0.0
    total = alpha.sum() - alpha[problem.end] + beta.sum() - beta[problem.start]
    expected = assignment_bound(problem.cost, problem.closure, problem.start, problem.end)
    assert total == pytest.approx(expected, rel=1e-9)
