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
  to a copy of node 0, with :func:`random_sop`'s precedences.

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


def atsp_sop(cost: np.ndarray, density: float, seed: int) -> SopProblem:
    """An SOP from an ATSP matrix: node 0 starts, a copy of node 0 ends, random precedences
    of ``density`` among the other nodes."""
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
    pairs = _pairs_from_order(inner, density, rng)
    return SopProblem(data, tuple(pairs), 0, m, f"atsp-{m}-{density:g}-{seed}")


__all__ = ["random_sop", "chain_sop", "atsp_sop"]
