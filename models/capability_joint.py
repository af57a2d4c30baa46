"""Chapter 3's corrected model as ONE MILP over all classes (``solve_capability(problem,
"joint")``, for teaching): (3.1)–(3.3) on class arcs and (2.5) per class, by DFJ cuts added
in a loop or by MTZ order variables.

References
----------
Thesis §3.2.1 (3.1)–(3.3), §2.2.1 (2.5).
"""

from __future__ import annotations

import math
import time
from typing import Any

import cvxpy as cp
import numpy as np
import scipy.sparse as sp

from taopt.bounds import arborescence as arborescence_lower
from taopt.capability.problem import CapabilityProblem, evaluate_capability
from taopt.errors import InstanceError, SolverError
from taopt.models.capability_model import CapabilityModel, _check
from taopt.models.highs import solve_highs
from taopt.result import Routes, Solution, finish
from taopt.runtime import MARGIN

JOINT_SUBTOUR_ELIMINATIONS = ("dfj", "mtz")

#: cvxpy's compile for HiGHS takes about 4-8x the time of building a model (see
#: :data:`taopt.models.sop.COMPILE_PER_BUILD`); a round under a limit keeps that in hand.
COMPILE_PER_BUILD = 8.0


def _joint_arcs(problem: CapabilityProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = problem.n
    tails, heads, classes = [], [], []
    for q, cls in enumerate(problem.classes):
        if cls.problem is None:
            continue
        points = list(cls.targets) + [n + k for k in cls.vehicles]
        cost = problem.cost_for(cls.capability)
        for i in points:
            for j in cls.targets:
                if i != j and math.isfinite(cost[i, j]):
                    tails.append(i)
                    heads.append(j)
                    classes.append(q)
    return np.array(tails, int), np.array(heads, int), np.array(classes, int)


def build_joint(
    problem: CapabilityProblem,
    sec: str = "dfj",
    cuts: list[tuple[int, tuple[int, ...]]] | None = None,
    relax: bool = False,
) -> CapabilityModel:
    """Build the corrected model as one MILP over all classes (see the module notes).

    Parameters
    ----------
    problem : CapabilityProblem
    sec : {"dfj", "mtz"}
        How (2.5) is written per class; for "dfj" only ``cuts`` are present.
    cuts : list of (class index q, subset of targets), optional
    relax : bool

    Returns
    -------
    CapabilityModel
        ``labels`` are class indices q.
    """
    _check(problem)
    if sec not in JOINT_SUBTOUR_ELIMINATIONS:
        raise InstanceError(f"sec must be one of {JOINT_SUBTOUR_ELIMINATIONS}, got {sec!r}")
    n, m = problem.n, problem.m
    size = n + m
    n_classes = len(problem.capabilities)
    tails, heads, classes = _joint_arcs(problem)
    count = len(tails)
    arcs = np.arange(count)
    travel_time = np.array(
        [
            problem.cost_for(problem.capabilities[q])[i, j]
            for i, j, q in zip(tails, heads, classes, strict=True)
        ]
    )
    sigma = (
        cp.Variable(count, name="sigma_ijq", nonneg=True)
        if relax
        else cp.Variable(count, name="sigma_ijq", boolean=True)
    )
    demand_keys = sorted({(int(j), int(q)) for j, q in zip(heads, classes, strict=True)})
    demand_rows = {key: r for r, key in enumerate(demand_keys)}
    row = np.array([demand_rows[int(j), int(q)] for j, q in zip(heads, classes, strict=True)])
    into = sp.csr_matrix((np.ones(count), (row, arcs)), shape=(len(demand_rows), count))
    out_of = sp.csr_matrix(
        (np.ones(count), (tails * n_classes + classes, arcs)), shape=(size * n_classes, count)
    )
    constraints = [
        (into @ sigma == 1).set_label("(3.2) every demanded (target, class) entered once"),
        (out_of @ sigma <= 1).set_label("(3.3) every point left at most once per class"),
    ]
    if relax:
        constraints.append((sigma <= 1).set_label("0 <= sigma_ijq <= 1 (LP relaxation)"))
    order = None
    cuts = list(cuts or [])
    if sec == "dfj" and cuts:
        rows: list[int] = []
        cols: list[int] = []
        for r, (q, subset) in enumerate(cuts):
            inside = np.isin(tails, subset) & np.isin(heads, subset) & (classes == q)
            cols.extend(np.flatnonzero(inside))
            rows.extend([r] * int(inside.sum()))
        lhs = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(cuts), count))
        rhs = np.array([len(s) - 1 for _, s in cuts], dtype=float)
        constraints.append(
            (lhs @ sigma <= rhs).set_label("(2.5) DFJ per class: sum_{i,j in S} sigma_ijq <= |S|-1")
        )
    elif sec == "mtz":
        # u[q, j] in [1, |T_q|]: target j's position on its class-q route. For a target arc
        # i -> j of class q: u_qi - u_qj + |T_q| sigma_ijq <= |T_q| - 1. Big-M: sigma = 1
        # forces u_qj >= u_qi + 1 (no cycle); sigma = 0 leaves u_qi - u_qj <= |T_q| - 1,
        # always true for positions in [1, |T_q|], so M = |T_q| cuts no route.
        order = cp.Variable(n_classes * n, name="u_qj")
        sizes = np.array([len(c.targets) for c in problem.classes], dtype=float)
        target_arcs = np.flatnonzero(tails < n)
        k = len(target_arcs)
        tail_of = sp.csr_matrix(
            (np.ones(k), (np.arange(k), classes[target_arcs] * n + tails[target_arcs])),
            shape=(k, n_classes * n),
        )
        head_of = sp.csr_matrix(
            (np.ones(k), (np.arange(k), classes[target_arcs] * n + heads[target_arcs])),
            shape=(k, n_classes * n),
        )
        big = sizes[classes[target_arcs]]
        upper = np.repeat(np.maximum(sizes, 1.0), n)
        constraints += [
            (order >= 1).set_label("MTZ: 1 <= u_qj"),
            (order <= upper).set_label("MTZ: u_qj <= |T_q|"),
            (
                tail_of @ order - head_of @ order + cp.multiply(big, sigma[target_arcs]) <= big - 1
            ).set_label("(2.5) MTZ per class: u_qi - u_qj + |T_q| sigma_ijq <= |T_q| - 1"),
        ]
    objective = cp.Minimize(travel_time @ sigma)  # (3.1)
    return CapabilityModel(
        problem=cp.Problem(objective, constraints),
        arc_use=sigma,
        tails=tails,
        heads=heads,
        labels=classes,
        formulation="joint",
        order=order,
        cuts=cuts,
    )


