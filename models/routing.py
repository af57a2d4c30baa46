"""Exact model of chapter 2: open multi-depot routing (2.2)–(2.5) in cvxpy + HiGHS.

Sets and data (thesis §2.2.1): targets ``T = {0..n-1}``, vehicle start points
``R = {n..n+m-1}``, travel times ``t(i, j)`` = ``problem.cost[i, j]``.

Variables: one binary ``σ_ij`` per arc ``i -> j`` with ``i ∈ T ∪ R``,
``j ∈ T``, ``i ≠ j`` (no self loops, no arcs into a start point). They are held
in ONE cvxpy vector over the arc list (a masked matrix flattened), so every
constraint family is a single sparse matrix expression, never a Python loop
per arc.

* (2.2) objective ``min Σ t(i, j) σ_ij``
* (2.3) in-degree one on every target
* (2.4) out-degree at most one on every point
* (2.5) no subtour among targets, in one of three ways (``sec``):

  - ``"dfj"`` — the thesis's own (2.5), Dantzig–Fulkerson–Johnson. It has one
    constraint per subset, so it is added lazily: solve, find every cycle
    among targets in the incumbent, add ``Σ_{i,j∈S} σ_ij ≤ |S| − 1`` for each,
    re-solve, until no cycle is left. The loop runs on ONE live HiGHS model
    (:class:`DfjModel`): the cvxpy model is compiled once, rows are added in
    place, rows violated by the root LP are separated exactly first, arcs that
    cannot improve on the incumbent (by LP reduced cost) are switched off, and
    every round starts from the best solution known (see :func:`solve_routing`).
  - ``"mtz"`` — Miller–Tucker–Zemlin order variables (compact).
  - ``"flow"`` — single-commodity flow from the vehicles (compact).

The three give the same optimum; their LP relaxations differ
(``solve_routing(..., relax=True)``): DFJ's is the strongest.

Example
-------
>>> import numpy as np
>>> from taopt import AssignmentProblem
>>> cost = np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]])
>>> solve_routing(AssignmentProblem(cost, 2)).routes
[[1, 0]]
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment
from scipy.sparse.csgraph import breadth_first_order, connected_components, maximum_flow

from taopt.errors import InstanceError, SolverError
from taopt.models.highs import OPTIMALITY_TOLERANCE, HighsModel, certify, relative_gap
from taopt.result import RELAXATION, Routes, Solution
from taopt.routing.problem import AssignmentProblem, evaluate_routes

logger = logging.getLogger(__name__)  # a child of the "taopt" logger

SUBTOUR_ELIMINATIONS = ("dfj", "mtz", "flow")

__all__ = [
    "CUT_TOLERANCE",
    "OPTIMALITY_TOLERANCE",
    "SUBTOUR_ELIMINATIONS",
    "DfjModel",
    "RootRelaxation",
    "assignment_bound",
    "RoutingModel",
    "build",
    "cut_rows",
    "decode",
    "describe",
    "dfj_root",
    "entry_bound",
    "find_subtours",
    "greedy_routes",
    "repair",
    "separate_subtours",
    "solve_routing",
]


# ----------------------------------------------------------------------------- arcs
def arc_list(problem: AssignmentProblem) -> tuple[np.ndarray, np.ndarray]:
    """Tails and heads of every arc ``i -> j``, ``i ∈ T ∪ R``, ``j ∈ T``, ``i ≠ j``.

    Row-major order of the masked ``(n + m) × n`` matrix of σ.
    """
    n, size = problem.n, problem.n + problem.m
    mask = np.ones((size, n), dtype=bool)
    mask[np.arange(n), np.arange(n)] = False  # σ_ii = 0: no self loops
    tails, heads = np.nonzero(mask)
    return tails, heads


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

    def arc_matrix(self) -> np.ndarray:
        """σ as a dense ``(n + m) × n`` matrix (zeros on the masked diagonal)."""
        n = int(self.heads.max()) + 1 if len(self.heads) else 0
        size = int(self.tails.max()) + 1 if len(self.tails) else 0
        matrix = np.zeros((size, n))
        if self.arc_use.value is not None:
            matrix[self.tails, self.heads] = self.arc_use.value
        return matrix


def _check(problem: Any, sec: str) -> None:
    if not isinstance(problem, AssignmentProblem):
        raise InstanceError(
            f"solve_routing needs an AssignmentProblem, got {type(problem).__name__}"
        )
    if sec not in SUBTOUR_ELIMINATIONS:
        raise InstanceError(f"sec must be one of {SUBTOUR_ELIMINATIONS}, got {sec!r}")


def _cut_matrix(cuts: list[tuple[int, ...]], tails, heads, n: int) -> sp.csr_matrix:
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
        present (the rest are added lazily by :func:`solve_routing`).
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
        bounds = []
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


# ------------------------------------------------------------------------- decoding
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
    problem: AssignmentProblem, model: RoutingModel | DfjModel, values: np.ndarray | None = None
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
        route, point = [], n + vehicle
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
    for cycle in subtours:
        cycle = np.asarray(list(cycle), dtype=np.int64)
        before = np.roll(cycle, 1)  # opening at p drops before[p] -> cycle[p]
        # every place: after point a = points[k][q], before b (-1 at a route's end)
        places_a, places_b, where = [], [], []
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

    Only a fallback incumbent for :func:`solve_routing` when a limit strikes
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


# ------------------------------------------------------------- separation of (2.5)
#: First core of the DFJ loop: at most this many arcs per point (n + m), by reduced cost.
CORE_SIZE = 4
#: HiGHS options of the DFJ rounds. A smaller cut pool than HiGHS's default (10000)
#: roughly halved the time of the hard rounds (p43, ry48p, n120m5; benchmarks/
#: bench_routing_exact.py); the optimum and its proof do not depend on it.
MIP_OPTIONS = {"mip_pool_soft_limit": 500}
#: Seconds per arc to build :class:`DfjModel` (arrays and HiGHS's ``passModel``), and per
#: arc before HiGHS's simplex first checks its clock (its setup of the LP): upper
#: estimates measured on a loaded 2-core machine (about 1 and 3.5 µs for n = 1000,
#: benchmarks/bench_routing_exact.py --limit). Under a time limit a stage is not started
#: when its estimate exceeds the time left: the incumbent and the bounds proven so far
#: are returned instead (status "time_limit").
BUILD_SECONDS_PER_ARC = 2e-6
#: Seconds per arc before HiGHS's simplex first checks its clock (see above).
LP_SECONDS_PER_ARC = 4e-6
#: Seconds per arc to build and compile the MTZ / flow model through cvxpy and for
#: HiGHS's MIP presolve, which does not stop at its time limit (flow at n = 150, m = 5,
#: 23,100 arcs, loaded 2-core machine: 0.5 s of cvxpy, then 1.75 s of presolve on a
#: 1.26 s limit): an upper estimate.
COMPACT_SECONDS_PER_ARC = 1e-4
#: HiGHS overruns its own ``time_limit``: MIP presolve and node 0 look at the clock
#: rarely (0.62 s of presolve on a 0.6 s limit for MTZ at n = 150, 0.3-0.65 s late on a
#: loaded machine). A MIP run is given the time left minus this.
HIGHS_OVERRUN = 0.25
#: Seconds per ``n^2 (n + m)`` of :func:`assignment_bound` (an upper estimate, as above).
ASSIGNMENT_SECONDS_PER_CUBE = 3e-10
#: Compact formulation that finishes a DFJ loop which stalls with an open gap.
FALLBACK_SEC = "flow"
#: A DFJ row (2.5) counts as violated when it is off by more than this.
CUT_TOLERANCE = 1e-6
#: Fixed-point scale of σ for scipy's integer maximum flow (errors below 2**-25 per arc).
_FLOW_SCALE = 2**24


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
    size = problem.n + problem.m
    rows, columns = [], []
    lower = np.empty(len(cuts))
    upper = np.empty(len(cuts))
    for r, subset in enumerate(cuts):
        inside = np.zeros(size, dtype=bool)
        inside[list(subset)] = True
        k = len(subset)
        if k * (k - 1) <= (size - k) * k:
            arcs = np.flatnonzero(inside[tails] & inside[heads])
            lower[r], upper[r] = -np.inf, k - 1  # (2.5) as printed
        else:
            arcs = np.flatnonzero(~inside[tails] & inside[heads])
            lower[r], upper[r] = 1.0, np.inf  # (2.5) in cut form, by (2.3)
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
    O(n) maximum flows on the support of σ (scipy's Dinic) per call.

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
    # targets in breadth-first order from the start points: a proven one proves its
    # strong successors
    order = _visit_order(graph, np.arange(n, size))
    order = np.concatenate([order[order < n], unreached])  # (unreached only off (2.3))
    covered = np.zeros(n, dtype=bool)
    for target in (int(v) for v in order):
        if covered[target] or safe[target]:
            continue
        if deadline is not None and time.perf_counter() >= deadline:
            break
        result = maximum_flow(flow_graph, source, target)
        if result.flow_value >= threshold:
            safe |= _reachable(strong_graph, np.array([target]))
            continue
        residual = (flow_graph - result.flow).tocsr()
        residual.data[residual.data < 0] = 0
        residual.eliminate_zeros()
        # the smallest sink side: every point that can still push flow to the target
        sink_side = breadth_first_order(
            residual.T.tocsr(), target, directed=True, return_predecessors=False
        )
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


# ------------------------------------------------------------- the persistent model
@dataclass
class RootRelaxation:
    """The DFJ LP relaxation at the root: (2.2)–(2.4) plus separated (2.5) rows.

    Attributes
    ----------
    cuts : list of tuple
        The subsets S whose (2.5) rows were added (every one a valid row).
    value : float
        HiGHS's LP value with those rows (``-inf`` if no LP finished).
    bound : float
        A proven lower bound on the optimum of (2.2)–(2.5) from the LP's row
        duals (:meth:`taopt.models.highs.HighsModel.lagrangian_bound`); equal
        to ``value`` up to solver tolerances.
    reduced_costs : ndarray
        Reduced cost ``d_a`` of every arc: a solution that uses arc a costs at
        least ``bound + d_a``.
    values : ndarray or None
        σ at the LP optimum.
    rounds : int
        LPs solved.
    complete : bool
        The last separation found no violated (2.5) row: ``value`` is the LP
        bound of the full (2.2)–(2.5).
    """

    cuts: list[tuple[int, ...]]
    value: float
    bound: float
    reduced_costs: np.ndarray
    values: np.ndarray | None
    rounds: int
    complete: bool


class DfjModel:
    """(2.2)–(2.4) passed once to one live HiGHS model; (2.5) rows added in place.

    The rows of :func:`build` (no cuts) are written straight into sparse
    arrays — column a is σ of arc ``tails[a] -> heads[a]``, with a 1 in row
    ``heads[a]`` of (2.3) and in row ``n + tails[a]`` of (2.4) — and passed to
    HiGHS by :meth:`taopt.models.highs.HighsModel.from_arrays`: the same model
    cvxpy would compile, without cvxpy's compilation (about 20 s for the
    million arcs of n = 1000, against a fraction of a second here; the
    cvxpy model is :attr:`formulation`, built on demand). Afterwards every
    (2.5) row found, at the root LP or in a MIP round, is added to the same
    ``highspy.Highs`` object; arcs are switched off and on through their upper
    bounds, and a MIP start is passed with ``Highs.setSolution``.
    """

    def __init__(self, problem: AssignmentProblem, verbose: bool = False) -> None:
        self.problem = problem
        n, m = problem.n, problem.m
        size = n + m
        self.tails, self.heads = arc_list(problem)
        n_arcs = len(self.tails)
        self.arcs = np.arange(n_arcs)
        # (2.3) rows 0..n-1: sum_i sigma_ij = 1; (2.4) rows n..2n+m-1: sum_j sigma_ij <= 1
        rows = np.empty(2 * n_arcs, dtype=np.int64)
        rows[0::2] = self.heads
        rows[1::2] = n + self.tails
        matrix = sp.csc_matrix(
            (np.ones(2 * n_arcs), rows, np.arange(0, 2 * n_arcs + 1, 2)),
            shape=(n + size, n_arcs),
        )
        self.model = HighsModel.from_arrays(
            cost=problem.cost[self.tails, self.heads],  # (2.2)
            matrix=matrix,
            lower=np.concatenate([np.ones(n), np.full(size, -np.inf)]),
            upper=np.ones(n + size),
            column_lower=np.zeros(n_arcs),
            column_upper=np.ones(n_arcs),
            integers=self.arcs,
            verbose=verbose,
        )
        self.cuts: list[tuple[int, ...]] = []
        self._known: set[tuple[int, ...]] = set()
        self.arc_index = np.full((size, n), -1, dtype=np.int64)
        self.arc_index[self.tails, self.heads] = np.arange(n_arcs)
        self._formulation: RoutingModel | None = None

    @property
    def formulation(self) -> RoutingModel:
        """The same (2.2)–(2.4) as a labelled cvxpy model (:func:`build`), built on first use."""
        if self._formulation is None:
            self._formulation = build(self.problem, "dfj")
        return self._formulation

    def add_cuts(self, cuts: list[tuple[int, ...]]) -> int:
        """Add the (2.5) rows of the subsets not in the model yet; returns how many."""
        new = []
        for subset in cuts:
            subset = tuple(sorted(int(v) for v in subset))
            if len(subset) >= 2 and subset not in self._known:
                self._known.add(subset)
                new.append(subset)
        if new:
            rows, lower, upper = cut_rows(self.problem, new, self.tails, self.heads)
            full = sp.csr_matrix(
                (rows.data, self.arcs[rows.indices], rows.indptr),
                shape=(rows.shape[0], self.model.n_columns),
            )
            self.model.add_rows(full, lower, upper)
            self.cuts.extend(new)
        return len(new)

    def arc_values(self, solution: np.ndarray | None = None) -> np.ndarray:
        """σ of every arc in the last solution (or in ``solution``, a full column vector)."""
        if solution is None:
            solution = self.model.highs.getSolution().col_value
        return np.asarray(solution, dtype=float)[self.arcs]

    def start_vector(self, routes: list[list[int]]) -> np.ndarray:
        """The full column vector of σ for ``routes`` (a MIP start)."""
        vector = np.zeros(self.model.n_columns)
        vector[self.arcs[self.route_arcs(routes)]] = 1.0
        return vector

    def route_arcs(self, routes: list[list[int]]) -> np.ndarray:
        """Arc indices used by ``routes``."""
        n = self.problem.n
        arcs = []
        for k, route in enumerate(routes):
            points = [n + k, *route]
            arcs.extend(self.arc_index[points[:-1], points[1:]])
        return np.asarray(arcs, dtype=np.int64)

    def root(
        self,
        budget: float | None = None,
        max_rounds: int | None = None,
    ) -> RootRelaxation:
        """Solve the DFJ LP, separating (2.5) exactly (:func:`separate_subtours`) until none is left.

        The model is switched to its LP relaxation for the loop and back to
        binary σ at the end. Each re-solve after new rows starts from the last
        basis. Stops early after ``budget`` seconds or ``max_rounds`` LPs
        (``complete`` False).
        """
        began = time.perf_counter()
        deadline = None if budget is None else began + budget
        self.model.relax(True)
        rounds, value, complete = 0, -np.inf, False
        bound, reduced, values = -np.inf, np.zeros(len(self.arcs)), None
        try:
            while max_rounds is None or rounds < max_rounds:
                left = None if budget is None else budget - (time.perf_counter() - began)
                if left is not None and left < LP_SECONDS_PER_ARC * len(self.arcs):
                    break  # HiGHS would not even reach its first clock check in time
                rounds += 1
                run = self.model.solve(time_limit=left)
                if run.solver_status != "optimal" or run.objective is None:
                    if run.solver_status not in ("user_limit",):
                        raise SolverError(
                            f"the DFJ LP relaxation ended with status {run.solver_status!r}"
                        )
                    break
                value = run.objective
                values = self.arc_values()
                bound, full_reduced = self.model.lagrangian_bound()
                reduced = full_reduced[self.arcs]
                found = separate_subtours(
                    self.problem, self.tails, self.heads, values, deadline=deadline
                )
                if deadline is not None and time.perf_counter() >= deadline:
                    self.add_cuts(found)  # valid rows, but the separation may be unfinished
                    break
                if not self.add_cuts(found):
                    complete = True
                    break
        finally:
            self.model.relax(False)
        return RootRelaxation(
            cuts=list(self.cuts),
            value=value,
            bound=bound,
            reduced_costs=reduced,
            values=values,
            rounds=rounds,
            complete=complete,
        )


def dfj_root(problem: AssignmentProblem, time_limit: float | None = None) -> RootRelaxation:
    """The root DFJ LP of (2.2)–(2.5) with its exactly separated (2.5) rows.

    Every returned subset S is a row of (2.5), so any feasible solution
    satisfies ``Σ_{i,j∈S} σ_ij ≤ |S| − 1``.

    Example
    -------
    >>> import numpy as np
    >>> from taopt import AssignmentProblem
    >>> cost = np.array([[0, 1, 9], [1, 0, 9], [5, 6, 0.0]])
    >>> root = dfj_root(AssignmentProblem(cost, 2))
    >>> root.cuts, root.value
    ([(0, 1)], 6.0)
    """
    _check(problem, "dfj")
    return DfjModel(problem).root(budget=time_limit)


# --------------------------------------------------------------------------- solving
def _as_routes(problem: AssignmentProblem, incumbent: Any) -> list[list[int]] | None:
    """The incumbent's routes (a list of routes or anything with ``.routes``), checked."""
    if incumbent is None:
        return None
    routes = getattr(incumbent, "routes", incumbent)
    routes = [[int(t) for t in route] for route in routes]
    evaluate_routes(problem, routes)  # raises FeasibilityError naming what is wrong
    return routes


