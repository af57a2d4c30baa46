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
    re-solve, until no cycle is left.
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

import time
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import networkx as nx
import numpy as np
import scipy.sparse as sp

from taopt.errors import InstanceError, SolverError
from taopt.models.highs import OPTIMALITY_TOLERANCE, certify, solve_highs
from taopt.result import RELAXATION, Routes, Solution
from taopt.routing.problem import AssignmentProblem, evaluate_routes

SUBTOUR_ELIMINATIONS = ("dfj", "mtz", "flow")

__all__ = [
    "OPTIMALITY_TOLERANCE",
    "SUBTOUR_ELIMINATIONS",
    "RoutingModel",
    "build",
    "decode",
    "describe",
    "entry_bound",
    "find_subtours",
    "greedy_routes",
    "repair",
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
        arc_use = cp.Variable(n_arcs, name="sigma", nonneg=True)
        bounds = [(arc_use <= 1).set_label("0 <= sigma_ij <= 1 (LP relaxation of binary sigma)")]
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
        Print a small table too.

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
        print(f"(2.2)-(2.5) with sec={sec!r}: n={n} targets, m={problem.m} vehicles")
        for family in families:
            print(f"  {family['rows']:>8}  {family['family']}")
    return families


# ------------------------------------------------------------------------- decoding
def _successors(model: RoutingModel, values: np.ndarray | None = None) -> dict[int, int]:
    values = model.arc_use.value if values is None else values
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
    problem: AssignmentProblem, model: RoutingModel, values: np.ndarray | None = None
) -> tuple[list[list[int]], list[list[int]]]:
    """Turn an integral σ into routes (one per vehicle) and the subtours left over.

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
    """Make routes feasible: open each subtour at its best arc and append it to a route.

    For each cycle, every way to open it (drop arc a -> b, keep the path b ... a)
    and every route to append it to is priced; the cheapest is taken. Used for
    a feasible incumbent when the DFJ loop stops at a limit.
    """
    cost = problem.cost
    routes = [list(r) for r in routes]
    for cycle in subtours:
        cycle = list(cycle)
        # opening at position p drops arc cycle[p-1] -> cycle[p]; the path starts at cycle[p]
        prev = np.roll(cycle, 1)
        ends = np.array([r[-1] if r else problem.n + k for k, r in enumerate(routes)])
        # price[k, p] = t(end of route k, cycle[p]) - t(cycle[p-1], cycle[p])
        price = cost[ends][:, cycle] - cost[prev, cycle][None, :]
        k, p = np.unravel_index(int(np.argmin(price)), price.shape)
        routes[k].extend(cycle[p:] + cycle[:p])
    return routes


def entry_bound(problem: AssignmentProblem) -> float:
    """``Σ_j min_{i≠j} t(i, j)``: a valid lower bound, since (2.3) enters each target once."""
    cost = np.array(problem.cost[:, : problem.n], dtype=float)
    cost[np.arange(problem.n), np.arange(problem.n)] = np.inf
    return float(cost.min(axis=0).sum())


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


# --------------------------------------------------------------------------- solving
def _run(model: RoutingModel, time_limit: float | None, mip_gap: float, verbose: bool):
    """Solve once with :func:`taopt.models.highs.solve_highs`; return the run and σ's values.

    The values are None when HiGHS holds no feasible point (a limit came first,
    or cvxpy raised). Any other outcome than optimal / a limit / a cvxpy error
    (e.g. "infeasible", impossible for (2.2)–(2.5) with a vehicle) raises.
    """
    run = solve_highs(
        model.problem,
        time_limit=time_limit,
        mip_rel_gap=None if model.relax else mip_gap,
        verbose=verbose,
    )
    if run.solver_status not in ("optimal", "user_limit", "solver_error"):
        raise SolverError(f"HiGHS returned status {run.solver_status!r} {run.message}".strip())
    values = model.arc_use.value if run.has_point else None
    return run, values


def solve_routing(
    problem: AssignmentProblem,
    sec: str = "dfj",
    time_limit: float | None = None,
    mip_gap: float = 1e-6,
    relax: bool = False,
    verbose: bool = False,
    max_rounds: int = 10_000,
) -> Solution:
    """Solve (2.2)–(2.5) exactly with HiGHS (or its LP relaxation).

    Parameters
    ----------
    problem : AssignmentProblem
    sec : {"dfj", "mtz", "flow"}
        Subtour elimination; all three give the same optimum.
    time_limit : float, optional
        Wall-clock seconds for the whole solve (all DFJ rounds together).
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
        Cap on DFJ rounds. A loop stopped by it returns the best repaired
        incumbent with status "feasible" (``info["stopped_by"] ==
        "max_rounds"``) unless its gap is already closed.

    Returns
    -------
    Solution
        ``routes`` (one list per vehicle), ``objective`` = ``evaluate(routes)``,
        ``status`` by :func:`taopt.models.highs.certify`: "optimal" (gap at
        most 1e-6), "time_limit", or "feasible" (loose ``mip_gap`` or
        ``max_rounds``; ``info["stopped_by"]`` says which),
        ``bound`` a proven lower bound (HiGHS's MIP dual bound, the DFJ LP
        value, or Σ_j min_i t(i, j), whichever is largest).
        ``info`` holds rounds, cuts and the solver status.

    Raises
    ------
    InstanceError
        Not an AssignmentProblem or unknown ``sec``.
    SolverError
        HiGHS returned an unexpected status (e.g. "infeasible").

    Notes
    -----
    DFJ loop: every round is a MIP with the cuts found so far; it is a
    relaxation of (2.2)–(2.5), so its proven bound is valid for the full
    problem. A solution with no cycle among targets is feasible, hence optimal.
    Cuts found in the LP relaxation (minimum-cut separation) are added before
    the first MIP round, which usually saves rounds.

    References
    ----------
    Thesis §2.2.1, (2.2)–(2.5).
    """
    _check(problem, sec)
    start = time.perf_counter()
    if relax:
        return _solve_relaxation(problem, sec, start, verbose)
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")

    def remaining() -> float | None:
        return None if time_limit is None else time_limit - (time.perf_counter() - start)

    cuts: list[tuple[int, ...]] = []
    rounds = 0
    # Start from a greedy incumbent and the trivial bound of (2.3): every target is
    # entered once, so the optimum is at least Σ_j min_i t(i, j).
    best_routes = greedy_routes(problem)
    best_value = evaluate_routes(problem, best_routes)
    best_bound = entry_bound(problem)
    if sec == "dfj":
        cuts, lp_bound = _lp_subtour_cuts(problem, verbose, budget=remaining())
        best_bound = max(best_bound, lp_bound)
    solver_status = ""
    stopped_by = "time_limit"
    message = ""
    while True:
        rounds += 1
        left = remaining()
        if left is not None and left <= 0:
            stopped_by = "time_limit"
            break
        model = build(problem, sec, cuts=cuts)
        run, values = _run(model, left, mip_gap, verbose)
        solver_status, message = run.solver_status, run.message
        if run.bound is not None:
            best_bound = max(best_bound, run.bound)
        if values is None:
            # no point: a limit came first (or cvxpy raised); the greedy/earlier
            # incumbent stands with the bound proven so far
            stopped_by = run.stopped_by
            break
        routes, subtours = decode(problem, model, values)
        candidate = repair(problem, routes, subtours) if subtours else routes
        value = evaluate_routes(problem, candidate)
        if value < best_value:
            best_routes, best_value = candidate, value
        if subtours:
            if sec != "dfj":
                raise SolverError(f"{sec} model returned a subtour {subtours[0]}; (2.5) violated")
            cuts.extend(tuple(sorted(c)) for c in subtours)
            if run.stopped_by == "time_limit":
                stopped_by = "time_limit"
                break
            if rounds >= max_rounds:
                stopped_by = "max_rounds"
                break
            continue
        stopped_by = run.stopped_by  # "optimal", "mip_gap" or "time_limit"
        break
    bound = min(best_bound, best_value)
    # the one rule of taopt.models.highs: optimal only when proven within 1e-6
    status, stopped_by = certify(best_value, bound, stopped_by)
    return Solution(
        objective=best_value,
        status=status,
        bound=bound,
        runtime=time.perf_counter() - start,
        method=f"exact-{sec}",
        solution=Routes(best_routes),
        info={
            "rounds": rounds,
            "cuts": len(cuts),
            "solver_status": solver_status,
            "mip_gap": mip_gap,
            "stopped_by": stopped_by,
            **({"solver_message": message} if message else {}),
        },
    )


# ------------------------------------------------------------------ LP relaxations
def _violated_subsets(problem: AssignmentProblem, model: RoutingModel, values) -> list[tuple]:
    """Exact separation of (2.5) for a fractional σ by minimum cuts.

    With (2.3), ``Σ_{i,j∈S} σ_ij = |S| − Σ_{i∉S, j∈S} σ_ij``, so (2.5) for S is
    the cut condition ``σ(into S) ≥ 1``. For every target j, a minimum cut from
    a super-source (joined to all start points) to j finds the most violated S
    containing j.
    """
    n = problem.n
    graph = nx.DiGraph()
    source = "source"
    for vehicle in range(problem.m):
        graph.add_edge(source, n + vehicle, capacity=float(n))
    support = np.flatnonzero(values > 1e-9)
    for arc in support:
        graph.add_edge(int(model.tails[arc]), int(model.heads[arc]), capacity=float(values[arc]))
    found: set[tuple[int, ...]] = set()
    for target in range(n):
        if target not in graph:
            continue
        value, (_, sink_side) = nx.minimum_cut(graph, source, target)
        if value < 1 - 1e-6:
            subset = tuple(sorted(int(v) for v in sink_side if v != source and v < n))
            if len(subset) >= 2:
                found.add(subset)
    return sorted(found)


def _lp_subtour_cuts(problem, verbose, budget=None, max_rounds=50) -> tuple[list, float]:
    """Solve the DFJ LP with cuts separated by minimum cut.

    Returns the cuts and the last LP value (a valid lower bound: every LP
    solved is a relaxation of (2.2)–(2.5)); ``-inf`` if no LP finished. Stops
    after half of ``budget`` seconds so the MIP rounds keep the rest.
    """
    start = time.perf_counter()
    cuts: list[tuple[int, ...]] = []
    bound = -np.inf
    for _ in range(max_rounds):
        left = None if budget is None else 0.5 * budget - (time.perf_counter() - start)
        if left is not None and left <= 0:
            break
        model = build(problem, "dfj", relax=True, cuts=cuts)
        run, values = _run(model, left, 0.0, verbose)
        if values is None or run.solver_status != "optimal" or run.bound is None:
            break
        bound = max(bound, run.bound)
        new = [c for c in _violated_subsets(problem, model, np.asarray(values)) if c not in cuts]
        if not new:
            break
        cuts.extend(new)
    return cuts, bound


def _solve_relaxation(problem, sec, start, verbose) -> Solution:
    cuts: list[tuple[int, ...]] = []
    rounds = 0
    while True:
        rounds += 1
        model = build(problem, sec, relax=True, cuts=cuts)
        run, values = _run(model, None, 0.0, verbose)
        if run.solver_status != "optimal" or run.bound is None:
            raise SolverError(f"LP relaxation ended with status {run.solver_status!r}")
        if sec != "dfj":
            break
        new = [c for c in _violated_subsets(problem, model, np.asarray(values)) if c not in cuts]
        if not new:
            break
        cuts.extend(new)
    value = float(run.bound)
    return Solution(
        objective=value,
        status=RELAXATION,
        bound=value,
        runtime=time.perf_counter() - start,
        method=f"lp-{sec}",
        info={"rounds": rounds, "cuts": len(cuts)},
    )
