"""The label bound's cheaper computations (issue 32) give the very values of the plain ones:
the per-drone first legs and fresh sorties against a reference written out plainly, the
least-largest split over the kept sets against every assignment, and the whole bound with
its caches warm (labels in search order) against cold caches, on a few hundred labels of
small instances (the search's labels: children of children of the root)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from taopt.fleet.instances import residential_fleet
from taopt.fleet.search import (
    INF,
    _air_reach,
    _bound,
    _children,
    _first_recoveries,
    _fresh_sorties,
    _kept_pairs,
    _least_largest_at,
    _release_floors,
    _release_rows,
    _Tables,
    _tail_table,
)

# one truck with two and three drones, capacity 1 and 2, precedences (residential)
SHAPES = [(6, 1, 2, 1), (6, 1, 2, 2), (6, 1, 3, 1), (6, 2, 1, 2)]


def _labels(p, count: int = 300) -> list[tuple]:
    """Up to ``count`` labels of the search tree, breadth first from the root, with a
    stride so that deeper labels (airborne drones, served customers) are among them."""
    tab = _Tables(p, walk=False)
    root_trucks = tuple(
        (p.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d))) for d in p.drones
    )
    layer = [(0, 0.0, (-1.0,) * p.n, root_trucks)]
    out: list[tuple] = []
    for _ in range(6):
        nxt = [child for label in layer for child, _act in _children(tab, label)]
        step = max(1, len(nxt) // 60)
        out += nxt[::step]
        layer = nxt[:: max(1, len(nxt) // 200)]
    return out[:count]


def _reference_first(tab, k, w, A, T, dr, S, svc, times) -> np.ndarray:
    """:func:`_first_recoveries` written out plainly (every customer, every stop)."""
    ws = -dr[1] - 1
    t, delta, seen = dr[3], dr[4], dr[7]
    fresh = not tab.lazy or dr[6]
    back = np.full(tab.s, INF)
    for j in range(tab.n):
        if S >> j & 1 or not tab.drone_ok[j]:
            continue
        if tab.owner is not None and tab.owner[j] != k:
            continue
        if not fresh and not tab.pred_mask[j] & ~seen:
            continue
        dist = delta + tab.fsd[j][ws]
        if dist + tab.near[j] > tab.limit:
            continue
        a = t + tab.fst[j][ws] + tab.tau
        for r in tab.preds[j]:
            if S >> r & 1:
                a = max(a, svc[r])
            elif times is not None:
                a = max(a, times[r])
        a = max(a, tab.release[j])
        for q in range(tab.s):
            if dist + tab.fsd[j][q] > tab.limit:
                continue
            arrive = A if q == w else T + tab.tt[w][q]
            back[q] = min(back[q], max(a + tab.fst[j][q], arrive) + tab.tau)
    return back


def _reference_fresh(tab, trucks, S, svc) -> list:
    """:func:`_fresh_sorties` written out plainly (one drive-and-fly step per drone)."""
    out = []
    for k, (w, A, T, _ev, fin, _F, drones) in enumerate(trucks):
        if fin or not drones:
            out.append(None)
            continue
        best = np.full(tab.n, INF)
        for dr in drones:
            if dr[0] == 0:
                a = max(dr[1], A)
                best = np.minimum(best, np.minimum(tab.Fnp[w] + a, tab.Gnp[w] + T))
                continue
            if dr[2] == 0:
                back = _reference_first(tab, k, w, A, T, dr, S, svc, None)
            else:
                arrive = T + tab.tt_np[w]
                arrive[w] = A
                o = dr[1]
                back = np.maximum(dr[3] + tab.fst_np[o], arrive) + tab.tau
                back[dr[4] + tab.fsd_np[o] > tab.limit] = INF
            best = np.minimum(best, (back[:, None] + tab.Gnp).min(axis=0))
        out.append((best + tab.tau).tolist())
    return out


@pytest.mark.parametrize("shape", SHAPES)
def test_first_legs_and_fresh_sorties_equal_the_plain_computation(shape):
    """On a few hundred labels, every launched drone's first-recovery bound (with and
    without earliest services) and the fresh-sortie times equal the plain computation."""
    n, K, D, c = shape
    p = residential_fleet(n, K, D, c, seed=3)
    tab = _Tables(p)
    labels = _labels(p)
    assert len(labels) >= 100
    firsts = 0
    rng = np.random.default_rng(0)
    for S, _M, svc, trucks in labels:
        times = [float(x) for x in rng.uniform(0.0, 300.0, p.n)]
        for k, (w, A, T, _ev, fin, _F, drones) in enumerate(trucks):
            for dr in drones:
                if fin or dr[0] != 1 or dr[2] != 0:
                    continue
                firsts += 1
                for tms in (None, times):
                    got = _first_recoveries(tab, k, w, A, T, dr, S, svc, tms)
                    want = _reference_first(tab, k, w, A, T, dr, S, svc, tms)
                    assert np.array_equal(got, want), (S, dr)
        assert _fresh_sorties(tab, trucks, S, svc) == _reference_fresh(tab, trucks, S, svc)
    assert firsts >= 20


@pytest.mark.parametrize("drones", [1, 2, 3])
def test_least_largest_over_kept_sets_equals_every_assignment(drones):
    """The least-largest split over the kept sets U \\ X (X ⊆ drop, |X| <= count) equals
    the least, over those sets and every assignment of them to the drones, of the largest
    drone's end."""
    rng = np.random.default_rng(drones)
    p = residential_fleet(6, 1, 2, 1, seed=0)
    tab = _Tables(p)
    for trial in range(30):
        U = int(rng.integers(1, 1 << p.n))
        cust = [j for j in range(p.n) if U >> j & 1]
        m = len(cust)
        drop = int(rng.integers(0, 1 << p.n)) & U
        count = int(rng.integers(1, 4))
        ends = [rng.uniform(0, 10, 1 << m) for _ in range(drones)]
        for e in ends:
            e[0] = 0.0
        local = [i for i, j in enumerate(cust) if drop >> j & 1]
        expected = math.inf
        for size in range(min(count, len(local)) + 1):
            for X in itertools.combinations(local, size):
                Z = [i for i in range(m) if i not in X]
                for a in itertools.product(range(drones), repeat=len(Z)):
                    parts = [
                        sum(1 << i for i, d in zip(Z, a, strict=True) if d == e)
                        for e in range(drones)
                    ]
                    expected = min(expected, max(ends[e][parts[e]] for e in range(drones)))
        assert _least_largest_at(ends, m, _kept_pairs(tab, U, drop, count)) == expected, trial
        full = min(
            max(ends[e][sum(1 << i for i in range(m) if a[i] == e)] for e in range(drones))
            for a in itertools.product(range(drones), repeat=m)
        )
        assert _least_largest_at(ends, m) == full