def _solution(
    problem: AssignmentProblem,
    objective: float,
    status: str,
    bound: float | None,
    started: float,
    method: str,
    routes: list[list[int]] | None,
    info: dict[str, Any],
) -> Solution:
    """The one place this module builds a :class:`taopt.Solution`."""
    return Solution(
        objective=objective,
        status=status,
        bound=bound,
        runtime=time.perf_counter() - started,
        method=method,
        solution=None if routes is None else Routes(routes),
        info=info,
    )


def solve_routing(
    problem: AssignmentProblem,
    sec: str = "dfj",
    time_limit: float | None = None,
    mip_gap: float = 1e-6,
    relax: bool = False,
    verbose: bool = False,
    max_rounds: int = 10_000,
    incumbent: Any = None,
) -> Solution:
    """Solve (2.2)–(2.5) exactly with HiGHS (or its LP relaxation).

    Parameters
    ----------
    problem : AssignmentProblem
    sec : {"dfj", "mtz", "flow"}
        Subtour elimination; all three give the same optimum.
    time_limit : float, optional
        Wall-clock seconds for the whole call, building included: it returns
        within about ``time_limit + 0.5`` s with status "time_limit", the best
        routes found and a proven bound. A stage (building the model, an LP,
        a MIP round; for MTZ / flow, cvxpy's compilation and HiGHS's presolve)
        is not started when its per-arc estimate (:data:`BUILD_SECONDS_PER_ARC`,
        :data:`LP_SECONDS_PER_ARC`, :data:`COMPACT_SECONDS_PER_ARC`) exceeds the
        time left; the bound is then the best of :func:`entry_bound`,
        :func:`assignment_bound` and what was proven (``info["stage"] ==
        "build"`` when no model was built).
    mip_gap : float
        Relative MIP gap passed to HiGHS (``mip_rel_gap``). The status is
        "optimal" only when the final gap is at most
        :data:`OPTIMALITY_TOLERANCE` (1e-6); a run stopped by a looser
        ``mip_gap`` is "feasible" with its proven bound
        (``info["stopped_by"] == "mip_gap"``).
    relax : bool
        Return the LP relaxation value instead (status "relaxation",
        objective = bound = LP value, routes None). For DFJ the LP is solved
        with *all* of (2.5), separated exactly by minimum cuts.
    verbose : bool
        HiGHS log.
    max_rounds : int
        Cap on DFJ MIP rounds. A loop stopped by it returns the best repaired
        incumbent with status "feasible" (``info["stopped_by"] ==
        "max_rounds"``) unless its gap is already closed.
    incumbent : list of routes or Solution, optional
        A feasible solution (one route per vehicle, or anything with
        ``.routes``), e.g. a heuristic's. It is the first incumbent and is
        given to HiGHS as a MIP start (``Highs.setSolution``). The models
        never call a heuristic themselves; without one, a greedy start
        (:func:`greedy_routes`) is used.

    Returns
    -------
    Solution
        ``routes`` (one list per vehicle), ``objective`` = ``evaluate(routes)``,
        ``status`` by :func:`taopt.models.highs.certify`: "optimal" (gap at
        most 1e-6), "time_limit", or "feasible" (loose ``mip_gap`` or
        ``max_rounds``; ``info["stopped_by"]`` says which),
        ``bound`` a proven lower bound, never above ``objective``.
        ``info`` holds the MIP rounds, the (2.5) rows added, the root LP and
        the solver status.

    Raises
    ------
    InstanceError
        Not an AssignmentProblem or unknown ``sec``.
    FeasibilityError
        ``incumbent`` is not a feasible solution.
    SolverError
        HiGHS returned an unexpected status (e.g. "infeasible").

    Notes
    -----
    DFJ (``sec="dfj"``), on ONE live HiGHS model (:class:`DfjModel`):

    1. Root: the LP of (2.2)–(2.4) is solved and (2.5) rows violated by its
       point are separated exactly (:func:`separate_subtours`) and added, until
       none is left. Its duals give a proven bound L and arc reduced costs d
       (:meth:`taopt.models.highs.HighsModel.lagrangian_bound`).
    2. Core: a solution that uses arc a costs at least ``L + d_a``, so an arc
       with ``d_a > UB − L`` (UB the incumbent's value) cannot be in a better
       solution. The MIP rounds run on a core, every other σ fixed to 0
       through its bound: the arcs with ``d_a ≤ min(UB − L, cap)`` plus the
       incumbent's, ``cap`` being the :data:`CORE_SIZE` ``(n + m)``-th smallest
       d until the core's own optimum has no cycle, then infinite.
    3. Rounds: each MIP round is a relaxation of (2.2)–(2.5) on the core; the
       cycles among targets of its answer, and of every solution HiGHS finds
       on the way (``kCallbackMipSolution``), become new (2.5) rows; every
       solution, its cycles patched in (:func:`repair`), may improve the
       incumbent, which is the next round's MIP start, and the core is
       resized to the new UB.

    Each round proves ``min(B, L + min_{a ∉ core} d_a)``, with B HiGHS's bound
    on the core: a solution either stays in the core (cost at least B) or
    uses an arc outside it. The reported bound is the largest of these, L, and
    ``Σ_j min_i t(i, j)`` (:func:`entry_bound`); the loop stops as soon as it
    is within ``max(mip_gap, 1e-6)`` of the incumbent.

    Every MIP answer is checked by :meth:`taopt.models.highs.HighsModel.solve`
    (HiGHS's objective must be the value of its point; HiGHS 1.16 can accept a
    MIP start in its presolved space with a wrong objective and call it optimal,
    and such a run is done again without presolve). Should a round still bring
    nothing new (no cycle, no change of the core) while the gap is open, the
    loop hands its incumbent to the compact :data:`FALLBACK_SEC` model on all
    arcs, which ends optimal without a time limit: no run without a limit
    ends "feasible" for want of progress.

    MTZ and flow are compact: one solve on a compiled model, with the
    incumbent as MIP start.

    References
    ----------
    Thesis §2.2.1, (2.2)–(2.5).
    """
    _check(problem, sec)
    started = time.perf_counter()
    if relax:
        return _solve_relaxation(problem, sec, started, verbose)
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    given = _as_routes(problem, incumbent)
    if sec == "dfj":
        return _solve_dfj(problem, time_limit, mip_gap, verbose, max_rounds, given, started)
    return _solve_compact(problem, sec, time_limit, mip_gap, verbose, given, started)


