"""A student's formulation against the certified optimum: the smallest counterexample.

:func:`~taopt.orchestration.checker.check_formulation` solves a student's cvxpy model on
random small instances of a family (seeded) and on the family's packaged example when it is
small, compares each answer with the certified optimum of ``taopt.solve(problem, "exact")``,
and on the first disagreement shrinks the instance (one target/customer less, one vehicle
less, while the disagreement persists) to the smallest counterexample it finds. The answer is a
:class:`~taopt.orchestration.checker.FormulationReport` (``str(report)`` prints it).

The contract a student's ``build`` follows::

    def build(problem):
        x = cp.Variable(...)
        model = cp.Problem(cp.Minimize(...), [...])   # any linear (MI)LP cvxpy solves

        def decode(problem):                          # called after model.solve()
            return [...]                               # the family's payload (routes, a Plan)

        return model, decode

The checker solves ``model`` with HiGHS, then calls ``decode(problem)`` and scores the
payload with the family's ``taopt.evaluate``, which checks every constraint.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from taopt.errors import InstanceError, TaoptError

__all__ = ["FAILURES", "FormulationReport", "check_formulation", "shrink_steps"]

#: The properties a check can fail, in the order they are looked at.
FAILURES = (
    "student model infeasible/unbounded",
    "infeasible plan",
    "objective too low",
    "objective too high",
)

#: Relative tolerance of the objective comparison (the status rule's optimality tolerance).
TOLERANCE = 1e-6

Build = Callable[[Any], tuple[Any, Callable[[Any], Any]]]


@dataclass
class FormulationReport:
    """What :func:`~taopt.orchestration.checker.check_formulation` found.

    Attributes
    ----------
    family : str
        The family's kind (``assignment_problem``, ``delivery_instance``, ``sop_problem``).
    tried : int
        Instances checked before the first disagreement (all of them when none was found).
    failed : str or None
        One of :data:`~taopt.orchestration.checker.FAILURES`, or None when the student's model
        agreed everywhere.
    detail : str
        Why: the violated constraint named by the family's ``evaluate``, or the two values.
    instance : problem or None
        The smallest counterexample found (None when none was found).
    student_objective, optimum : float
        The student model's value and the certified optimum on ``instance``.
    student_plan, optimal_plan : payload
        The decoded student plan and an optimal plan.
    path : Path or None
        The counterexample's instance file (``out=``).
    shrunk_from : int
        The size (targets or customers) of the first disagreeing instance.
    """

    family: str
    tried: int
    failed: str | None = None
    detail: str = ""
    instance: Any = None
    student_objective: float = math.nan
    optimum: float = math.nan
    student_plan: Any = None
    optimal_plan: Any = None
    path: Path | None = None
    shrunk_from: int = 0
    sizes: dict[str, int] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when no counterexample was found."""
        return self.failed is None

    def __str__(self) -> str:
        if self.ok:
            return f"{self.family}: no counterexample in {self.tried} instances"
        size = ", ".join(f"{v} {k[:-1] if v == 1 else k}" for k, v in self.sizes.items())
        lines = [
            f"{self.family}: counterexample after {self.tried} instances "
            f"(shrunk from {self.shrunk_from} to {size})",
            f"  failed property: {self.failed}",
            f"  why: {self.detail}",
            f"  student objective {_number(self.student_objective)}, "
            f"optimum {_number(self.optimum)}",
            f"  student plan: {_plan_text(self.student_plan)}",
            f"  optimal plan: {_plan_text(self.optimal_plan)}",
        ]
        if self.path is not None:
            lines.append(f"  instance saved: {self.path}")
        lines += ["  instance:", *("    " + line for line in _instance_text(self.instance))]
        return "\n".join(lines)


def _number(value: float) -> str:
    return f"{value:.6g}" if isinstance(value, (int, float)) else str(value)


