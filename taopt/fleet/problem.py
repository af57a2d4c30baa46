"""The fleet family's data: several trucks, each carrying several multi-parcel drones (§6.2).

Thesis §6.2 (recommendations 2 and 3) asks for "one or several trucks, each of which carries
several drones", a drone that "can deliver packages to several customers after each package
recharging from the truck", and precedence across the fleet. :class:`FleetProblem` is chapter
5's data (:class:`~taopt.delivery.instance.DeliveryInstance`: a street network of stops, the
depot, customers, speeds, a flight range, a precedence DAG G^p, a landing/loading time τ)
extended with

* K trucks, truck k carrying D_k drones (``drones``), each drone serving at most c customers
  per sortie (``capacity``), its range the total flight distance of one sortie (all legs);
* per customer who may serve it (``service``): ``"drone"`` (chapter 5), ``"both"`` (a
  customer at a stop, as in TSP-D) or ``"truck"``; a truck serves customer j when it is at
  ``customer_stop[j]``;
* the objective: ``"last_service"`` (the thesis's f (5.1), the time the last customer is
  served; default) or ``"return"`` (every truck, drones aboard, back at the depot; TSP-D's).

A solution is a :class:`FleetPlan` (payload ``fleet_plan``); :func:`taopt.fleet.evaluate.evaluate_fleet`
is the family's one scorer. Customers are indices ``0..n-1``, stops ``0..s-1``, trucks
``0..K-1``, drone d of truck k is ``(k, d)``.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import networkx as nx
import numpy as np
from numpy.typing import ArrayLike

from taopt.errors import FeasibilityError, InstanceError
from taopt.instance import check_schema, plain
from taopt.io import load_json, save_json
from taopt.result import register_payload
from taopt.schemas import naming
from taopt.streets import StreetData, precedence_dag, street_network
from taopt.streets import as_index as _index
from taopt.streets import as_points as _points
from taopt.streets import positive as _positive

#: Who may serve a customer.
SERVICE_MODES = ("drone", "both", "truck")

#: The objectives.
OBJECTIVES = ("last_service", "return")


def _count(value: Any, what: str, minimum: int) -> int:
    try:
        k = int(value)
        ok = float(value) == k and not isinstance(value, bool)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InstanceError(f"{what} must be an integer, got {plain(value)!r}")
    if k < minimum:
        raise InstanceError(f"{what} = {k} must be >= {minimum}")
    return k


@dataclass(frozen=True, eq=False)
class FleetProblem(StreetData):
    """K trucks with D_k drones each, multi-customer sorties, precedence across the fleet.

    Parameters
    ----------
    customers : (n, 2) array_like
        Customer positions (metres), indices 0..n-1.
    stops : (s, 2) array_like
        Stop positions (the street network's vertices), indices 0..s-1.
    graph : networkx.Graph
        Street network on the stops, each edge with a ``"length"`` at least the straight
        line between its stops (chapter 5's rule); connected. Copied and frozen.
    depot : int
        The stop w_0 where every truck starts, its drones aboard.
    drones : int or sequence of int
        D_k, the drones truck k carries (>= 0 each); an int gives every truck that many.
    trucks : int
        K >= 1 (only read when ``drones`` is an int; otherwise ``len(drones)``).
    capacity : int
        c >= 1, the most customers one sortie serves.
    flight_range : float or None
        The longest total flight distance of one sortie (launch stop -> customers -> recovery
        stop), (5.6) generalised; None or ``inf`` = unlimited.
    v_truck, v_drone : float
        Speeds (> 0); truck times are street shortest paths over ``v_truck``, drone times
        straight lines over ``v_drone``.
    service : sequence of str or str
        Per customer ``"drone"`` (default, chapter 5), ``"both"`` or ``"truck"``.
    customer_stop : sequence of (int or None)
        Per customer the stop where a truck serves it; required (an int) for customers a truck
        may serve, ignored (None) for drone-only ones. Default: None for all.
    precedences : iterable of (r, j)
        r is served no later than j, whichever vehicles serve them ((5.7) across the fleet).
    service_time : float
        τ >= 0, chapter 5's landing/loading time: paid by a drone at each customer it serves
        and once at its recovery (a truck serves its customers in no time).
    objective : {"last_service", "return"}
        ``"last_service"`` (default): f = the time the last customer is served (5.1);
        ``"return"``: the time every truck is back at the depot with its drones aboard.
    name : str
        Optional label.

    Attributes (derived, read-only)
    -------------------------------
    n, s, K, D (total drones), truck_time (s, s), flight_stop (n, s) customer-stop distances,
    flight_customer (n, n) customer-customer distances, precedence_graph (networkx.DiGraph).

    Raises
    ------
    InstanceError
        Naming the item: a non-finite or negative value, a bad index, a truck-servable customer
        without a stop, an unknown service mode or objective, a self-precedence, a precedence
        cycle (e.g. ``precedence cycle 3 -> 5 -> 3``), a disconnected street network, a street
        shorter than the straight line.

    Notes
    -----
    An instance may have no feasible plan (a drone-only customer out of every drone's range,
    or no drones at all): that is not an error here; :meth:`unservable` names such customers
    and the exact method reports ``infeasible``.

    Example
    -------
    >>> import networkx as nx
    >>> g = nx.Graph(); g.add_edge(0, 1, length=100.0)
    >>> p = FleetProblem([[50, 30]], [[0, 0], [100, 0]], g, depot=0, drones=[1, 2],
    ...                  capacity=2, flight_range=500, v_truck=10, v_drone=20)
    >>> p.K, p.D, p.drones, p.n
    (2, 3, (1, 2), 1)

    References
    ----------
    Thesis §5.2 ((5.1)–(5.7)), §6.2 (recommendations 2 and 3).
    """

    # the fields as stored (normalised by __post_init__); __init__ below says what is accepted
    # and holds the defaults
    customers: np.ndarray
    stops: np.ndarray
    graph: nx.Graph
    depot: int
    drones: tuple[int, ...]
    trucks: int
    capacity: int
    flight_range: float
    v_truck: float
    v_drone: float
    service: tuple[str, ...]
    customer_stop: tuple[int | None, ...]
    precedences: tuple[tuple[int, int], ...]
    service_time: float
    objective: str
    name: str

    def __init__(
        self,
        customers: ArrayLike,
        stops: ArrayLike,
        graph: nx.Graph,
        depot: int | np.integer[Any],
        drones: int | np.integer[Any] | Sequence[int | np.integer[Any]] | np.ndarray = 1,
        trucks: int | np.integer[Any] = 1,
        capacity: int | np.integer[Any] = 1,
        flight_range: float | None = None,
        v_truck: float = 1.0,
        v_drone: float = 1.0,
        service: str | Sequence[str] = "drone",
        customer_stop: Sequence[int | np.integer[Any] | None] | np.ndarray | None = None,
        precedences: Iterable[Sequence[int | np.integer[Any]]] = (),
        service_time: float = 0.0,
        objective: str = "last_service",
        name: str = "",
    ) -> None:
        # the dataclass __init__, typed by what it accepts: store the raw values, then
        # __post_init__ checks and normalises them (as the generated __init__ would)
        raw: dict[str, Any] = dict(
            customers=customers,
            stops=stops,
            graph=graph,
            depot=depot,
            drones=drones,
            trucks=trucks,
            capacity=capacity,
            flight_range=flight_range,
            v_truck=v_truck,
            v_drone=v_drone,
            service=service,
            customer_stop=customer_stop,
            precedences=precedences,
            service_time=service_time,
            objective=objective,
            name=name,
        )
        for key, value in raw.items():
            object.__setattr__(self, key, value)
        self.__post_init__()

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        # the raw constructor arguments (any type __init__ accepts), read before normalising
        raw: Any = self
        customers = _points(self.customers, "customers")
        stops = _points(self.stops, "stops")
        n, s = len(customers), len(stops)
        if n < 1:
            raise InstanceError("customers: need at least one customer")
        if s < 1:
            raise InstanceError("stops: need at least one stop")
        set_(self, "customers", customers)
        set_(self, "stops", stops)
        set_(self, "depot", _index(raw.depot, "depot", s, "stop"))
        # -- fleet ---------------------------------------------------------------------
        if isinstance(raw.drones, (str, bytes)):
            raise InstanceError(f"drones must be an int or a list of ints, got {raw.drones!r}")
        if isinstance(raw.drones, (Sequence, np.ndarray)):
            drones = tuple(_count(d, f"drones[{k}]", 0) for k, d in enumerate(list(raw.drones)))
            if not drones:
                raise InstanceError("drones: need at least one truck (one entry per truck)")
        else:
            trucks = _count(raw.trucks, "trucks", 1)
            drones = (_count(raw.drones, "drones", 0),) * trucks
        set_(self, "drones", drones)
        set_(self, "trucks", len(drones))
        set_(self, "capacity", _count(raw.capacity, "capacity", 1))
        if raw.flight_range is None:
            set_(self, "flight_range", math.inf)
        else:
            try:
                rng = float(raw.flight_range)
            except (TypeError, ValueError):
                raise InstanceError(
                    f"flight_range must be a number or None, got {plain(raw.flight_range)!r}"
                ) from None
            if math.isnan(rng) or rng <= 0:
                raise InstanceError(f"flight_range = {rng} must be > 0 (None for unlimited)")
            set_(self, "flight_range", rng)
        set_(self, "v_truck", _positive(raw.v_truck, "v_truck"))
        set_(self, "v_drone", _positive(raw.v_drone, "v_drone"))
        set_(self, "service_time", _positive(raw.service_time, "service_time", allow_zero=True))
        if raw.objective not in OBJECTIVES:
            raise InstanceError(f"objective {raw.objective!r} is not one of {OBJECTIVES}")
        set_(self, "name", str(raw.name))
        # -- who serves whom -------------------------------------------------------------
        modes = [raw.service] * n if isinstance(raw.service, str) else list(raw.service)
        if len(modes) != n:
            raise InstanceError(f"service has {len(modes)} entries but there are {n} customers")
        for j, mode in enumerate(modes):
            if mode not in SERVICE_MODES:
                raise InstanceError(f"service[{j}] = {mode!r} is not one of {SERVICE_MODES}")
        set_(self, "service", tuple(modes))
        raw_stop = [None] * n if raw.customer_stop is None else list(raw.customer_stop)
        if len(raw_stop) != n:
            raise InstanceError(
                f"customer_stop has {len(raw_stop)} entries but there are {n} customers"
            )
        at: list[int | None] = []
        for j, (mode, w) in enumerate(zip(modes, raw_stop, strict=True)):
            if mode == "drone":
                at.append(None if w is None else _index(w, f"customer_stop[{j}]", s, "stop"))
            elif w is None:
                raise InstanceError(
                    f"customer {j} may be served by a truck (service {mode!r}) but "
                    f"customer_stop[{j}] is None: name the stop where a truck serves it"
                )
            else:
                at.append(_index(w, f"customer_stop[{j}]", s, "stop"))
        set_(self, "customer_stop", tuple(at))
        # -- street network ------------------------------------------------------------------
        graph, truck_distance = street_network(self.graph, stops, self.depot)
        set_(self, "graph", graph)
        truck_time = truck_distance / self.v_truck
        diff = customers[:, None, :] - stops[None, :, :]
        flight_stop = np.sqrt((diff**2).sum(axis=2))
        diff = customers[:, None, :] - customers[None, :, :]
        flight_customer = np.sqrt((diff**2).sum(axis=2))
        # -- precedences ---------------------------------------------------------------------
        pairs, dag = precedence_dag(raw.precedences, n, "no plan can serve these customers")
        set_(self, "precedences", pairs)
        for arr in (truck_distance, truck_time, flight_stop, flight_customer):
            arr.setflags(write=False)
        set_(self, "_truck_distance", truck_distance)
        set_(self, "_truck_time", truck_time)
        set_(self, "_flight_stop", flight_stop)
        set_(self, "_flight_customer", flight_customer)
        set_(self, "_precedence_graph", nx.freeze(dag))

    # -- derived data ----------------------------------------------------------------------
    @property
    def K(self) -> int:  # noqa: N802  (the thesis's symbol)
        """Number of trucks."""
        return len(self.drones)

    @property
    def D(self) -> int:  # noqa: N802
        """Total number of drones, Σ_k D_k."""
        return int(sum(self.drones))

    @property
    def flight_stop(self) -> np.ndarray:
        """(n, s) straight-line distances customer j – stop w."""
        return self._flight_stop  # type: ignore[attr-defined]

    @property
    def flight_customer(self) -> np.ndarray:
        """(n, n) straight-line distances between customers."""
        return self._flight_customer  # type: ignore[attr-defined]

    def drone_ids(self) -> list[tuple[int, int]]:
        """Every drone as ``(truck, d)``."""
        return [(k, d) for k, count in enumerate(self.drones) for d in range(count)]

    def truck_servable(self, j: int) -> bool:
        """Whether a truck may serve customer j (service ``"truck"`` or ``"both"``)."""
        return self.service[j] != "drone"

    def drone_servable(self, j: int) -> bool:
        """Whether a drone may serve customer j (service ``"drone"`` or ``"both"``)."""
        return self.service[j] != "truck"

    def truck_stop(self, j: int) -> int:
        """``customer_stop[j]``, the stop where a truck serves customer j, for a customer a
        truck may serve (the constructor requires it then; raises InstanceError when unset)."""
        w = self.customer_stop[j]
        if w is None:
            raise InstanceError(f"customer {j} has no customer_stop: no truck serves it")
        return w

    def unservable(self) -> list[int]:
        """Customers no plan can serve: drone-only and out of range of every stop (the
        shortest sortie, nearest stop and back, is longer than the range), or drone-only when
        no truck carries a drone. Empty when a feasible plan exists (serve every drone
        customer by its own sortie from its nearest stop, in a topological order)."""
        out = []
        for j in range(self.n):
            if self.service[j] != "drone":
                continue
            if self.D == 0 or 2.0 * float(self.flight_stop[j].min()) > self.flight_limit:
                out.append(j)
        return out

    def to_delivery(self) -> Any:
        """Chapter 5's :class:`~taopt.delivery.instance.DeliveryInstance` on the same street
        network, customers, speeds, range, precedences and τ (the fleet's K = D = c = 1 reading;
        trucks, drones, capacity, service modes and the objective are dropped).

        Raises
        ------
        InstanceError
            When chapter 5's own checks refuse the data (e.g. a customer out of range).
        """
        from taopt.delivery.instance import DeliveryInstance

        return DeliveryInstance(
            customers=self.customers,
            stops=self.stops,
            graph=self.graph,
            depot=self.depot,
            v_drone=self.v_drone,
            v_truck=self.v_truck,
            flight_range=self.flight_range,
            precedences=self.precedences,
            service_time=self.service_time,
            name=self.name,
        )

    def replace(self, **changes: Any) -> FleetProblem:
        """A validated copy with some fields changed (e.g. ``capacity=2``)."""
        if "drones" in changes and "trucks" not in changes and isinstance(changes["drones"], int):
            changes["trucks"] = self.K
        return dataclasses.replace(self, **changes)

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return (
            f"FleetProblem{label}(n={self.n}, s={self.s}, K={self.K}, drones={list(self.drones)}, "
            f"c={self.capacity}, range={self.flight_range:g}, precedences={len(self.precedences)}, "
            f"objective={self.objective!r})"
        )

    # -- readers ------------------------------------------------------------------------------
    @classmethod
    def from_delivery(cls, instance: Any, **changes: Any) -> FleetProblem:
        """Chapter 5's instance as a fleet problem: K = D = c = 1, drone-only customers,
        ``last_service`` (f of (5.1)); same network, speeds, range, τ and precedences.
        ``changes`` override fields (e.g. ``drones=2``)."""
        fields = dict(
            customers=instance.customers,
            stops=instance.stops,
            graph=instance.graph,
            depot=instance.depot,
            drones=(1,),
            capacity=1,
            flight_range=instance.flight_range,
            v_truck=instance.v_truck,
            v_drone=instance.v_drone,
            service="drone",
            precedences=instance.precedences,
            service_time=instance.service_time,
            objective="last_service",
            name=instance.name,
        )
        fields.update(changes)
        return cls(**fields)

    @classmethod
    def from_tspd(cls, path: str | os.PathLike[str], **changes: Any) -> FleetProblem:
        """Read an Agatz–Bouman–Schmidt TSP-D instance (``uniform-*-n*.txt``).

        The format: comments ``/* ... */``; the truck's and the drone's cost per unit of
        distance (speeds are their inverses), the number of nodes N, then N lines ``x y
        name``, the depot first; optional ``#MAXFLY r`` (flight range, in distance; unlimited
        otherwise) and ``#NOVISIT i j ...`` (nodes the drone may not serve: truck-only).
        Built as: stops = the N nodes on the complete Euclidean graph, customer j = node
        j + 1 at its stop, served by truck or drone, one truck with one drone, c = 1, τ = 0,
        objective ``"return"``. ``changes`` override fields.

        Raises
        ------
        InstanceError
            The file cannot be read or does not follow the grammar (naming the path).
        """
        where = Path(path)
        try:
            text = where.read_text(encoding="utf-8")
        except OSError as exc:
            raise InstanceError(f"{where}: cannot be read ({exc.strerror or exc})") from None
        maxfly: float | None = None
        novisit: set[int] = set()
        for match in re.finditer(r"#MAXFLY\s+([-0-9.eE+]+)", text):
            maxfly = float(match.group(1))
        for match in re.finditer(r"#NOVISIT((?:\s+\d+)+)", text):
            novisit.update(int(x) for x in match.group(1).split())
        body = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
        body = re.sub(r"#(MAXFLY|NOVISIT)[^\n]*", " ", body)
        lines = [line.split() for line in body.splitlines() if line.strip()]
        try:
            truck_cost = float(lines[0][0])
            drone_cost = float(lines[1][0])
            count = int(lines[2][0])
            nodes = np.array([[float(r[0]), float(r[1])] for r in lines[3 : 3 + count]])
        except (IndexError, ValueError):
            raise InstanceError(f"{where}: not a TSP-D instance (speeds, N, N nodes)") from None
        if len(nodes) != count or count < 2:
            raise InstanceError(f"{where}: {count} nodes announced, {len(nodes)} read")
        graph = nx.Graph()
        for a in range(count):
            for b in range(a + 1, count):
                graph.add_edge(a, b, length=float(np.hypot(*(nodes[a] - nodes[b]))))
        fields: dict[str, Any] = dict(
            customers=nodes[1:],
            stops=nodes,
            graph=graph,
            depot=0,
            drones=(1,),
            capacity=1,
            flight_range=maxfly,
            v_truck=1.0 / truck_cost,
            v_drone=1.0 / drone_cost,
            service=["truck" if j + 1 in novisit else "both" for j in range(count - 1)],
            customer_stop=list(range(1, count)),
            objective="return",
            name=where.stem,
        )
        fields.update(changes)
        with naming(str(where)):
            return cls(**fields)

    # -- JSON --------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON data of kind ``fleet_problem`` (``flight_range`` null = unlimited)."""
        return {
            "schema_version": 1,
            "kind": "fleet_problem",
            "name": self.name,
            "customers": self.customers.tolist(),
            "stops": self.stops.tolist(),
            "edges": [
                [int(u), int(v), float(d["length"])]
                for u, v, d in sorted(self.graph.edges(data=True), key=lambda e: (e[0], e[1]))
            ],
            "depot": self.depot,
            "drones": list(self.drones),
            "capacity": self.capacity,
            "flight_range": None if math.isinf(self.flight_range) else self.flight_range,
            "v_truck": self.v_truck,
            "v_drone": self.v_drone,
            "service": list(self.service),
            "customer_stop": list(self.customer_stop),
            "precedences": [list(p) for p in self.precedences],
            "service_time": self.service_time,
            "objective": self.objective,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str | None = None) -> FleetProblem:
        """Inverse of :meth:`to_dict`: checked against ``fleet_problem.schema.json`` first
        (``source`` names the data in messages), then by the constructor.

        Raises
        ------
        InstanceError
            A schema violation (naming the JSON path and the value), a street listed twice,
            or the constructor's own complaint.
        """
        where = source or "fleet_problem"
        check_schema(data, "fleet_problem", source)
        graph = nx.Graph()
        graph.add_nodes_from(range(len(data["stops"])))
        first: dict[frozenset[int], int] = {}
        for k, (u, v, length) in enumerate(data["edges"]):
            key = frozenset((int(u), int(v)))
            if key in first:
                raise InstanceError(
                    f"{where}: edges[{k}]: the street ({int(u)}, {int(v)}) is already "
                    f"edges[{first[key]}]"
                )
            if int(u) == int(v):
                raise InstanceError(
                    f"{where}: edges[{k}]: the street ({int(u)}, {int(v)}) joins stop "
                    f"{int(u)} to itself"
                )
            first[key] = k
            graph.add_edge(int(u), int(v), length=length)
        with naming(where):
            return cls(
                customers=data["customers"],
                stops=data["stops"],
                graph=graph,
                depot=data["depot"],
                drones=list(data["drones"]),
                capacity=data.get("capacity", 1),
                flight_range=data.get("flight_range"),
                v_truck=data["v_truck"],
                v_drone=data["v_drone"],
                service=data.get("service", "drone"),
                customer_stop=data.get("customer_stop"),
                precedences=tuple(tuple(p) for p in data.get("precedences", [])),
                service_time=data.get("service_time", 0.0),
                objective=data.get("objective", "last_service"),
                name=data.get("name", ""),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write JSON atomically."""
        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> FleetProblem:
        """Read a JSON file written by :meth:`save` (strict JSON, validated; every failure an
        InstanceError naming the path)."""
        return cls.from_dict(load_json(path, "fleet_problem"), source=str(path))


# -- the payload -----------------------------------------------------------------------------------
def _ints(value: Any, what: str) -> tuple[int, ...]:
    if isinstance(value, (str, bytes)):
        raise FeasibilityError(f"{what} must be a list of integers, got {value!r}")
    try:
        items = list(value)
        out = tuple(int(x) for x in items)
        ok = all(float(x) == int(x) and not isinstance(x, bool) for x in items)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise FeasibilityError(f"{what} must be a list of integers, got {value!r}")
    return out


@dataclass(frozen=True)
class Sortie:
    """One drone flight: launched at position ``launch`` of its truck's stop sequence, serving
    ``customers`` in order, recovered by the same truck at position ``recovery >= launch``."""

    launch: int
    customers: tuple[int, ...]
    recovery: int

    def __post_init__(self) -> None:
        (launch,) = _ints([self.launch], "sortie launch")
        (recovery,) = _ints([self.recovery], "sortie recovery")
        object.__setattr__(self, "launch", launch)
        object.__setattr__(self, "recovery", recovery)
        object.__setattr__(self, "customers", _ints(self.customers, "sortie customers"))

    def to_list(self) -> list[Any]:
        """``[launch, [customers...], recovery]``."""
        return [self.launch, list(self.customers), self.recovery]


def _sortie(item: Any, what: str) -> Sortie:
    if isinstance(item, Sortie):
        return item
    try:
        launch, customers, recovery = item
    except (TypeError, ValueError):
        raise FeasibilityError(
            f"{what} must be [launch, [customers...], recovery], got {item!r}"
        ) from None
    return Sortie(launch, customers, recovery)


@register_payload(
    "fleet_plan",
    schema={
        "description": (
            "Per truck its stop sequence (from the depot), the customers it serves as "
            "[position, customer] pairs, and per drone its sorties as "
            "[launch position, [customers...], recovery position]."
        ),
        "type": "object",
        "required": ["routes"],
        "additionalProperties": False,
        "properties": {
            "routes": {"type": "array", "items": {"$ref": "#/$defs/indices"}},
            "truck_service": {
                "type": "array",
                "items": {
                    "type": "array",
                    "items": {
                        "type": "array",
                        "prefixItems": [{"$ref": "#/$defs/index"}, {"$ref": "#/$defs/index"}],
                        "minItems": 2,
                        "maxItems": 2,
                    },
                },
            },
            "sorties": {
                "type": "array",
                "items": {
                    "type": "array",
                    "items": {
                        "type": "array",
                        "items": {
                            "type": "array",
                            "prefixItems": [
                                {"$ref": "#/$defs/index"},
                                {"$ref": "#/$defs/indices"},
                                {"$ref": "#/$defs/index"},
                            ],
                            "minItems": 3,
                            "maxItems": 3,
                        },
                    },
                },
            },
        },
    },
)
@dataclass(frozen=True)
class FleetPlan:
    """A fleet solution (payload ``fleet_plan``).

    Parameters
    ----------
    routes : sequence of K sequences of int
        ``routes[k]`` is truck k's stop sequence, ``routes[k][0]`` the depot; a stop may
        repeat (a truck may revisit a stop). Consecutive stops are joined by street shortest
        paths. Under ``"return"`` the drive from the last stop back to the depot is implied.
    truck_service : sequence of K sequences of (position, customer)
        ``(p, j)`` in ``truck_service[k]``: truck k serves customer j when at position p of
        its sequence (the stop ``routes[k][p]`` must be ``customer_stop[j]``).
    sorties : sequence of K sequences of D_k sequences of Sortie
        ``sorties[k][d]`` are drone (k, d)'s sorties in flying order, each a :class:`Sortie`
        or ``[launch, [customers...], recovery]`` with positions in ``routes[k]``.

    Raises
    ------
    FeasibilityError
        Something that is not a list of integers where one is needed (the scorer checks the
        rest against the problem).

    Example
    -------
    >>> plan = FleetPlan([[0, 1]], [[]], [[[[0, [0], 1]]]])
    >>> plan.sorties[0][0][0]
    Sortie(launch=0, customers=(0,), recovery=1)
    """

    # the fields as stored (normalised by __post_init__); __init__ below says what is accepted
    # and holds the defaults
    routes: tuple[tuple[int, ...], ...]
    truck_service: tuple[tuple[tuple[int, int], ...], ...]
    sorties: tuple[tuple[tuple[Sortie, ...], ...], ...]

    def __init__(
        self,
        routes: Sequence[Sequence[int]],
        truck_service: Sequence[Sequence[Sequence[int]]] = (),
        sorties: Sequence[Sequence[Sequence[Sortie | Sequence[Any]]]] = (),
    ) -> None:
        # the dataclass __init__, typed by what it accepts (lists or tuples): store the raw
        # values, then __post_init__ checks and normalises them to tuples
        object.__setattr__(self, "routes", routes)
        object.__setattr__(self, "truck_service", truck_service)
        object.__setattr__(self, "sorties", sorties)
        self.__post_init__()

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if isinstance(self.routes, (str, bytes)):
            raise FeasibilityError(f"routes must be a list of stop lists, got {self.routes!r}")
        routes = tuple(_ints(r, f"routes[{k}]") for k, r in enumerate(self.routes))
        set_(self, "routes", routes)
        served: list[Sequence[Any]] = (
            list(self.truck_service) if self.truck_service else [[] for _ in routes]
        )
        truck_service = []
        for k, items in enumerate(served):
            pairs = []
            for i, item in enumerate(items):
                pair = _ints(item, f"truck_service[{k}][{i}]")
                if len(pair) != 2:
                    raise FeasibilityError(
                        f"truck_service[{k}][{i}] must be [position, customer], got {item!r}"
                    )
                pairs.append((pair[0], pair[1]))
            truck_service.append(tuple(pairs))
        set_(self, "truck_service", tuple(truck_service))
        raw: list[Sequence[Any]] = list(self.sorties) if self.sorties else [[] for _ in routes]
        sorties = []
        for k, per_truck in enumerate(raw):
            drones = []
            for d, flights in enumerate(per_truck):
                drones.append(
                    tuple(_sortie(f, f"sorties[{k}][{d}][{i}]") for i, f in enumerate(flights))
                )
            sorties.append(tuple(drones))
        set_(self, "sorties", tuple(sorties))

    def to_dict(self) -> dict[str, Any]:
        return {
            "routes": [list(r) for r in self.routes],
            "truck_service": [[list(p) for p in items] for items in self.truck_service],
            "sorties": [[[f.to_list() for f in fl] for fl in drones] for drones in self.sorties],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> FleetPlan:
        return cls(data["routes"], data.get("truck_service", ()), data.get("sorties", ()))

    @classmethod
    def from_delivery_plan(cls, plan: Any, depot: int) -> FleetPlan:
        """Chapter 5's :class:`~taopt.delivery.instance.Plan` as a fleet plan (K = D = 1): the
        truck visits ``depot, launch[0], landing[0], launch[1], ...``; sortie p is launched at
        position 2p + 1 and recovered at 2p + 2, so the times are chapter 5's."""
        route = [depot]
        flights = []
        for j, i, k in zip(plan.order, plan.launch, plan.landing, strict=True):
            route += [int(i), int(k)]
            flights.append(Sortie(len(route) - 2, (int(j),), len(route) - 1))
        return cls([route], [[]], [[flights]])

    def customers(self) -> list[int]:
        """Every customer the plan serves (truck ones first), with repeats if any."""
        out = [j for items in self.truck_service for _, j in items]
        out += [j for drones in self.sorties for fl in drones for f in fl for j in f.customers]
        return out


__all__ = ["FleetProblem", "FleetPlan", "Sortie", "SERVICE_MODES", "OBJECTIVES"]