def _first_incumbent(
    problem: AssignmentProblem, given: list[list[int]] | None
) -> tuple[list[list[int]], float]:
    """The better of the given routes and the greedy start, with its value."""
    best_routes = greedy_routes(problem)
    best_value = evaluate_routes(problem, best_routes)
    if given is not None:
        value = evaluate_routes(problem, given)
        if value <= best_value:
            best_routes, best_value = given, value
    return best_routes, best_value


def _solve_dfj(problem, time_limit, mip_gap, verbose, max_rounds, given, started) -> Solution:
    def remaining() -> float | None:
        return None if time_limit is None else time_limit - (time.perf_counter() - started)

    n, m = problem.n, problem.m
    best_routes, best_value = _first_incumbent(problem, given)
    best_bound = entry_bound(problem)
    left = remaining()
    if left is None or left > ASSIGNMENT_SECONDS_PER_CUBE * n**2 * (n + m):
        best_bound = max(best_bound, assignment_bound(problem))
    n_arcs = (n + m) * n - n
    left = remaining()
    if left is not None and left < BUILD_SECONDS_PER_ARC * n_arcs:
        # no time to build the model: the incumbent with the bounds proven so far
        bound = min(best_bound, best_value)
        status, stopped_by = certify(best_value, bound, "time_limit")
        info = {"rounds": 0, "cuts": 0, "arcs": n_arcs, "stopped_by": stopped_by}
        info.update(solver_status="", stage="build", mip_gap=mip_gap)
        return _solution(
            problem, best_value, status, bound, started, "exact-dfj", best_routes, info
        )
    dfj = DfjModel(problem, verbose=verbose)
    # 1. root LP with exact separation; at most half of a time limit
    budget = remaining()
    root = dfj.root(budget=None if budget is None else 0.5 * budget)
    root_cuts = len(dfj.cuts)
    best_bound = max(best_bound, root.bound)
    # 2. the core: arcs of small reduced cost, at most CORE_SIZE per point at first
    # (all arcs if the root LP did not finish)
    if np.isfinite(root.bound):
        size = min(CORE_SIZE * (n + m), len(dfj.arcs))
        cap = float(np.partition(root.reduced_costs, size - 1)[size - 1])
    else:
        cap = np.inf
    core = np.ones(len(dfj.arcs), dtype=bool)

    def resize_core() -> bool:
        """Core := arcs with ``d_a <= min(UB − L, cap)``, plus the incumbent's. Changed?

        Arcs with ``d_a > UB − L`` cannot be in a solution better than the incumbent
        (``UB``); ``cap`` keeps the first rounds small while UB is still poor.
        """
        if not np.isfinite(root.bound):
            return False
        slack = 1e-9 * max(1.0, abs(best_value))
        wanted = root.reduced_costs <= min(best_value - root.bound + slack, cap)
        wanted[dfj.route_arcs(best_routes)] = True
        on, off = wanted & ~core, core & ~wanted
        dfj.model.set_upper(dfj.arcs[on], 1.0)
        dfj.model.set_upper(dfj.arcs[off], 0.0)
        core[:] = wanted
        return bool(on.any() or off.any())

    resize_core()

    def outside_bound() -> float:
        """Proven bound on every solution using an arc outside the core."""
        if core.all():
            return np.inf
        return root.bound + float(root.reduced_costs[~core].min())

    # 3. MIP rounds on the core, (2.5) rows from every solution HiGHS reports
    harvested: list[tuple[int, ...]] = []
    candidates: list[tuple[float, list[list[int]]]] = []

    def harvest(solution: np.ndarray) -> None:
        values = dfj.arc_values(solution)
        try:
            routes, subtours = decode(problem, dfj, values)
        except SolverError:  # not an integral point of (2.3)-(2.4): nothing to learn
            return
        if subtours:
            harvested.extend(tuple(sorted(c)) for c in subtours)
            routes = repair(problem, routes, subtours)
        candidates.append((evaluate_routes(problem, routes), routes))

    target_gap = max(float(mip_gap), OPTIMALITY_TOLERANCE)
    rounds = 0
    solver_status, stopped_by = "", "time_limit"
    stall = False
    while True:
        left = remaining()
        if left is not None and left < LP_SECONDS_PER_ARC * int(core.sum()):
            stopped_by = "time_limit"  # HiGHS would overrun the limit before its first check
            break
        rounds += 1
        dfj.model.set_start(dfj.start_vector(best_routes))
        harvested.clear()
        candidates.clear()
        run = dfj.model.solve(
            time_limit=_highs_limit(left),
            mip_rel_gap=mip_gap,
            on_solution=harvest,
            options=MIP_OPTIONS,
        )
        solver_status = run.solver_status
        if solver_status not in ("optimal", "user_limit"):
            raise SolverError(f"HiGHS returned status {solver_status!r} on the DFJ model")
        # every solution stays in the core (cost >= HiGHS's bound) or leaves it
        core_bound = run.bound if run.bound is not None else -np.inf
        best_bound = max(best_bound, min(core_bound, outside_bound()))
        for value, routes in candidates:
            if value < best_value:
                best_routes, best_value = routes, value
        subtours: list[list[int]] = []
        if run.has_point:
            routes, subtours = decode(problem, dfj, dfj.arc_values())
            candidate = repair(problem, routes, subtours) if subtours else routes
            value = evaluate_routes(problem, candidate)
            if value < best_value:
                best_routes, best_value = candidate, value
        dfj.add_cuts([*map(tuple, subtours), *harvested])
        stopped_by = run.stopped_by
        if relative_gap(best_value, min(best_bound, best_value)) <= target_gap:
            break  # proven: "optimal", or "mip_gap" for a loose gap
        if run.stopped_by in ("time_limit", "solver_limit"):
            break  # a limit: the incumbent stands with the bound proven so far
        if rounds >= max_rounds:
            stopped_by = "max_rounds"
            break
        # only arcs that can still improve on the incumbent stay in the model; once
        # the core's own optimum has no cycle, every such arc comes in
        if not subtours:
            cap = np.inf
        if not run.has_point or (not resize_core() and not subtours):
            # Nothing left to learn, yet the gap is open: the round's answer contradicts
            # the proof (a solver fault, as HiGHS 1.16's MIP starts in a presolved space
            # were before HighsModel checked them). A compact model closes it.
            stall = True
            break
    if stall:
        fallback = _solve_compact(
            problem, FALLBACK_SEC, time_limit, mip_gap, verbose, best_routes, started
        )
        if fallback.objective < best_value:
            best_routes, best_value = fallback.routes, fallback.objective
        if fallback.bound is not None:
            best_bound = max(best_bound, fallback.bound)
        stopped_by = fallback.info["stopped_by"]
        solver_status = fallback.info["solver_status"]
    bound = min(best_bound, best_value)
    # the one rule of taopt.models.highs: optimal only when proven within 1e-6
    status, stopped_by = certify(best_value, bound, stopped_by)
    info = {
        "rounds": rounds,
        "cuts": len(dfj.cuts),
        "root_cuts": root_cuts,
        "root_rounds": root.rounds,
        "lp_bound": root.bound,
        "core_arcs": int(core.sum()),
        "arcs": len(dfj.arcs),
        "solver_status": solver_status,
        "mip_gap": mip_gap,
        "stopped_by": stopped_by,
        "reruns": dfj.model.reruns,
        "fallback": FALLBACK_SEC if stall else None,
    }
    return _solution(problem, best_value, status, bound, started, "exact-dfj", best_routes, info)


