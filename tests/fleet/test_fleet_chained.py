"""The chained-recovery term of the fleet label bound
(:func:`taopt.fleet.search._chained_recoveries`, issue 32): the first recoveries of several
airborne drones of one truck made one after another on its timeline. At every label of tiny
label trees the bound with the term is <= the label's best completion (every completion,
no dominance: :func:`reference_fleet.best_completion`), the term lifts some labels above the
bound without it, and the label search with it proves the brute-force optimum on one truck
with two or three drones."""

from __future__ import annotations

import math

import pytest
from reference_fleet import best_completion, root_label

import taopt.fleet.search as search
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.search import _bound, _Tables, label_search

#: (seed, n, D, c, stops, precedence, objective): drone-only tiny instances (K = 1) with labels
#: the chained term lifts (found by a scan over seeds). With D = 2 the term is switched on
#: for two drones (``CHAIN_MIN_DRONES = 2``; its proof does not depend on the count).
CHAINED_CASES = [
    (18, 3, 3, 1, 2, False, "return"),
    (17, 3, 3, 1, 2, False, "return"),
    (29, 3, 3, 1, 2, True, "return"),
    pytest.param((5, 4, 2, 1, 2, True, "last_service"), marks=pytest.mark.slow),
    pytest.param((12, 3, 3, 1, 2, True, "return"), marks=pytest.mark.slow),
    pytest.param((5, 3, 3, 1, 2, True, "return"), marks=pytest.mark.slow),
    pytest.param((1, 4, 2, 1, 2, True, "last_service"), marks=pytest.mark.slow),
    pytest.param((6, 4, 2, 1, 2, False, "last_service"), marks=pytest.mark.slow),
]


def _drone_only(seed: int, n: int, D: int, c: int, stops: int, precedence: bool, objective: str):
    p = tiny_instance(seed, n, 1, D, c, precedence, objective, stops=stops)
    p = p.replace(service=("drone",) * n, customer_stop=(None,) * n)
    assert bool(p.precedences) == precedence
    return p


@pytest.mark.parametrize("case", CHAINED_CASES)
def test_chained_recoveries_never_above_a_labels_best_completion(case, monkeypatch):
    """At every label the bound with the chained term is <= the best completion below it,
    and the term lifts some labels above the bound without it."""
    seed, n, D, c, stops, precedence, objective = case
    monkeypatch.setattr(search, "CHAIN_MIN_DRONES", 2)
    p = _drone_only(seed, n, D, c, stops, precedence, objective)
    tab = _Tables(p)
    seen: list = []
    memo: dict = {}
    assert best_completion(tab, root_label(p), memo, seen) < math.inf
    for bound, best in seen:
        assert bound <= best * (1 + 1e-9) + 1e-9
    monkeypatch.setattr(search, "CHAIN_MIN_DRONES", 99)  # the term off
    # (memo and seen are filled together, in the same order)
    lifted = sum(
        bound > _bound(tab, label) + 1e-9 for label, (bound, _) in zip(memo, seen, strict=True)
    )
    assert lifted > 0


@pytest.mark.parametrize("case", CHAINED_CASES[:2])
def test_chained_recoveries_with_a_cutoff(case, monkeypatch):
    """With a cutoff the bound is the one without it where that is below the cutoff, and
    at least the cutoff where that is not (the caller prunes the same labels)."""
    seed, n, D, c, stops, precedence, objective = case
    monkeypatch.setattr(search, "CHAIN_MIN_DRONES", 2)
    p = _drone_only(seed, n, D, c, stops, precedence, objective)
    tab = _Tables(p)
    memo: dict = {}
    best_completion(tab, root_label(p), memo)
    for label in list(memo)[:400]:
        plain = _bound(tab, label)
        if not plain < math.inf:
            continue
        for cutoff in (0.9 * plain, plain * (1 - 1e-9), 1.05 * plain):
            cut = _bound(tab, label, cutoff)
            assert cut <= plain * (1 + 1e-12)
            assert (cut >= cutoff) == (plain >= cutoff)


def _one_truck(seed: int) -> tuple:
    """A tiny one-truck instance: D in {2, 3}, c in {1, 2, 3}, with and without precedence,
    both objectives (n = 3, 2 stops, the seed picks the shape)."""
    D = 2 + seed % 2
    c = 1 + (seed // 2) % 3
    precedence = bool((seed // 6) % 2)
    objective = ("last_service", "return")[(seed // 12) % 2]
    return tiny_instance(seed, 3, 1, D, c, precedence, objective, stops=2), (D, c)


@pytest.mark.parametrize(
    "seed", [*range(500, 504), *(pytest.param(s, marks=pytest.mark.slow) for s in range(504, 548))]
)
def test_search_with_the_chained_term_equals_brute_force(seed, monkeypatch):
    """The label search (no beam, the term on for two drones or more) proves the brute-force
    optimum on tiny one-truck instances (24 shapes of D, c, precedence and objective over
    seeds 500-547)."""
    monkeypatch.setattr(search, "CHAIN_MIN_DRONES", 2)
    problem, _ = _one_truck(seed)
    value, plan, _ = brute_force(problem)
    result = label_search(problem, beam=0)
    if plan is None:
        assert result["plan"] is None
        return
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)