def _joint_decode(
    problem: CapabilityProblem, model: CapabilityModel, values: np.ndarray
) -> tuple[list[list[int]], list[tuple[int, tuple[int, ...]]]]:
    """Routes from the class starts and the cycles among targets, per class."""
    n = problem.n
    used = np.flatnonzero(np.asarray(values) > 0.5)
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    cycles: list[tuple[int, tuple[int, ...]]] = []
    for q, cls in enumerate(problem.classes):
        if cls.problem is None:
            continue
        successor = {int(model.tails[a]): int(model.heads[a]) for a in used if model.labels[a] == q}
        seen: set[int] = set()
        for k in cls.vehicles:
            point, route = n + k, []
            while point in successor:
                point = successor[point]
                route.append(point)
            routes[k] = route
            seen.update(route)
        left = [t for t in cls.targets if t not in seen]
        while left:
            cycle, point = [], left[0]
            while point not in cycle:
                cycle.append(point)
                point = successor[point]
            cycles.append((q, tuple(sorted(cycle))))
            left = [t for t in left if t not in cycle]
    return routes, cycles


def _repair(
    problem: CapabilityProblem, routes: list[list[int]], cycles: list[tuple[int, tuple[int, ...]]]
) -> list[list[int]]:
    """A feasible solution from routes plus subtours: each cycle appended to a class route."""
    routes = [list(r) for r in routes]
    for q, cycle in cycles:
        vehicle = problem.classes[q].vehicles[0]
        routes[vehicle].extend(cycle)
    return routes


