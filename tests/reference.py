"""Reference problems of every registered family, each with its known optimum.

In the style of cvxpy's ``solver_test_helpers``: each function returns a :class:`Reference`
(the problem, its optimum and where that number comes from); :func:`check_method` runs one
registered method on it and checks the property that method promises — an exact method hits
the optimum and proves it, a heuristic, peer or simulation is feasible (re-scored by
``taopt.evaluate``) and never below the optimum, a bound is never above it.

Optima come from hand computation or from an independent brute force written here (never
from the solvers under test).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import networkx as nx
import numpy as np

import taopt
from taopt.registry import family_of, methods

REL = 1e-6


@dataclass(frozen=True)
class Reference:
    """A problem with its known optimum."""

    name: str
    problem: Any
    optimum: float
    source: str
    options: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: An optimal payload when it is unique (routes, order, ...), else None.
    solution: Any = None


#: Every reference problem :func:`check_method` runs every method on: the functions marked
#: with :func:`reference` here, then each ``tests/reference_<family>.py`` module's
#: ``REFERENCES`` (a new family adds a file, not a line here).
REFERENCES: list[Callable[[], Reference]] = []


def reference(make: Callable[[], Reference]) -> Callable[[], Reference]:
    """Decorator: add ``make`` to :data:`REFERENCES`."""
    REFERENCES.append(make)
    return make


@dataclass(frozen=True)
class BruteForce:
    """Random small instances of a family with their optima by an independent brute force,
    on which an exact method must end "optimal" at that value (an infinite optimum: the
    method must prove "infeasible").

    Attributes
    ----------
    name : str
        The test id ("routing", "dp", "milp", ...).
    method : str
        The registered exact method run on them.
    cases : callable
        ``cases(seeds) -> [(problem, optimum), ...]``.
    fast, slow : int
        Instances in the default run, and more (seeds after those) in the ``slow`` run.
    """

    name: str
    method: str
    cases: Callable[[range], list[tuple[Any, float]]]
    fast: int
    slow: int


#: Every brute-force check of ``tests/core/test_exact_brute_force.py``: those registered with
#: :func:`brute_force` there, then each ``tests/reference_<family>.py`` module's
#: ``BRUTE_FORCE``.
BRUTE_FORCE: list[BruteForce] = []


def brute_force(
    name: str, method: str, fast: int, slow: int
) -> Callable[[Callable[[range], list[tuple[Any, float]]]], Callable[..., Any]]:
    """Decorator: register ``cases(seeds)`` as the brute-force check ``name`` of ``method``."""

    def wrap(cases: Callable[[range], list[tuple[Any, float]]]) -> Callable[..., Any]:
        BRUTE_FORCE.append(BruteForce(name, method, cases, fast, slow))
        return cases

    return wrap


# -- independent brute force ----------------------------------------------------------------


def brute_force_routing(cost: np.ndarray, n: int) -> float:
    """Optimum of (2.2)–(2.5) by enumerating every assignment and every visiting order."""
    m = len(cost) - n
    best = np.inf
    for owners in itertools.product(range(m), repeat=n):
        total = 0.0
        for vehicle in range(m):
            mine = [t for t in range(n) if owners[t] == vehicle]
            route_best = np.inf
            for order in itertools.permutations(mine):
                nodes = [n + vehicle, *order]
                route_best = min(route_best, sum(cost[a, b] for a, b in itertools.pairwise(nodes)))
            total += route_best
        best = min(best, total)
    return float(best)


def brute_force_delivery(instance: Any) -> float:
    """Best makespan over all precedence-feasible orders, each scheduled by the exact DP."""
    orders = nx.all_topological_sorts(instance.precedence_graph)
    return min(taopt.schedule(instance, list(order)).objective for order in orders)


# -- the references ----------------------------------------------------------------------------


def layered_grid_delivery(n: int, seed: int = 0) -> Any:
    """n random customers on a 1 km grid of 11 x 11 stops with layered precedences (unit speeds,
    L = 300 m): the delivery instance the verify and Ctrl-C tests share."""
    from taopt.delivery.dags import layered_dag
    from taopt.delivery.instance import DeliveryInstance

    rng = np.random.default_rng(seed)
    customers = rng.uniform(0, 1000, size=(n, 2))
    pairs = layered_dag(n, layers=3, density=0.2, seed=rng)
    return DeliveryInstance.grid(
        customers, 11, 1000.0, v_drone=1.0, v_truck=1.0, flight_range=300.0,
        precedences=pairs, name=f"delivery-{n}",
    )  # fmt: skip


@reference
def routing_line() -> Reference:
    """Targets at 1, 2, 4 and vehicles at 0 and 5 on a line: 0→1→2 and 5→4, total 3."""
    x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    problem = taopt.AssignmentProblem(abs(x[:, None] - x[None, :]), n_targets=3, name="line")
    return Reference("routing-line", problem, 3.0, "by hand", solution=[[0, 1], [2]])


def routing_quick_tour() -> Reference:
    """The package docstring's 2-target, 1-vehicle matrix: the optimum 4 by the route [1, 0]."""
    cost = np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]], dtype=float)
    problem = taopt.AssignmentProblem(cost, n_targets=2, name="quick-tour")
    return Reference("routing-quick-tour", problem, 4.0, "by hand", solution=[[1, 0]])


