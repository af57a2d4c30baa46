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
* :func:`rbg_from_atsp`: a stand-in for TSPLIB's rbg SOP family built from the same
  stacker-crane application's ATSP moves (``rbg403``/``rbg443``) with precedences from the
  jobs' time windows (an interval order, as rbg048a and rbg050c are), the unseen rbg
  instances of issue 33.
* :func:`rbg_like_sop` and :func:`esc_like_sop`: the first stand-ins for TSPLIB's rbg and ESC
  families (chains with cross links to a closure share, uniform costs 0-33, unlike the real
  rbg files: CP-SAT finds no order on them; sparse random precedences, costs up to 1000).

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


def _window_pairs(release: np.ndarray, width: np.ndarray, share: float) -> np.ndarray:
    """The pairs ``i -> j`` with ``release[i] + s * width[i] < release[j]`` for the largest
    scale ``s`` whose pairs hold at least ``share`` of all pairs (bisection: the pairs only
    shrink as ``s`` grows); an interval order, transitively closed by construction."""
    m = len(release)
    wanted = share * m * (m - 1) / 2

    def pairs(scale: float) -> np.ndarray:
        return (release + scale * width)[:, None] < release[None, :]

    low, high = 0.0, float(release.max() - release.min() + 1) / max(float(width.min()), 1e-9)
    if pairs(low).sum() < wanted:  # the jobs of one batch are never ordered
        raise ValueError(
            f"closure {share:g} is beyond the {pairs(low).sum() / (m * (m - 1) / 2):.3f} the "
            "batches allow: ask smaller batches"
        )
    for _ in range(60):
        mid = (low + high) / 2
        if pairs(mid).sum() >= wanted:
            low = mid
        else:
            high = mid
    return pairs(low)


def rbg_from_atsp(
    cost: np.ndarray,
    n: int,
    seed: int,
    closure: float = 0.85,
    batch: float = 6.0,
    contiguous: bool = True,
) -> SopProblem:
    """A stand-in for TSPLIB's rbg SOP family from a stacker-crane ATSP matrix.

    TSPLIB's rbg SOP files and its rbg ATSP files (``rbg403``, ``rbg443``) come from the
    same stacker-crane application (Ascheuer; "Stacker crane application (Norbert
    Ascheuer)" in the files' COMMENT, see ``shared/benchmarks/tsplib/README.md``): the
    costs are the crane's moves between jobs, the precedences come from the jobs' time
    windows (a job whose window closes before another's opens goes first).

    Parameters
    ----------
    cost : numpy.ndarray
        The ATSP matrix (``rbg403``/``rbg443``: integer moves 0-33, 7 % zeros); ``n - 2``
        of its nodes become the jobs.
    n : int
        Nodes of the SOP: a start (cost 0 to every job), the jobs, an end (cost 0 from every
        job), as in the rbg files.
    seed : int
    closure : float
        Share of the job pairs that are ordered (the precedences are their own transitive
        closure). The larger rbg files hold 5,000-64,000 precedence pairs on 111-380 nodes,
        about 0.8-0.89 of the pairs; rbg048a and rbg050c 0.40-0.42.
    batch : float
        Mean number of jobs released together: each job gets the release time of its batch
        and a window of exponential length (one scale for all, set by bisection to reach
        ``closure``); ``i`` precedes ``j`` when ``i``'s window closes before ``j``'s
        release. The precedences then form an interval order with at most one distinct
        predecessor set per batch, as in rbg048a and rbg050c (8 and 14 distinct
        predecessor sets on 48 and 50 jobs; both interval orders).
    contiguous : bool
        The jobs are ``n - 2`` consecutive nodes of the matrix from a random first one (a
        stretch of the crane's work, its jobs at neighbouring places: the ATSP files list
        jobs of the same place next to each other); False: drawn at random from all.

    Returns
    -------
    SopProblem
        Start 0, end ``n - 1``, the jobs numbered by release (the rbg files list them so).

    Example
    -------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> p = rbg_from_atsp(rng.integers(0, 34, size=(60, 60)).astype(float), 40, 1, closure=0.5)
    >>> p.n, p.start, p.end
    (40, 0, 39)
    """
    source = np.asarray(cost, dtype=float)
    m = n - 2
    if m < 1 or m > source.shape[0]:
        raise ValueError(f"rbg_from_atsp: n={n} needs 1..{source.shape[0]} jobs, not {m}")
    rng = np.random.default_rng([38, n, seed])
    if contiguous:
        first = int(rng.integers(0, source.shape[0] - m + 1))
        jobs = np.arange(first, first + m)
    else:
        jobs = np.sort(rng.choice(source.shape[0], size=m, replace=False))
    batches = max(2, round(m / batch))
    release = np.sort(rng.integers(0, batches, size=m)).astype(float)
    width = rng.exponential(1.0, size=m)
    ordered = _window_pairs(release, width, closure)
    data = np.full((n, n), np.inf)
    data[1:-1, 1:-1] = source[np.ix_(jobs, jobs)]
    data[0, 1:-1] = 0.0  # the start: no move yet
    data[1:-1, -1] = 0.0  # the end: nothing after the last job
    np.fill_diagonal(data, 0.0)
    a, b = np.nonzero(ordered)
    pairs = tuple((int(i) + 1, int(j) + 1) for i, j in zip(a, b, strict=True))
    return SopProblem(data, pairs, 0, n - 1, f"rbg-atsp-{n}-{closure:g}-{seed}")


__all__ = ["random_sop", "chain_sop", "atsp_sop", "rbg_like_sop", "esc_like_sop", "rbg_from_atsp"]
