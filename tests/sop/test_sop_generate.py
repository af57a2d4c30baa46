"""The stand-ins for the unseen TSPLIB SOP families (``taopt.sop.generate``) and the DP's
per-ideal completion bound on them (issue 33)."""

from __future__ import annotations

import numpy as np
import pytest
from reference_exact import sop_brute_force

from taopt.models import sop_dp
from taopt.models.sop import solve_sop_problem
from taopt.result import OPTIMAL
from taopt.sop.generate import atsp_sop, esc_like_sop, random_sop, rbg_from_atsp, rbg_like_sop
from taopt.sop.problem import evaluate_order


def _inner_share(problem) -> float:
    """The closure's share of the pairs of inner nodes (start and end pairs left out)."""
    ends = {problem.start, problem.end}
    inner = sum(1 for a, b in problem.closure.edges if a not in ends and b not in ends)
    m = problem.n - 2
    return inner / (m * (m - 1) / 2)


@pytest.mark.parametrize(
    ("n", "share", "low", "high"), [(110, 0.85, 5_000, 6_000), (380, 0.89, 63_000, 66_000)]
)
def test_rbg_like_closure_is_in_the_rbg_range(n, share, low, high):
    """rbg-like instances are acyclic SOPs whose closure holds 5,000-64,000 pairs at 110-380
    nodes, the asked share of inner pairs, with integer costs in [0, 33]."""
    problem = rbg_like_sop(n, 1, share)  # SopProblem refuses a cyclic precedence
    assert problem.n == n and (problem.start, problem.end) == (0, n - 1)
    assert low <= problem.closure.number_of_edges() <= high
    assert share <= _inner_share(problem) < share + 0.02
    off = problem.cost[~np.eye(n, dtype=bool)]
    assert off.min() >= 0 and off.max() <= 33 and np.all(off == np.round(off))


def test_esc_like_and_atsp_closure_shares():
    """ESC-like and ATSP-derived instances reach the asked closure share (TSPLIB's .2/.3)."""
    esc = esc_like_sop(65, 1, 0.15)
    assert esc.n == 65 and 0.15 <= _inner_share(esc) < 0.17
    cost = np.random.default_rng(0).integers(1, 50, size=(30, 30)).astype(float)
    sop = atsp_sop(cost, 0.0, 2, closure=0.3)
    assert sop.n == 31 and 0.3 <= _inner_share(sop) < 0.33


def test_generators_are_deterministic():
    """Same arguments, same instance (costs and precedences)."""
    a, b = rbg_like_sop(60, 3, 0.6), rbg_like_sop(60, 3, 0.6)
    assert np.array_equal(a.cost, b.cost) and a.precedences == b.precedences


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_portfolio_equals_brute_force_on_small_rbg_like(seed):
    """The portfolio proves the brute-force optimum of a 10-node rbg-like instance."""
    problem = rbg_like_sop(10, seed, 0.5, chains=2)
    expected = sop_brute_force(problem)
    result = solve_sop_problem(problem, time_limit=30)
    assert result.status == OPTIMAL and result.objective == expected
    assert evaluate_order(problem, result.order) == expected


def test_dense_and_per_node_ideal_bounds_agree(monkeypatch):
    """The completion bound's dense per-ideal minima equal the per-node binary searches on
    the states of a 70-node rbg-like instance (two-word masks)."""
    problem = rbg_like_sop(70, 4, 0.7)
    search = sop_dp._Search(problem)
    layer = search.first()[:3]
    for _ in range(8):
        layer = search.grow(*layer, sop_dp.Deadline(None))[:3]
    mask, last = layer[0], layer[1]
    monkeypatch.setattr(sop_dp, "DENSE_ARC_SHARE", 0.0)  # dense whatever the arcs
    dense = search.bound(mask, last)
    monkeypatch.setattr(sop_dp, "DENSE_NODES", 0)  # per-node binary searches
    assert np.allclose(dense, search.bound(mask, last))


