"""Split-dependent releases in the fleet's split DP (:func:`taopt.fleet.sorties.split_dp`):
every split's bound with releases lies between the release-free one and the brute-force
optimum restricted to that split."""

from __future__ import annotations

import networkx as nx
import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.problem import FleetProblem
from taopt.fleet.sorties import _sequences, _sortie_dp, _table, split_dp


def _drone_only(seed: int, n: int, trucks: int, capacity: int, objective: str) -> FleetProblem:
    p = tiny_instance(seed, n, trucks, 1, capacity, True, objective, stops=3)
    return p.replace(service=["drone"] * p.n, customer_stop=[None] * p.n)


def _owner(key: tuple[int, ...], n: int) -> list[int]:
    return [next(k for k, m in enumerate(key) if m >> j & 1) for j in range(n)]


def _check_splits(n: int, seeds: range, capacity: int, objective: str) -> int:
    """Assert the bracket on every split; return how many splits the releases raised."""
    raised = 0
    for seed in seeds:
        p = _drone_only(700 + seed, n, 2, capacity, objective)
        closure = {(int(r), int(j)) for r, j in nx.transitive_closure_dag(p.precedence_graph).edges}
        seqs = _sequences(p, closure)
        pre = (seqs, _table(p, seqs))
        trace: list = []
        split_dp(p, trace=trace)
        for bound, _value, key, _release in trace:
            free = max(
                _sortie_dp(p, None, None, False, m, closure, pre)["value"] if m else 0.0
                for m in key
            )
            restricted = brute_force(p, truck_of=_owner(key, p.n))[0]
            assert free <= bound + 1e-9
            assert bound <= restricted + 1e-9
            raised += bound > free + 1e-9
    return raised


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("capacity", [1, 2])
def test_split_dp_released_split_bounds_never_above_the_restricted_optimum(capacity, objective):
    """Per split (n = 3): release-free bound <= released bound <= restricted optimum."""
    _check_splits(3, range(4), capacity, objective)


@pytest.mark.slow
@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("capacity", [1, 2])
def test_split_dp_releases_bite_and_stay_valid_at_four_customers(capacity, objective):
    """Per split (n = 4): the bracket holds and the releases raise some split's bound."""
    assert _check_splits(4, range(4), capacity, objective) > 0