def _solve_joint(
    problem: CapabilityProblem,
    time_limit: float | None,
    incumbent: Any,
    sec: str,
    mip_gap: float,
    verbose: bool,
    start: float,
    max_rounds: int = 10_000,
) -> Solution:
    if sec not in JOINT_SUBTOUR_ELIMINATIONS:
        raise InstanceError(f"sec must be one of {JOINT_SUBTOUR_ELIMINATIONS}, got {sec!r}")
    best_routes: list[list[int]] | None = None
    best_value = math.inf
    if incumbent is not None:
        best_routes = Routes(getattr(incumbent, "solution", incumbent)).as_lists()
        best_value = evaluate_capability(problem, best_routes)
    best_bound = 0.0
    cuts: list[tuple[int, tuple[int, ...]]] = []
    rounds = 0
    stopped_by = "optimal"
    solver_status = ""
    while True:
        rounds += 1
        left = None if time_limit is None else time_limit - (time.perf_counter() - start)
        if left is not None and left <= 0:
            stopped_by = "time_limit"
            break
        building = time.perf_counter()
        model = build_joint(problem, sec, cuts)
        if time_limit is not None:  # cvxpy compiles outside HiGHS's clock: about 4-8x the build
            left = time_limit - (time.perf_counter() - start)
            left -= COMPILE_PER_BUILD * (time.perf_counter() - building) + MARGIN
            if left <= 0:
                stopped_by = "time_limit"
                break
        run = solve_highs(model.problem, time_limit=left, mip_rel_gap=mip_gap, verbose=verbose)
        solver_status = run.solver_status
        if run.status in ("error", "infeasible"):
            raise SolverError(f"HiGHS returned {run.solver_status!r} on the joint model")
        if run.bound is not None:
            best_bound = max(best_bound, run.bound)
        if not run.has_point:
            stopped_by = run.stopped_by
            break
        arc_values = model.arc_use.value
        assert arc_values is not None  # has_point
        routes, cycles = _joint_decode(problem, model, arc_values)
        candidate = _repair(problem, routes, cycles) if cycles else routes
        value = evaluate_capability(problem, candidate)
        if value < best_value:
            best_routes, best_value = candidate, value
        if cycles:
            if sec != "dfj":
                raise SolverError(f"the MTZ joint model returned a subtour {cycles[0]}")
            cuts.extend(cycles)
            if run.stopped_by == "time_limit" or rounds >= max_rounds:
                stopped_by = "time_limit" if run.stopped_by == "time_limit" else "max_rounds"
                break
            continue
        stopped_by = run.stopped_by
        break

    info = {
        "formulation": "joint",
        "sec": sec,
        "rounds": rounds,
        "cuts": len(cuts),
        "solver_status": solver_status,
        "stopped_by": stopped_by,
    }
    return _joint_answer(problem, best_routes, best_bound, stopped_by, info, start)


def _joint_answer(
    problem: CapabilityProblem,
    best_routes: list[list[int]] | None,
    best_bound: float,
    stopped_by: str,
    info: dict[str, Any],
    start: float,
) -> Solution:
    """The joint model's answer by :func:`taopt.result.finish`; on a time limit the
    family's arborescence bound (:func:`taopt.bounds.arborescence`) keeps the gap honest.
    Without routes only a time limit is an answer (status "time_limit", objective inf)."""
    if best_routes is None:
        if stopped_by != "time_limit":
            raise SolverError(
                f"the joint model found no feasible solution ({info['solver_status']})"
            )
        # no plan in time: status time_limit, objective inf, the bound stands
        return finish(
            problem,
            None,
            method="exact-joint",
            stop="time_limit",
            bound=max(best_bound, float(arborescence_lower(problem))),
            runtime=time.perf_counter() - start,
            info=info,
        )
    if stopped_by == "time_limit":  # a valid bound of the family keeps the gap honest
        best_bound = max(best_bound, float(arborescence_lower(problem)))
    return finish(
        problem,
        Routes(best_routes),
        method="exact-joint",
        stop=stopped_by,
        bound=best_bound,
        runtime=time.perf_counter() - start,
        info=info,
    )
