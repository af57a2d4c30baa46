"""The fleet label search resumed from its memo (:func:`taopt.fleet.search.label_search`,
``memo``): a search stopped by its label cap or clock and continued ends exact, under a lower
cutoff or a higher floor too; a memo is only reused for the same releases and cut."""

from __future__ import annotations

import math

import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.search import label_search

# (seed, K, D, c, objective): n = 3 with precedence, 3 stops; each needs 31-74 labels, so a
# cap rising by STEP stops it several times
CASES = [
    (724, 1, 1, 1, "return"),
    (813, 1, 2, 1, "return"),
    (822, 1, 2, 2, "last_service"),
    (852, 1, 2, 2, "return"),
    (866, 2, 1, 1, "last_service"),
    (880, 2, 1, 1, "return"),
    (901, 2, 1, 2, "last_service"),
    (923, 2, 1, 2, "return"),
    (941, 2, 2, 1, "last_service"),
    (967, 2, 2, 1, "return"),
    (982, 2, 2, 2, "last_service"),
    (1001, 2, 2, 2, "return"),
]

#: Labels added to the cap at each resumed run.
STEP = 6


def _instance(case: tuple):
    seed, K, D, c, objective = case
    return tiny_instance(seed, 3, K, D, c, True, objective, stops=3)


def _stopped(problem, memo: dict, cap: int = STEP, **kwargs) -> dict:
    """One run stopped by the label cap, its search left in ``memo``."""
    found = label_search(problem, max_labels=cap, memo=memo, beam=0, **kwargs)
    assert found["stopped_by"] == "size"
    assert "state" in memo
    return found


@pytest.mark.parametrize("case", CASES, ids=[str(c) for c in CASES])
def test_resumed_search_reaches_the_brute_force_optimum(case):
    """Stopped by the label cap and resumed with its memo again and again, the search ends
    with the brute-force optimum, a feasible plan of that value and an emptied memo."""
    p = _instance(case)
    optimum, _, _ = brute_force(p)
    memo: dict = {}
    cap, runs, bounds = STEP, 0, []
    while True:
        runs += 1
        found = label_search(p, max_labels=cap, memo=memo, beam=0)
        if found["stopped_by"] != "size":
            break
        assert found["bound"] <= optimum * (1 + 1e-9)
        bounds.append(found["bound"])
        cap += STEP
    assert runs >= 3
    assert bounds == sorted(bounds)  # the proven bound never falls when resumed
    assert found["stopped_by"] == "optimal" and found["resumed"]
    assert math.isclose(found["value"], optimum, rel_tol=1e-9)
    assert math.isclose(evaluate_fleet(p, found["plan"]), optimum, rel_tol=1e-9)
    assert "state" not in memo


@pytest.mark.parametrize("case", CASES[::3], ids=[str(c) for c in CASES[::3]])
def test_resumed_with_lower_cutoff_or_higher_floor_is_exact(case):
    """Resumed with a cutoff just above the optimum, or a floor raised to it, the search
    still ends with the optimum; with a cutoff below it, with a bound no higher than it."""
    p = _instance(case)
    optimum, _, _ = brute_force(p)
    memo: dict = {}
    _stopped(p, memo)
    found = label_search(p, memo=memo, beam=0, cutoff=optimum * (1 + 1e-6))
    assert found["resumed"] and found["stopped_by"] == "optimal"
    assert math.isclose(found["value"], optimum, rel_tol=1e-9)
    memo = {}
    _stopped(p, memo)
    found = label_search(p, memo=memo, beam=0, floor=optimum)
    assert found["resumed"] and math.isclose(found["value"], optimum, rel_tol=1e-9)
    memo = {}
    _stopped(p, memo)
    found = label_search(p, memo=memo, beam=0, cutoff=optimum * 0.99)
    assert found["resumed"] and found["stopped_by"] == "optimal"
    assert found["bound"] <= optimum


def test_resumed_after_the_clock_is_exact():
    """A run stopped by its clock (no time at all) and resumed without a limit ends with the
    brute-force optimum."""
    p = _instance(CASES[6])
    optimum, _, _ = brute_force(p)
    memo: dict = {}
    first = label_search(p, time_limit=0.0, memo=memo, beam=0)
    assert first["stopped_by"] == "time_limit" and first["bound"] <= optimum
    found = label_search(p, memo=memo, beam=0)
    assert found["resumed"] and math.isclose(found["value"], optimum, rel_tol=1e-9)


def test_memo_with_other_release_or_higher_cut_is_not_reused():
    """A memo left under one ``release`` (or one cutoff) is not continued under another
    release (or a higher cutoff): the run starts fresh and equals a run without a memo."""
    p = _instance(CASES[9])
    release = [0.0, 40.0, 0.0]
    memo: dict = {}
    _stopped(p, memo, release=[0.0] * p.n)
    found = label_search(p, memo=memo, beam=0, release=release)
    alone = label_search(p, beam=0, release=release)
    assert not found["resumed"]
    assert math.isclose(found["value"], alone["value"], rel_tol=1e-9)
    assert found["labels"] == alone["labels"]
    optimum, _, _ = brute_force(p)
    memo = {}
    _stopped(p, memo, cutoff=optimum * 1.001)
    found = label_search(p, memo=memo, beam=0)
    assert not found["resumed"]
    assert math.isclose(found["value"], optimum, rel_tol=1e-9)