def routing_one_way() -> Reference:
    """One vehicle, two targets: 0 -> 1 costs 1 but 1 -> 0 costs 100; optimum 2 by [0, 1]."""
    cost = np.array([[0, 1, 50], [100, 0, 50], [1, 1, 0]], dtype=float)
    problem = taopt.AssignmentProblem(cost, n_targets=2, name="one-way")
    return Reference("routing-one-way", problem, 2.0, "by hand", solution=[[0, 1]])


def routing_idle_vehicle() -> Reference:
    """Targets at 1, 2, 3 and vehicles at 0 and 100 on a line: the far one stays idle; 3."""
    x = np.array([1.0, 2.0, 3.0, 0.0, 100.0])
    problem = taopt.AssignmentProblem(abs(x[:, None] - x[None, :]), n_targets=3, name="idle")
    return Reference("routing-idle-vehicle", problem, 3.0, "by hand", solution=[[0, 1, 2], []])


@reference
def routing_asymmetric() -> Reference:
    """A random asymmetric 5-target, 2-vehicle matrix (brute force over all routes)."""
    rng = np.random.default_rng(11)
    cost = rng.uniform(1.0, 20.0, size=(7, 7))
    problem = taopt.AssignmentProblem(cost, n_targets=5, name="asym-5-2")
    return Reference(
        "routing-asymmetric", problem, brute_force_routing(problem.cost, 5), "brute force"
    )


@reference
def delivery_small() -> Reference:
    """Five customers on a 3×3 street grid with two precedences (brute force over orders)."""
    rng = np.random.default_rng(5)
    inst = taopt.DeliveryInstance.grid(
        rng.uniform(0, 600, size=(5, 2)), 3, 600.0, 1.0, 1.0, 700.0, precedences=[(0, 1), (2, 3)]
    )
    return Reference(
        "delivery-small",
        inst,
        brute_force_delivery(inst),
        "every topological order scheduled exactly",
        options={"GA": {"population": 8, "generations": 20}},
    )


@reference
def sop_esc07() -> Reference:
    """TSPLIB's ESC07 sequential ordering instance, optimum 2125 (TSPLIB95)."""
    return Reference("sop-ESC07", taopt.SopProblem.load("ESC07"), 2125.0, "TSPLIB95")


def sop_esc12() -> Reference:
    """TSPLIB's ESC12 sequential ordering instance (14 nodes), optimum 1675 (TSPLIB95)."""
    return Reference("sop-ESC12", taopt.SopProblem.load("ESC12"), 1675.0, "TSPLIB95")


