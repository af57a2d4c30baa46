"""The model of chapter 2: (2.2)–(2.5) built in cvxpy, decoded and repaired.

:func:`build` writes open multi-depot routing (2.2)–(2.5) as one cvxpy problem over the arc
list (:func:`arc_list`), with the subtour elimination (2.5) as DFJ rows (only the subsets
given), MTZ order variables or a single-commodity flow (:data:`SUBTOUR_ELIMINATIONS`);
:func:`describe` lists its variable and constraint families. :func:`decode` turns an integral
σ into routes and the subtours left, :func:`repair` patches subtours into the routes, and
:func:`entry_bound`, :func:`assignment_bound` and :func:`greedy_routes` give the bounds and
the first incumbent every solve starts from. The package :mod:`taopt.models.routing`
describes the whole model and its solve.

References
----------
Thesis §2.2.1, (2.2)–(2.5).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any, Protocol

import cvxpy as cp
import numpy as np
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment

from taopt.errors import InstanceError, SolverError, require
from taopt.routing.problem import AssignmentProblem
from taopt.routing.subtours import arc_list  # the arc list σ is indexed by (core)

# the logger of the package (a child of the "taopt" logger), as before the split
logger = logging.getLogger("taopt.models.routing")

#: The ways (2.5) can be written: DFJ rows (added lazily), MTZ order variables, a flow.
SUBTOUR_ELIMINATIONS = ("dfj", "mtz", "flow")


class ArcModel(Protocol):
    """What :func:`decode` reads of a model: its arc list, σ's columns in order
    (:class:`RoutingModel`, the DFJ model, the budgeted resource model)."""

    tails: np.ndarray
    heads: np.ndarray


@dataclass
class RoutingModel:
    """A built (2.2)–(2.5) model: the cvxpy problem and handles to its variables.

    Attributes
    ----------
    problem : cvxpy.Problem
    arc_use : cvxpy.Variable
        σ over the arc list (``tails[a] -> heads[a]``), binary unless relaxed.
    tails, heads : numpy arrays
        The arc list (see :func:`arc_list`).
    sec : str
        ``"dfj"``, ``"mtz"`` or ``"flow"``.
    order : cvxpy.Variable or None
        MTZ position ``u_j`` of each target on its route.
    flow : cvxpy.Variable or None
        Single-commodity flow on each arc.
    cuts : list of tuple
        The DFJ subsets S currently in the model.
    relax : bool
        True for the LP relaxation.
    """

    problem: cp.Problem
    arc_use: cp.Variable
    tails: np.ndarray
    heads: np.ndarray
    sec: str
    order: cp.Variable | None = None
    flow: cp.Variable | None = None
    cuts: list[tuple[int, ...]] = field(default_factory=list)
    relax: bool = False


def _check(problem: Any, sec: str) -> None:
    require(problem, AssignmentProblem, "solve_routing")
    if sec not in SUBTOUR_ELIMINATIONS:
        raise InstanceError(f"sec must be one of {SUBTOUR_ELIMINATIONS}, got {sec!r}")


def _cut_matrix(
    cuts: list[tuple[int, ...]], tails: np.ndarray, heads: np.ndarray, n: int
) -> sp.csr_matrix:
    """Rows of (2.5): row r has a 1 on every arc with both ends in cut r's subset S."""
    rows, cols = [], []
    for r, subset in enumerate(cuts):
        inside = np.zeros(n + 1, dtype=bool)  # index n stands for "any start point"
        inside[list(subset)] = True
        arcs = np.flatnonzero(inside[np.minimum(tails, n)] & inside[heads])
        rows.append(np.full(len(arcs), r))
        cols.append(arcs)
    return sp.csr_matrix(
        (np.ones(sum(len(c) for c in cols)), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(cuts), len(tails)),
    )


