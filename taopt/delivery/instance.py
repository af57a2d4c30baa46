"""Chapter 5 problem data: one truck on a street network carrying one drone.

A :class:`DeliveryInstance` is immutable, validated on construction (every
error an :class:`~taopt.errors.InstanceError` naming the item) and carries
the derived matrices every chapter 5 method uses: street shortest paths
between stops, truck times, drone flight distances and times, and the
precedence digraph G^p. A :class:`Plan` is a solution: for each sortie, the
customer it serves and its launch and landing stops.

Notation (thesis §5.2.2): customers ``C = {c_1..c_n}`` are indices
``0..n-1`` here; stopping points ``I = W ∪ {w_0}`` are the stops ``0..s-1``
and the depot ``w_0`` is one of them (``depot``). A precedence pair
``(r, j)`` means ``p^r_j = 1``: customer r is served before customer j (5.7).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import networkx as nx
import numpy as np

from taopt.errors import FeasibilityError, InstanceError
from taopt.instance import check_schema
from taopt.io import load_json, save_json
from taopt.result import register_payload
from taopt.schemas import naming
from taopt.streets import (
    FLIGHT_TOLERANCE,
    STREET_TOLERANCE,
    StreetData,
    as_index,
    as_points,
    positive,
    precedence_dag,
    street_network,
)

# the shared checks (core): kept under their old names, which tests and other modules import
_points, _positive, _index = as_points, positive, as_index


@dataclass(frozen=True, eq=False)
class DeliveryInstance(StreetData):
    """Precedence-constrained truck–drone delivery data, thesis §5.2.

    Parameters
    ----------
    customers : (n, 2) array_like
        Customer positions c_1..c_n (metres), indices 0..n-1.
    stops : (s, 2) array_like
        Stopping-point positions (the street-network vertices), indices 0..s-1.
    graph : networkx.Graph
        Street network on the stop indices 0..s-1; every edge has a ``"length"``
        attribute (street length, at least the straight-line distance between its two
        stops, up to a relative ``STREET_TOLERANCE``). Must be connected. It is copied
        and frozen. A self-loop is dropped with a warning (documented normalisation; a file
        with one is refused by :meth:`from_dict`).
    depot : int
        The stop w_0 where the truck and the drone start.
    v_drone, v_truck : float
        Constant speeds v_d, v_t (> 0, metres per second or any consistent unit).
    flight_range : float
        The drone's maximum flight distance L per sortie (out and back), (5.6).
    precedences : iterable of (r, j)
        Customer-index pairs: r is served before j (5.7). Duplicates are dropped (a file
        listing one twice is refused by its schema).
    service_time : float
        Landing/loading time τ >= 0, paid once at the customer and once at the
        truck per sortie (0 in §5.5, 30 s in the Fig. 5.6 example).
    name : str
        Optional label.

    Attributes (derived once, read-only arrays)
    -------------------------------------------
    n, s : int
    truck_distance : (s, s) street shortest-path lengths (scipy.sparse.csgraph).
    truck_time : (s, s) ``truck_distance / v_truck``.
    flight_distance : (n, s) Euclidean customer–stop distances.
    flight_time : (n, s) ``flight_distance / v_drone``.
    precedence_graph : networkx.DiGraph over customers 0..n-1 (G^p).

    Raises
    ------
    InstanceError
        Non-finite or negative data, bad indices, a self-precedence, a precedence
        cycle (named, e.g. ``precedence cycle 3 -> 5 -> 3``), a disconnected street
        network, a street shorter than the straight line between its stops (named, with
        both lengths), a depot that is not a stop, a customer no stop can serve within L
        (named, with its nearest stop distance).

    Example
    -------
    >>> inst = DeliveryInstance.grid([[150, 40], [420, 380]], k=3, side=1000,
    ...                              v_drone=1.0, v_truck=1.0, flight_range=600)
    >>> inst.n, inst.s, inst.depot
    (2, 9, 0)

    References
    ----------
    Thesis §5.2 (formulation (5.1)–(5.7)), §5.5 (the simulation setup).
    """

    customers: np.ndarray
    stops: np.ndarray
    graph: nx.Graph
    depot: int
    v_drone: float
    v_truck: float
    flight_range: float
    precedences: tuple[tuple[int, int], ...] = ()
    service_time: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        customers = _points(self.customers, "customers")
        stops = _points(self.stops, "stops")
        n, s = len(customers), len(stops)
        if n < 1:
            raise InstanceError("customers: need at least one customer")
        if s < 1:
            raise InstanceError("stops: need at least one stop")
        set_(self, "customers", customers)
        set_(self, "stops", stops)
        set_(self, "v_drone", _positive(self.v_drone, "v_drone"))
        set_(self, "v_truck", _positive(self.v_truck, "v_truck"))
        set_(self, "flight_range", _positive(self.flight_range, "flight_range"))
        set_(self, "service_time", _positive(self.service_time, "service_time", allow_zero=True))
        set_(self, "depot", _index(self.depot, "depot", s, "stop"))
        set_(self, "name", str(self.name))

        # -- street network ------------------------------------------------------------
        graph, truck_distance = street_network(self.graph, stops, self.depot)
        set_(self, "graph", graph)
        truck_time = truck_distance / self.v_truck

        # -- drone flights (Euclidean) -----------------------------------------------------
        diff = customers[:, None, :] - stops[None, :, :]
        flight_distance = np.sqrt((diff**2).sum(axis=2))
        flight_time = flight_distance / self.v_drone
        nearest = flight_distance.min(axis=1)
        bad = np.flatnonzero(2.0 * nearest > self.flight_limit)
        if bad.size:
            j = int(bad[0])
            k = int(flight_distance[j].argmin())
            raise InstanceError(
                f"customer {j} cannot be served: its nearest stop {k} is {nearest[j]:.6g} away, "
                f"so the shortest sortie is {2 * nearest[j]:.6g} > flight_range L = "
                f"{self.flight_range:.6g} (5.6)"
            )

        # -- precedences (5.7) -----------------------------------------------------------
        pairs, precedence_graph = precedence_dag(
            self.precedences, n, "no order can serve these customers (5.7)"
        )
        set_(self, "precedences", pairs)

        for arr in (truck_distance, truck_time, flight_distance, flight_time):
            arr.setflags(write=False)
        set_(self, "_truck_distance", truck_distance)
        set_(self, "_truck_time", truck_time)
        set_(self, "_flight_distance", flight_distance)
        set_(self, "_flight_time", flight_time)
        set_(self, "_precedence_graph", nx.freeze(precedence_graph))

    # -- derived data ----------------------------------------------------------------------
    @property
    def flight_distance(self) -> np.ndarray:
        """(n, s) Euclidean distances d(c_j, w_i) between customers and stops."""
        return self._flight_distance  # type: ignore[attr-defined]

    @property
    def flight_time(self) -> np.ndarray:
        """(n, s) drone flight times ``flight_distance / v_drone``."""
        return self._flight_time  # type: ignore[attr-defined]

    def replace(self, **changes: Any) -> DeliveryInstance:
        """A validated copy with some fields changed (e.g. ``flight_range=300``)."""
        return dataclasses.replace(self, **changes)

    def __repr__(self) -> str:
        return (
            f"DeliveryInstance(name={self.name!r}, n={self.n}, s={self.s}, depot={self.depot}, "
            f"v_drone={self.v_drone:g}, v_truck={self.v_truck:g}, L={self.flight_range:g}, "
            f"precedences={len(self.precedences)}, service_time={self.service_time:g})"
        )

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def grid(
        cls,
        customers: Any,
        k: int,
        side: float,
        v_drone: float,
        v_truck: float,
        flight_range: float,
        precedences: Iterable[tuple[int, int]] = (),
        service_time: float = 0.0,
        name: str = "",
    ) -> DeliveryInstance:
        """The §5.5 street network: k×k stops evenly spread over ``[0, side]^2``.

        Stop ``row * k + col`` sits at ``(col * h, row * h)`` with ``h = side / (k - 1)``
        (row-major, stop 0 at (0, 0)); streets join 4-neighbours with Euclidean lengths
        ``h``; the depot is stop 0 at (0, 0). §5.5 uses ``k = 11, side = 1000``.
        """
        k = int(k)
        if k < 1:
            raise InstanceError(f"grid size k = {k} must be >= 1")
        side = _positive(side, "side", allow_zero=True)
        h = side / (k - 1) if k > 1 else 0.0
        cols, rows = np.meshgrid(np.arange(k), np.arange(k))
        stops = np.column_stack([cols.ravel() * h, rows.ravel() * h])
        graph = nx.Graph()
        graph.add_nodes_from(range(k * k))
        for r in range(k):
            for c in range(k):
                a = r * k + c
                if c + 1 < k:
                    graph.add_edge(a, a + 1, length=h)
                if r + 1 < k:
                    graph.add_edge(a, a + k, length=h)
        return cls(
            customers=customers,
            stops=stops,
            graph=graph,
            depot=0,
            v_drone=v_drone,
            v_truck=v_truck,
            flight_range=flight_range,
            precedences=tuple(precedences),
            service_time=service_time,
            name=name,
        )

    # -- JSON ------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (schema_version 1, kind "delivery_instance")."""
        return {
            "schema_version": 1,
            "kind": "delivery_instance",
            "name": self.name,
            "customers": self.customers.tolist(),
            "stops": self.stops.tolist(),
            "edges": [
                [int(u), int(v), float(d["length"])]
                for u, v, d in sorted(self.graph.edges(data=True), key=lambda e: (e[0], e[1]))
            ],
            "depot": self.depot,
            "v_drone": self.v_drone,
            "v_truck": self.v_truck,
            "flight_range": self.flight_range,
            "precedences": [list(p) for p in self.precedences],
            "service_time": self.service_time,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str | None = None) -> DeliveryInstance:
        """Inverse of :meth:`to_dict`: checked against ``delivery_instance.schema.json``
        first (``source`` names the data in messages), then by the constructor.

        Raises
        ------
        InstanceError
            A schema violation (naming the JSON path and the value), a street listed
            twice or joining a stop to itself, or the constructor's own complaint (bad index, a street shorter than
            the straight line, a disconnected network, a precedence cycle, ...).
        """
        check_schema(data, "delivery_instance", source)
        graph = nx.Graph()
        graph.add_nodes_from(range(len(data["stops"])))
        first: dict[frozenset[int], int] = {}
        for k, (u, v, length) in enumerate(data["edges"]):
            if int(u) == int(v):
                raise InstanceError(
                    f"{source or 'delivery_instance'}: edges[{k}]: the street ({int(u)}, "
                    f"{int(v)}) joins stop {int(u)} to itself (a self-loop is not a street)"
                )
            key = frozenset((int(u), int(v)))
            if key in first:
                raise InstanceError(
                    f"{source or 'delivery_instance'}: edges[{k}]: the street ({int(u)}, "
                    f"{int(v)}) is already edges[{first[key]}]"
                )
            first[key] = k
            graph.add_edge(int(u), int(v), length=length)
        with naming(source or "delivery_instance"):
            return cls(
                customers=data["customers"],
                stops=data["stops"],
                graph=graph,
                depot=data["depot"],
                v_drone=data["v_drone"],
                v_truck=data["v_truck"],
                flight_range=data["flight_range"],
                precedences=tuple(tuple(p) for p in data.get("precedences", [])),
                service_time=data.get("service_time", 0.0),
                name=data.get("name", ""),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write JSON atomically."""
        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> DeliveryInstance:
        """Read a JSON file written by :meth:`save` (strict JSON, validated; every failure
        an InstanceError naming the path)."""
        return cls.from_dict(load_json(path, "delivery_instance"), source=str(path))


@register_payload(
    "plan",
    schema={
        "description": "A chapter 5 plan: the customer served by each sortie, its launch and "
        "landing stops.",
        "type": "object",
        "required": ["order", "launch", "landing"],
        "additionalProperties": False,
        "properties": {
            "order": {"$ref": "#/$defs/indices"},
            "launch": {"$ref": "#/$defs/indices"},
            "landing": {"$ref": "#/$defs/indices"},
        },
    },
)
@dataclass(frozen=True)
class Plan:
    """A chapter 5 solution: one drone sortie per customer, in serving order.

    Parameters
    ----------
    order : sequence of int
        ``order[p]`` is the customer served by sortie p.
    launch, landing : sequence of int
        ``launch[p]`` is the stop w_i where the truck releases the drone for sortie p,
        ``landing[p]`` the stop w_k where it recovers it (σ_ijk = 1 in (5.2)–(5.6)).

    The truck path is implied: depot -> launch[0] -> landing[0] -> launch[1] -> ...,
    each leg a street shortest path. Times follow from :func:`taopt.delivery.evaluate.timeline`.

    Raises
    ------
    FeasibilityError
        The three sequences differ in length or hold non-integers.
    """

    order: tuple[int, ...]
    launch: tuple[int, ...]
    landing: tuple[int, ...]

    def __post_init__(self) -> None:
        for name in ("order", "launch", "landing"):
            value = getattr(self, name)
            try:
                items = tuple(int(x) for x in value)
                ok = all(float(x) == int(x) for x in value)
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise FeasibilityError(f"plan {name} must be a sequence of integers, got {value!r}")
            object.__setattr__(self, name, items)
        if not len(self.order) == len(self.launch) == len(self.landing):
            raise FeasibilityError(
                f"plan has {len(self.order)} customers in order but {len(self.launch)} launch "
                f"and {len(self.landing)} landing stops"
            )

    def __len__(self) -> int:
        return len(self.order)

    def to_dict(self) -> dict[str, Any]:
        return {
            "order": list(self.order),
            "launch": list(self.launch),
            "landing": list(self.landing),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Sequence[int]]) -> Plan:
        return cls(tuple(data["order"]), tuple(data["launch"]), tuple(data["landing"]))


__all__ = ["DeliveryInstance", "Plan", "FLIGHT_TOLERANCE", "STREET_TOLERANCE"]