def _plan_text(plan: Any) -> str:
    if plan is None:
        return "-"
    if hasattr(plan, "launch"):  # a delivery Plan
        return (
            f"order {list(plan.order)}, launch stops {list(plan.launch)}, "
            f"landing stops {list(plan.landing)}"
        )
    try:  # routes (a Routes payload too), as lists; an order, as a list
        items = list(plan)
        return str([list(route) if hasattr(route, "__iter__") else route for route in items])
    except TypeError:
        return str(plan)


def _instance_text(problem: Any) -> list[str]:
    if problem is None:
        return []
    if hasattr(problem, "customers"):  # delivery
        return [
            f"customers {np.round(problem.customers, 1).tolist()}",
            f"stops {problem.s} (depot {problem.depot}), v_drone {problem.v_drone:.4g}, "
            f"v_truck {problem.v_truck:.4g}, flight range L {problem.flight_range:.6g}",
            f"precedences {list(problem.precedences)}",
        ]
    cost = np.asarray(problem.cost)
    head = (
        f"targets 0..{problem.n - 1}, start points {problem.n}..{problem.n + problem.m - 1} "
        "(one per vehicle)"
        if hasattr(problem, "m")
        else f"nodes 0..{len(cost) - 1}, start {problem.start}, end {problem.end}, "
        f"precedences {list(problem.precedences)}"
    )
    return [head, "cost:", *(" ".join(f"{v:8.4g}" for v in row) for row in cost)]


# ----------------------------------------------------------------------------- families
def _routing_random(rng: np.random.Generator, size: int) -> Any:
    """``size`` targets, 1–3 vehicles, asymmetric costs of one of three kinds (uniform reals,
    small integers with ties, 0/1), as ``tests/reference_exact.py`` draws them."""
    from taopt.routing.problem import AssignmentProblem

    m = int(rng.integers(1, 4))
    points = size + m
    kind = int(rng.integers(0, 3))
    if kind == 0:
        cost = rng.uniform(0.0, 100.0, size=(points, points))
    elif kind == 1:
        cost = rng.integers(0, 4, size=(points, points)).astype(float)
    else:
        cost = np.where(rng.random((points, points)) < 0.5, 0.0, 1.0)
    return AssignmentProblem(np.round(cost, 3), size)


def _routing_smaller(problem: Any) -> Iterator[Any]:
    """Each target dropped, then each vehicle dropped (at least one of each kept)."""
    from taopt.routing.problem import AssignmentProblem

    n, m = problem.n, problem.m
    points = np.arange(n + m)
    drops = [(j, n - 1) for j in range(n) if n > 1] + [(n + k, n) for k in range(m) if m > 1]
    for point, targets in drops:
        keep = points[points != point]
        yield AssignmentProblem(problem.cost[np.ix_(keep, keep)], targets)


def _delivery_random(rng: np.random.Generator, size: int) -> Any:
    """``size`` customers on chapter 5's 3×3 street grid over [0, 600]², random precedences,
    a drone 1–3 times faster than the truck and a flight range L between 1.02 and 1.8 times
    the shortest range that serves every customer (so (5.6) binds)."""
    from taopt.delivery.instance import DeliveryInstance

    customers = rng.uniform(0, 600, size=(size, 2))
    stops = np.array([(c * 300.0, r * 300.0) for r in range(3) for c in range(3)])
    nearest = np.sqrt(((customers[:, None, :] - stops[None]) ** 2).sum(axis=2)).min(axis=1)
    pairs = [(a, b) for a in range(size) for b in range(a + 1, size) if rng.random() < 0.3]
    return DeliveryInstance.grid(
        np.round(customers, 1),
        3,
        600.0,
        round(float(rng.uniform(1.0, 3.0)), 3),
        1.0,
        round(2.0 * float(nearest.max()) * float(rng.uniform(1.02, 1.8)), 1),
        precedences=pairs,
    )