def build(
    problem: AssignmentProblem,
    sec: str = "dfj",
    relax: bool = False,
    cuts: list[tuple[int, ...]] | None = None,
) -> RoutingModel:
    """Build (2.2)–(2.5) as a cvxpy problem.

    Parameters
    ----------
    problem : AssignmentProblem
    sec : {"dfj", "mtz", "flow"}
        How (2.5) is written. For ``"dfj"`` only the subsets in ``cuts`` are
        present (the rest are added lazily by :func:`~taopt.models.routing.solve_routing`).
    relax : bool
        Continuous ``0 ≤ σ ≤ 1`` instead of binary: the LP relaxation.
    cuts : list of subsets of targets, optional
        DFJ subsets S to include as ``Σ_{i,j∈S} σ_ij ≤ |S| − 1``.

    Returns
    -------
    RoutingModel

    Notes
    -----
    Sizes: ``(n + m) n − n`` arcs; (2.3) n rows; (2.4) n + m rows; MTZ adds n
    order variables and ``n (n − 1)`` rows; flow adds one flow per arc, n
    conservation rows and ``2 × arcs`` linking rows.
    """
    _check(problem, sec)
    n, m = problem.n, problem.m
    size = n + m
    tails, heads = arc_list(problem)
    n_arcs = len(tails)
    arc_range = np.arange(n_arcs)
    into = sp.csr_matrix((np.ones(n_arcs), (heads, arc_range)), shape=(n, n_arcs))
    out_of = sp.csr_matrix((np.ones(n_arcs), (tails, arc_range)), shape=(size, n_arcs))
    travel_time = problem.cost[tails, heads]

    if relax:
        # 0 <= sigma_ij <= 1: the LP relaxation of binary sigma (column bounds)
        arc_use = cp.Variable(n_arcs, name="sigma", bounds=[0, 1])
        bounds: list[Any] = []
    else:
        arc_use = cp.Variable(n_arcs, name="sigma", boolean=True)
        bounds = []

    objective = cp.Minimize(travel_time @ arc_use)  # (2.2)
    constraints = [
        (into @ arc_use == 1).set_label("(2.3) every target entered once"),
        (out_of @ arc_use <= 1).set_label("(2.4) every point left at most once"),
        *bounds,
    ]
    order = flow = None
    cuts = list(cuts or [])
    if sec == "dfj":
        if cuts:
            lhs = _cut_matrix(cuts, tails, heads, n)
            rhs = np.array([len(c) - 1 for c in cuts], dtype=float)
            constraints.append(
                (lhs @ arc_use <= rhs).set_label("(2.5) DFJ: sum_{i,j in S} sigma_ij <= |S| - 1")
            )
    elif sec == "mtz":
        # u_j ∈ [1, n] is target j's position on its route. For a target-target arc
        # i -> j:  u_i - u_j + n σ_ij <= n - 1.
        # Big-M derivation: σ_ij = 1 gives u_j >= u_i + 1 (positions increase
        # along a route, so no cycle among targets can exist); σ_ij = 0 gives
        # u_i - u_j <= n - 1, always true because both lie in [1, n]. So M = n is
        # the smallest constant that never cuts a feasible route.
        order = cp.Variable(n, name="u")
        target_arcs = np.flatnonzero(tails < n)
        head_of = sp.csr_matrix(
            (np.ones(len(target_arcs)), (np.arange(len(target_arcs)), heads[target_arcs])),
            shape=(len(target_arcs), n),
        )
        tail_of = sp.csr_matrix(
            (np.ones(len(target_arcs)), (np.arange(len(target_arcs)), tails[target_arcs])),
            shape=(len(target_arcs), n),
        )
        constraints += [
            (order >= 1).set_label("MTZ: 1 <= u_j"),
            (order <= n).set_label("MTZ: u_j <= n"),
            (tail_of @ order - head_of @ order + n * arc_use[target_arcs] <= n - 1).set_label(
                "(2.5) MTZ: u_i - u_j + n sigma_ij <= n - 1"
            ),
        ]
    else:  # flow
        # Each vehicle ships one unit to every target on its route; a target keeps
        # one unit: inflow - outflow = 1. An arc carries flow only if used:
        # σ_ij <= f_ij <= M_ij σ_ij.
        # Big-M derivation: the total demand is n, so an arc out of a start point
        # carries at most n; an arc out of target i carries at most n - 1 because i
        # has already kept its own unit. Lower link: a used arc i -> j carries at
        # least j's unit. A cycle S among targets receives no flow from outside
        # (every target of S is entered from S), so its conservation rows sum to
        # 0 = |S|: impossible, which is (2.5).
        flow = cp.Variable(n_arcs, name="f", nonneg=True)
        capacity = np.where(tails >= n, float(n), float(n - 1))
        constraints += [
            (into @ flow - out_of[:n] @ flow == 1).set_label(
                "(2.5) flow: inflow - outflow = 1 at every target"
            ),
            (flow <= cp.multiply(capacity, arc_use)).set_label(
                "(2.5) flow: f_ij <= M_ij sigma_ij (M = n from a start, n - 1 from a target)"
            ),
            (flow >= arc_use).set_label("(2.5) flow: f_ij >= sigma_ij"),
        ]
    return RoutingModel(
        problem=cp.Problem(objective, constraints),
        arc_use=arc_use,
        tails=tails,
        heads=heads,
        sec=sec,
        order=order,
        flow=flow,
        cuts=cuts,
        relax=relax,
    )


