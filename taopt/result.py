"""The one result type shared by every problem family and method, and its payloads.

A :class:`Solution` carries the status (a :class:`Status`), the objective (scored by the
family's one :func:`taopt.evaluate`), the best proven lower bound, the gap, the runtime,
the seed, method details (``info``) and ONE payload, :attr:`Solution.solution`: a domain
object of the problem's family,

* :class:`Routes` — one list of target indices per vehicle (chapters 2 and 3);
* :class:`taopt.delivery.Plan` — sorties of a truck–drone plan (chapter 5);
* :class:`Order` — a visiting order (sequential ordering, TSPLIB SOP);
* the driven trajectories of a chapter 4 simulation.

Each payload type has ``to_dict`` / ``from_dict`` and registers itself under a name with
:func:`register_payload`, so a solution round-trips through JSON
(:meth:`Solution.save` / :meth:`Solution.load`) and ``taopt verify`` re-scores it from
the instance alone. ``.routes``, ``.plan`` and ``.order`` are read-only shortcuts to the
payload where they apply (``None`` elsewhere).

Example
-------
>>> s = Solution(objective=4.0, status="feasible", solution=Routes([[1, 0]]), method="MC")
>>> s.routes, s.status
([[1, 0]], 'feasible')
>>> Solution.from_dict(s.to_dict()) == s
True
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from taopt import schemas
from taopt.errors import FeasibilityError, InstanceError
from taopt.families import ensure_families

# the statuses are the status rule's (taopt.status, which imports nothing of this module)
from taopt.status import (
    ERROR,
    FEASIBLE,
    INFEASIBLE,
    NO_SOLUTION,
    OPTIMAL,
    RELAXATION,
    STATUSES,
    TIME_LIMIT,
    Status,
    decide,
)

# -- payloads ------------------------------------------------------------------------------

_PAYLOADS: dict[str, type] = {}
_PAYLOAD_SCHEMAS: dict[str, dict[str, Any]] = {}


def register_payload(name: str, schema: Mapping[str, Any] | None = None) -> Callable[[type], type]:
    """Class decorator: register a payload type under ``name`` for JSON round trips.

    The class needs ``to_dict() -> dict`` and ``from_dict(dict)``; its ``payload_kind``
    attribute is set to ``name``.

    Parameters
    ----------
    name : str
        The ``payload_kind`` of solution files.
    schema : dict
        The JSON Schema (draft 2020-12) of ``to_dict()``'s output. It becomes
        ``$defs/<name>`` of the solution schema, with the rule "payload_kind ``name`` ->
        payload of this schema" (:func:`taopt.schemas.schema` adds both, so the shipped
        ``solution.schema.json`` lists no payload kind); it may refer to the solution
        schema's ``#/$defs/index`` (an index) and ``#/$defs/indices`` (a list of them).
        Every family's payload declares one (the family checklist test).
    """

    def wrap(cls: type) -> type:
        if name in _PAYLOADS and _PAYLOADS[name] is not cls:
            raise InstanceError(f"payload kind {name!r} is already registered")
        _PAYLOADS[name] = cls
        if schema is not None:
            _PAYLOAD_SCHEMAS[name] = json.loads(json.dumps(schema))
        cls.payload_kind = name  # type: ignore[attr-defined]
        return cls

    return wrap


def payload_schemas() -> dict[str, dict[str, Any]]:
    """The JSON Schema each registered payload kind declares (every family imported)."""
    ensure_families()
    return {name: json.loads(json.dumps(s)) for name, s in sorted(_PAYLOAD_SCHEMAS.items())}


def _add_payload_kinds(contents: dict[str, Any]) -> None:
    """Complete the solution schema: one ``$defs`` entry and one rule per payload kind."""
    for name, payload_schema in payload_schemas().items():
        contents.setdefault("$defs", {})[name] = payload_schema
        contents.setdefault("allOf", []).append(
            {
                "if": {
                    "properties": {"payload_kind": {"const": name}},
                    "required": ["payload_kind"],
                },
                "then": {"properties": {"payload": {"$ref": f"#/$defs/{name}"}}},
            }
        )


schemas.extend("solution", _add_payload_kinds)


def payload_type(name: str) -> type[Any]:
    """The payload class registered under ``name`` (families register theirs on import)."""
    ensure_families()
    try:
        return _PAYLOADS[name]
    except KeyError:
        raise InstanceError(f"unknown payload kind {name!r}; known: {sorted(_PAYLOADS)}") from None


def _index_list(values: Any, what: str) -> tuple[int, ...]:
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
        raise FeasibilityError(f"{what} must be a list of integer indices, got {values!r}")
    out = []
    for k, value in enumerate(values):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            if not (isinstance(value, float) and value.is_integer()):
                raise FeasibilityError(f"{what}[{k}] = {value!r} is not an integer index")
        out.append(int(value))
    return tuple(out)


@register_payload(
    "routes",
    schema={
        "description": "One route per vehicle, each a list of target indices in visiting order.",
        "type": "object",
        "required": ["routes"],
        "additionalProperties": False,
        "properties": {"routes": {"type": "array", "items": {"$ref": "#/$defs/indices"}}},
    },
)
@dataclass(frozen=True)
class Routes:
    """One route per vehicle, each a list of target indices in visiting order.

    Iterates as lists (``for route in routes``), indexes as lists (``routes[j]``) and
    compares equal to a list of lists, so code written for plain lists keeps working.

    Example
    -------
    >>> r = Routes([[2, 0], [], [1]])
    >>> len(r), r[0], r == [[2, 0], [], [1]]
    (3, [2, 0], True)
    """

    routes: tuple[tuple[int, ...], ...]

    def __init__(self, routes: Any) -> None:
        if isinstance(routes, Routes):
            routes = routes.routes
        if isinstance(routes, (str, bytes)) or not isinstance(routes, (Sequence, np.ndarray)):
            raise FeasibilityError(f"routes must be a list of lists, got {routes!r}")
        clean = tuple(_index_list(r, f"route {j}") for j, r in enumerate(routes))
        object.__setattr__(self, "routes", clean)

    def __iter__(self) -> Iterator[list[int]]:
        return (list(r) for r in self.routes)

    def __len__(self) -> int:
        return len(self.routes)

    def __getitem__(self, j: int) -> list[int]:
        return list(self.routes[j])

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Routes):
            return self.routes == other.routes
        if isinstance(other, (list, tuple)):
            try:
                return self.routes == tuple(tuple(int(t) for t in r) for r in other)
            except (TypeError, ValueError):
                return False
        return NotImplemented

    __hash__ = object.__hash__

    def as_lists(self) -> list[list[int]]:
        """The routes as a fresh list of lists."""
        return [list(r) for r in self.routes]

    def to_dict(self) -> dict[str, Any]:
        return {"routes": self.as_lists()}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Routes:
        if not isinstance(data, Mapping) or "routes" not in data:
            raise InstanceError("a routes payload needs a 'routes' list")
        return cls(data["routes"])

    def __repr__(self) -> str:
        return f"Routes({self.as_lists()!r})"


@register_payload(
    "order",
    schema={
        "description": "A visiting order: node indices of a Hamiltonian path (SOP).",
        "type": "object",
        "required": ["order"],
        "additionalProperties": False,
        "properties": {"order": {"$ref": "#/$defs/indices"}},
    },
)
@dataclass(frozen=True)
class Order:
    """A visiting order: the sequence of node indices of a Hamiltonian path (SOP)."""

    sequence: tuple[int, ...]

    def __init__(self, sequence: Any) -> None:
        if isinstance(sequence, Order):
            sequence = sequence.sequence
        object.__setattr__(self, "sequence", _index_list(sequence, "order"))

    def __iter__(self) -> Iterator[int]:
        return iter(self.sequence)

    def __len__(self) -> int:
        return len(self.sequence)

    def __getitem__(self, k: int) -> int:
        return self.sequence[k]

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Order):
            return self.sequence == other.sequence
        if isinstance(other, (list, tuple)):
            return list(self.sequence) == list(other)
        return NotImplemented

    __hash__ = object.__hash__

    def to_dict(self) -> dict[str, Any]:
        return {"order": list(self.sequence)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Order:
        if not isinstance(data, Mapping) or "order" not in data:
            raise InstanceError("an order payload needs an 'order' list")
        return cls(data["order"])

    def __repr__(self) -> str:
        return f"Order({list(self.sequence)!r})"


# -- the result ----------------------------------------------------------------------------


def _plain(value: Any) -> Any:
    """``value`` as plain JSON data (numpy to lists/numbers, non-finite floats to None)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if value is None or isinstance(value, str):
        return value
    if hasattr(value, "to_dict"):
        return _plain(value.to_dict())
    return str(value)