def _delivery_smaller(problem: Any) -> Iterator[Any]:
    """Each customer dropped (precedences through it kept transitively)."""
    import networkx as nx

    n = problem.n
    if n <= 1:
        return
    closure = nx.transitive_closure_dag(problem.precedence_graph)
    for j in range(n):
        keep = [c for c in range(n) if c != j]
        index = {c: i for i, c in enumerate(keep)}
        pairs = sorted((index[a], index[b]) for a, b in closure.edges() if j not in (a, b))
        yield problem.replace(customers=problem.customers[keep], precedences=tuple(pairs))


def _sop_random(rng: np.random.Generator, size: int) -> Any:
    """:func:`taopt.sop.generate.random_sop` with ``size`` inner nodes (density 0–0.5)."""
    from taopt.sop.generate import random_sop

    return random_sop(size + 2, float(rng.uniform(0.0, 0.5)), int(rng.integers(0, 2**31)))


def _sop_smaller(problem: Any) -> Iterator[Any]:
    """Each inner node dropped (precedences through it kept transitively)."""
    import networkx as nx

    from taopt.sop.problem import SopProblem

    size = len(problem.cost)
    if size <= 3:
        return
    graph = nx.DiGraph(list(problem.precedences))
    graph.add_nodes_from(range(size))
    closure = nx.transitive_closure_dag(graph)
    for v in range(size):
        if v in (problem.start, problem.end):
            continue
        keep = [c for c in range(size) if c != v]
        index = {c: i for i, c in enumerate(keep)}
        pairs = tuple(sorted((index[a], index[b]) for a, b in closure.edges() if v not in (a, b)))
        yield SopProblem(
            problem.cost[np.ix_(keep, keep)], pairs, index[problem.start], index[problem.end]
        )


@dataclass(frozen=True)
class _Family:
    kind: str
    type_name: str
    random: Callable[[np.random.Generator, int], Any]
    smaller: Callable[[Any], Iterator[Any]]
    size: Callable[[Any], dict[str, int]]


_FAMILIES = {
    f.kind: f
    for f in (
        _Family(
            "assignment_problem",
            "AssignmentProblem",
            _routing_random,
            _routing_smaller,
            lambda p: {"targets": p.n, "vehicles": p.m},
        ),
        _Family(
            "delivery_instance",
            "DeliveryInstance",
            _delivery_random,
            _delivery_smaller,
            lambda p: {"customers": p.n},
        ),
        _Family(
            "sop_problem",
            "SopProblem",
            _sop_random,
            _sop_smaller,
            lambda p: {"nodes": len(p.cost)},
        ),
    )
}


def _family(family: Any) -> _Family:
    name = family if isinstance(family, str) else getattr(family, "__name__", str(family))
    for spec in _FAMILIES.values():
        if name in (spec.kind, spec.type_name):
            return spec
    raise InstanceError(
        f"check_formulation: unknown family {name!r}; choose one of "
        + ", ".join(f"{f.kind} ({f.type_name})" for f in _FAMILIES.values())
    )


def shrink_steps(problem: Any) -> list[Any]:
    """The instances one step smaller than ``problem`` that the checker tries (one target,
    customer or inner node dropped; one vehicle dropped)."""
    return list(_family(type(problem).__name__).smaller(problem))


# ----------------------------------------------------------------------------- one check
@dataclass
class _Verdict:
    failed: str | None
    detail: str = ""
    student_objective: float = math.nan
    optimum: float = math.nan
    student_plan: Any = None
    optimal_plan: Any = None