def _start_vector(problem, model: HighsModel, formulation: RoutingModel, routes) -> np.ndarray:
    """σ, and MTZ positions u or single-commodity flows f, of ``routes`` as a MIP start."""
    n = problem.n
    vector = np.zeros(model.n_columns)
    arc_index = np.full((n + problem.m, n), -1, dtype=np.int64)
    arc_index[formulation.tails, formulation.heads] = np.arange(len(formulation.tails))
    arc_columns = model.columns(formulation.arc_use)
    for k, route in enumerate(routes):
        points = np.array([n + k, *route], dtype=np.int64)
        arcs = arc_index[points[:-1], points[1:]]
        vector[arc_columns[arcs]] = 1.0
        if formulation.order is not None:  # u_j = position of j on its route
            vector[model.columns(formulation.order)[points[1:]]] = np.arange(1, len(route) + 1)
        if formulation.flow is not None:  # f on the arc into j = targets from j to the end
            vector[model.columns(formulation.flow)[arcs]] = np.arange(len(route), 0, -1)
    return vector


def _highs_limit(left: float | None) -> float | None:
    """HiGHS's ``time_limit`` for ``left`` seconds: :data:`HIGHS_OVERRUN` less (at least 1 ms)."""
    return None if left is None else max(left - HIGHS_OVERRUN, 1e-3)


