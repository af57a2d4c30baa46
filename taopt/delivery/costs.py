"""The thesis's drone cost model (5.8)–(5.11) and the digraph G^d of §5.3.2.

Index convention of every matrix here: customers keep their indices ``0..n-1``
and the depot w_0 is node ``n`` (last row/column), as in chapter 2 where the
vehicle starts follow the targets. So ``D[r, j]`` is t*(c_r, c_j) and ``D[n, j]``
is t*(w_0, c_j).

Readings of the printed equations (where the thesis is ambiguous)
------------------------------------------------------------------
* ``d(w_i, w_k)`` in (5.8) and (5.10) is a *truck* distance. §5.2.2 defines d as
  Euclidean, but the truck drives the street network, so by default
  (``truck_metric="street"``) we use the street shortest path, which is the true
  truck time; ``truck_metric="euclidean"`` takes the printed reading literally. Both
  keep the bound valid (street >= Euclidean, and the true time uses the street).
* V_j (viable deployment stops of c_j) are the stops w_i with
  ``d(w_i, c_j) + min_k d(c_j, w_k) <= L``: launched from w_i the drone can serve c_j
  and return to at least one stop.
* L_{c_r} = L − min_{w_h ∈ V_r} d(w_h, c_r) (the text after (5.10)); the nearest stop
  is always in V_r, so this is L minus the distance to the nearest stop.
* In (5.8) the minimum runs over landing stops w_i with ``d(c_r, w_i) <= L_{c_r}``
  (after serving c_r) and relaunch stops w_k ∈ V_j; pattern β (5.9) is α with
  w_i = w_k, and pattern γ (5.10) lands at w_k and relaunches from w_k, so
  γ >= β at the same stop and **t* = t_α always** (the max in γ only adds time).
  γ needs the truck's position w_i while the drone is at c_r, which the cost model
  does not know: we take the most favourable launch stop of c_r compatible with
  landing at w_k (any w_i with d(w_i, c_r) + d(c_r, w_k) <= L).
* Landing time τ (``service_time``): under the timing semantics of
  :mod:`taopt.delivery.evaluate` two consecutive services are at least
  ``t_α + 2τ`` apart (land at the customer, land on the truck), and the first is at
  least ``min_i truck_time[w_0, i] + flight_time[j, i] + τ`` after time 0. With
  ``include_service=True`` (default) t* includes these τ's; with τ = 0 (§5.5) it is
  exactly (5.11).

Validity: for consecutive customers r, j of any feasible plan,
``t_j − t_r >= t*(c_r, c_j)``, and ``t_first >= t*(w_0, c_first)`` (proof in the
docstring of :func:`drone_cost_matrix`), which is what Proposition 5.3 needs.
"""

from __future__ import annotations

from collections.abc import Iterable

import networkx as nx
import numpy as np

from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError

TRUCK_METRICS = ("street", "euclidean")
EDGE_RULES = ("precede", "consecutive", "thesis")


def viable_stops(instance: DeliveryInstance) -> list[np.ndarray]:
    """V_j for every customer: stops from which the drone can serve c_j and return (§5.3.1).

    Returns
    -------
    list of int arrays, one per customer, sorted stop indices.
    """
    fd = instance.flight_distance
    mask = fd + fd.min(axis=1, keepdims=True) <= instance.flight_limit
    return [np.flatnonzero(row) for row in mask]


def remaining_range(instance: DeliveryInstance) -> np.ndarray:
    """L_{c_r} = L − min_{w_h ∈ V_r} d(w_h, c_r) for every customer (text after (5.10))."""
    return instance.flight_range - instance.flight_distance.min(axis=1)


def _truck_times(instance: DeliveryInstance, truck_metric: str) -> np.ndarray:
    if truck_metric == "street":
        return instance.truck_time
    if truck_metric == "euclidean":
        diff = instance.stops[:, None, :] - instance.stops[None, :, :]
        return np.sqrt((diff**2).sum(axis=2)) / instance.v_truck
    raise InstanceError(f"truck_metric must be one of {TRUCK_METRICS}, got {truck_metric!r}")