def _check_one(build: Build, problem: Any) -> _Verdict:
    """Compare the student's model with the certified optimum on one instance."""
    import cvxpy as cp

    from taopt.orchestration.pipeline import solve
    from taopt.runtime.highs import stdout_discarded
    from taopt.scoring import evaluate

    reference = solve(problem, "exact")
    if reference.status not in ("optimal", "infeasible"):  # pragma: no cover - no limit given
        raise TaoptError(f"the exact method ended {reference.status} on {problem!r}")
    optimum = reference.objective if reference.status == "optimal" else math.inf
    model, decode = build(problem)
    with stdout_discarded():
        model.solve(solver=cp.HIGHS)
    verdict = _Verdict(None, optimum=optimum, optimal_plan=reference.solution)
    if model.status not in ("optimal", "optimal_inaccurate"):
        if math.isinf(optimum) and model.status in ("infeasible", "infeasible_inaccurate"):
            return verdict  # both infeasible
        verdict.failed = FAILURES[0]
        verdict.detail = f"HiGHS ended {model.status} on the student's model"
        if math.isfinite(optimum):
            verdict.detail += f"; the problem has an optimum of {optimum:.6g}"
        return verdict
    value = float(model.value)
    verdict.student_objective = value
    try:
        plan = decode(problem)
    except TaoptError as exc:
        verdict.failed, verdict.detail = FAILURES[1], f"the decoder failed: {exc}"
        return verdict
    verdict.student_plan = plan
    try:
        score = float(evaluate(problem, plan))
    except TaoptError as exc:
        verdict.failed, verdict.detail = FAILURES[1], str(exc)
        return verdict
    scale = TOLERANCE * max(1.0, abs(optimum) if math.isfinite(optimum) else 1.0)
    if value < optimum - scale:
        verdict.failed = FAILURES[2]
        verdict.detail = (
            f"the model's optimum {value:.6g} is below the certified optimum {optimum:.6g}: "
            "a constraint (or a cost term) is missing"
        )
    elif score > value + scale:
        verdict.failed = FAILURES[2]
        verdict.detail = (
            f"the model values its plan at {value:.6g}, evaluate at {score:.6g}: the model "
            "under-counts its own plan (a missing constraint or cost term)"
        )
    elif value > optimum + scale:
        verdict.failed = FAILURES[3]
        verdict.detail = (
            f"the model's optimum {value:.6g} is above the certified optimum {optimum:.6g}: "
            "a constraint cuts off the optimal plan"
        )
    return verdict


def _shrink(build: Build, spec: _Family, problem: Any, verdict: _Verdict) -> tuple[Any, _Verdict]:
    """Drop one item at a time while the disagreement persists (greedy, first success)."""
    changed = True
    while changed:
        changed = False
        for smaller in spec.smaller(problem):
            try:
                candidate = _check_one(build, smaller)
            except InstanceError:  # e.g. a customer no stop can serve any more
                continue
            if candidate.failed is not None:
                problem, verdict, changed = smaller, candidate, True
                break
    return problem, verdict


def _instances(
    spec: _Family, sizes: Iterable[int], trials: int, seed: int, extra: Iterable[Any]
) -> Iterator[Any]:
    """The extra (reference) instances, the packaged example when it is small, then
    ``trials`` random ones with sizes cycling through ``sizes``."""
    yield from extra
    from taopt import examples
    from taopt.orchestration.solving import load_problem_file

    example, _ = load_problem_file(examples.path(spec.kind), progress=False)
    if sum(spec.size(example).values()) <= 10:
        yield example
    rng = np.random.default_rng([34, seed])
    size_list = list(sizes)
    for trial in range(trials):
        yield spec.random(rng, int(size_list[trial % len(size_list)]))