def describe(problem: AssignmentProblem, sec: str = "dfj", show: bool = True) -> list[dict]:
    """The model's variable and constraint families, with equations and counts.

    Parameters
    ----------
    problem : AssignmentProblem
    sec : {"dfj", "mtz", "flow"}
    show : bool
        Log a small table too, at INFO on the ``taopt`` logger (the command line shows it;
        elsewhere ``pandas.DataFrame(describe(...))`` displays the families).

    Returns
    -------
    list of dict
        One dict per family: ``family``, ``equation``, ``rows`` (or variables).
    """
    _check(problem, sec)
    model = build(problem, sec)
    n = problem.n
    families = [
        {"family": "variables sigma_ij (binary)", "equation": "(2.2)", "rows": len(model.tails)}
    ]
    if model.order is not None:
        families.append({"family": "variables u_j (MTZ order)", "equation": "(2.5)", "rows": n})
    if model.flow is not None:
        families.append(
            {"family": "variables f_ij (flow)", "equation": "(2.5)", "rows": len(model.tails)}
        )
    for constraint in model.problem.constraints:
        label = constraint.label or str(constraint)
        equation = label.split(" ")[0] if label.startswith("(") else "bounds"
        families.append({"family": label, "equation": equation, "rows": int(constraint.size)})
    if sec == "dfj":
        families.append(
            {
                "family": "(2.5) DFJ subtour cuts, added lazily (2^n - n - 1 subsets in full)",
                "equation": "(2.5)",
                "rows": 0,
            }
        )
    if show:
        lines = [f"(2.2)-(2.5) with sec={sec!r}: n={n} targets, m={problem.m} vehicles"]
        lines += [f"  {family['rows']:>8}  {family['family']}" for family in families]
        logger.info("\n".join(lines))
    return families


def _successors(model: Any, values: np.ndarray | None = None) -> dict[int, int]:
    if values is None:
        values = model.arc_use.value if isinstance(model, RoutingModel) else None
    if values is None:
        raise SolverError("the model has no solution values to decode")
    used = np.flatnonzero(np.asarray(values) > 0.5)
    successor: dict[int, int] = {}
    for arc in used:
        tail = int(model.tails[arc])
        if tail in successor:
            raise SolverError(
                f"point {tail} is left twice in the solver's solution; (2.4) violated"
            )
        successor[tail] = int(model.heads[arc])
    return successor


def decode(
    problem: AssignmentProblem, model: ArcModel, values: np.ndarray | None = None
) -> tuple[list[list[int]], list[list[int]]]:
    """Turn an integral σ into routes (one per vehicle) and the subtours left over.

    ``values`` is σ over the model's arc list (``model.tails``, ``model.heads``);
    by default the cvxpy variable's value of a :class:`RoutingModel`.

    Returns
    -------
    routes : list of list of int
        Targets in visiting order from each vehicle's start point.
    subtours : list of list of int
        Cycles among targets not reached from any vehicle (violations of (2.5)).
    """
    successor = _successors(model, values)
    n = problem.n
    routes, reached = [], set()
    for vehicle in range(problem.m):
        route: list[int] = []
        point = n + vehicle
        while point in successor:
            point = successor[point]
            if point in reached or len(route) > n:
                raise SolverError(f"target {point} is entered twice; (2.3) violated")
            route.append(point)
            reached.add(point)
        routes.append(route)
    subtours = []
    for start in range(n):
        if start in reached:
            continue
        cycle, point = [], start
        while point not in reached:
            reached.add(point)
            cycle.append(point)
            if point not in successor:
                raise SolverError(f"target {point} is on no route and no cycle")
            point = successor[point]
        subtours.append(cycle)
    return routes, subtours


def find_subtours(problem: AssignmentProblem, model: RoutingModel) -> list[list[int]]:
    """Every cycle among targets in the model's current integral solution."""
    return decode(problem, model)[1]