@pytest.mark.parametrize("shape", SHAPES)
def test_bound_with_warm_caches_equals_cold(shape):
    """The label bound computed in search order on one table (its caches warm) equals the
    bound of each label on a table whose caches are emptied before it, at no cutoff and at
    a cutoff near the label's value (where the early returns are taken)."""
    n, K, D, c = shape
    p = residential_fleet(n, K, D, c, seed=5)
    warm = _Tables(p)
    cold = _Tables(p)
    caches = [
        name for name, v in vars(cold).items() if name.startswith("_") and isinstance(v, dict)
    ]
    for label in _labels(p):
        v = _bound(warm, label)
        for name in caches:
            getattr(cold, name).clear()
        cold._arrive_key = None
        assert _bound(cold, label) == v
        if v < INF:
            assert _bound(warm, label, 1.01 * v) == _bound(cold, label, 1.01 * v)


@pytest.mark.parametrize("drones", [2, 3])
def test_release_floors_equal_the_sequential_computation(drones):
    """The release term's releases, taken for all customers at once then raised along the
    precedences, equal the customer-by-customer computation in a topological order, on
    random drone ends, earliest services and served sets of a residential instance."""
    p = residential_fleet(6, 1, drones, 1, seed=2)
    tab = _Tables(p)
    assert tab.lazy
    rng = np.random.default_rng(drones)
    hop, _tail, anc, _desc = _tail_table(tab)
    for trial in range(40):
        S = int(rng.integers(0, 1 << p.n))
        U = tab.full & ~S
        if not U:
            continue
        m = bin(U).count("1")
        drop = int(rng.integers(0, 1 << p.n)) & U if trial % 2 else 0
        rows = _release_rows(tab, U, drones, drop, 1 if drop else 0)
        if rows is None:
            continue
        parts = tab._release_parts[(U, drones, drop, 1 if drop else 0)]
        plain = [rng.uniform(0, 100, 1 << m) for _ in range(drones)]
        for e in plain:
            e[0] = 0.0
        svc = tuple(float(x) for x in rng.uniform(0, 100, p.n))
        times = [float(x) for x in rng.uniform(0, 150, p.n)]
        got = _release_floors(tab, rows, plain, S, svc, times)
        cust = [j for j in range(p.n) if U >> j & 1]
        loc = {X: i for i, X in enumerate(x for x in range(1 << p.n) if not x & ~U)}
        for row, owners in enumerate(parts):
            owner = {j: d for d in range(drones) for j in cust if owners[d] >> j & 1}
            L: dict[int, float] = {}
            for j in tab.topo:
                if not U >> j & 1:
                    continue
                v = max(
                    plain[d][loc[(owners[d] & anc[j]) | (1 << j if owner.get(j) == d else 0)]]
                    for d in range(drones)
                )
                v = max(v, times[j], tab.release[j])
                v = max([v] + [svc[r] for r in tab.preds[j] if S >> r & 1])
                for r in tab.preds[j]:
                    if U >> r & 1:
                        same = r in owner and owner.get(j) == owner[r]
                        v = max(v, L[r] + (hop[r][j] if same else 0.0))
                L[j] = v
            assert [got[i, row] for i in range(m)] == [L[j] for j in rows[1]], (trial, row)


