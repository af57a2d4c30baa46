"""Student formulations for :func:`taopt.check_formulation`: three textbook mistakes and the
correct models they come from (tests and the docs page ``docs/export-and-checker.md``).

Each ``build(problem)`` returns ``(cvxpy.Problem, decode)`` with ``decode(problem)`` the
family's payload, the checker's contract. Chapter 2's models are written from scratch the
way a course would (a matrix ``x[i, j]`` over points × targets); chapter 5's reuse the
toolkit's builder (:func:`taopt.models.delivery.build`).

* :func:`mtz_no_start_rows` — MTZ without the rows "each vehicle leaves its start at most
  once" ((2.4) at the start points): a vehicle may leave its start twice.
* :func:`dfj_pairs_only` — (2.5) written only for |S| = 2 (``x_ij + x_ji <= 1``): a subtour
  of three targets survives.
* :func:`drone_without_range` — the truck–drone model without (5.6) (the flight range L):
  sorties too long for the drone.
* :func:`every_vehicle_leaves` — (2.4) at the start points written ``= 1``: every vehicle
  must move (an over-constraint, or no solution when vehicles outnumber targets).
* :func:`forgets_start_legs` — the objective (2.2) without the legs out of the start points:
  feasible plans, a value too low.
* :func:`mtz_complete`, :func:`toolkit_routing`, :func:`toolkit_delivery` — correct.
"""

from __future__ import annotations

from typing import Any

import cvxpy as cp
import numpy as np


def _routes(problem: Any, x: cp.Variable) -> list[list[int]]:
    """A textbook decoder: from each vehicle's start follow the arc used out of each point."""
    n = problem.n
    successor = {}
    for i, j in zip(*np.nonzero(x.value > 0.5), strict=True):
        successor[int(i)] = int(j)  # a point left twice keeps its last arc
    routes = []
    for k in range(problem.m):
        route, point = [], n + k
        while point in successor and successor[point] not in route:
            point = successor[point]
            route.append(point)
        routes.append(route)
    return routes


def _routing_model(
    problem: Any, start_rows: bool | str, sec: str, start_legs: bool = True
) -> tuple[cp.Problem, Any]:
    """(2.2)–(2.5) over ``x[i, j]``, i a target or start point, j a target."""
    n, m = problem.n, problem.m
    size = n + m
    x = cp.Variable((size, n), boolean=True, name="x")
    cost = problem.cost[:, :n].copy()
    if not start_legs:
        cost[n:] = 0.0
    rows = [
        cp.sum(x, axis=0) == 1,  # (2.3) every target entered once
        cp.sum(x[:n], axis=1) <= 1,  # (2.4) every target left at most once
        cp.diag(x[:n]) == 0,  # no self loop
    ]
    if start_rows == "equal":
        rows.append(cp.sum(x[n:], axis=1) == 1)  # WRONG: every vehicle must leave its start
    elif start_rows:
        rows.append(cp.sum(x[n:], axis=1) <= 1)  # (2.4) every vehicle leaves its start once
    if sec == "mtz":
        u = cp.Variable(n, name="u")
        rows += [u >= 1, u <= n]
        rows += [
            u[i] - u[j] + n * x[i, j] <= n - 1 for i in range(n) for j in range(n) if i != j
        ]  # (2.5) MTZ
    else:  # (2.5) for |S| = 2 only
        rows += [x[i, j] + x[j, i] <= 1 for i in range(n) for j in range(i + 1, n)]
    model = cp.Problem(cp.Minimize(cp.sum(cp.multiply(cost, x))), rows)
    return model, lambda problem: _routes(problem, x)


def mtz_no_start_rows(problem: Any) -> tuple[cp.Problem, Any]:
    """WRONG: MTZ routing without the start-vehicle rows of (2.4)."""
    return _routing_model(problem, start_rows=False, sec="mtz")


def dfj_pairs_only(problem: Any) -> tuple[cp.Problem, Any]:
    """WRONG: subtour rows (2.5) only for the subsets of two targets."""
    return _routing_model(problem, start_rows=True, sec="pairs")


def every_vehicle_leaves(problem: Any) -> tuple[cp.Problem, Any]:
    """WRONG: (2.4) at the start points as an equation, so no vehicle may stay idle."""
    return _routing_model(problem, start_rows="equal", sec="mtz")


def forgets_start_legs(problem: Any) -> tuple[cp.Problem, Any]:
    """WRONG: the objective leaves out the first leg of every route."""
    return _routing_model(problem, start_rows=True, sec="mtz", start_legs=False)


def mtz_complete(problem: Any) -> tuple[cp.Problem, Any]:
    """Correct: the same MTZ model with the start-vehicle rows."""
    return _routing_model(problem, start_rows=True, sec="mtz")


def toolkit_routing(problem: Any) -> tuple[cp.Problem, Any]:
    """Correct: the toolkit's own MTZ model (:func:`taopt.models.routing.build`)."""
    from taopt.models.routing import build, decode

    built = build(problem, sec="mtz")
    return built.problem, lambda problem: decode(problem, built)[0]


def drone_without_range(problem: Any) -> tuple[cp.Problem, Any]:
    """WRONG: the truck–drone model with every sortie allowed, whatever its length ((5.6) left
    out: the model is built for a drone of unlimited range)."""
    from taopt.models.delivery import build, decode

    built = build(problem.replace(flight_range=1e9))
    return built.problem, lambda problem: decode(built, problem)


def toolkit_delivery(problem: Any) -> tuple[cp.Problem, Any]:
    """Correct: the toolkit's truck–drone model (:func:`taopt.models.delivery.build`)."""
    from taopt.models.delivery import build, decode

    built = build(problem)
    return built.problem, lambda problem: decode(built, problem)


def toolkit_sop(problem: Any) -> tuple[cp.Problem, Any]:
    """Correct: the toolkit's SOP model (:func:`taopt.models.sop.build`, MTZ form)."""
    from taopt.models.sop import build, decode

    built = build(problem.cost, problem.precedences, problem.start, problem.end, "mtz")
    return built.problem, lambda problem: decode(built)


def sop_without_precedences(problem: Any) -> tuple[cp.Problem, Any]:
    """WRONG: the SOP model built without its precedence rows (a plain Hamiltonian path)."""
    from taopt.models.sop import build, decode

    built = build(problem.cost, (), problem.start, problem.end, "mtz")
    return built.problem, lambda problem: decode(built)
