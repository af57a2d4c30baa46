"""The one result type shared by exact models, heuristics and bounds.

A :class:`Solution` carries the status, the objective (scored by the problem's
one ``evaluate`` function), the best proven lower bound, the gap, the runtime,
the seed and the domain solution itself (routes for chapter 2, a plan for
chapter 5, an order for sequencing problems).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

# Named statuses. Only a proven optimum is called OPTIMAL.
OPTIMAL = "optimal"
TIME_LIMIT = "time_limit"  # stopped by a limit; objective is the incumbent, bound is proven
FEASIBLE = "feasible"  # a feasible solution with no optimality claim (heuristics)
RELAXATION = "relaxation"  # the value of a relaxation: a bound, not a solution
INFEASIBLE = "infeasible"
ERROR = "error"

STATUSES = (OPTIMAL, TIME_LIMIT, FEASIBLE, RELAXATION, INFEASIBLE, ERROR)


@dataclass
class Solution:
    """Result of a method on a problem.

    Attributes
    ----------
    objective : float
        Objective value (total travel time for chapter 2, makespan for chapter 5).
    status : str
        One of :data:`STATUSES`.
    bound : float or None
        Best proven lower bound on the optimum, or None when the method proves none.
    runtime : float
        Wall-clock seconds spent by the method.
    method : str
        Name of the method that produced it ("exact-dfj", "MC", "GA", ...).
    seed : int or None
        Seed of a randomised method.
    routes : list of list of int, optional
        Chapter 2: one list of target indices per vehicle, in visiting order.
    plan : object, optional
        Chapter 5: a :class:`taopt.delivery.Plan`.
    order : list of int, optional
        Sequencing problems (SOP): the visiting order.
    info : dict
        Method-specific details (iterations, cuts, solver messages).
    """

    objective: float
    status: str
    bound: float | None = None
    runtime: float = 0.0
    method: str = ""
    seed: int | None = None
    routes: list[list[int]] | None = None
    plan: Any = None
    order: list[int] | None = None
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def gap(self) -> float | None:
        """Relative gap ``(objective - bound) / objective``; None without a bound."""
        if self.bound is None or not math.isfinite(self.objective):
            return None
        if self.objective == 0:
            return 0.0
        return max(0.0, (self.objective - self.bound) / abs(self.objective))

    @property
    def is_optimal(self) -> bool:
        return self.status == OPTIMAL

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

    def __str__(self) -> str:  # pragma: no cover - cosmetic
        return self.summary()