def deployment_times(instance: DeliveryInstance, truck_metric: str = "street") -> dict:
    """The three deployment patterns of Fig. 5.4: t_α (5.8), t_β (5.9), t_γ (5.10).

    Parameters
    ----------
    instance : DeliveryInstance
    truck_metric : {"street", "euclidean"}
        How d(w_i, w_k) is measured for the truck (see the module notes).

    Returns
    -------
    dict with keys "alpha", "beta", "gamma": (n, n) arrays of drone travel times from
    customer c_r (row) to customer c_j (column) without landing times; ``inf`` where a
    pattern is impossible; the diagonal is ``inf``.

    Notes
    -----
    O(n s² + n² s) time and O(n s²) memory (vectorised).
    """
    fd = instance.flight_distance
    ft = instance.flight_time
    tt = _truck_times(instance, truck_metric)
    limit = instance.flight_limit
    nearest = fd.min(axis=1, keepdims=True)
    # landing stops after c_r: d(c_r, w) <= L_{c_r}  (== d(w_h, c_r) + d(c_r, w) <= L)
    land = np.where(fd + nearest <= limit, ft, np.inf)  # (n, s) [r, w]
    # relaunch stops for c_j: w ∈ V_j (same condition)
    relaunch = land  # (n, s) [j, w]; V_j is the same test
    # (5.8): min_{w_i, w_k} ft[r, w_i] + tt[w_i, w_k] + ft[j, w_k]
    to_customer = (tt[None, :, :] + relaunch[:, None, :]).min(axis=2)  # (n, s) [j, w_i]
    alpha = (land[:, None, :] + to_customer[None, :, :]).min(axis=2)
    # (5.9): same stop
    beta = (land[:, None, :] + relaunch[None, :, :]).min(axis=2)
    # (5.10): max(drone c_r -> w_k, truck w_i -> w_k) + drone w_k -> c_j, with the truck's
    # w_i the most favourable launch stop of c_r compatible with landing at w_k
    pair_ok = fd[:, :, None] + fd[:, None, :] <= limit  # (n, s, s) [r, w_i, w_k]
    truck_to = np.where(pair_ok, tt[None, :, :], np.inf).min(axis=1)  # (n, s) [r, w_k]
    gamma = (np.maximum(land, truck_to)[:, None, :] + relaunch[None, :, :]).min(axis=2)
    for m in (alpha, beta, gamma):
        np.fill_diagonal(m, np.inf)
    return {"alpha": alpha, "beta": beta, "gamma": gamma}


def drone_cost_matrix(
    instance: DeliveryInstance, truck_metric: str = "street", include_service: bool = True
) -> np.ndarray:
    """t* of (5.11) for every ordered pair, with the depot w_0 as node n.

    Parameters
    ----------
    instance : DeliveryInstance
    truck_metric : {"street", "euclidean"}
    include_service : bool
        Add the landing times τ the timing semantics force (2τ between customers,
        τ from the depot). No effect when τ = 0.

    Returns
    -------
    (n + 1, n + 1) float array D: ``D[r, j] = t*(c_r, c_j)`` for customers,
    ``D[n, j] = min_{w_i ∈ V_j} truck_time[w_0, w_i] + flight_time[j, w_i] (+ τ)``,
    ``D[j, n] = inf`` (nothing returns to the depot), diagonal 0. Precedences are NOT
    applied here (see :func:`edge_cost_matrix`).

    Notes
    -----
    Validity. Let r then j be consecutive sorties p, p+1 of a feasible plan, launched at
    i_p, landing at k_p, next launch i_{p+1}. Then t_r = S_p + ft[r, i_p] + τ,
    R_p >= t_r + ft[r, k_p] + τ, t_j = R_p + tt[k_p, i_{p+1}] + ft[j, i_{p+1}] + τ, with
    d(c_r, k_p) <= L − d(i_p, c_r) <= L_{c_r} and i_{p+1} ∈ V_j. So
    t_j − t_r >= t_α(c_r, c_j) + 2τ = D[r, j] (street metric; the Euclidean metric is
    smaller still). Likewise t_first >= D[n, first].

    Example
    -------
    >>> inst = DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> drone_cost_matrix(inst).round(3).tolist()
    [[0.0, 10.0, inf], [10.0, 0.0, inf], [10.0, 14.142, 0.0]]
    """
    times = deployment_times(instance, truck_metric)
    n = instance.n
    tau = instance.service_time if include_service else 0.0
    D = np.full((n + 1, n + 1), np.inf)
    star = np.minimum(np.minimum(times["alpha"], times["beta"]), times["gamma"])
    D[:n, :n] = star + 2.0 * tau
    fd = instance.flight_distance
    tt = _truck_times(instance, truck_metric)
    viable = fd + fd.min(axis=1, keepdims=True) <= instance.flight_limit
    first = np.where(viable, tt[instance.depot][None, :] + instance.flight_time, np.inf)
    D[n, :n] = first.min(axis=1) + tau
    np.fill_diagonal(D, 0.0)
    return D


