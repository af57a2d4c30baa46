"""Street networks and precedence DAGs: the checks chapter 5's families share (core).

Chapter 5's :class:`~taopt.delivery.instance.DeliveryInstance` and §6.2's
:class:`~taopt.fleet.problem.FleetProblem` read the same data (stop and customer positions, an
undirected street network with lengths, a precedence DAG over customers). Their checks live
here once, with messages that name the offending item, so neither family imports the other's
private helpers (docs/architecture.md, "Layers").
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from typing import Any

import networkx as nx
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, shortest_path

from taopt.errors import InstanceError
from taopt.instance import plain

#: Relative tolerance on street lengths: an edge may not be shorter than the straight
#: line between its stops, ``length >= dist * (1 - STREET_TOLERANCE)``.
STREET_TOLERANCE = 1e-9

#: Relative tolerance on the flight-range constraint (5.6): a sortie with
#: ``d(i, c) + d(c, k) <= L * (1 + FLIGHT_TOLERANCE)`` is within range.
FLIGHT_TOLERANCE = 1e-9


class StreetData:
    """The derived data of a problem on a street network with customers (chapter 5's
    :class:`~taopt.delivery.instance.DeliveryInstance`, §6.2's
    :class:`~taopt.fleet.problem.FleetProblem`), read from the caches their constructors set
    (``_truck_distance``, ``_truck_time``, ``_precedence_graph``): one definition for both.
    """

    customers: np.ndarray
    stops: np.ndarray
    flight_range: float

    @property
    def n(self) -> int:
        """Number of customers."""
        return len(self.customers)

    @property
    def s(self) -> int:
        """Number of stops (the depot included)."""
        return len(self.stops)

    @property
    def flight_limit(self) -> float:
        """The flight range L with the relative tolerance used by every check of (5.6)."""
        return self.flight_range * (1.0 + FLIGHT_TOLERANCE)

    @property
    def truck_distance(self) -> np.ndarray:
        """(s, s) street shortest-path lengths between stops."""
        # ignore (here and below): the caches are set by the constructors (object.__setattr__)
        # and are not dataclass fields, so mypy cannot see them
        return self._truck_distance  # type: ignore[attr-defined]

    @property
    def truck_time(self) -> np.ndarray:
        """(s, s) truck driving times ``truck_distance / v_truck``."""
        return self._truck_time  # type: ignore[attr-defined]

    @property
    def precedence_graph(self) -> nx.DiGraph:
        """G^p: a frozen DiGraph on customers 0..n-1 with an edge r -> j per precedence."""
        return self._precedence_graph  # type: ignore[attr-defined]


def as_points(value: Any, what: str) -> np.ndarray:
    """``value`` as a read-only (N, 2) float array of finite numbers (``what`` names it)."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InstanceError(f"{what} must be an (N, 2) array of numbers") from None
    if arr.size == 0:
        arr = arr.reshape(0, 2)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InstanceError(f"{what} must be an (N, 2) array, got shape {arr.shape}")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        k = int(bad[0][0])
        raise InstanceError(f"{what}[{k}] = {arr[k].tolist()} is not finite")
    arr.setflags(write=False)
    return arr


