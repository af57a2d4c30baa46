"""Tests of the TSPLIB .sop loader and the exact SOP model (helper-6).

Solutions are checked without trusting the solver: the decoded order is re-scored
from the cost matrix, every precedence is re-checked, and random instances are
compared with an independent Held–Karp dynamic programme written here.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from taopt.errors import InstanceError, SolverError
from taopt.models import solve_sop
from taopt.models.highs import OPTIMALITY_TOLERANCE
from taopt.models.sop import _check_path, build, describe
from taopt.sop.problem import KNOWN_OPTIMA, load_sop, path_cost, shipped_sop


# ----------------------------------------------------------------------------- helpers
def held_karp_sop(cost: np.ndarray, precedences, start: int, end: int) -> float:
    """Exact SOP optimum by dynamic programming over (visited set, last node).

    A node v may be appended once all its predecessors are visited; ``end`` only
    last. Independent of the MILP (plain Python, n <= 12).
    """
    n = len(cost)
    need = [0] * n
    for r, j in precedences:
        need[j] |= 1 << r
    full = (1 << n) - 1
    best = {(1 << start, start): 0.0}
    for size in range(1, n):
        layer = {}
        for (mask, last), value in best.items():
            if bin(mask).count("1") != size:
                continue
            for v in range(n):
                if mask >> v & 1 or need[v] & ~mask or not np.isfinite(cost[last, v]):
                    continue
                if v == end and (mask | 1 << v) != full:
                    continue
                key = (mask | 1 << v, v)
                cand = value + cost[last, v]
                if cand < layer.get(key, np.inf):
                    layer[key] = cand
        best.update(layer)
    return best.get((full, end), np.inf)


def random_sop(seed: int, n: int):
    """Random asymmetric integer costs, a few random forbidden arcs and precedences."""
    rng = np.random.default_rng(seed)
    cost = rng.integers(0, 50, size=(n, n)).astype(float)
    cost[rng.random((n, n)) < 0.1] = np.inf
    np.fill_diagonal(cost, 0.0)
    inner = rng.permutation(np.arange(1, n - 1))
    precedences = [
        (int(inner[a]), int(inner[b]))
        for a, b in itertools.combinations(range(n - 2), 2)
        if rng.random() < 0.35
    ]
    return cost, precedences, 0, n - 1


def assert_valid_order(order, cost, precedences, start, end, objective):
    n = len(cost)
    assert sorted(order) == list(range(n))
    assert order[0] == start and order[-1] == end
    position = {v: p for p, v in enumerate(order)}
    for r, j in precedences:
        assert position[r] < position[j], f"precedence ({r}, {j}) violated by {order}"
    assert path_cost(cost, order) == pytest.approx(objective, rel=1e-9)


# ----------------------------------------------------------------------------- loader
def test_shipped_files_parse_with_the_tsplib_convention():
    """The shipped SOP files parse with TSPLIB's convention (first token skipped, -1 = precedence)."""
    assert {"ESC07", "ESC11", "ESC12", "br17.10", "br17.12"} <= set(shipped_sop())
    expected = {"ESC07": (9, 7), "ESC11": (13, 5), "ESC12": (14, 11), "br17.10": (18, 15)}
    for name, (n, n_prec) in expected.items():
        cost, precedences, start, end, read_name = load_sop(name)
        assert read_name == name and cost.shape == (n, n)
        assert (start, end) == (0, n - 1)
        assert len(precedences) == n_prec  # inner -1 entries (closed relation)
        assert np.isinf(cost[start, end])
        for r, j in precedences:
            assert np.isinf(cost[j, r])  # the arc back to an earlier node is unusable
            assert start not in (r, j) and end not in (r, j)