def simplify_precedences(precedences: Iterable[tuple[int, int]], n: int) -> tuple:
    """Drop redundant precedences (Fig. 5.2 (a) -> (b)): the transitive reduction of G^p.

    A pair (r, j) is redundant when another directed path leads from r to j (§5.3.1).

    Returns
    -------
    tuple of (r, j) pairs, sorted.

    Raises
    ------
    InstanceError
        The precedences contain a cycle.
    """
    graph = nx.DiGraph()
    graph.add_nodes_from(range(n))
    graph.add_edges_from((int(r), int(j)) for r, j in precedences)
    if not nx.is_directed_acyclic_graph(graph):
        cycle = nx.find_cycle(graph)
        path = " -> ".join(str(u) for u, _ in cycle) + f" -> {cycle[0][0]}"
        raise InstanceError(f"precedence cycle {path}")
    return tuple(sorted(nx.transitive_reduction(graph).edges))


def successor_sets(precedences: Iterable[tuple[int, int]], n: int) -> list[set[int]]:
    """The sets S_r as printed in §5.3.2 (backward recursion on the simplified G^p).

    S_r = C \\ {c_r} for c_r outside V^p; for c_r in V^p,
    S_r = ∪_{r -> j} (S_j ∪ {c_j}) with sinks of V^p getting S = C \\ V^p. The result is
    ``descendants(r) ∪ (C \\ V^p)``: customers of V^p that are merely incomparable with
    c_r are left out, although c_r may be served right before them (the NIA example of
    §5.4.2 serves c_3 right before c_2, yet c_2 ∉ S_3). Kept for fidelity; the bound
    uses the rule "precede" by default.
    """
    pairs = simplify_precedences(precedences, n)
    graph = nx.DiGraph(pairs)
    in_vp = set(graph.nodes)
    free = set(range(n)) - in_vp
    sets: list[set[int]] = [set() for _ in range(n)]
    for r in range(n):
        if r not in in_vp:
            sets[r] = set(range(n)) - {r}
    for r in reversed(list(nx.topological_sort(graph))):
        succ = list(graph.successors(r))
        if not succ:
            sets[r] = set(free)
        else:
            sets[r] = set().union(*(sets[j] | {j} for j in succ))
    return sets


def feasible_edges(instance: DeliveryInstance, rule: str = "precede") -> list[tuple[int, int]]:
    """E^d: directed edges (u, v) of G^d over customers 0..n-1 and the depot node n.

    Parameters
    ----------
    rule : {"precede", "consecutive", "thesis"}
        "precede" (default; the §5.3.2 sentence "if c_r can be visited before c_j"):
        r -> j unless j must precede r (j is an ancestor of r in G^p).
        "consecutive": additionally drop r -> j when some c_x must lie between them
        (r ≺ x ≺ j), since such r, j are never consecutive; tighter, still valid.
        "thesis": r -> j for j ∈ S_r as printed (:func:`successor_sets`); not
        guaranteed to contain an optimal path, so its arborescence is not a proven bound.
        In every rule the depot n points at the customers without predecessors.

    Returns
    -------
    list of (u, v) pairs, sorted.
    """
    n = instance.n
    graph = instance.precedence_graph
    sources = [j for j in range(n) if graph.in_degree(j) == 0]
    edges = [(n, j) for j in sources]
    if rule == "thesis":
        sets = successor_sets(instance.precedences, n)
        edges += [(r, j) for r in range(n) for j in sorted(sets[r])]
        return sorted(edges)
    if rule not in EDGE_RULES:
        raise InstanceError(f"rule must be one of {EDGE_RULES}, got {rule!r}")
    closure = nx.transitive_closure_dag(graph)
    reduced = nx.transitive_reduction(graph) if rule == "consecutive" else None
    for r in range(n):
        ancestors = set(closure.predecessors(r))
        descendants = set(closure.successors(r))
        for j in range(n):
            if j == r or j in ancestors:
                continue
            if reduced is not None and j in descendants and not reduced.has_edge(r, j):
                continue
            edges.append((r, j))
    return sorted(edges)


def edge_cost_matrix(
    instance: DeliveryInstance,
    rule: str = "precede",
    truck_metric: str = "street",
    include_service: bool = True,
) -> np.ndarray:
    """D^d of §5.3.2: t* on the edges E^d, ``inf`` elsewhere (depot = node n)."""
    D = drone_cost_matrix(instance, truck_metric, include_service)
    out = np.full_like(D, np.inf)
    edges = np.array(feasible_edges(instance, rule), dtype=np.int64).reshape(-1, 2)
    out[edges[:, 0], edges[:, 1]] = D[edges[:, 0], edges[:, 1]]
    return out


__all__ = [
    "viable_stops",
    "remaining_range",
    "deployment_times",
    "drone_cost_matrix",
    "simplify_precedences",
    "successor_sets",
    "feasible_edges",
    "edge_cost_matrix",
]
