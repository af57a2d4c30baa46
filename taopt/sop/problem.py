"""TSPLIB sequential ordering problem (SOP) files: loader and the shipped instances.

The sequential ordering problem is the precedence-constrained Hamiltonian path
that chapter 5's ordering step solves on the drone cost matrix t* (5.11): find
the cheapest path ``start -> ... -> end`` through every node of an asymmetric
cost matrix such that every precedence pair ``(r, j)`` has r before j
(precedences as in (5.7)). TSPLIB's SOP instances, with their proven optima,
certify the exact solver :func:`taopt.models.solve_sop`.

TSPLIB .sop convention (TSPLIB95 documentation §3.4, checked on the files):

* ``EDGE_WEIGHT_FORMAT: FULL_MATRIX``; the ``EDGE_WEIGHT_SECTION`` starts with
  an extra token repeating the dimension, then n·n integers (read as a token
  stream, never line by line).
* ``C[j][r] == -1`` means r must come BEFORE j (the row is the later node).
* Node 0 is first (column 0 is -1 in every other row), node n-1 is last (row
  n-1 is -1 everywhere else); ``C[0][n-1] = 1000000`` forbids start -> end.
  These structural -1 are not returned as precedences.
* The objective is the length of the Hamiltonian PATH 0 -> ... -> n-1 (no
  return arc); the diagonal is ignored.

Shipped files (unmodified copies of TSPLIB95 via ``pdrozdowski/TSPLib.Net@5cb1449``;
provenance and optimum sources in the project's ``shared/benchmarks/tsplib/README.md``):
see :data:`KNOWN_OPTIMA`.

Example
-------
>>> cost, precedences, start, end, name = load_sop("ESC07")
>>> cost.shape, start, end, len(precedences)
((9, 9), 0, 8, 7)
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import networkx as nx
import numpy as np

from taopt.errors import FeasibilityError, InstanceError
from taopt.result import Order
from taopt.schemas import naming

# path_cost is defined in taopt.tsplib and re-exported here (models and tests import it from
# this module).
from taopt.tsplib import path_cost, read_tsplib, shipped_tsplib, tsplib_file

__all__ = [
    "KNOWN_OPTIMA",
    "SopProblem",
    "check_sop",
    "evaluate_order",
    "negative_cost",
    "load_sop",
    "shipped_sop",
    "sop_path",
    "path_cost",
    "usable_arcs",
]

#: Proven optima of the shipped .sop files (TSPLIB95 DOC.PS Table 3; confirmed by
#: xgillard/ddo and IsaacRudich/ImprovedPnB, and by a Held–Karp DP for all but ESC25;
#: ESC47, p43.4, ry48p.4, ft53.4, rbg048a and rbg050c by the ideal DP here,
#: :func:`taopt.models.sop_dp.solve_sop_dp`; rbg048a and rbg050c also by OR-Tools CP-SAT).
KNOWN_OPTIMA: dict[str, int] = {
    "ESC07": 2125,
    "ESC11": 2075,
    "ESC12": 1675,
    "ESC25": 1681,
    "ESC47": 1288,
    "br17.10": 55,
    "br17.12": 55,
    "p43.4": 83005,
    "ry48p.4": 31446,
    "ft53.4": 14425,
    "rbg048a": 351,
    "rbg050c": 467,
}

#: The largest |weight| a file may hold (docs/file-formats.md, "Magnitudes"); TSPLIB's
#: structural 1000000 is well inside it.
MAX_MAGNITUDE = 1e9


def negative_cost(i: int, j: int, value: float) -> str:
    """The one message refusing a negative SOP cost (Python, JSON files and TSPLIB files).

    Example
    -------
    >>> negative_cost(2, 5, -3.0)
    'arc (2, 5) has cost -3 < 0: SOP costs must be >= 0 (inf forbids an arc in Python, -1 in a file; adding one constant to every cost changes no order)'
    """
    return (
        f"arc ({int(i)}, {int(j)}) has cost {float(value):g} < 0: SOP costs must be >= 0 "
        "(inf forbids an arc in Python, -1 in a file; adding one constant to every cost "
        "changes no order)"
    )


def _first_negative(cost: np.ndarray, marker: float | None = None) -> tuple[int, int] | None:
    """The first off-diagonal ``(i, j)`` with ``cost[i, j] < 0`` (other than ``marker``)."""
    negative = cost < 0
    if marker is not None:
        negative &= cost != marker
    np.fill_diagonal(negative, False)
    if not negative.any():
        return None
    i, j = np.argwhere(negative)[0]
    return int(i), int(j)


def shipped_sop() -> list[str]:
    """Names (without ``.sop``) of the SOP files shipped in ``taopt/data/tsplib``."""
    return shipped_tsplib(".sop")


def sop_path(name: str) -> Path:
    """Path of a shipped SOP file, e.g. ``sop_path("ESC07")``."""
    stem = name[: -len(".sop")] if name.endswith(".sop") else name
    path = tsplib_file(f"{stem}.sop")
    if not path.is_file():
        raise InstanceError(f"no shipped SOP file {stem!r}; shipped: {shipped_sop()}")
    return path


def load_sop(
    path_or_name: str | os.PathLike[str],
) -> tuple[np.ndarray, list[tuple[int, int]], int, int, str]:
    """Read a TSPLIB .sop file.

    Parameters
    ----------
    path_or_name : str or Path
        A file path, or the name of a shipped instance ("ESC07", "br17.10").

    Returns
    -------
    cost : (n, n) float array
        ``cost[i, j]`` = cost of arc i -> j. Entries that are -1 in the file
        (arcs into an earlier node, never usable) become ``inf``, as does
        ``cost[start, end]``; the diagonal is 0.
    precedences : list of (r, j)
        r must be visited before j, from ``C[j][r] == -1``, excluding the
        structural ones involving the start and end nodes. The file's
        relation is transitively closed, so this list is too.
    start, end : int
        0 and n-1.
    name : str
        The ``NAME`` field (without a trailing ``.sop``).

    Raises
    ------
    InstanceError
        The file is not FULL_MATRIX SOP, has the wrong number of weights, or
        its -1 entries are not consistent with node 0 first and n-1 last.
    """
    path = Path(path_or_name)
    if not path.is_file():
        path = sop_path(str(path_or_name))
    header, weights = read_tsplib(path)
    tokens = weights or []  # no EDGE_WEIGHT_SECTION: reported below as 0 numbers
    if header.get("TYPE", "").upper() != "SOP":
        raise InstanceError(f"{path}: TYPE is {header.get('TYPE')!r}, expected SOP")
    if header.get("EDGE_WEIGHT_FORMAT", "").upper() != "FULL_MATRIX":
        raise InstanceError(f"{path}: only EDGE_WEIGHT_FORMAT FULL_MATRIX is supported")
    dimension = header.get("DIMENSION", "")
    if not dimension.isdigit() or int(dimension) < 2:
        raise InstanceError(f"{path}: DIMENSION {dimension!r} is not a whole number >= 2")
    n = int(dimension)
    if len(tokens) != n * n + 1:
        raise InstanceError(
            f"{path}: EDGE_WEIGHT_SECTION holds {len(tokens)} numbers, expected "
            f"{n * n + 1} (the leading dimension token plus {n}x{n})"
        )
    try:
        values = [float(t) for t in tokens]
    except ValueError as exc:
        raise InstanceError(f"{path}: EDGE_WEIGHT_SECTION holds a non-number ({exc})") from None
    if values[0] != n:
        raise InstanceError(f"{path}: leading token {tokens[0]} is not the dimension {n}")
    raw = np.array(values[1:]).reshape(n, n)
    if not np.isfinite(raw).all() or np.abs(raw).max() > MAX_MAGNITUDE:
        i, j = np.argwhere(~(np.abs(raw) <= MAX_MAGNITUDE))[0]
        raise InstanceError(
            f"{path}: weight [{i}][{j}] = {float(raw[i, j]):g} is not a number with "
            f"|value| <= {MAX_MAGNITUDE:g}"
        )
    start, end = 0, n - 1
    minus = raw == -1
    np.fill_diagonal(minus, False)
    if not (minus[1:, start].all() and minus[end, :end].all() and not minus[start].any()):
        raise InstanceError(f"{path}: node 0 is not first or node {end} is not last")
    precedences = [
        (int(r), int(j)) for j, r in zip(*np.nonzero(minus), strict=True) if r != start and j != end
    ]
    negative = _first_negative(raw, marker=-1.0)
    if negative is not None:
        raise InstanceError(f"{path}: {negative_cost(*negative, raw[negative])}")
    cost = np.where(minus, np.inf, raw)
    np.fill_diagonal(cost, 0.0)
    cost[start, end] = np.inf
    name = header.get("NAME", path.stem)
    name = name[: -len(".sop")] if name.endswith(".sop") else name
    return cost, precedences, start, end, name


def check_sop(cost: Any, precedences: Any, start: Any, end: Any) -> tuple[np.ndarray, nx.DiGraph]:
    """Validate SOP data; return the cost array and the closed precedence DAG.

    The DAG holds every node, the given pairs, ``start -> v`` and ``v -> end``
    for every other node, transitively closed.

    Raises
    ------
    InstanceError
        Non-square or NaN cost, a negative cost off the diagonal (:func:`negative_cost`
        names the arc and the value), bad indices, start == end (n > 1), a self or
        cyclic precedence, a precedence putting something before start or
        after end.
    """
    from taopt.instance import plain

    try:
        cost = np.array(cost, dtype=float)
    except (TypeError, ValueError):
        raise InstanceError("cost must be a square matrix of numbers") from None
    if cost.ndim != 2 or cost.shape[0] != cost.shape[1] or cost.shape[0] < 2:
        raise InstanceError(f"cost must be a square matrix with n >= 2, got shape {cost.shape}")
    if np.isnan(cost).any():
        i, j = np.argwhere(np.isnan(cost))[0]
        raise InstanceError(f"cost[{i}, {j}] is NaN")
    if np.isneginf(cost).any():
        i, j = np.argwhere(np.isneginf(cost))[0]
        raise InstanceError(f"cost[{i}, {j}] is -inf")
    negative = _first_negative(cost)
    if negative is not None:
        raise InstanceError(negative_cost(*negative, cost[negative]))
    n = cost.shape[0]
    for label, node in (("start", start), ("end", end)):
        if isinstance(node, bool) or not (isinstance(node, (int, np.integer)) and 0 <= node < n):
            raise InstanceError(f"{label} = {plain(node)!r} is not a node index in 0..{n - 1}")
    if start == end:
        raise InstanceError(f"start and end are the same node {start}")
    graph = nx.DiGraph()
    graph.add_nodes_from(range(n))
    for pair in precedences:
        try:
            r, j = (int(v) for v in pair)
        except (TypeError, ValueError, OverflowError):
            raise InstanceError(
                f"precedence {plain(pair)!r} is not a pair of node indices"
            ) from None
        if not (0 <= r < n and 0 <= j < n):
            raise InstanceError(f"precedence ({r}, {j}) has a node outside 0..{n - 1}")
        if r == j:
            raise InstanceError(f"self-precedence ({r}, {j})")
        if j == start or r == end:
            raise InstanceError(f"precedence ({r}, {j}) puts a node before start or after end")
        graph.add_edge(r, j)
    for v in range(n):
        if v != start:
            graph.add_edge(start, v)
        if v != end:
            graph.add_edge(v, end)
    if not nx.is_directed_acyclic_graph(graph):
        cycle = [u for u, _ in nx.find_cycle(graph)]
        raise InstanceError("precedence cycle " + " -> ".join(str(v) for v in cycle + [cycle[0]]))
    return cost, nx.transitive_closure_dag(graph)


@dataclass(frozen=True, eq=False)
class SopProblem:
    """Sequential ordering: the cheapest precedence-respecting Hamiltonian path.

    Parameters
    ----------
    cost : (n, n) array_like
        Arc costs >= 0 (asymmetric allowed; ``inf`` forbids an arc; diagonal ignored).
        A negative cost is refused (see Notes).
    precedences : iterable of (r, j)
        r must be visited before j (as (5.7)).
    start, end : int
        The path's first and last nodes.
    name : str

    Raises
    ------
    InstanceError
        Bad data (see :func:`check_sop`), naming the item.

    Notes
    -----
    Costs are lengths or travel times (TSPLIB, the t* matrix (5.11)), so every one is
    >= 0. A negative cost is refused rather than supported: in a file -1 is TSPLIB's
    forbidden-arc marker, so any other negative number would be ambiguous; and nothing is
    lost, since every order uses exactly n - 1 arcs: adding one constant to every finite
    cost shifts every order's cost by (n - 1) times it and changes no optimum.

    Example
    -------
    >>> p = SopProblem.load("ESC07")
    >>> p.n, p.start, p.end
    (9, 0, 8)
    """

    cost: np.ndarray
    precedences: tuple[tuple[int, int], ...]
    start: int
    end: int
    name: str = ""

    def __post_init__(self) -> None:
        cost, closure = check_sop(self.cost, self.precedences, self.start, self.end)
        cost.setflags(write=False)
        object.__setattr__(self, "cost", cost)
        pairs = tuple((int(r), int(j)) for r, j in self.precedences)
        object.__setattr__(self, "precedences", pairs)
        object.__setattr__(self, "start", int(self.start))
        object.__setattr__(self, "end", int(self.end))
        object.__setattr__(self, "name", str(self.name))
        object.__setattr__(self, "_closure", closure)

    @property
    def n(self) -> int:
        """Number of nodes."""
        return self.cost.shape[0]

    @property
    def closure(self) -> nx.DiGraph:
        """Transitively closed precedence DAG (start before and end after every node)."""
        # ignore: set by __post_init__ (object.__setattr__), not a dataclass field
        return self._closure  # type: ignore[attr-defined]

    def replace(self, **changes: Any) -> SopProblem:
        return dataclasses.replace(self, **changes)

    @classmethod
    def load(cls, name_or_path: str | os.PathLike[str]) -> SopProblem:
        """A TSPLIB ``.sop`` file (a path or a shipped name such as "ESC07"), or a JSON
        file of kind "sop_problem".

        Raises
        ------
        InstanceError
            The file cannot be read, breaks its format or the schema, or holds bad data;
            the message starts with the path.
        """
        path = Path(name_or_path)
        if path.suffix.lower() == ".json":
            from taopt.io import load_json

            return cls.from_dict(load_json(path), source=str(path))  # from_dict checks the schema
        cost, precedences, start, end, name = load_sop(name_or_path)
        label = str(path) if path.is_file() else str(sop_path(str(name_or_path)))
        with naming(label):
            return cls(cost, tuple(precedences), start, end, name)

    def to_dict(self) -> dict[str, Any]:
        finite = np.where(np.isfinite(self.cost), self.cost, -1.0)
        return {
            "schema_version": 1,
            "kind": "sop_problem",
            "name": self.name,
            "cost": finite.tolist(),
            "precedences": [list(p) for p in self.precedences],
            "start": self.start,
            "end": self.end,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> SopProblem:
        """From JSON data; a cost of -1 marks a forbidden arc (as in TSPLIB).

        Parameters
        ----------
        data : mapping
            Parsed JSON of kind "sop_problem" (checked against its schema first).
        source : str, optional
            What to call the data in messages (the file path); default "sop_problem".

        Raises
        ------
        InstanceError
            A negative cost other than -1 (:func:`negative_cost`, before the schema so the
            message is the one Python gives), a schema violation (a cost above 1e9
            included), a row of another length than
            the matrix (named), or :func:`check_sop`'s complaint; the message starts with
            ``source``.
        """
        from taopt.instance import check_schema, check_square

        label = source or "sop_problem"
        _refuse_negative_costs(data, label)
        check_schema(data, "sop_problem", label)
        check_square(data["cost"], "cost", label)
        cost = np.array(data["cost"], dtype=float)
        cost[cost == -1] = np.inf
        with naming(label):
            return cls(
                cost,
                # pairs: __post_init__ (check_sop) refuses anything else, naming it
                cast(
                    "tuple[tuple[int, int], ...]",
                    tuple(tuple(int(v) for v in p) for p in data.get("precedences", [])),
                ),
                int(data["start"]),
                int(data["end"]),
                data.get("name", ""),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        from taopt.io import save_json

        save_json(self.to_dict(), path)

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return f"SopProblem{label}(n={self.n}, precedences={len(self.precedences)})"


def _refuse_negative_costs(data: Any, label: str) -> None:
    """Raise :func:`negative_cost`'s message for the first off-diagonal cost below 0 other
    than -1 in JSON data (a well-formed numeric matrix only; anything else is left to the
    schema, which refuses the same values in other words)."""
    rows = data.get("cost") if isinstance(data, Mapping) else None
    if not isinstance(rows, list) or not all(isinstance(row, list) for row in rows):
        return
    if any(isinstance(v, bool) for row in rows for v in row):
        return
    try:
        cost = np.array(rows, dtype=float)
    except (TypeError, ValueError, OverflowError):
        return
    if cost.ndim != 2 or cost.shape[0] != cost.shape[1]:
        return
    with np.errstate(invalid="ignore"):
        negative = _first_negative(cost, marker=-1.0)
    if negative is not None:
        raise InstanceError(f"{label}: {negative_cost(*negative, cost[negative])}")


def evaluate_order(problem: SopProblem, order: Iterable[int]) -> float:
    """The one scorer of the SOP: check the order, then return its path cost.

    Raises
    ------
    FeasibilityError
        The order does not start at ``start``, end at ``end`` or visit every node once,
        uses a forbidden arc, or breaks a precedence (each named).
    """
    order = list(Order(order))
    n = problem.n
    if sorted(order) != list(range(n)):
        missing = sorted(set(range(n)) - set(order))
        twice = sorted({v for v in order if order.count(v) > 1})
        raise FeasibilityError(
            f"order must visit every node 0..{n - 1} once: missing {missing[:10]}, "
            f"repeated {twice[:10]}"
        )
    if order[0] != problem.start or order[-1] != problem.end:
        raise FeasibilityError(
            f"order runs {order[0]} -> ... -> {order[-1]}, not start {problem.start} -> "
            f"end {problem.end}"
        )
    where = np.empty(n, dtype=np.int64)
    where[order] = np.arange(n)
    for r, j in problem.precedences:
        if where[r] > where[j]:
            raise FeasibilityError(f"precedence ({r}, {j}) violated: {j} is visited before {r}")
    legs = problem.cost[order[:-1], order[1:]]
    if not np.isfinite(legs).all():
        leg = int(np.flatnonzero(~np.isfinite(legs))[0])
        raise FeasibilityError(f"order uses forbidden arc {order[leg]} -> {order[leg + 1]}")
    return float(legs.sum())


def sop_arborescence_bound(problem: SopProblem) -> float:
    """Valid lower bound: a min-cost arborescence rooted at ``start`` on the usable arcs.

    A feasible order is a Hamiltonian path from ``start``, i.e. a spanning arborescence in
    which each node has one parent; arcs ``i -> j`` with ``j`` required before ``i`` can
    never be used and are dropped, so the minimum over all arborescences is never above the
    optimum.
    """
    from taopt.arborescence import min_arborescence

    weights = problem.cost.copy()
    for r, j in problem.closure.edges:
        weights[j, r] = np.inf  # j -> r would put r after j
    weights[problem.end, :] = np.inf  # nothing leaves the end of the path
    return float(min_arborescence(weights, problem.start))


def usable_arcs(cost: np.ndarray, closure: nx.DiGraph) -> tuple[np.ndarray, np.ndarray]:
    """Tails and heads of the arcs a path respecting ``closure`` can use.

    ``i -> j`` is dropped when the cost is infinite, when ``j ≺ i``, or when
    some k has ``i ≺ k ≺ j`` (k must be visited between them).
    """
    n = cost.shape[0]
    before = nx.to_numpy_array(closure, nodelist=range(n), dtype=bool, weight=None)
    between = (before.astype(np.int32) @ before.astype(np.int32)) > 0  # i ≺ k ≺ j
    allowed = np.isfinite(cost) & ~before.T & ~between
    np.fill_diagonal(allowed, False)
    tails, heads = np.nonzero(allowed)
    return tails, heads
