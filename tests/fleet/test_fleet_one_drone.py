"""The one-drone table (:func:`taopt.fleet.cover.one_drone_table`) and the label bound's
one-drone term (:func:`taopt.fleet.search._sortie_time_bound`): the table equals brute force
on tiny one-truck, one-drone instances; the bound never exceeds the best completion of any
label of tiny several-drone instances."""

from __future__ import annotations

import math

import numpy as np
import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.cover import one_drone_table
from taopt.fleet.problem import FleetProblem
from taopt.fleet.search import _bound, _children, _complete, _sortie_time_bound, _Tables


def _drone_only(seed: int, n: int, drones: int, c: int, prec: bool, objective: str):
    """A tiny one-truck instance with every customer drone-only."""
    p = tiny_instance(seed, n, 1, drones, c, prec, objective, stops=2)
    return p.replace(service=("drone",) * n, customer_stop=(None,) * n)


def _restricted(p: FleetProblem, X: int) -> FleetProblem:
    """``p`` with one drone and only the customers of X (the pairs inside X kept)."""
    keep = [j for j in range(p.n) if X >> j & 1]
    col = {j: i for i, j in enumerate(keep)}
    return p.replace(
        customers=np.asarray(p.customers)[keep],
        drones=(1,),
        service=("drone",) * len(keep),
        customer_stop=(None,) * len(keep),
        precedences=tuple((col[r], col[j]) for r, j in p.precedences if r in col and j in col),
    )


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("c", [1, 2])
@pytest.mark.parametrize("prec", [False, True])
def test_one_drone_table_equals_brute_force(objective, c, prec):
    """V[depot, X] equals the brute-force optimum of one truck and one drone serving X."""
    for seed in (3, 11):
        p = _drone_only(seed, 3, 1, c, prec, objective)
        V = one_drone_table(p)
        assert V is not None
        for X in range(1, 1 << p.n):
            value, _, _ = brute_force(_restricted(p, X))
            assert V[p.depot, X] == pytest.approx(value, rel=1e-9, abs=1e-9), (seed, X)


def _best_below(tab: _Tables, label: tuple, memo: dict, check: list) -> float:
    """The least objective over every completion of ``label`` (all children, no dominance),
    recording (bound, best) for each label visited."""
    got = memo.get(label)
    if got is not None:
        return got
    if _complete(tab, label):
        trucks = label[3]
        best = max(tr[5] for tr in trucks) if tab.ret else label[1]
    else:
        best = math.inf
        for child, _ in _children(tab, label):
            best = min(best, _best_below(tab, child, memo, check))
    memo[label] = best
    # the term alone where no airborne drone may still take a customer (_bound leaves those
    # customers out of it)
    open_ = any(dr[0] == 1 and dr[5] for tr in label[3] for dr in tr[6])
    term = 0.0 if open_ else _sortie_time_bound(tab, tab.drone_only & ~label[0], label[3])
    check.append((_bound(tab, label), term, best))
    return best


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("drones,c", [(2, 1), (2, 2), pytest.param(3, 1, marks=pytest.mark.slow)])
@pytest.mark.parametrize("prec", [False, True])
def test_bound_is_below_every_labels_best_completion(objective, drones, c, prec):
    """At every label of a tiny one-truck instance (n = 3, several drones) the label bound
    and its one-drone term are <= the best completion below it."""
    p = _drone_only(7 + drones + 3 * c, 3, drones, c, prec, objective)
    tab = _Tables(p)
    assert tab.one_drone
    trucks = tuple(
        (p.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d))) for d in p.drones
    )
    root = (0, 0.0, (-1.0,) * p.n, trucks)
    check: list = []
    opt = _best_below(tab, root, {}, check)
    assert opt < math.inf
    for bound, term, best in check:
        assert term <= best * (1 + 1e-9) + 1e-9
        if bound < math.inf:
            assert bound <= best * (1 + 1e-9) + 1e-9


def test_one_drone_table_stops_on_its_cap_and_deadline(monkeypatch):
    """Over its work cap or past its deadline the table is None, and the search falls back to
    the precedence-free table and still proves the brute-force optimum."""
    from taopt.fleet import cover
    from taopt.fleet.instances import residential_fleet
    from taopt.fleet.search import label_search
    from taopt.runtime import Deadline

    assert one_drone_table(residential_fleet(5, 1, 2, 2, seed=1), Deadline(0.0)) is None
    p = _drone_only(5, 3, 2, 2, True, "last_service")
    monkeypatch.setattr(cover, "ONE_DRONE_MAX_WORK", 0)
    assert one_drone_table(p) is None
    tab = _Tables(p)
    assert not tab.one_drone and tab.sortie_time is not None
    value, _, _ = brute_force(p)
    result = label_search(p, beam=0)
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("objective", ["last_service", "return"])
def test_split_set_values_match_the_free_dp_without_precedences(objective):
    """Without precedences the split DP's set values (the one-drone table) equal its
    precedence-free sortie DP over every subset; with them they are no lower."""
    from taopt.fleet.instances import residential_fleet
    from taopt.fleet.sorties import _free_values, _set_values
    from taopt.runtime import Deadline

    p = residential_fleet(5, 2, 1, 2, seed=2, objective=objective)
    assert p.precedences
    q = p.replace(precedences=())
    assert _set_values(q, Deadline(None)) == pytest.approx(_free_values(q), rel=1e-9)
    free = _free_values(p)
    got = _set_values(p, Deadline(None))
    assert got is not None
    assert all(a >= b * (1 - 1e-9) for a, b in zip(got, free, strict=True))


def test_split_dp_with_no_time_returns_a_proven_bound():
    """split_dp with a zero limit stops at once: time_limit with bound 0 (never above the
    optimum), no exception."""
    from taopt.fleet.instances import residential_fleet
    from taopt.fleet.sorties import split_dp

    result = split_dp(residential_fleet(6, 2, 1, 2, seed=0), time_limit=0.0)
    assert result["stopped_by"] == "time_limit"
    assert result["bound"] == 0.0
