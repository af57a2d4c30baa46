"""Chapter 3 baselines per capability class: §3.7's GA, and chapter 2's MC.

The problem splits exactly by class (§3.4.2, §3.6), so a chapter 2 method run on each
class's :class:`~taopt.AssignmentProblem` (``problem.classes[q].problem``: targets T_q,
vehicles R_q) and joined gives a solution of (3.1)–(3.3) whose value is the sum of the
classes' values.

* "GA" (§3.7): chapter 2's GA (:func:`taopt.heuristics.ga_routing.genetic_algorithm`,
  marker-gene encoding, tournament selection; its operators are documented there and in
  ``docs/ga-operators.md``) on each class with population ``3 (|T_q| + |R_q|)``, crossover
  rate 0.9, mutation rate 0.1 and 350 generations, as §3.7 prescribes. ``operators`` picks
  the chapter 2 GA's operator set: its default ("memetic", with local search) or
  "ox-inversion" (OX1, inversion, no local search: the plain GA the thesis describes, used
  for the reproduction in ``docs/reproduction/chapter3.md``). Class q's seed is drawn from ``(seed, q)`` by
  ``numpy.random.SeedSequence``, so the same seed gives the same routes.
* "MC": chapter 2's marginal-cost clustering (2.15) per class (a cheap, strong baseline the
  thesis does not run in chapter 3).
"""

from __future__ import annotations

import inspect
import time
from typing import Any

import numpy as np

from taopt.capability.problem import CapabilityProblem
from taopt.errors import InstanceError
from taopt.heuristics.clustering import mc
from taopt.heuristics.ga_routing import genetic_algorithm, improve_routes
from taopt.registry import register_improver, register_method
from taopt.result import FEASIBLE, Routes, Solution, make_solution
from taopt.runtime import Deadline

__all__ = ["class_seed", "ga_per_class", "mc_per_class"]


def class_seed(seed: int | None, q: int) -> int | None:
    """Seed of class q's run from the method's seed (None stays None: not reproducible)."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InstanceError(f"seed must be a non-negative integer or None, got {seed!r}")
    return int(np.random.SeedSequence([int(seed), int(q)]).generate_state(1)[0])


# the exact model of chapter 3 solves each class as a chapter-2 problem: the same improver
register_improver(CapabilityProblem)(improve_routes)


@register_method(CapabilityProblem, "GA")
def ga_per_class(
    problem: CapabilityProblem,
    seed: int | None = 0,
    generations: int = 350,
    crossover_rate: float = 0.9,
    mutation_rate: float = 0.1,
    population_factor: int = 3,
    tournament: int | None = None,
    operators: str | None = None,
    time_limit: float | None = None,
) -> Solution:
    """§3.7's GA: chapter 2's GA on each class, population 3 (|T_q| + |R_q|).

    Parameters
    ----------
    problem : CapabilityProblem
    seed : int or None
        Same seed, same result.
    generations : int
        Iterations per class (thesis: 350).
    crossover_rate, mutation_rate : float
        Thesis: 0.9 and 0.1.
    population_factor : int
        Population ``population_factor * (|T_q| + |R_q|)`` (thesis: 3); at least 2.
    tournament : int, optional
        Tournament size (the thesis gives none; default: the chapter 2 GA's).
    operators : str, optional
        The chapter 2 GA's operator set ("memetic", "ox-inversion"; default: its default).
    time_limit : float, optional
        Wall-clock seconds for all classes, shared out evenly over the classes still to
        run; each class's GA stops on its share with its best so far.

    Returns
    -------
    Solution
        ``info["per_class"]``: each class's population, objective and time.

    References
    ----------
    Thesis §3.7 (population 3(|T_q| + |R_q|), rates 0.9 / 0.1, 350 generations).
    """
    start = time.perf_counter()
    takes = inspect.signature(genetic_algorithm).parameters
    extra: dict[str, Any] = {}
    if tournament is not None:
        extra["tournament"] = tournament
    if operators is not None:
        if "operators" not in takes:
            raise InstanceError("this version of the chapter 2 GA has no 'operators' option")
        extra["operators"] = operators
    class_routes = {}
    per_class = []
    deadline = Deadline(time_limit)
    classes = [(q, cls) for q, cls in enumerate(problem.classes) if cls.problem is not None]
    for index, (q, cls) in enumerate(classes):
        left = deadline.remaining()  # None without a limit
        if left is not None:
            extra["time_limit"] = max(left / (len(classes) - index), 1e-3)
        population = max(2, population_factor * (len(cls.targets) + len(cls.vehicles)))
        result = genetic_algorithm(
            cls.problem,
            seed=class_seed(seed, q),
            population=population,
            generations=generations,
            crossover_rate=crossover_rate,
            mutation_rate=mutation_rate,
            **extra,
        )
        class_routes[cls.capability] = result.routes
        per_class.append(
            {
                "capability": str(cls.capability),
                "population": population,
                "objective": result.objective,
                "runtime": result.runtime,
            }
        )
    routes = problem.join(class_routes)
    return make_solution(
        problem,
        Routes(routes),
        method="GA",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
        info={"per_class": per_class},
    )


@register_method(CapabilityProblem, "MC")
def mc_per_class(problem: CapabilityProblem, seed: int | None = 0) -> Solution:
    """Chapter 2's marginal-cost clustering (2.15) on each class (deterministic)."""
    start = time.perf_counter()
    class_routes = {
        cls.capability: mc(cls.problem).routes for cls in problem.classes if cls.problem
    }
    return make_solution(
        problem,
        Routes(problem.join(class_routes)),
        method="MC",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )
