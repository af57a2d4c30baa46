"""Generated SOP instances: random precedences of any density, chains, ATSP-derived.

The exact engine is checked on instances it was not built against; these are the families
the tests and ``benchmarks/bench_sop.py`` draw from (seeded, deterministic).

* :func:`random_sop`: integer costs in ``[1, 100]`` and random acyclic precedences: the
  inner nodes in a random order, each pair of that order a precedence with probability
  ``density`` (0: a TSP path; 1: a single chain).
* :func:`chain_sop`: the inner nodes split into ``chains`` totally ordered chains (as the
  jobs of a stacker crane, the rbg family of TSPLIB) and a share ``cross`` of random pairs
  between chains: few ideals (at most the product of the chain lengths plus one), many
  nodes.
* :func:`atsp_sop`: an ATSP cost matrix (a TSPLIB ``.atsp`` file) made a path from node 0
  to a copy of node 0, with :func:`random_sop`'s precedences or random pairs up to a
  closure share (``closure=``, TSPLIB's .1-.4 densities).
* :func:`rbg_like_sop` and :func:`esc_like_sop`: stand-ins for TSPLIB's rbg and ESC families
  (chains with cross links to a closure share, small integer costs; sparse random
  precedences, costs up to 1000), the unseen instances of issue 33.

Example
-------
>>> p = chain_sop(80, chains=3, seed=1)
>>> p.n, p.start, p.end
(80, 0, 79)
"""

from __future__ import annotations

import numpy as np

from taopt.sop.problem import SopProblem


def _pairs_from_order(order: np.ndarray, density: float, rng: np.random.Generator) -> list:
    """Each pair ``(order[a], order[b])``, a < b, with probability ``density``."""
    m = len(order)
    if m < 2 or density <= 0:
        return []
    a, b = np.triu_indices(m, 1)
    chosen = rng.random(len(a)) < density
    return [(int(order[i]), int(order[j])) for i, j in zip(a[chosen], b[chosen], strict=True)]


def random_sop(n: int, density: float, seed: int, high: int = 100) -> SopProblem:
    """A random SOP of ``n`` nodes (start 0, end n - 1) with precedence ``density``."""
    rng = np.random.default_rng([33, n, seed])
    cost = rng.integers(1, high + 1, size=(n, n)).astype(float)
    np.fill_diagonal(cost, 0.0)
    inner = rng.permutation(np.arange(1, n - 1))
    pairs = _pairs_from_order(inner, density, rng)
    return SopProblem(cost, tuple(pairs), 0, n - 1, f"random-{n}-{density:g}-{seed}")


def chain_sop(n: int, chains: int, seed: int, cross: float = 0.0, high: int = 100) -> SopProblem:
    """A random SOP whose inner nodes form ``chains`` chains (plus ``cross`` random pairs
    between them, kept acyclic by a random interleaving of the chains)."""
    rng = np.random.default_rng([34, n, chains, seed])
    cost = rng.integers(1, high + 1, size=(n, n)).astype(float)
    np.fill_diagonal(cost, 0.0)
    inner = rng.permutation(np.arange(1, n - 1))
    label = rng.integers(0, chains, size=len(inner))
    pairs: list[tuple[int, int]] = []
    for c in range(chains):
        members = inner[label == c]
        pairs += [(int(a), int(b)) for a, b in zip(members[:-1], members[1:], strict=True)]
    # cross pairs follow the order of `inner`, which every chain respects: acyclic
    pairs += [p for p in _pairs_from_order(inner, cross, rng) if p not in set(pairs)]
    return SopProblem(cost, tuple(pairs), 0, n - 1, f"chains-{n}-{chains}-{seed}")


def atsp_sop(
    cost: np.ndarray, density: float, seed: int, closure: float | None = None
) -> SopProblem:
    """An SOP from an ATSP matrix: node 0 starts, a copy of node 0 ends, random precedences
    of ``density`` among the other nodes; or, given ``closure``, random pairs added until
    their transitive closure holds that share of the inner pairs (TSPLIB's .1-.4 files:
    about 0.01, 0.15, 0.30, 0.60)."""
    rng = np.random.default_rng([35, cost.shape[0], seed])
    m = cost.shape[0]
    n = m + 1
    data = np.zeros((n, n))
    data[:m, :m] = cost
    data[:m, m] = cost[:, 0]  # into the end copy of node 0
    data[m, :] = np.inf  # nothing leaves the end
    data[:, 0] = np.inf  # nothing enters the start
    data[0, m] = np.inf  # start -> end directly is not a path through everything
    np.fill_diagonal(data, 0.0)
    inner = rng.permutation(np.arange(1, m))
    if closure is None:
        pairs = _pairs_from_order(inner, density, rng)
        return SopProblem(data, tuple(pairs), 0, m, f"atsp-{m}-{density:g}-{seed}")
    a, b = np.triu_indices(len(inner), 1)
    pick = rng.permutation(len(a))
    pairs = _to_closure(inner, [], [(int(inner[a[i]]), int(inner[b[i]])) for i in pick], closure)
    return SopProblem(data, tuple(pairs), 0, m, f"atsp-{m}-c{closure:g}-{seed}")


def _closure_pairs(order: np.ndarray, pairs: list[tuple[int, int]]) -> int:
    """The number of pairs in the transitive closure of ``pairs`` (all consistent with
    ``order``): reachability as Python-int bitsets, swept against ``order``."""
    successors: dict[int, list[int]] = {}
    for a, b in pairs:
        successors.setdefault(a, []).append(b)
    reach: dict[int, int] = {}
    total = 0
    for v in order[::-1]:
        bits = 0
        for s in successors.get(int(v), ()):
            bits |= (1 << s) | reach[s]
        reach[int(v)] = bits
        total += bits.bit_count()
    return total


def _to_closure(
    order: np.ndarray, base: list[tuple[int, int]], extra: list[tuple[int, int]], share: float
) -> list[tuple[int, int]]:
    """``base`` and the shortest prefix of ``extra`` whose closure holds at least ``share`` of
    the pairs of ``order`` (bisection: the closure only grows with the prefix)."""
    m = len(order)
    wanted = share * m * (m - 1) / 2
    low, high = 0, len(extra)
    while low < high:
        mid = (low + high) // 2
        if _closure_pairs(order, base + extra[:mid]) >= wanted:
            high = mid
        else:
            low = mid + 1
    return base + extra[:low]


def rbg_like_sop(
    n: int, seed: int, closure: float = 0.85, chains: int = 4, high: int = 33
) -> SopProblem:
    """A stand-in for TSPLIB's rbg family (stacker-crane schedules): the inner nodes form
    ``chains`` chains, linked across by random pairs until the transitive closure holds a
    share ``closure`` of all inner pairs; integer costs in ``[0, high]`` (rbg048a and
    rbg050c: 0-33, closure 0.44-0.46; the larger rbg files: 5,000-64,000 closure pairs on
    109-380 nodes, about 0.85-0.89). Few ideals, many nodes: the ideal DP's home ground."""
    rng = np.random.default_rng([36, n, seed])
    cost = rng.integers(0, high + 1, size=(n, n)).astype(float)
    np.fill_diagonal(cost, 0.0)
    inner = rng.permutation(np.arange(1, n - 1))
    label = rng.integers(0, chains, size=len(inner))
    base: list[tuple[int, int]] = []
    for c in range(chains):
        members = inner[label == c]
        base += [(int(a), int(b)) for a, b in zip(members[:-1], members[1:], strict=True)]
    # cross links between chains, short ones first (a crane's jobs overlap locally), each
    # following `inner`, which every chain respects: acyclic
    m = len(inner)
    a, b = np.triu_indices(m, 1)
    cross = label[a] != label[b]
    a, b = a[cross], b[cross]
    key = (b - a) * rng.uniform(0.5, 1.5, size=len(a))
    pick = np.argsort(key, kind="stable")
    extra = [(int(inner[a[i]]), int(inner[b[i]])) for i in pick]
    pairs = _to_closure(inner, base, extra, closure)
    return SopProblem(cost, tuple(pairs), 0, n - 1, f"rbg-like-{n}-{closure:g}-{seed}")


def esc_like_sop(n: int, seed: int, closure: float = 0.15, high: int = 1000) -> SopProblem:
    """A stand-in for TSPLIB's ESC family (60-80 nodes in ESC63, ESC78): random precedences
    (pairs of a random order, added until the closure holds ``closure`` of the inner pairs;
    ESC25 and ESC47: 0.11-0.18) and integer costs in ``[0, high]`` with one in twenty 0
    (ESC's zero-cost arcs make many orders tie)."""
    rng = np.random.default_rng([37, n, seed])
    cost = rng.integers(0, high + 1, size=(n, n)).astype(float)
    cost[rng.random((n, n)) < 0.05] = 0.0
    np.fill_diagonal(cost, 0.0)
    inner = rng.permutation(np.arange(1, n - 1))
    m = len(inner)
    a, b = np.triu_indices(m, 1)
    pick = rng.permutation(len(a))
    extra = [(int(inner[a[i]]), int(inner[b[i]])) for i in pick]
    pairs = _to_closure(inner, [], extra, closure)
    return SopProblem(cost, tuple(pairs), 0, n - 1, f"esc-like-{n}-{closure:g}-{seed}")


__all__ = ["random_sop", "chain_sop", "atsp_sop", "rbg_like_sop", "esc_like_sop"]