@pytest.mark.parametrize("shape", [(6, 1, 2, 2), (6, 1, 3, 2), (6, 2, 1, 3)])
def test_air_reach_equals_the_two_passes(shape):
    """Per airborne drone with room, the memoised reach equals the plain two passes over
    the customers (the rule on a stale drone first, then any customer within range)."""
    n, K, D, c = shape
    p = residential_fleet(n, K, D, c, seed=4)
    tab = _Tables(p)
    checked = 0
    for S, _M, _svc, trucks in _labels(p):
        for k, tr in enumerate(trucks):
            for dr in tr[6]:
                if tr[4] or not (dr[0] == 1 and dr[5] and dr[2] < tab.c):
                    continue
                o, passes, rule = dr[1], [], tab.lazy and not dr[6]
                flights = {}
                while True:
                    takes = 0
                    for j in range(tab.n):
                        if S >> j & 1 or not tab.drone_ok[j]:
                            continue
                        if rule and not tab.pred_mask[j] & ~dr[7]:
                            continue
                        if o >= 0:
                            dist, fly = tab.fcd[o][j], tab.fct[o][j]
                        else:
                            dist, fly = tab.fsd[j][-o - 1], tab.fst[j][-o - 1]
                        if dr[4] + dist + tab.near[j] <= tab.limit:
                            takes |= 1 << j
                            flights[j] = fly
                    passes.append(takes)
                    if not (rule and takes and tab.c - dr[2] >= 2):
                        break
                    rule = False
                later = passes[1] if len(passes) == 2 else 0
                extra = tab.c - dr[2] - 1 if len(passes) == 2 else 0
                got = _air_reach(tab, k, dr, S)
                assert got[:3] == (passes[0], later, extra)
                assert sorted(got[3]) == sorted(flights.items())
                checked += 1
    assert checked >= 20