@dataclass(frozen=True)
class Solution:
    """Result of a method on a problem (one type for every family and method).

    Attributes
    ----------
    objective : float
        Objective value (total travel time for chapters 2–3, total distance for chapter 4,
        makespan for chapter 5, path cost for SOP). For a relaxation, the relaxation's value.
    status : Status
        A :class:`Status` (a plain string such as ``"optimal"`` is accepted and converted).
    solution : payload or None
        The ONE domain solution: :class:`Routes`, a ``Plan``, an :class:`Order`, or
        trajectories. None only for a relaxation or an error.
    bound : float or None
        Best proven lower bound on the optimum, or None when the method proves none.
    runtime : float
        Wall-clock seconds spent by the method.
    method : str
        Name of the method that produced it (as registered: "exact", "MC", "GA", ...).
    seed : int or None
        Seed of a randomised method.
    info : dict
        Method-specific details (iterations, cuts, solver messages, bytes exchanged).
    """

    objective: float
    status: Status
    solution: Any = None
    bound: float | None = None
    runtime: float = 0.0
    method: str = ""
    seed: int | None = None
    info: dict[str, Any] = field(default_factory=dict)
    #: Set by :func:`make_solution` only: (process id, ``id(problem)``) of the problem whose
    #: scorer gave ``objective``, so :func:`taopt.solve` does not score it again. Not data:
    #: left out of ``to_dict``, equality and repr; reset by :meth:`replace` when the
    #: objective or payload changes.
    scored_for: tuple[int, int] | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        try:
            set_(self, "status", Status(self.status))
        except ValueError:
            raise InstanceError(
                f"unknown status {self.status!r}; one of {[s.value for s in Status]}"
            ) from None
        set_(self, "objective", float(self.objective))
        if self.bound is not None:
            set_(self, "bound", float(self.bound))
        set_(self, "runtime", float(self.runtime))
        if self.seed is not None:
            whole = isinstance(self.seed, (float, np.floating)) and float(self.seed).is_integer()
            if (
                whole
                or isinstance(self.seed, (int, np.integer))
                and not isinstance(self.seed, bool)
            ):
                set_(self, "seed", int(self.seed))  # 2.0 stays the seed 2, not null
            else:  # a Generator or other non-integer seed is not recorded
                set_(self, "seed", None)
        set_(self, "info", dict(self.info))

    # -- shortcuts to the payload ------------------------------------------------------------
    @property
    def routes(self) -> list[list[int]] | None:
        """The routes (a fresh list of lists) when the payload is :class:`Routes`."""
        payload = self.solution
        return payload.as_lists() if isinstance(payload, Routes) else None

    @property
    def plan(self) -> Any:
        """The chapter 5 ``Plan`` when the payload is one."""
        return self.solution if getattr(self.solution, "payload_kind", None) == "plan" else None

    @property
    def order(self) -> list[int] | None:
        """The visiting order (a fresh list): an :class:`Order` payload, or a plan's order."""
        payload = self.solution
        if isinstance(payload, Order):
            return list(payload)
        order = getattr(payload, "order", None)
        return None if order is None else [int(k) for k in order]

    # -- derived -------------------------------------------------------------------------------
    @property
    def gap(self) -> float | None:
        """Relative gap ``(objective - bound) / |objective|``; None without a bound."""
        if self.bound is None or not math.isfinite(self.objective):
            return None
        if self.objective == 0:
            return 0.0
        return max(0.0, (self.objective - self.bound) / abs(self.objective))

    @property
    def is_optimal(self) -> bool:
        return self.status is Status.OPTIMAL

    def replace(self, **changes: Any) -> Solution:
        """A copy with some fields changed (the solution itself is frozen).

        A new ``objective`` or ``solution`` drops the mark of :func:`make_solution` (the
        copy is scored again by :func:`taopt.solve`).
        """
        if ("objective" in changes or "solution" in changes) and "scored_for" not in changes:
            changes["scored_for"] = None
        return dataclasses.replace(self, **changes)

    def is_scored_for(self, problem: Any) -> bool:
        """Whether :func:`make_solution` scored this payload on ``problem`` (this process)."""
        return self.scored_for is not None and self.scored_for == _score_key(problem)

    def summary(self) -> str:
        """One line: method, status, objective, bound, gap and runtime."""
        parts = [f"{self.method or 'solution'}: {self.status}", f"objective={self.objective:.6g}"]
        if self.bound is not None:
            parts.append(f"bound={self.bound:.6g}")
        gap = self.gap
        if gap is not None:
            parts.append(f"gap={100 * gap:.3f}%")
        parts.append(f"time={self.runtime:.3f}s")
        if self.seed is not None:
            parts.append(f"seed={self.seed}")
        return ", ".join(parts)

    def __str__(self) -> str:
        return self.summary()

    # -- JSON --------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain JSON data (schema_version 1, kind "solution")."""
        payload = self.solution
        kind = getattr(payload, "payload_kind", None)
        if payload is not None and kind is None:
            raise InstanceError(f"payload of type {type(payload).__name__} is not registered")
        return {
            "schema_version": 1,
            "kind": "solution",
            "method": self.method,
            "status": self.status.value,
            "objective": _plain(self.objective),
            "bound": _plain(self.bound),
            "runtime": self.runtime,
            "seed": self.seed,
            "payload_kind": kind,
            "payload": None if payload is None else _plain(payload.to_dict()),
            "info": _plain(self.info),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> Solution:
        """Inverse of :meth:`to_dict` (validated against the solution schema first).

        Parameters
        ----------
        data : mapping
            Parsed JSON of kind "solution".
        source : str, optional
            What to call the data in messages (the file path); default "solution".

        Raises
        ------
        InstanceError
            A schema violation (an unknown key in the payload included: the schema holds
            the keys of each payload kind), an unknown payload kind, or a payload its type
            refuses; the message starts with ``source``.
        """
        from taopt.instance import check_schema
        from taopt.schemas import naming

        label = source or "solution"
        check_schema(data, "solution", label)
        kind = data.get("payload_kind")
        with naming(label):
            payload = None
            if kind is not None:
                try:
                    payload = payload_type(kind).from_dict(data["payload"])
                except FeasibilityError as exc:  # a payload type's own complaint about its data
                    raise InstanceError(f"payload: {exc}") from None
            objective = data["objective"]
            seed = data.get("seed")
            return cls(
                objective=math.nan if objective is None else objective,
                status=data["status"],
                solution=payload,
                bound=data.get("bound"),
                runtime=data.get("runtime", 0.0),
                method=data.get("method", ""),
                seed=None if seed is None else int(seed),  # the schema allows 2.0 for 2
                info=dict(data.get("info") or {}),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the solution as JSON, atomically."""
        from taopt.io import save_json

        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Solution:
        """Read a solution written by :meth:`save` (strict JSON, validated; every failure an
        InstanceError starting with the path)."""
        from taopt.io import load_json

        return cls.from_dict(load_json(path), source=str(path))  # from_dict checks the schema

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Solution):
            return NotImplemented
        mine, theirs = self.to_dict(), other.to_dict()
        return json.dumps(mine, sort_keys=True) == json.dumps(theirs, sort_keys=True)

    __hash__ = object.__hash__


def _score_key(problem: Any) -> tuple[int, int]:
    return (os.getpid(), id(problem))


def make_solution(
    problem: Any,
    payload: Any,
    *,
    method: str,
    status: Status | str,
    bound: float | None = None,
    runtime: float = 0.0,
    seed: int | np.random.Generator | None = None,
    info: Mapping[str, Any] | None = None,
    objective: float | None = None,
) -> Solution:
    """A method's :class:`Solution` with a status it knows: the payload scored once.

    Heuristics ("feasible"), relaxations ("relaxation") and the like build their result here;
    an exact method or a peer ends through :func:`finish`, which decides the status from its
    stop and calls this.

    Parameters
    ----------
    problem : a registered problem
        The problem the payload solves (its family's scorer, :func:`taopt.evaluate`,
        gives the objective).
    payload : Routes, Plan, Order, trajectories or None
        The domain solution; None for a relaxation, an error or a limit with no incumbent.
    method : str
        The method's (or variant's) name.
    status : Status or str
        The status.
    bound : float, optional
        A proven lower bound (the gap, :attr:`Solution.gap`, follows from it).
    runtime : float
        Wall-clock seconds.
    seed : int or numpy.random.Generator, optional
        The method's seed; a Generator is not recorded (``Solution.seed`` None).
    info : mapping, optional
    objective : float, optional
        Only without a payload: a relaxation's value (default ``inf``: no incumbent).

    Returns
    -------
    Solution
        Marked as scored for ``problem``, so :func:`taopt.solve` does not score it again
        (one scorer per family holds by construction: objective == evaluate(problem, payload)).

    Raises
    ------
    TypeError
        An ``objective`` with a payload.
    FeasibilityError
        The payload is not feasible for ``problem`` (the scorer's check).

    Notes
    -----
    One call of the family's scorer (O(payload) for every family here).

    Example
    -------
    >>> import numpy as np, taopt
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), n_targets=2)
    >>> s = make_solution(p, Routes([[1, 0]]), method="MC", status="feasible")
    >>> s.objective, s.is_scored_for(p)
    (4.0, True)
    """
    if payload is not None:
        if objective is not None:
            raise TypeError("make_solution scores the payload: pass no objective with it")
        from taopt.scoring import evaluate

        value = float(evaluate(problem, payload))
        key: tuple[int, int] | None = _score_key(problem)
    else:
        value = math.inf if objective is None else float(objective)
        key = None
    return Solution(
        objective=value,
        status=Status(status),
        solution=payload,
        bound=bound,
        runtime=runtime,
        method=method,
        seed=None if isinstance(seed, np.random.Generator) else seed,  # a Generator is not recorded
        info=dict(info or {}),
        scored_for=key,
    )


def finish(
    problem: Any,
    payload: Any,
    *,
    method: str,
    stop: str,
    bound: float | None = None,
    runtime: float = 0.0,
    seed: int | None = None,
    info: Mapping[str, Any] | None = None,
    objective: float | None = None,
    solver: str | None = None,
    time_limited: bool = False,
) -> Solution:
    """The one path from an engine's stop to a :class:`Solution` (every exact model and peer).

    The payload (the best incumbent, or None) is scored once by the family's scorer; the
    bound is capped at that value (a valid lower bound never exceeds an incumbent's value);
    the status is :func:`taopt.status.decide` of the stop, the scored value and the bound,
    and ``info["stopped_by"]`` records the reason it gives.

    Parameters
    ----------
    problem : a registered problem
    payload : the incumbent's payload, or None (no incumbent: objective ``inf``)
    method : str
    stop : str
        Why the engine stopped: a word of :data:`taopt.status.STOPS` ("optimal",
        "infeasible", "time_limit", "solver_limit", "interrupted", "mip_gap",
        "max_rounds", "error"); with ``solver``, that solver's raw status word.
    bound : float, optional
        A proven lower bound (``inf`` for a proof of infeasibility).
    runtime : float
    seed : int, optional
    info : mapping, optional
        Method details; ``stopped_by`` is set here.
    objective : float, optional
        Only without a payload (e.g. a relaxation's value).
    solver : str, optional
        "highs", "cpsat" or "dp": ``stop`` is that solver's raw status
        (:data:`taopt.status.RAW_OUTCOMES`).
    time_limited : bool
        With ``solver``: whether a time limit was set.

    Returns
    -------
    Solution

    Example
    -------
    >>> import numpy as np, taopt
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), n_targets=2)
    >>> finish(p, Routes([[1, 0]]), method="x", stop="time_limit", bound=4).status
    'optimal'
    >>> s = finish(p, Routes([[0, 1]]), method="x", stop="time_limit", bound=4)
    >>> s.status, s.info["stopped_by"], s.bound
    ('time_limit', 'time_limit', 4.0)
    >>> finish(p, None, method="x", stop="time_limit", bound=3.0).objective
    inf
    """
    result = make_solution(
        problem,
        payload,
        method=method,
        status=FEASIBLE,
        runtime=runtime,
        seed=seed,
        info=info,
        objective=objective,
    )
    if bound is not None:
        bound = min(float(bound), result.objective)
    status, stopped_by = decide(
        stop,
        result.objective,
        bound,
        solver=solver,
        time_limited=time_limited,
        has_point=None if solver is None else payload is not None,
    )
    result.info["stopped_by"] = stopped_by
    return dataclasses.replace(result, status=Status(status), bound=bound)


__all__ = [
    "Status",
    "Solution",
    "make_solution",
    "finish",
    "Routes",
    "Order",
    "register_payload",
    "payload_type",
    "OPTIMAL",
    "TIME_LIMIT",
    "FEASIBLE",
    "RELAXATION",
    "INFEASIBLE",
    "NO_SOLUTION",
    "ERROR",
    "STATUSES",
]