@pytest.mark.slow
def test_portfolio_certifies_a_wide_rbg_like_instance():
    """On 70 nodes with dense precedence the portfolio proves an optimum that the
    forward-only DP without a beam (another search order) proves too."""
    problem = rbg_like_sop(70, 2, 0.9)
    result = solve_sop_problem(problem, time_limit=60)
    assert result.status == OPTIMAL and not result.info["ideals_capped"]
    assert evaluate_order(problem, result.order) == result.objective
    again = sop_dp.solve_sop_dp(problem, beam_width=0, both=False)
    assert again.status == OPTIMAL and again.objective == result.objective


def test_dp_rate_of_the_memory_estimate_falls_beyond_64_nodes():
    """The states a DP stage is expected to make (keep) per second halve at 128 (256) nodes, so
    the guard at 60 s of a 150-node rbg-like instance counts at most that many states."""
    from taopt.models.sop import (
        BASE_BYTES,
        DP_STATES_PER_SECOND,
        GUARD_FILL_FACTOR,
        GUARD_STATE_FACTOR,
        _footprint,
        dp_bytes,
        dp_states_in,
        dp_states_per_second,
        fill_states,
    )

    assert dp_states_per_second(40) == dp_states_per_second(64) == DP_STATES_PER_SECOND
    assert dp_states_per_second(128) == DP_STATES_PER_SECOND / 2
    assert fill_states(256, 60.0, False) == fill_states(64, 60.0, False) / 2
    problem = rbg_like_sop(150, 1, 0.8)
    estimate, _ = _footprint(problem, {"time_limit": 60.0, "engine": "dp", "cpsat": False})
    fill = GUARD_FILL_FACTOR * fill_states(150, 60.0, False)
    states = max(GUARD_STATE_FACTOR * dp_states_in(150, 60.0), fill)
    assert estimate <= BASE_BYTES + dp_bytes(150, states) + 1


def test_dp_state_share_of_the_estimate_falls_with_denser_precedence():
    """A state's estimated bytes fall with the closure's share, within [0.2, 1]."""
    from taopt.models.sop import dp_state_share

    shares = [dp_state_share(esc_like_sop(60, 1, 0.1))]
    shares += [dp_state_share(rbg_like_sop(60, 1, c)) for c in (0.5, 0.9)]
    assert shares[0] >= shares[1] >= shares[2]
    assert all(0.2 <= s <= 1.0 for s in shares) and shares[0] == 1.0


def _crane_moves() -> np.ndarray:
    """The inner moves of the shipped rbg048a (the stacker-crane application of rbg403 and
    rbg443): a small ATSP matrix for :func:`rbg_from_atsp`."""
    from taopt.sop.problem import SopProblem

    cost = SopProblem.load("rbg048a").cost[1:-1, 1:-1].copy()
    cost[~np.isfinite(cost)] = 33.0  # the ordered pairs' arcs: any move of the range
    return cost


@pytest.mark.parametrize(("n", "share", "batch"), [(30, 0.4, 6.0), (40, 0.85, 3.0)])
def test_rbg_from_atsp_is_valid_at_the_closure_asked(n, share, batch):
    """rbg_from_atsp gives an acyclic SOP (start 0, end n - 1) whose closed precedences hold
    at least the asked share of job pairs, an interval order (the jobs' predecessor sets
    nested), with the source's costs between jobs and free start and end moves."""
    problem = rbg_from_atsp(_crane_moves(), n, 3, share, batch)  # SopProblem refuses a cycle
    assert (problem.n, problem.start, problem.end) == (n, 0, n - 1)
    assert share <= _inner_share(problem) < share + 0.1
    assert len(problem.precedences) == problem.closure.number_of_edges() - 2 * (n - 2) - 1
    ends = {0, n - 1}
    preds = [
        frozenset(a for a in problem.closure.predecessors(v) if a not in ends)
        for v in range(1, n - 1)
    ]
    assert all(a <= b or b <= a for a in preds for b in preds)
    assert np.all(problem.cost[0, 1:-1] == 0) and np.all(problem.cost[1:-1, -1] == 0)
    inner = problem.cost[1:-1, 1:-1][~np.eye(n - 2, dtype=bool)]
    assert inner.min() >= 0 and inner.max() <= 33