def test_loader_rejects_a_non_sop_file(tmp_path):
    """A non-SOP file or an unknown name raises InstanceError."""
    bad = tmp_path / "x.sop"
    bad.write_text("NAME: x\nTYPE: ATSP\nDIMENSION: 2\nEDGE_WEIGHT_FORMAT: FULL_MATRIX\n")
    with pytest.raises(InstanceError, match="SOP"):
        load_sop(bad)
    with pytest.raises(InstanceError, match="no shipped"):
        load_sop("nope")


# ----------------------------------------------------------------------------- TSPLIB
@pytest.mark.parametrize("name", ["ESC07", "ESC11"])
def test_tsplib_optimum_is_certified(name):
    """The flow model certifies TSPLIB's optimum of ESC07 and ESC11."""
    cost, precedences, start, end, _ = load_sop(name)
    sol = solve_sop(cost, precedences, start, end)
    assert sol.status == "optimal"
    assert sol.objective == KNOWN_OPTIMA[name]
    assert sol.bound == pytest.approx(KNOWN_OPTIMA[name], abs=1e-6)
    assert_valid_order(sol.order, cost, precedences, start, end, sol.objective)


def test_held_karp_reproduces_esc07():
    """The test's own DP agrees with the TSPLIB value (it is a valid reference)."""
    cost, precedences, start, end, _ = load_sop("ESC07")
    assert held_karp_sop(cost, precedences, start, end) == KNOWN_OPTIMA["ESC07"]


def test_incumbent_solution_without_an_order_is_ignored():
    """A Solution incumbent that holds no order is ignored like an infeasible one, not a crash."""
    from taopt.result import TIME_LIMIT, make_solution
    from taopt.sop.problem import SopProblem

    cost = np.array([[0, 1, 5, 9], [9, 0, 1, 5], [1, 9, 0, 1], [9, 9, 9, 0.0]])
    problem = SopProblem(cost, ((2, 1),), 0, 3)
    empty = make_solution(problem, None, method="none", status=TIME_LIMIT)
    solution = solve_sop(cost, [(2, 1)], 0, 3, incumbent=empty)
    assert solution.order == [0, 2, 1, 3]
    assert solution.objective == held_karp_sop(cost, [(2, 1)], 0, 3)


def test_mtz_formulation_agrees_on_esc07():
    """The MTZ model certifies the same ESC07 optimum as the flow model."""
    cost, precedences, start, end, _ = load_sop("ESC07")
    sol = solve_sop(cost, precedences, start, end, formulation="mtz")
    assert sol.status == "optimal" and sol.objective == KNOWN_OPTIMA["ESC07"]


def test_time_limit_returns_a_certified_gap_or_no_plan():
    """A time limit gives a valid path with a proven bound, or no plan and a bound; never an
    error and never a fake optimum."""
    cost, precedences, start, end, _ = load_sop("br17.10")
    sol = solve_sop(cost, precedences, start, end, time_limit=1.0)
    assert sol.status in ("time_limit", "optimal")
    assert sol.bound <= KNOWN_OPTIMA["br17.10"] + 1e-6 <= sol.objective + 2e-6
    if sol.order is None:  # no path within the limit: status time_limit, objective inf
        assert sol.status == "time_limit" and sol.objective == float("inf")
    else:
        assert_valid_order(sol.order, cost, precedences, start, end, sol.objective)


def test_loose_mip_gap_is_not_called_optimal():
    """mip_gap=0.5 on ESC12 with the weak MTZ model: HiGHS stops early (review item 4).

    "optimal" is only allowed with a gap within 1e-6; otherwise "feasible",
    stopped by the gap, with a bound below and an incumbent above the TSPLIB optimum.
    """
    cost, precedences, start, end, _ = load_sop("ESC12")
    optimum = KNOWN_OPTIMA["ESC12"]
    for formulation in ("mtz", "flow"):
        sol = solve_sop(cost, precedences, start, end, formulation=formulation, mip_gap=0.5)
        assert_valid_order(sol.order, cost, precedences, start, end, sol.objective)
        assert sol.bound <= optimum + 1e-6 <= sol.objective + 2e-6
        if sol.status == "optimal":
            assert sol.gap <= OPTIMALITY_TOLERANCE
            assert sol.objective == optimum
        else:
            assert sol.status == "feasible" and sol.info["stopped_by"] == "mip_gap"
            assert OPTIMALITY_TOLERANCE < sol.gap <= 0.5 + 1e-9