@reference
def capability_small() -> Reference:
    """Two capabilities, 4 targets (one demanding both), 3 vehicles; per-class brute force."""
    rng = np.random.default_rng(3)
    points = rng.uniform(0, 100, size=(7, 2))
    cost = np.linalg.norm(points[:, None] - points[None, :], axis=2)
    problem = taopt.CapabilityProblem(
        cost, 4, ["a", "a", "b"], [{"a"}, {"a", "b"}, {"b"}, {"a"}], name="cap-4-3"
    )
    optimum = sum(
        brute_force_routing(c.problem.cost, c.problem.n) for c in problem.classes if c.problem
    )
    return Reference("capability-small", problem, optimum, "brute force per class (§3.6 split)")


@reference
def comm_small() -> Reference:
    """Chapter 4: 5 targets of two attributes, 3 vehicles, r = 30 m; f_o by brute force per
    class of ``full_information()`` (any simulation drives at least f_o)."""
    rng = np.random.default_rng(4)
    problem = taopt.CommProblem(
        rng.uniform(0, 100, size=(5, 2)),
        rng.uniform(0, 100, size=(3, 2)),
        ["a", "b", "a", "b", "a"],
        ["a", "b", "a"],
        30.0,
        name="comm-5-3",
    )
    optimum = sum(
        brute_force_routing(c.problem.cost, c.problem.n)
        for c in problem.full_information().classes
        if c.problem
    )
    return Reference("comm-small", problem, optimum, "brute force per attribute class")


def _discover() -> None:
    """Add each ``tests/reference_<family>.py`` module's ``REFERENCES`` and ``BRUTE_FORCE``
    (families added later bring their references and brute force in a file of their own)."""
    import importlib
    from pathlib import Path

    for path in sorted(Path(__file__).parent.glob("reference_*.py")):
        module = importlib.import_module(path.stem)
        REFERENCES.extend(getattr(module, "REFERENCES", ()))
        BRUTE_FORCE.extend(getattr(module, "BRUTE_FORCE", ()))


_discover()


def cases() -> list[tuple[Callable[[], Reference], str]]:
    """Every (reference, registered method) pair."""
    import taopt.orchestration.pipeline  # noqa: F401  (registers every method)

    out = []
    for make in REFERENCES:
        problem_type = family_of(make().problem).problem_type
        for name in methods(problem_type):
            out.append((make, name))
    return out


def check_method(reference: Reference, method: str) -> taopt.Solution:
    """Run ``method`` on the reference and check what its category promises."""
    spec = methods(reference.problem)[method]
    options = dict(reference.options.get(method, {}))
    # exact models and peers get 30 s (a peer's worker start-up counts against its limit and
    # takes seconds on a loaded machine; the peers stop on their own, CP-SAT at its proof)
    limit = 30.0 if spec.exact or spec.category == "peer" else 1.0
    solution = taopt.solve(reference.problem, method, seed=0, time_limit=limit, **options)
    value = taopt.evaluate(reference.problem, solution.solution)
    assert abs(value - solution.objective) <= REL * max(1.0, abs(value)), (method, value)
    optimum = reference.optimum
    assert solution.objective >= optimum * (1 - REL) - 1e-9, (method, solution.objective, optimum)
    if solution.bound is not None:
        assert solution.bound <= optimum * (1 + REL) + 1e-9, (method, solution.bound, optimum)
    if spec.exact:
        assert solution.status == "optimal", (method, solution.summary())
    elif spec.category == "peer":  # a peer may prove its answer (CP-SAT does), or stop on the limit
        assert solution.status in ("optimal", "feasible", "time_limit"), (
            method,
            solution.summary(),
        )
    else:
        assert solution.status == "feasible", (method, solution.summary())
    if solution.status == "optimal":  # whoever claims the optimum must be at it
        assert abs(solution.objective - optimum) <= REL * max(1.0, optimum), (method, optimum)
    return solution
