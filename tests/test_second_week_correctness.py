"""Issue 30, defects 1-3: no false "optimal", heuristics that answer instead of raising.

Reproducers of the defects, then an adversarial round on tiny instances: every method's
answer re-scored by ``taopt.evaluate`` and compared with brute force (budgeted) or the
exact method (SOP). The larger sweeps are ``@pytest.mark.slow``.
"""

from __future__ import annotations

import math

import numpy as np
from reference_budgeted import brute_force_budgeted

import taopt
from taopt.budgeted import BudgetedProblem
from taopt.heuristics import budgeted
from taopt.heuristics.budgeted import genetic_algorithm

# -- defect 2: the budgeted GA -------------------------------------------------------------------


def test_budgeted_ga_with_zero_travel_times_keeps_the_capacity():
    """All travel times 0, capacity [None, 1]: every seed answers a feasible optimum 0."""
    problem = BudgetedProblem(np.zeros((5, 5)), 3, capacity=[None, 1])
    for seed in range(10):
        answer = genetic_algorithm(problem, seed=seed, population=20, generations=20)
        assert str(answer.status) == "feasible"
        assert taopt.evaluate(problem, answer.solution) == answer.objective == 0.0


def test_budgeted_ga_on_an_infeasible_zero_cost_instance_gives_no_solution():
    """Three targets, capacities 0 and 1, travel times 0: no_solution with the reason."""
    problem = BudgetedProblem(np.zeros((5, 5)), 3, capacity=[0, 1])
    assert math.isinf(brute_force_budgeted(problem))
    for seed in range(3):
        answer = genetic_algorithm(problem, seed=seed, population=10, generations=10)
        assert str(answer.status) == "no_solution" and answer.solution is None
        assert "GA met no chromosome" in answer.info["error"]


def test_capacity_unit_is_positive():
    """The price of a target over a capacity is never 0, whatever the travel times."""
    assert budgeted.capacity_unit(BudgetedProblem(np.zeros((4, 4)), 2, capacity=[1, 1])) == 1.0
    cost = np.zeros((4, 4))
    cost[2, 0] = 6.0
    assert budgeted.capacity_unit(BudgetedProblem(cost, 2, capacity=[1, 1])) == 6.0
