"""Chapter 2's subtour rows (2.5): the arc list and their exact separation.

:func:`separate_subtours` finds every subset S of targets whose (2.5) row a fractional or
integral σ violates (reachability, then one maximum flow per target); :func:`cut_rows` writes
the rows of given subsets, each in its sparser equivalent form. They serve the core's DFJ LP
bound (:func:`taopt.routing.bounds.lp_bound`) and the exact models' DFJ loops
(:mod:`taopt.models.routing.dfj`, :mod:`taopt.models.budgeted`), which import them from here.

References
----------
Thesis (2.5); Padberg and Rinaldi's exact separation of subtour constraints.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, maximum_flow

from taopt.routing.problem import AssignmentProblem


def arc_list(problem: AssignmentProblem) -> tuple[np.ndarray, np.ndarray]:
    """Tails and heads of every arc ``i -> j``, ``i ∈ T ∪ R``, ``j ∈ T``, ``i ≠ j``.

    Row-major order of the masked ``(n + m) × n`` matrix of σ.
    """
    n, size = problem.n, problem.n + problem.m
    mask = np.ones((size, n), dtype=bool)
    mask[np.arange(n), np.arange(n)] = False  # σ_ii = 0: no self loops
    tails, heads = np.nonzero(mask)
    return tails, heads


#: A DFJ row (2.5) counts as violated when it is off by more than this.
CUT_TOLERANCE = 1e-6


#: Fixed-point scale of σ for scipy's integer maximum flow (errors below 2**-25 per arc).
_FLOW_SCALE = 2**24


def new_subsets(cuts: Any, known: set[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """The subsets of ``cuts`` (each sorted into a tuple) not in ``known`` and of at least two
    targets, in order; each is added to ``known``. The bookkeeping of every model that keeps a
    pool of (2.5) rows (the DFJ loop, the budgeted models)."""
    new = []
    for subset in cuts:
        subset = tuple(sorted(int(v) for v in subset))
        if len(subset) >= 2 and subset not in known:
            known.add(subset)
            new.append(subset)
    return new


def cut_rows(
    problem: AssignmentProblem,
    cuts: list[tuple[int, ...]],
    tails: np.ndarray,
    heads: np.ndarray,
) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """(2.5) rows for the subsets ``cuts``, each in its sparser equivalent form.

    For a subset S of targets, (2.5) reads ``Σ_{i,j∈S} σ_ij ≤ |S| − 1``
    (``|S|(|S| − 1)`` coefficients). Summing (2.3) over S gives
    ``Σ_{i,j∈S} σ_ij + Σ_{i∉S, j∈S} σ_ij = |S|``, so under (2.3) the same row is
    the cut ``Σ_{i∉S, j∈S} σ_ij ≥ 1`` (``(n + m − |S|) |S|`` coefficients). Each
    subset gets whichever form has fewer coefficients; both cut off exactly the
    same points of (2.3).

    Returns
    -------
    matrix : (len(cuts), arcs) csr_matrix
    lower, upper : arrays
        Row bounds (``-inf`` / ``inf`` for an open side).
    """
    return rounded_cut_rows(problem.n + problem.m, [(subset, 1) for subset in cuts], tails, heads)


def rounded_cut_rows(
    size: int,
    cuts: list[tuple[tuple[int, ...], int]],
    tails: np.ndarray,
    heads: np.ndarray,
) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """Rows ``σ(δ⁻(S)) ≥ k`` for the pairs ``(S, k)`` of ``cuts``, each in its sparser form.

    Under (2.3) (every target entered once), ``σ(δ⁻(S)) ≥ k`` is the same row as
    ``σ(A(S)) ≤ |S| − k`` (the arcs inside S); each pair gets whichever form has fewer
    coefficients. ``k = 1`` is the subtour row (2.5) (:func:`cut_rows`); ``k > 1`` a rounded
    capacity inequality (the budgeted model's ``capacity_rows``).

    Parameters
    ----------
    size : int
        ``n + m``, the nodes of the arc list.
    cuts : list of (tuple of int, int)
        Subsets of targets and their right-hand sides ``k``.
    tails, heads : arrays
        The arc list (:func:`arc_list`).

    Returns
    -------
    matrix : (len(cuts), arcs) csr_matrix
    lower, upper : arrays
        Row bounds (``-inf`` / ``inf`` for an open side).
    """
    rows, columns = [], []
    lower = np.empty(len(cuts))
    upper = np.empty(len(cuts))
    for r, (subset, k) in enumerate(cuts):
        inside = np.zeros(size, dtype=bool)
        inside[list(subset)] = True
        s = len(subset)
        if s * (s - 1) <= (size - s) * s:
            arcs = np.flatnonzero(inside[tails] & inside[heads])
            lower[r], upper[r] = -np.inf, s - k  # (2.5) as printed when k = 1
        else:
            arcs = np.flatnonzero(~inside[tails] & inside[heads])
            lower[r], upper[r] = float(k), np.inf  # the cut form, by (2.3)
        rows.append(np.full(len(arcs), r))
        columns.append(arcs)
    matrix = sp.csr_matrix(
        (
            np.ones(sum(len(c) for c in columns)),
            (np.concatenate(rows) if rows else [], np.concatenate(columns) if columns else []),
        ),
        shape=(len(cuts), len(tails)),
    )
    return matrix, lower, upper


def separate_subtours(
    problem: AssignmentProblem,
    tails: np.ndarray,
    heads: np.ndarray,
    values: np.ndarray,
    tolerance: float = CUT_TOLERANCE,
    deadline: float | None = None,
) -> list[tuple[int, ...]]:
    """Subsets S of targets whose (2.5) row is violated by σ = ``values`` (exact separation).

    Under (2.3), (2.5) for S is the cut condition ``σ(into S) ≥ 1`` (see
    :func:`cut_rows`). Two stages:

    1. Targets not reachable from any start point along arcs with σ > 0:
       every strongly connected component of them that nothing outside
       enters has ``σ(into S) = 0`` (the subtours of an integral σ are such
       components). They are returned if there are any.
    2. Otherwise, for every target j, a maximum flow from a super-source
       (joined to every start point) to j gives the most violated S that
       contains j (the smallest sink side of a minimum cut). Targets already
       inside a found S are skipped.

    Returns an empty list only if no S has ``σ(into S) < 1 − tolerance``
    (up to the ``2**-24`` fixed-point rounding of σ for scipy's integer
    maximum flow; every returned S is checked in floating point) — unless
    ``deadline`` (a ``time.perf_counter()`` value) passes during stage 2,
    which then stops with the subsets found so far (each still violated).

    Notes
    -----
    O(n) maximum flows on the support of σ (scipy's Dinic) per call, fewer in practice: no
    flow for a target inside a set already found, one reached from a start point along arcs
    with σ ≥ 1 − tolerance, or one entered by such an arc from a target (a violated set
    that holds it holds that target too, so the first target of the chain answers for it).
    On the root LPs of chapter 2 and 3 instances this halved the separation time with the
    same rows found (``docs/benchmarks.md``).

    References
    ----------
    Thesis (2.5); Padberg and Rinaldi's exact separation of subtour constraints.
    """
    n, m = problem.n, problem.m
    size = n + m
    source = size
    values = np.asarray(values, dtype=float)
    support = np.flatnonzero(values > 1e-9)

    def inflow(members: np.ndarray) -> float:
        inside = np.zeros(size, dtype=bool)
        inside[members] = True
        arcs = support[~inside[tails[support]] & inside[heads[support]]]
        return float(values[arcs].sum())

    graph = sp.csr_matrix(
        (np.ones(len(support)), (tails[support], heads[support])), shape=(size, size)
    )
    reached = _reachable(graph, np.arange(n, size))
    unreached = np.flatnonzero(~reached[:n])
    found: list[tuple[int, ...]] = []
    if len(unreached):
        sub = graph[unreached][:, unreached]
        count, label = connected_components(sub, directed=True, connection="strong")
        for component in range(count):
            members = unreached[label == component]
            if len(members) >= 2 and inflow(members) < 1 - tolerance:
                found.append(tuple(sorted(int(v) for v in members)))
        if found:
            return sorted(found)
    # stage 2: a minimum cut per target on the fixed-point capacities
    capacity = np.round(values[support] * _FLOW_SCALE)
    keep = capacity > 0
    flow_graph = sp.csr_matrix(
        (
            np.concatenate([capacity[keep], np.full(m, _FLOW_SCALE)]).astype(np.int32),
            (
                np.concatenate([tails[support][keep], np.full(m, source)]),
                np.concatenate([heads[support][keep], np.arange(n, size)]),
            ),
        ),
        shape=(size + 1, size + 1),
    )
    # the residual graph reversed is C^T - F^T = C^T + F (F antisymmetric): C^T once here
    flow_graph_t = flow_graph.T.tocsr()
    # a violated S has true inflow < 1 - tolerance, so a rounded cut below this
    slack = 0.5 * len(support) + 1.0
    threshold = (1 - tolerance) * _FLOW_SCALE + slack
    # Every cut separating the source from j meets every path to j, so a path of
    # arcs with σ >= 1 - tolerance from a start point, or from a target whose own
    # cut is >= 1, proves j's cut >= 1 - tolerance: such targets need no flow.
    strong = support[values[support] >= 1 - tolerance]
    strong_graph = sp.csr_matrix(
        (np.ones(len(strong)), (tails[strong], heads[strong])), shape=(size, size)
    )
    safe = _reachable(strong_graph, np.arange(n, size))
    # A violated S that holds j holds i too when σ_ij >= 1 - tolerance (else that arc
    # alone brings 1 - tolerance into S), so along a chain of such arcs only its first
    # target needs a flow: a violated S through the chain shows at its first target.
    # (Targets on a cycle of such arcs have no first one and keep their flows.)
    inner = strong[heads[strong] < n]
    inner = inner[tails[inner] < n]
    has_strong_parent = np.zeros(n, dtype=bool)
    has_strong_parent[heads[inner]] = True
    first = np.flatnonzero(~has_strong_parent)
    if len(inner) and len(first):
        chain_graph = sp.csr_matrix(
            (np.ones(len(inner)), (tails[inner], heads[inner])), shape=(size, size)
        )
        follows = _reachable(chain_graph, first)[:n]
        follows[first] = False
    else:
        follows = np.zeros(n, dtype=bool)
    # targets in breadth-first order from the start points: a proven one proves its
    # strong successors
    order = _visit_order(graph, np.arange(n, size))
    order = np.concatenate([order[order < n], unreached])  # (unreached only off (2.3))
    covered = np.zeros(n, dtype=bool)
    for target in (int(v) for v in order):
        if covered[target] or safe[target] or follows[target]:
            continue
        if deadline is not None and time.perf_counter() >= deadline:
            break
        result = maximum_flow(flow_graph, source, target)
        if result.flow_value >= threshold:
            safe[breadth_first_order(strong_graph, target, return_predecessors=False)] = True
            continue
        backward = (flow_graph_t + result.flow).tocsr()
        backward.data[backward.data < 0] = 0
        backward.eliminate_zeros()
        # the smallest sink side: every point that can still push flow to the target
        sink_side = breadth_first_order(backward, target, directed=True, return_predecessors=False)
        members = np.sort(sink_side[sink_side < n])
        if len(members) >= 2 and inflow(members) < 1 - tolerance:
            found.append(tuple(int(v) for v in members))
            covered[members] = True
    return sorted(set(found))


def _visit_order(graph: sp.csr_matrix, sources: np.ndarray) -> np.ndarray:
    """Points reachable from any of ``sources`` in ``graph``, in breadth-first order."""
    size = graph.shape[0]
    hub = sp.csr_matrix(
        (np.ones(len(sources)), (np.zeros(len(sources), dtype=int), sources)), shape=(1, size + 1)
    )
    extended = sp.vstack([sp.hstack([graph, sp.csr_matrix((size, 1))]), hub]).tocsr()
    order = breadth_first_order(extended, size, directed=True, return_predecessors=False)
    return order[1:]


def _reachable(graph: sp.csr_matrix, sources: np.ndarray) -> np.ndarray:
    """Boolean mask of the points reachable from any of ``sources`` in ``graph``."""
    mask = np.zeros(graph.shape[0], dtype=bool)
    mask[_visit_order(graph, sources)] = True
    mask[sources] = True
    return mask


__all__ = ["CUT_TOLERANCE", "arc_list", "cut_rows", "new_subsets", "separate_subtours"]