def repair(
    problem: AssignmentProblem, routes: list[list[int]], subtours: list[list[int]]
) -> list[list[int]]:
    """Make routes feasible: patch each subtour into the routes where it costs least.

    A cycle ``c_0 -> ... -> c_{L-1} -> c_0`` is opened by dropping one of its
    arcs ``c_{p-1} -> c_p`` and the path ``c_p ... c_{p-1}`` is spliced between a
    point a on a route and its successor b (or after the route's last point):
    the change of cost is ``t(a, c_p) + t(c_{p-1}, b) − t(a, b) − t(c_{p-1}, c_p)``
    (without the b terms at a route's end). Every opening and every place is
    priced at once and the cheapest is taken, cycle after cycle (Karp's
    patching). Used to turn a DFJ round's answer into a feasible incumbent.
    """
    cost = problem.cost
    n = problem.n
    routes = [list(r) for r in routes]
    for subtour in subtours:
        cycle = np.asarray(list(subtour), dtype=np.int64)
        before = np.roll(cycle, 1)  # opening at p drops before[p] -> cycle[p]
        # every place: after point a = points[k][q], before b (-1 at a route's end)
        places_a: list[int] = []
        places_b: list[int] = []
        where: list[tuple[int, int]] = []
        for k, route in enumerate(routes):
            points = [n + k, *route]
            places_a.extend(points)
            places_b.extend([*route, -1])
            where.extend((k, q) for q in range(len(points)))
        a = np.asarray(places_a, dtype=np.int64)
        b = np.asarray(places_b, dtype=np.int64)
        inner = b >= 0
        price = cost[a][:, cycle] - cost[before, cycle][None, :]
        price[inner] += cost[before][:, b[inner]].T - cost[a[inner], b[inner]][:, None]
        place, p = np.unravel_index(int(np.argmin(price)), price.shape)
        k, q = where[place]
        path = [int(v) for v in np.roll(cycle, -p)]
        routes[k][q:q] = path
    return routes


def entry_bound(problem: AssignmentProblem) -> float:
    """``Σ_j min_{i≠j} t(i, j)``: a valid lower bound, since (2.3) enters each target once."""
    cost = np.array(problem.cost[:, : problem.n], dtype=float)
    cost[np.arange(problem.n), np.arange(problem.n)] = np.inf
    return float(cost.min(axis=0).sum())


def assignment_bound(problem: AssignmentProblem) -> float:
    """Optimum of (2.2)–(2.4) without (2.5): a valid lower bound, at least :func:`entry_bound`.

    (2.3) and (2.4) alone are a rectangular assignment of every target to a distinct
    predecessor point (its own excluded), solved exactly by
    :func:`scipy.optimize.linear_sum_assignment` in ``O((n + m) n^2)`` — about 0.1 s for
    n = 1000, so it is the bound a time limit leaves when no LP can be solved in time.
    """
    cost = np.array(problem.cost[:, : problem.n], dtype=float)
    # a self loop is never used: any finite value above every route's cost excludes it
    cost[np.arange(problem.n), np.arange(problem.n)] = cost.sum() + 1.0
    rows, columns = linear_sum_assignment(cost)
    return float(cost[rows, columns].sum())


def greedy_routes(problem: AssignmentProblem) -> list[list[int]]:
    """A quick feasible solution: repeatedly append the cheapest (route end, target) pair.

    Only a fallback incumbent for :func:`~taopt.models.routing.solve_routing` when a limit strikes
    before the solver finds one; the thesis's heuristics live in
    ``taopt.heuristics``.
    """
    n, m = problem.n, problem.m
    cost = problem.cost[:, :n].copy()
    routes: list[list[int]] = [[] for _ in range(m)]
    ends = np.arange(n, n + m)
    left = np.ones(n, dtype=bool)
    for _ in range(n):
        price = np.where(left[None, :], cost[ends], np.inf)
        k, target = np.unravel_index(int(np.argmin(price)), price.shape)
        routes[k].append(int(target))
        ends[k] = target
        left[target] = False
    return routes


__all__ = [
    "SUBTOUR_ELIMINATIONS",
    "RoutingModel",
    "arc_list",
    "build",
    "describe",
    "decode",
    "find_subtours",
    "repair",
    "entry_bound",
    "assignment_bound",
    "greedy_routes",
]
