"""taopt.ideals: the order ideals both exact DPs (chapter 5, SOP) run over."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from taopt.ideals import count_ideals, ideal_layers, predecessor_masks


def _random_pairs(n: int, seed: int) -> list[tuple[int, int]]:
    """A random DAG by index order (r < j)."""
    rng = np.random.default_rng([31, seed])
    return [(r, j) for r, j in itertools.combinations(range(n), 2) if rng.random() < 0.3]


def _brute_force_ideals(n: int, pairs: list[tuple[int, int]], first: int = 0) -> set[int]:
    """Every subset (as a mask) holding ``first`` and closed under predecessors."""
    return {
        mask
        for mask in range(1 << n)
        if mask & first == first and all(not (mask >> j) & 1 or (mask >> r) & 1 for r, j in pairs)
    }


@pytest.mark.parametrize("seed", range(12))
def test_layers_are_exactly_the_down_sets_by_size(seed):
    """ideal_layers enumerates every down-set once, layer k holding those of k nodes (brute
    force over all 2^n subsets), from the empty set and from a given first ideal."""
    n = 3 + seed % 6
    pairs = _random_pairs(n, seed)
    need = predecessor_masks(n, pairs)
    layers = ideal_layers(need, n, cap=1 << n)
    found = [int(m) for layer in layers for m in layer]
    assert len(found) == len(set(found))
    assert set(found) == _brute_force_ideals(n, pairs)
    assert all(int(m).bit_count() == k for k, layer in enumerate(layers) for m in layer)
    assert count_ideals(need, n) == (len(found), False)
    root = 1 << 0  # node 0 has no predecessor: {0} is an ideal
    assert count_ideals(need, n, first=root)[0] == len(_brute_force_ideals(n, pairs, root))


def test_cap_and_size_limits():
    """Past the cap (or 64 nodes) the count says so instead of enumerating."""
    free = predecessor_masks(10, [])
    assert count_ideals(free, 10) == (1024, False)
    assert count_ideals(free, 10, cap=100) == (101, True)
    assert ideal_layers(free, 10, cap=100) is None
    assert count_ideals(predecessor_masks(65, []), 65, cap=5) == (6, True)


def test_both_families_count_through_the_core():
    """The delivery DP's and the SOP DP's counts agree with the core's on their DAGs."""
    import taopt
    from taopt.delivery.ideal_dp import count_ideals as delivery_count
    from taopt.models.sop_dp import count_ideals as sop_count

    instance = taopt.DeliveryInstance.grid(
        np.random.default_rng(3).uniform(0, 600, size=(7, 2)), 3, 600.0, 1.0, 1.0, 700.0,
        precedences=[(0, 1), (1, 2), (3, 4)],
    )  # fmt: skip
    need = predecessor_masks(7, instance.precedences)
    # chains 0<1<2 (4 down-sets) and 3<4 (3), nodes 5 and 6 free (2 each): 4 * 3 * 2 * 2
    assert delivery_count(instance) == count_ideals(need, 7)[0] == 4 * 3 * 2 * 2
    sop = taopt.SopProblem.load("ESC07")
    closure = predecessor_masks(sop.n, sop.closure.edges)
    assert sop_count(sop) == count_ideals(closure, sop.n, first=1 << sop.start) == (41, False)


def test_count_stops_at_an_expired_deadline_or_a_proven_cap():
    """Given a deadline, the count ends as capped when it has expired, or when a layer's
    candidates alone prove more than ``cap`` ideals; the exact count otherwise."""
    from taopt.runtime import Deadline

    free = predecessor_masks(12, [])  # 2^12 ideals
    assert count_ideals(free, 12, cap=10**6, deadline=Deadline(0.0)) == (10**6 + 1, True)
    assert count_ideals(free, 12, cap=100, deadline=Deadline(60.0)) == (101, True)
    assert count_ideals(free, 12, cap=10**6, deadline=Deadline(60.0)) == (2**12, False)