def check_formulation(
    build: Build,
    family: Any,
    sizes: Iterable[int] = (2, 3, 4, 5),
    trials: int = 20,
    seed: int = 0,
    out: str | Path | None = None,
    instances: Iterable[Any] = (),
) -> FormulationReport:
    """Check a student's model against the certified optimum; shrink the first counterexample.

    Parameters
    ----------
    build : callable
        ``build(problem) -> (model, decode)``: ``model`` a linear cvxpy ``Problem`` (a MILP),
        ``decode(problem) -> payload`` called after ``model`` is solved, returning the
        family's payload (routes for a routing problem, a
        :class:`~taopt.delivery.instance.Plan` for a delivery instance, an order for an SOP).
    family : str or type
        ``"assignment_problem"``, ``"delivery_instance"`` or ``"sop_problem"`` (or the
        problem type or its name).
    sizes : iterable of int
        Targets (customers, inner nodes) of the random instances, cycled through.
    trials : int
        Random instances (the family's generator, seeded by ``seed``).
    seed : int
        Same seed, same instances, same report.
    out : path, optional
        Save the counterexample here as the family's JSON file (re-read through the
        schema before it is reported).
    instances : iterable of problems
        Checked first (e.g. reference instances); the packaged example of the family is
        checked next when it has at most 10 targets and vehicles.

    Returns
    -------
    FormulationReport
        ``report.ok`` when every instance agreed; otherwise the smallest counterexample
        found, the failed property (:data:`~taopt.orchestration.checker.FAILURES`:
        ``infeasible plan`` with the violated constraint named by ``evaluate``,
        ``objective too low`` (a missing constraint), ``objective too high`` (an
        over-constraint), ``student model infeasible/unbounded``), both objectives and both
        plans. ``print(report)``.

    Raises
    ------
    InstanceError
        An unknown family.

    Example
    -------
    >>> import cvxpy as cp, numpy as np, taopt
    >>> def assign_only(problem):  # (2.2)-(2.4) with no subtour rows at all
    ...     n, size = problem.n, problem.n + problem.m
    ...     x = cp.Variable((size, n), boolean=True)
    ...     rows = [cp.sum(x, axis=0) == 1, cp.sum(x, axis=1) <= 1, cp.diag(x[:n]) == 0]
    ...     model = cp.Problem(cp.Minimize(cp.sum(cp.multiply(problem.cost[:, :n], x))), rows)
    ...     def decode(problem):
    ...         nxt = {i: int(np.argmax(x.value[i])) for i in range(size) if x.value[i].max() > .5}
    ...         routes = []
    ...         for k in range(problem.m):
    ...             route, point = [], n + k
    ...             while point in nxt and nxt[point] not in route:
    ...                 point = nxt[point]
    ...                 route.append(point)
    ...             routes.append(route)
    ...         return routes
    ...     return model, decode
    >>> report = taopt.check_formulation(assign_only, "assignment_problem", trials=10)
    >>> report.failed, report.sizes["targets"] <= 3
    ('infeasible plan', True)

    Notes
    -----
    Each instance costs one exact solve and one HiGHS solve of the student's model. The
    shrinking is greedy: the first smaller instance (one item dropped) that still disagrees
    is kept, until none does, so the counterexample is minimal by one-item removal (not
    necessarily the smallest of all).

    References
    ----------
    Thesis §2.2.1 (2.2)–(2.5), §5.2.2 (5.1)–(5.7).
    """
    spec = _family(family)
    if trials < 0:
        raise InstanceError(f"trials must be >= 0, got {trials}")
    tried = 0
    for problem in _instances(spec, sizes, trials, seed, instances):
        tried += 1
        verdict = _check_one(build, problem)
        if verdict.failed is None:
            continue
        first = sum(v for k, v in spec.size(problem).items() if k != "vehicles")
        problem, verdict = _shrink(build, spec, problem, verdict)
        path = _save(problem, out) if out is not None else None
        return FormulationReport(
            family=spec.kind,
            tried=tried,
            failed=verdict.failed,
            detail=verdict.detail,
            instance=problem,
            student_objective=verdict.student_objective,
            optimum=verdict.optimum,
            student_plan=verdict.student_plan,
            optimal_plan=verdict.optimal_plan,
            path=path,
            shrunk_from=first,
            sizes=spec.size(problem),
        )
    return FormulationReport(family=spec.kind, tried=tried)


def _save(problem: Any, out: str | Path) -> Path:
    """Write the family's JSON file and read it back through its schema."""
    from taopt.io import save_json
    from taopt.orchestration.solving import load_problem_file
    from taopt.registry import family_of

    path = Path(out)
    save_json(family_of(problem).to_dict(problem), path)
    load_problem_file(path, progress=False)  # validated by the schema, or an error naming it
    return path