def test_rbg_from_atsp_is_deterministic_per_seed():
    """Same arguments, same instance; another seed, another instance."""
    moves = _crane_moves()
    a, b = rbg_from_atsp(moves, 36, 5, 0.6), rbg_from_atsp(moves, 36, 5, 0.6)
    assert np.array_equal(a.cost, b.cost) and a.precedences == b.precedences
    c = rbg_from_atsp(moves, 36, 6, 0.6)
    assert not (np.array_equal(a.cost, c.cost) and a.precedences == c.precedences)


def test_rbg_from_atsp_names_what_it_cannot_build():
    """More jobs than the matrix has, or a closure the batches cannot reach, is an error
    naming the size or the closure."""
    with pytest.raises(ValueError, match="n=60"):
        rbg_from_atsp(np.zeros((40, 40)), 60, 1)
    with pytest.raises(ValueError, match="closure 0.95"):
        rbg_from_atsp(np.zeros((40, 40)), 30, 1, 0.95, batch=10.0)


@pytest.mark.parametrize("seed", [0, 1])
def test_portfolio_equals_brute_force_on_small_rbg_from_atsp(seed):
    """The portfolio proves the brute-force optimum of a 10-node crane instance."""
    problem = rbg_from_atsp(_crane_moves(), 10, seed, 0.4, batch=2.0, contiguous=False)
    expected = sop_brute_force(problem)
    result = solve_sop_problem(problem, time_limit=30)
    assert result.status == OPTIMAL and result.objective == expected
    assert evaluate_order(problem, result.order) == expected


@pytest.mark.slow
def test_portfolio_equals_cpsat_proof_on_a_crane_instance():
    """On a 24-node crane instance the portfolio's own stages (CP-SAT off) prove the optimum
    that CP-SAT, run alone, proves too."""
    from taopt.heuristics.peers import cpsat_sop

    problem = rbg_from_atsp(_crane_moves(), 24, 2, 0.4, batch=3.0)
    ours = solve_sop_problem(problem, time_limit=30, cpsat=False)
    theirs = cpsat_sop(problem, time_limit=30)
    assert ours.status == OPTIMAL and theirs.status == OPTIMAL
    assert ours.objective == theirs.objective == evaluate_order(problem, ours.order)


@pytest.mark.parametrize(
    "problem",
    [random_sop(14, 0.5, 3), rbg_like_sop(70, 4, 0.7), rbg_like_sop(130, 2, 0.85)],
    ids=["random-14-dense", "rbg-like-70", "rbg-like-130"],
)
def test_band_and_per_node_ideal_bounds_agree(problem, monkeypatch):
    """The completion bound confined to the layer's band equals the per-node binary searches."""
    search = sop_dp._Search(problem)
    layer = search.first()[:3]
    for _ in range(min(10, problem.n - 3)):
        layer = search.grow(*layer, sop_dp.Deadline(None))[:3]
        monkeypatch.setattr(sop_dp, "BAND", True)
        band = search.bound(layer[0], layer[1])
        monkeypatch.setattr(sop_dp, "BAND", False)
        monkeypatch.setattr(sop_dp, "DENSE_NODES", 0)  # per-node binary searches
        assert np.allclose(band, search.bound(layer[0], layer[1]), equal_nan=True)
        assert np.isfinite(band).any()


@pytest.mark.parametrize("seed", range(6))
def test_band_dp_equals_brute_force_on_dense_precedence(seed):
    """The DP with the band's completion bound, each direction and both met, proves the
    brute-force optimum of random 10-node SOPs with dense precedence."""
    problem = random_sop(10, 0.6 + 0.05 * seed, seed)
    expected = sop_brute_force(problem)
    for both in (False, True):
        result = sop_dp.solve_sop_dp(problem, beam_width=0, both=both)
        assert result.status == OPTIMAL and result.objective == expected
        assert result.bound <= expected + 1e-9