def positive(value: Any, what: str, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (>= 0 with ``allow_zero``)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InstanceError(f"{what} must be a number, got {plain(value)!r}") from None
    if not np.isfinite(x):
        raise InstanceError(f"{what} = {x} is not finite")
    if x < 0 or (x == 0 and not allow_zero):
        raise InstanceError(f"{what} = {x} must be {'>= 0' if allow_zero else '> 0'}")
    return x


def as_index(value: Any, what: str, size: int, kind: str) -> int:
    """``value`` as an integer index in ``0..size-1`` of a ``kind`` (e.g. "stop")."""
    try:
        k = int(value)
        ok = float(value) == k
    except (TypeError, ValueError):
        ok = False
    if not ok or isinstance(value, bool):
        raise InstanceError(f"{what} must be an integer {kind} index, got {plain(value)!r}")
    if not 0 <= k < size:
        raise InstanceError(f"{what} = {k} is not a {kind} (valid: 0..{size - 1})")
    return k


def cycle_path(graph: nx.DiGraph) -> str | None:
    """A directed cycle of ``graph`` written "a -> b -> a", or None if it is acyclic.

    The one precedence-cycle check (5.7 has no feasible order on a cycle), shared by
    :class:`~taopt.delivery.instance.DeliveryInstance`, :class:`~taopt.fleet.problem.FleetProblem`
    and the sequencing heuristics.
    """
    try:
        cycle = nx.find_cycle(graph)
    except nx.NetworkXNoCycle:
        return None
    return " -> ".join(str(u) for u, _ in cycle) + f" -> {cycle[0][0]}"


def street_network(graph: Any, stops: np.ndarray, depot: int) -> tuple[nx.Graph, np.ndarray]:
    """The frozen street network on stops ``0..s-1`` and its (s, s) shortest-path lengths.

    Every edge needs a ``"length"`` at least the straight line between its stops (within
    :data:`STREET_TOLERANCE`); a self-loop is dropped with a warning (it never shortens a
    truck path); every stop must be reachable from ``depot``.

    Notes
    -----
    Dijkstra from every stop (``scipy.sparse.csgraph.shortest_path``), O(s (e + s log s)).
    """
    s = len(stops)
    if not isinstance(graph, nx.Graph) or graph.is_directed():
        raise InstanceError("graph must be an undirected networkx.Graph on the stop indices")
    out = nx.Graph()
    out.add_nodes_from(range(s))
    for node in graph.nodes:
        as_index(node, f"graph node {node!r}", s, "stop")
    rows, cols, vals = [], [], []
    for u, v, data in graph.edges(data=True):
        a = as_index(u, f"graph edge ({u!r}, {v!r})", s, "stop")
        b = as_index(v, f"graph edge ({u!r}, {v!r})", s, "stop")
        if "length" not in data:
            raise InstanceError(f"graph edge ({a}, {b}) has no 'length' attribute")
        length = positive(data["length"], f"graph edge ({a}, {b}) length", allow_zero=True)
        if a == b:  # documented normalisation: a loop never shortens a truck path
            warnings.warn(f"graph edge ({a}, {b}) is a self-loop; it is dropped", stacklevel=4)
            continue
        straight = float(np.hypot(*(stops[a] - stops[b])))
        if length < straight * (1.0 - STREET_TOLERANCE):
            raise InstanceError(
                f"street edge ({a}, {b}) has length {length:.9g}, shorter than the straight "
                f"line {straight:.9g} between stops {a} and {b}"
            )
        out.add_edge(a, b, length=length)
        rows += [a, b]
        cols += [b, a]
        # csgraph treats explicit zeros as missing edges: use a tiny stand-in, fixed below
        vals += [length if length > 0 else np.finfo(float).tiny] * 2
    adjacency = csr_matrix((vals, (rows, cols)), shape=(s, s))
    n_parts, labels = connected_components(adjacency, directed=False)
    if n_parts > 1:
        lonely = int(np.flatnonzero(labels != labels[depot])[0])
        raise InstanceError(
            f"street network is disconnected ({n_parts} components): stop {lonely} "
            f"cannot be reached from the depot {depot}"
        )
    distance = shortest_path(adjacency, method="D", directed=False)
    distance[distance < 1e-300] = 0.0
    np.fill_diagonal(distance, 0.0)
    return nx.freeze(out), distance


def precedence_dag(
    items: Iterable[Any], n: int, cycle: str = "no order can serve these customers"
) -> tuple[tuple[tuple[int, int], ...], nx.DiGraph]:
    """The distinct precedence pairs ``(r, j)`` over customers ``0..n-1`` and their DAG.

    Raises :class:`InstanceError` naming a malformed pair, a self-precedence, or a cycle
    (``"precedence cycle [...]: " + cycle``).
    """
    pairs: list[tuple[int, int]] = []
    seen: set[tuple[int, int]] = set()
    try:
        listed = list(items)
    except TypeError:
        raise InstanceError("precedences must be an iterable of (r, j) pairs") from None
    for item in listed:
        try:
            r_raw, j_raw = item
        except (TypeError, ValueError):
            raise InstanceError(f"precedence {plain(item)!r} is not an (r, j) pair") from None
        r = as_index(r_raw, f"precedence {plain(tuple(item))!r}", n, "customer")
        j = as_index(j_raw, f"precedence {plain(tuple(item))!r}", n, "customer")
        if r == j:
            raise InstanceError(f"precedence ({r}, {j}): customer {r} cannot precede itself")
        if (r, j) not in seen:
            seen.add((r, j))
            pairs.append((r, j))
    dag = nx.DiGraph()
    dag.add_nodes_from(range(n))
    dag.add_edges_from(pairs)
    path = cycle_path(dag)
    if path:
        raise InstanceError(f"precedence cycle {path}: {cycle}")
    return tuple(pairs), dag


__all__ = [
    "FLIGHT_TOLERANCE",
    "STREET_TOLERANCE",
    "StreetData",
    "as_points",
    "positive",
    "as_index",
    "street_network",
    "precedence_dag",
    "cycle_path",
]
