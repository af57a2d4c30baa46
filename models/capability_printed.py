"""Chapter 3's (3.1)–(3.3) as printed (``solve_capability(problem, "printed")``): the model,
a relaxation, and :func:`~taopt.models.capability_printed.decode_printed`, which names every way its arcs fail to be routes.

The formulation and why it is only a lower bound: :mod:`taopt.models.capability`.

References
----------
Thesis §3.2.1 (3.1)–(3.3).
"""

from __future__ import annotations

import time
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import networkx as nx
import numpy as np
import scipy.sparse as sp

from taopt.capability.problem import CapabilityProblem
from taopt.errors import InstanceError, SolverError
from taopt.models.capability_model import CapabilityModel, _check, _class_index
from taopt.models.highs import solve_highs
from taopt.result import OPTIMAL, RELAXATION, Routes, Solution, make_solution

#: The printed model is meant for small instances (teaching); refuse to build beyond this.
PRINTED_MAX_VARIABLES = 400_000


def _printed_arcs(problem: CapabilityProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n, m = problem.n, problem.m
    size = n + m
    tails, heads, vehicles = [], [], []
    for k, cap in enumerate(problem.vehicle_capability):
        cost = problem.cost_for(cap)
        demanded = np.array([cap in problem.demands[j] for j in range(n)])
        i, j = np.nonzero((~np.eye(size, n, dtype=bool)) & demanded[None, :])
        keep = np.isfinite(cost[i, j])
        tails.append(i[keep])
        heads.append(j[keep])
        vehicles.append(np.full(int(keep.sum()), k))
    return np.concatenate(tails), np.concatenate(heads), np.concatenate(vehicles)


def build_printed(problem: CapabilityProblem, relax: bool = False) -> CapabilityModel:
    """Build (3.1)–(3.3) literally (see the module notes).

    Parameters
    ----------
    problem : CapabilityProblem
    relax : bool
        ``0 <= σ <= 1`` instead of binary.

    Returns
    -------
    CapabilityModel
        ``labels`` are the vehicles k of ``σ_ijk``.

    Raises
    ------
    InstanceError
        More than :data:`PRINTED_MAX_VARIABLES` variables (the printed model has
        ``(n + m - 1) n m`` of them at most; it is for small instances).
    """
    _check(problem)
    n, m = problem.n, problem.m
    size = n + m
    tails, heads, vehicles = _printed_arcs(problem)
    count = len(tails)
    if count > PRINTED_MAX_VARIABLES:
        raise InstanceError(
            f"the printed model would have {count} variables (> {PRINTED_MAX_VARIABLES}); "
            "it is meant for small instances"
        )
    index = _class_index(problem)
    arc_class = np.array([index[problem.vehicle_capability[k]] for k in vehicles], dtype=int)
    n_classes = len(problem.capabilities)
    arcs = np.arange(count)
    travel_time = np.array(
        [
            problem.cost_for(problem.vehicle_capability[k])[i, j]
            for i, j, k in zip(tails, heads, vehicles, strict=True)
        ]
    )
    sigma = (
        cp.Variable(count, name="sigma_ijk", nonneg=True)
        if relax
        else cp.Variable(count, name="sigma_ijk", boolean=True)
    )
    # (3.2): one row per (j, q) with y_jq = 1 (rows with y_jq = 0 have no variable left).
    demand_rows = {
        (j, q): r
        for r, (j, q) in enumerate(
            (j, index[cap])
            for j in range(n)
            for cap in sorted(problem.demands[j], key=lambda c: index[c])
        )
    }
    row = np.array([demand_rows[j, q] for j, q in zip(heads, arc_class, strict=True)])
    into = sp.csr_matrix((np.ones(count), (row, arcs)), shape=(len(demand_rows), count))
    # (3.3): one row per (i, q).
    out_of = sp.csr_matrix(
        (np.ones(count), (tails * n_classes + arc_class, arcs)), shape=(size * n_classes, count)
    )
    constraints = [
        (into @ sigma == 1).set_label("(3.2) sum_{i, k in R_q} sigma_ijk = y_jq (y_jq = 1 rows)"),
        (out_of @ sigma <= 1).set_label("(3.3) sum_{j, k in R_q} sigma_ijk <= 1 per point, class"),
    ]
    if relax:
        constraints.append((sigma <= 1).set_label("0 <= sigma_ijk <= 1 (LP relaxation)"))
    objective = cp.Minimize(travel_time @ sigma)  # (3.1)
    return CapabilityModel(
        problem=cp.Problem(objective, constraints),
        arc_use=sigma,
        tails=tails,
        heads=heads,
        labels=vehicles,
        formulation="printed",
    )


@dataclass(frozen=True)
class PrintedArcs:
    """The arcs chosen by the printed model and what makes them not a routing.

    Attributes
    ----------
    arcs : list of (i, j, k)
        ``σ_ijk = 1``: "vehicle k travels from point i to target j".
    subtours : list of (capability, [targets])
        Cycles among targets in one class's arcs (no vehicle ever reaches them).
    foreign_tails : list of (i, j, k)
        Arcs leaving a point class ``a_k`` never visits: another class's start or a
        target that does not demand ``a_k`` (no flow conservation).
    vehicle_switches : list of (i, j, k, other)
        Arcs whose label k differs from the vehicle ``other`` that is at i: the vehicle
        whose start i is, or the vehicle that entered target i in the same class.
    routes : Routes or None
        When there are no subtours and no foreign tails, the arcs are routes from the
        class starts (relabelled by the start's vehicle): the printed optimum is then
        feasible, hence optimal.
    """

    arcs: list[tuple[int, int, int]]
    subtours: list[tuple[Hashable, list[int]]]
    foreign_tails: list[tuple[int, int, int]]
    vehicle_switches: list[tuple[int, int, int, int]]
    routes: Routes | None

    @property
    def is_routing(self) -> bool:
        return self.routes is not None

    def to_dict(self) -> dict[str, Any]:
        return {
            "arcs": [list(a) for a in self.arcs],
            "subtours": [[str(c), t] for c, t in self.subtours],
            "foreign_tails": [list(a) for a in self.foreign_tails],
            "vehicle_switches": [list(a) for a in self.vehicle_switches],
        }


def decode_printed(
    problem: CapabilityProblem, model: CapabilityModel, values: np.ndarray | None = None
) -> PrintedArcs:
    """Read the printed model's arcs and name every way they fail to be routes."""
    values = model.arc_use.value if values is None else values
    if values is None:
        raise SolverError("the printed model has no solution values to decode")
    n = problem.n
    used = np.flatnonzero(np.asarray(values) > 0.5)
    arcs = [(int(model.tails[a]), int(model.heads[a]), int(model.labels[a])) for a in used]
    subtours: list[tuple[Hashable, list[int]]] = []
    foreign: list[tuple[int, int, int]] = []
    switches: list[tuple[int, int, int, int]] = []
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    clean = True
    for cls in problem.classes:
        cap = cls.capability
        mine = [(i, j, k) for i, j, k in arcs if problem.vehicle_capability[k] == cap]
        own = set(cls.targets) | {n + k for k in cls.vehicles}
        entered_by = {j: k for _, j, k in mine}
        successor = {}
        for i, j, k in mine:
            successor[i] = j
            if i not in own:
                foreign.append((i, j, k))
            holder = i - n if i >= n else entered_by.get(i)
            if holder is not None and holder != k:
                switches.append((i, j, k, holder))
        graph = nx.DiGraph(list(successor.items()))
        for cycle in nx.simple_cycles(graph):
            if all(c < n for c in cycle):
                subtours.append((cap, sorted(cycle)))
        if any(i not in own for i, _, _ in mine) or any(c for c_cap, c in subtours if c_cap == cap):
            clean = False
            continue
        for k in cls.vehicles:
            point, route = n + k, []
            while point in successor:
                point = successor[point]
                route.append(point)
            routes[k] = route
    return PrintedArcs(
        arcs=arcs,
        subtours=subtours,
        foreign_tails=foreign,
        vehicle_switches=switches,
        routes=Routes(routes) if clean else None,
    )


def _solve_printed(
    problem: CapabilityProblem, time_limit: float | None, verbose: bool, start: float
) -> Solution:
    model = build_printed(problem)
    run = solve_highs(model.problem, time_limit=time_limit, verbose=verbose)
    if not run.has_point:
        raise SolverError(f"HiGHS found no point of the printed model ({run.solver_status})")
    decoded = decode_printed(problem, model)
    assert run.objective is not None  # has_point
    value = float(run.objective)
    bound = value if run.status == OPTIMAL else run.bound
    info = {
        "formulation": "printed",
        "variables": len(model.tails),
        "solver_status": run.solver_status,
        "stopped_by": run.stopped_by,
        **decoded.to_dict(),
    }
    if decoded.is_routing and run.status == OPTIMAL:
        # the relaxation's optimum is a feasible routing: it is the true optimum
        solution = make_solution(
            problem,
            decoded.routes,
            method="exact-printed",
            status=OPTIMAL,
            runtime=time.perf_counter() - start,
            info=info,
        )
        return solution.replace(bound=solution.objective)
    return make_solution(
        problem,
        None,
        method="exact-printed",
        status=RELAXATION,
        objective=value,
        bound=bound,
        runtime=time.perf_counter() - start,
        info=info,
    )
