"""The fleet teaching MILP under a wall-clock limit: built as arrays, stopped while building or
in HiGHS, always with the incumbent, the family's bound and status ``time_limit``."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
from taopt.fleet.bounds import fleet_lower
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.instances import residential_fleet
from taopt.models import fleet_milp
from taopt.models.fleet_milp import BuildTimeout, build, solve_fleet_milp
from taopt.runtime import Deadline


def _big() -> taopt.FleetProblem:
    """n = 10, K = 2, D = 2, c = 2: 253k rows, a million nonzeros."""
    return residential_fleet(10, 2, 2, 2, seed=0)


def test_build_stops_at_an_expired_deadline():
    """build() raises BuildTimeout (caught by the solver) once its deadline has passed."""
    with pytest.raises(BuildTimeout):
        build(_big(), deadline=Deadline(0.0))


def test_tiny_limit_on_a_big_model_returns_incumbent_and_family_bound():
    """A limit too short to build the model: status time_limit, a feasible plan, and the
    family's bound (<= the objective) instead of an exception."""
    problem = _big()
    solution = solve_fleet_milp(problem, time_limit=1e-3)
    assert solution.status == "time_limit"
    assert solution.info["stopped_in"] == "build"
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)
    assert solution.bound == pytest.approx(fleet_lower(problem))
    assert solution.bound <= solution.objective


def test_tiny_limit_through_solve_is_scored_and_bounded():
    """taopt.solve with a 0.05 s limit: warm start, then the MILP stops; bound <= objective."""
    problem = _big()
    solution = taopt.solve(problem, "milp", time_limit=0.05)
    assert solution.status == "time_limit"
    assert solution.bound is not None and 0 < solution.bound <= solution.objective
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)


def test_rows_and_names_of_the_array_model():
    """Every row belongs to a labelled (F..) family; names follow the export's scheme and are
    unique; column -1 never reaches the matrix."""
    model = build(residential_fleet(3, 1, 2, 2, seed=1))
    assert sum(f["rows"] for f in model.families) == model.matrix.shape[0]
    assert all(f["label"].startswith("(F") for f in model.families)
    names = model.row_names()
    assert len(set(names)) == len(names) and names[0].startswith("eqF1_")
    columns = model.column_names()
    assert len(set(columns)) == model.n_columns and "f" in columns
    assert model.matrix.indices.min() >= 0


def test_array_model_as_cvxpy_has_the_same_optimum():
    """The cvxpy view of the model (``build(problem).problem``) solves to the MILP's optimum,
    which equals brute force."""
    problem = tiny_instance(4, n=2, trucks=1, drones=1, capacity=1, precedence=True, stops=3)
    value, _, _ = brute_force(problem)
    cvx = build(problem).problem
    cvx.solve(solver="HIGHS")
    assert cvx.value == pytest.approx(value, rel=1e-6)
    assert solve_fleet_milp(problem).objective == pytest.approx(value, rel=1e-6)


@pytest.mark.slow
def test_worker_run_certifies_a_tiny_instance(monkeypatch):
    """Slow (a worker process starts): the worker path (every model "big") certifies the same
    optimum as brute force."""
    monkeypatch.setattr(fleet_milp, "WORKER_MIN_NONZEROS", 0)
    problem = tiny_instance(5, n=2, trucks=1, drones=1, capacity=2, precedence=True, stops=3)
    value, _, _ = brute_force(problem)
    solution = solve_fleet_milp(problem, time_limit=30.0)
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(value, rel=1e-6)


@pytest.mark.slow
def test_worker_killed_at_the_limit_keeps_the_incumbent():
    """Slow: HiGHS in its worker is still presolving n = 10 at a 3 s limit; the run returns
    time_limit with a feasible plan and a bound <= the objective."""
    problem = _big()
    solution = solve_fleet_milp(problem, time_limit=3.0)
    assert solution.status == "time_limit"
    assert solution.bound is not None and solution.bound <= solution.objective
    assert np.isfinite(taopt.evaluate(problem, solution.solution))


def test_truck_precedence_rows_keep_the_optimum():
    """Truck-served customers under precedence: the (F16') rows (a truck serves r before j at
    an earlier position) are built, and the MILP still equals brute force."""
    problem = tiny_instance(1, n=3, trucks=1, drones=0, capacity=1, precedence=True, stops=3)
    labels = [f["label"] for f in build(problem).families]
    assert any(label.startswith("(F16')") for label in labels)
    value, _, _ = brute_force(problem)
    solution = solve_fleet_milp(problem)
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(value, rel=1e-6)