def test_decoded_path_is_checked_against_precedences_and_model_value():
    """Review item 6: a decoded order is re-checked, never trusted."""
    cost = np.array([[0, 1, 5, 9], [9, 0, 1, 5], [1, 9, 0, 1], [9, 9, 9, 0.0]])
    model = build(cost, [(2, 1)], 0, 3)
    assert _check_path(model, [0, 2, 1, 3], [(2, 1)], 19.0) == 19.0
    with pytest.raises(SolverError, match=r"precedence \(2, 1\) violated"):
        _check_path(model, [0, 1, 2, 3], [(2, 1)], 3.0)
    with pytest.raises(SolverError, match="model's objective"):
        _check_path(model, [0, 2, 1, 3], [(2, 1)], 19.5)


# ----------------------------------------------------------------------------- random
@pytest.mark.parametrize("formulation", ["flow", "mtz"])
@pytest.mark.parametrize("seed", range(6))
def test_random_sop_matches_held_karp(seed, formulation):
    """Random SOPs: the MILP equals an independent Held-Karp DP (or both find none: the MILP
    says "infeasible", it does not raise)."""
    cost, precedences, start, end = random_sop(seed, n=5 + seed % 4)
    expected = held_karp_sop(cost, precedences, start, end)
    sol = solve_sop(cost, precedences, start, end, formulation=formulation)
    if not np.isfinite(expected):
        assert sol.status == "infeasible" and sol.order is None and sol.objective == np.inf
        return
    assert sol.status == "optimal"
    assert sol.objective == pytest.approx(expected, abs=1e-9)
    assert_valid_order(sol.order, cost, precedences, start, end, sol.objective)


def test_precedences_change_the_answer():
    """Without the precedence 2 -> 1 the cheap path 0,1,2,3 is optimal; with it, not."""
    cost = np.array([[0, 1, 5, 9], [9, 0, 1, 5], [1, 9, 0, 1], [9, 9, 9, 0.0]])
    assert solve_sop(cost, [], 0, 3).order == [0, 1, 2, 3]
    sol = solve_sop(cost, [(2, 1)], 0, 3)
    assert sol.order == [0, 2, 1, 3] and sol.objective == 5 + 9 + 5


# ----------------------------------------------------------------------------- input
def test_bad_input_is_rejected_before_solving():
    """Precedence cycles, bad endpoints, shapes and formulations are refused with named errors."""
    cost = np.zeros((4, 4))
    with pytest.raises(InstanceError, match="precedence cycle"):
        solve_sop(cost, [(1, 2), (2, 1)], 0, 3)
    with pytest.raises(InstanceError, match="self-precedence"):
        solve_sop(cost, [(1, 1)], 0, 3)
    with pytest.raises(InstanceError, match="before start"):
        solve_sop(cost, [(1, 0)], 0, 3)
    with pytest.raises(InstanceError, match="square"):
        solve_sop(np.zeros((3, 4)), [], 0, 2)
    with pytest.raises(InstanceError, match="same node"):
        solve_sop(cost, [], 1, 1)
    with pytest.raises(InstanceError, match="formulation"):
        solve_sop(cost, [], 0, 3, formulation="dfj")


def test_describe_lists_labelled_families():
    """describe() lists every labelled constraint family with its row count."""
    cost, precedences, start, end, _ = load_sop("ESC07")
    table = describe(cost, precedences, start, end, show=False)
    labels = " ".join(row["label"] for row in table)
    assert "degree" in labels and "flow conservation" in labels and "(5.7)" in labels
    assert all(row["rows"] > 0 for row in table)
