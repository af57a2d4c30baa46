"""Proposition 5.3: a lower bound on the optimal makespan from a min-cost arborescence.

G^d has the customers and the depot w_0 as vertices, the edges E^d allowed by the
precedences (:func:`taopt.delivery.costs.feasible_edges`) and the weights t* (5.11)
(:func:`taopt.delivery.costs.drone_cost_matrix`). The serving order of any feasible
plan is a Hamiltonian path w_0 -> c_π1 -> ... -> c_πn in G^d, which is an
arborescence rooted at w_0, and its weight is at most the makespan because t*
never exceeds the time between consecutive services. So the min-cost arborescence
(Edmonds' algorithm, networkx) is a valid lower bound f_a <= f_o.
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from taopt.delivery.costs import drone_cost_matrix, feasible_edges
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError, SolverError


def _find_cycles(pred: np.ndarray, root: int) -> list[list[int]]:
    """Cycles of the functional graph v -> pred[v] (the root has no predecessor)."""
    state = np.zeros(len(pred), dtype=np.int8)  # 0 new, 1 on the current walk, 2 done
    state[root] = 2
    cycles = []
    for start in range(len(pred)):
        walk = []
        v = start
        while state[v] == 0:
            state[v] = 1
            walk.append(v)
            v = int(pred[v])
        if state[v] == 1:  # closed a cycle on this walk
            cycles.append(walk[walk.index(v) :])
        for u in walk:
            state[u] = 2
    return cycles


def min_arborescence_weight(weights: np.ndarray, root: int) -> float:
    """Weight of a min-cost spanning arborescence rooted at ``root`` (Chu–Liu/Edmonds).

    Dense numpy version of Edmonds' algorithm computing the value only: pick the
    cheapest in-edge of every vertex; if they form no cycle that is optimal, otherwise
    contract each cycle C, charging Σ_{v∈C} min-in(v) and re-weighting edges into C by
    w(u, v) − min-in(v), and recurse. O(N³) worst case with N vectorised steps; the
    tests check it against networkx's ``minimum_spanning_arborescence``.

    Parameters
    ----------
    weights : (N, N) array
        ``weights[u, v]`` the cost of edge u -> v; ``inf`` where there is no edge.
    root : int

    Raises
    ------
    SolverError
        Some vertex cannot be reached from the root.
    """
    W = np.array(weights, dtype=float)
    if W.ndim != 2 or W.shape[0] != W.shape[1]:
        raise InstanceError(f"weights must be square, got shape {W.shape}")
    total = 0.0
    while True:
        N = len(W)
        np.fill_diagonal(W, np.inf)
        W[:, root] = np.inf
        pred = W.argmin(axis=0)
        best = W[pred, np.arange(N)]
        best[root] = 0.0
        if not np.isfinite(best).all():
            v = int(np.flatnonzero(~np.isfinite(best))[0])
            raise SolverError(f"no arborescence: vertex {v} has no entering edge")
        pred[root] = root
        cycles = _find_cycles(pred, root)
        if not cycles:
            return total + float(best.sum())
        label = np.full(N, -1, dtype=np.int64)
        for c, cycle in enumerate(cycles):
            label[cycle] = c
            total += float(best[cycle].sum())
        in_cycle = label >= 0
        rest = np.flatnonzero(~in_cycle)
        label[rest] = len(cycles) + np.arange(rest.size)
        adjusted = W - np.where(in_cycle, best, 0.0)[None, :]
        order = np.argsort(label, kind="stable")
        starts = np.flatnonzero(np.r_[True, np.diff(label[order]) != 0])
        packed = adjusted[np.ix_(order, order)]
        W = np.minimum.reduceat(np.minimum.reduceat(packed, starts, axis=0), starts, axis=1)
        root = int(label[root])


def arborescence_bound(
    instance: DeliveryInstance,
    rule: str = "precede",
    truck_metric: str = "street",
    include_service: bool = True,
    method: str = "numpy",
) -> float:
    """f_a of Proposition 5.3: the weight of a min-cost arborescence of G^d rooted at w_0.

    Parameters
    ----------
    instance : DeliveryInstance
    rule : {"precede", "consecutive", "thesis"}
        Which E^d (see :func:`taopt.delivery.costs.feasible_edges`). "precede" (default)
        and "consecutive" give valid bounds; "thesis" builds E^d from the sets S_r as
        printed in §5.3.2, which can miss the optimal path's edges, so it is not a
        proven bound (kept to compare with the thesis's q (5.19)).
    truck_metric : {"street", "euclidean"}
        Truck distance inside t* (both valid; "street" is tighter).
    include_service : bool
        Include the landing times τ in t* (valid; no effect when τ = 0).
    method : {"numpy", "networkx"}
        Edmonds' algorithm by :func:`min_arborescence_weight` (dense numpy, ~10 ms for
        120 customers) or by ``networkx.minimum_spanning_arborescence`` (the reference;
        pure Python, ~10 s for 120 customers). Both give the same value.

    Returns
    -------
    float
        f_a <= f_o, the optimal makespan (5.1) (for the valid rules).

    Raises
    ------
    SolverError
        G^d has no arborescence rooted at w_0 (cannot happen for the valid rules on a
        validated instance).

    Notes
    -----
    Edges get weight t* and the depot has no in-edges, so every spanning arborescence
    is rooted at w_0.

    Example
    -------
    >>> inst = DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> arborescence_bound(inst)  # w0 -> c0 (10 s) -> c1 (10 s)
    20.0

    References
    ----------
    Thesis §5.3.2, Proposition 5.3; (5.19) uses f_a for q = f / f_a.
    """
    n = instance.n
    D = drone_cost_matrix(instance, truck_metric, include_service)
    weights = np.full_like(D, np.inf)
    edges = np.array(feasible_edges(instance, rule), dtype=np.int64).reshape(-1, 2)
    weights[edges[:, 0], edges[:, 1]] = D[edges[:, 0], edges[:, 1]]
    if method == "numpy":
        return min_arborescence_weight(weights, root=n)
    if method != "networkx":
        raise InstanceError(f"method must be 'numpy' or 'networkx', got {method!r}")
    graph = nx.DiGraph()
    graph.add_nodes_from(range(n + 1))
    for u, v in zip(*np.nonzero(np.isfinite(weights)), strict=True):
        if u != v:
            graph.add_edge(int(u), int(v), weight=float(weights[u, v]))
    try:
        tree = nx.minimum_spanning_arborescence(graph, attr="weight", preserve_attrs=True)
    except nx.NetworkXException as exc:
        raise SolverError(f"G^d has no spanning arborescence rooted at the depot ({exc})") from None
    return float(sum(d["weight"] for _, _, d in tree.edges(data=True)))


__all__ = ["arborescence_bound", "min_arborescence_weight"]