def _solve_compact(problem, sec, time_limit, mip_gap, verbose, given, started) -> Solution:
    """MTZ or flow: one solve of the compiled model, the incumbent as MIP start."""

    def remaining() -> float | None:
        return None if time_limit is None else time_limit - (time.perf_counter() - started)

    n, m = problem.n, problem.m
    best_routes, best_value = _first_incumbent(problem, given)
    best_bound = entry_bound(problem)
    left = remaining()
    if left is None or left > ASSIGNMENT_SECONDS_PER_CUBE * n**2 * (n + m):
        best_bound = max(best_bound, assignment_bound(problem))
    left = remaining()
    if left is not None and left < COMPACT_SECONDS_PER_ARC * ((n + m) * n - n):
        # cvxpy's build and compilation, and HiGHS's presolve (which does not stop at its
        # time limit), would not fit: the incumbent and the bounds so far
        bound = min(best_bound, best_value)
        status, stopped_by = certify(best_value, bound, "time_limit")
        info = {"rounds": 0, "cuts": 0, "stopped_by": stopped_by, "solver_status": ""}
        info.update(stage="build", mip_gap=mip_gap)
        method = f"exact-{sec}"
        return _solution(problem, best_value, status, bound, started, method, best_routes, info)
    formulation = build(problem, sec)
    model = HighsModel(formulation.problem, verbose=verbose)
    left = remaining()
    model.set_start(_start_vector(problem, model, formulation, best_routes))
    run = model.solve(time_limit=_highs_limit(left), mip_rel_gap=mip_gap)
    if run.solver_status not in ("optimal", "user_limit"):
        raise SolverError(f"HiGHS returned status {run.solver_status!r} on the {sec} model")
    if run.bound is not None:
        best_bound = max(best_bound, run.bound)
    stopped_by = run.stopped_by
    if run.has_point:
        routes, subtours = decode(problem, formulation, model.values(formulation.arc_use))
        if subtours:
            raise SolverError(f"{sec} model returned a subtour {subtours[0]}; (2.5) violated")
        value = evaluate_routes(problem, routes)
        if value < best_value:
            best_routes, best_value = routes, value
    bound = min(best_bound, best_value)
    status, stopped_by = certify(best_value, bound, stopped_by)
    info = {
        "rounds": 1,
        "cuts": 0,
        "nodes": run.nodes,
        "solver_status": run.solver_status,
        "mip_gap": mip_gap,
        "stopped_by": stopped_by,
    }
    return _solution(problem, best_value, status, bound, started, f"exact-{sec}", best_routes, info)


# ------------------------------------------------------------------ LP relaxations
def _solve_relaxation(problem, sec, started, verbose) -> Solution:
    """LP value of (2.2)–(2.5): DFJ with all of (2.5) (exact separation), or MTZ / flow."""
    if sec == "dfj":
        root = DfjModel(problem, verbose=verbose).root()
        if not root.complete:
            raise SolverError("the DFJ LP relaxation did not finish")
        value, rounds, cuts = float(root.value), root.rounds, len(root.cuts)
    else:
        model = HighsModel(build(problem, sec, relax=True).problem, verbose=verbose)
        run = model.solve()
        if run.solver_status != "optimal" or run.bound is None:
            raise SolverError(f"LP relaxation ended with status {run.solver_status!r}")
        value, rounds, cuts = float(run.bound), 1, 0
    info = {"rounds": rounds, "cuts": cuts}
    return _solution(problem, value, RELAXATION, value, started, f"lp-{sec}", None, info)
