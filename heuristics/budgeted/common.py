"""What the budgeted heuristics share: the limit test and the answer (thesis §6.2)."""

from __future__ import annotations

import math
import time
from typing import Any

from taopt.budgeted.problem import BudgetedProblem, evaluate_budgeted
from taopt.heuristics.ga_penalised_search import SLACK
from taopt.result import FEASIBLE, NO_SOLUTION, Routes, Solution


def _fits(time_needed: Any, limit: float) -> Any:
    """Whether a travel time is within ``limit`` (``inf``: no limit), with the heuristics'
    :data:`~taopt.heuristics.ga_penalised_search.SLACK`."""
    return time_needed <= limit + SLACK * max(1.0, limit) if math.isfinite(limit) else True


def _answer(
    problem: BudgetedProblem,
    routes: list[list[int]] | None,
    method: str,
    seed: Any,
    start: float,
    info: dict[str, Any],
) -> Solution:
    """A scored Solution, or status "no_solution" when ``routes`` is None."""
    if routes is None:
        return Solution(
            objective=math.inf,
            status=NO_SOLUTION,
            solution=None,
            runtime=time.perf_counter() - start,
            method=method,
            seed=seed,
            info=info,
        )
    return Solution(
        objective=evaluate_budgeted(problem, routes),  # the one scorer re-checks every limit
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        method=method,
        seed=seed,
        solution=Routes(routes),
        info=info,
    )


def _no_solution(method: str, left: int) -> dict[str, Any]:
    return {
        "unassigned": int(left),
        "error": (
            f"{method} left {left} target(s) that no vehicle can take within its capacity and "
            "maximum travel time (a heuristic's failure, not a proof that the instance is "
            "infeasible)"
        ),
    }
