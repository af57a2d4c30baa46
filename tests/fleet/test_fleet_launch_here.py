"""The truck-timeline sharpening of the sortie-time term (:func:`taopt.fleet.search.
_sortie_time_bound` with :func:`taopt.fleet.cover.one_drone_tables`' ``H``): an aboard drone
launches either before its truck leaves its stop or after T. Checked against the best
completion of every label of tiny instances (brute force over all children, no dominance),
for every number of trucks, drones and capacity tried."""

from __future__ import annotations

import numpy as np
import pytest
from reference_fleet import best_completion, root_label

from taopt.fleet.brute import tiny_instance
from taopt.fleet.cover import one_drone_table, one_drone_tables
from taopt.fleet.search import _bound, _sortie_time_bound, _Tables


def _drone_only(seed: int, n: int, K: int, D: int, c: int, prec: bool, objective: str):
    p = tiny_instance(seed, n, K, D, c, prec, objective, stops=3)
    return p.replace(service=("drone",) * n, customer_stop=(None,) * n)


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("prec", [False, True])
def test_launch_here_table_is_consistent(objective, prec):
    """V = min_v tt(u, v) + H[v, .], H >= V, H[., ∅] = V[., ∅], and V is one_drone_table's."""
    p = _drone_only(41, 4, 1, 2, 2, prec, objective)
    got = one_drone_tables(p)
    assert got is not None
    V, H = got
    assert np.array_equal(V, one_drone_table(p))
    tt = np.asarray(p.truck_time, dtype=float)
    assert np.allclose(V, np.min(tt[:, :, None] + H[None, :, :], axis=1), rtol=1e-12, atol=0)
    assert np.all(H >= V - 1e-12)
    assert np.array_equal(H[:, 0], V[:, 0])


# (K, D, c): one and two trucks, one to three drones each, capacity 1 to 3. Larger shapes
# ((1, 2, 2), (2, 2, 1), (1, 3, 2), (2, 1, 3)) enumerate every label below the root with no
# dominance and ran out of memory (13 GB in one worker); the exact method's equality with the
# brute force on 320 tiny instances (tests/fleet/test_fleet.py, slow) covers them.
SHAPES = [(1, 1, 1), (1, 2, 1), (1, 3, 1), (1, 2, 3), (2, 1, 1)]


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("prec", [False, True])
@pytest.mark.parametrize("shape", SHAPES)
def test_bound_with_launch_here_never_above_a_labels_best_completion(shape, prec, objective):
    """At every label of tiny drone-only instances (n = 3, 3 stops) the label bound is <=
    the best completion below it."""
    K, D, c = shape
    for seed in (5,):
        p = _drone_only(seed + 100 * D + 10 * c + K, 3, K, D, c, prec, objective)
        tab = _Tables(p)
        assert tab.launch_here is not None
        memo: dict = {}
        best_completion(tab, root_label(p), memo)
        for label, best in memo.items():
            b = _bound(tab, label)
            assert b <= best * (1 + 1e-9) + 1e-9, (seed, label, b, best)


def test_launch_here_lifts_the_sortie_term(monkeypatch):
    """On tiny one-truck, two-drone instances the sharpened sortie-time term is above the
    plain one at some labels, never below it, and never above their best completion (the
    term alone, at the labels without a drone that may still take a customer)."""
    lifted = 0
    for seed in (14, 27):
        p = _drone_only(seed, 3, 1, 2, 1, False, "last_service")
        tab = _Tables(p)
        memo: dict = {}
        best_completion(tab, root_label(p), memo)
        closed = [
            (label, best)
            for label, best in memo.items()
            if not any(dr[0] == 1 and dr[5] for tr in label[3] for dr in tr[6])
        ]
        sharp = [
            _sortie_time_bound(tab, tab.drone_only & ~label[0], label[3]) for label, _ in closed
        ]
        with monkeypatch.context() as m:
            m.setattr(tab, "launch_here", None)
            plain = [
                _sortie_time_bound(tab, tab.drone_only & ~label[0], label[3]) for label, _ in closed
            ]
        for a, b, (_, best) in zip(sharp, plain, closed, strict=True):
            assert b - 1e-9 <= a <= best * (1 + 1e-9) + 1e-9
        lifted += sum(a > b + 1e-9 for a, b in zip(sharp, plain, strict=True))
    assert lifted > 0
