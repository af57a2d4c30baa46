"""The memetic GA of §2.5 with a penalty for violated limits (thesis §2.5, §6.2):
:func:`genetic_algorithm` and its memetic step."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.budgeted.problem import BudgetedProblem
from taopt.errors import InstanceError
from taopt.heuristics.budgeted.common import _answer
from taopt.heuristics.budgeted.descent import LimitedDescent, repair
from taopt.heuristics.ga_local_search import local_search
from taopt.heuristics.ga_penalised_search import PenalisedSearch, slack_limits
from taopt.heuristics.ga_routing import (
    OPERATOR_SETS,
    _mutate,
    _separate_clones,
    decode,
    encode,
    nodes_to_genes,
    order_crossover,
    path_matrix,
    path_nodes,
)
from taopt.registry import register_method
from taopt.result import Solution
from taopt.runtime import Deadline

#: The GA's memetic steps under limits (:func:`genetic_algorithm`, ``memetic``).
MEMETIC_STEPS = ("penalised", "chapter2")


# -- the GA with a penalty -----------------------------------------------------------------------


def route_times(problem: BudgetedProblem, genes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-vehicle travel times and target counts of chromosomes with vehicle markers.

    Parameters
    ----------
    problem : BudgetedProblem
    genes : (P, n + m − 1) int array
        Chromosomes as :mod:`taopt.heuristics.ga_routing` reads them with
        ``markers="vehicle"`` (marker gene ``n + k − 1`` starts vehicle k's route).

    Returns
    -------
    times : (P, m) array
        Travel time of each vehicle's open route.
    counts : (P, m) int array
        Targets on each vehicle's route.

    Notes
    -----
    Vectorised: O(P (n + m)) numpy work (``np.bincount`` over (row, vehicle) cells).
    """
    n, m = problem.n, problem.m
    genes = np.atleast_2d(genes)
    rows, length = genes.shape
    nodes = path_nodes(problem.routing, genes)
    targets = nodes[:, 1:-1]
    is_target = targets < n
    step = np.where(is_target, problem.cost[nodes[:, :-2], np.where(is_target, targets, 0)], 0.0)
    # vehicle of each gene: the vehicle of the last marker at or before it (0 before any)
    marker_vehicle = np.where(is_target, 0, genes - n + 1)
    last_marker = np.maximum.accumulate(np.where(is_target, -1, np.arange(length)), axis=1)
    vehicle = np.where(
        last_marker >= 0,
        np.take_along_axis(marker_vehicle, np.maximum(last_marker, 0), axis=1),
        0,
    )
    cell = (np.arange(rows)[:, None] * m + vehicle).ravel()
    times = np.bincount(cell, weights=step.ravel(), minlength=rows * m).reshape(rows, m)
    counts = np.bincount(cell, weights=is_target.ravel(), minlength=rows * m).reshape(rows, m)
    return times, counts.astype(int)


def penalised_cost(
    problem: BudgetedProblem, genes: np.ndarray, weight: float, unit: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Total travel time (2.2) + ``weight`` × total violation of each chromosome.

    The violation is ``Σ_k max(0, t_k − T_k) + unit · Σ_k max(0, |o_k| − Q_k)``: excess time
    in time units, and each target beyond a capacity priced at ``unit`` time units.

    Returns
    -------
    penalised : (P,) array
    cost : (P,) array
        The plain total travel time.
    violation : (P,) array
        0 exactly for the chromosomes that keep every limit (with
        :data:`~taopt.heuristics.ga_penalised_search.SLACK`).
    """
    times, counts = route_times(problem, genes)
    limit = slack_limits(problem.max_time)
    over_time = np.where(times > limit, times - problem.max_time, 0.0)
    over_count = np.maximum(counts - problem.capacity, 0.0)
    violation = over_time.sum(axis=1) + unit * over_count.sum(axis=1)
    total = times.sum(axis=1)
    return total + weight * violation, total, violation


def capacity_unit(problem: BudgetedProblem) -> float:
    """Time units of violation per target over a capacity: the median travel time between
    targets (from the starts when n = 1), or, when that is 0, the median positive entry, or 1.

    It must be positive: with a unit of 0 a chromosome over a capacity would count as
    violating nothing, and the GA would return it as feasible (a 3-target instance with all
    travel times 0 and capacity ``[None, 1]`` did, on 7 of 10 seeds).
    """
    n = problem.n
    between = problem.cost[:n, :n][~np.eye(n, dtype=bool)]
    unit = float(np.median(between)) if between.size else float(np.median(problem.cost[n:, :n]))
    if unit > 0:
        return unit
    positive = problem.cost[(problem.cost > 0) & np.isfinite(problem.cost)]
    return float(np.median(positive)) if positive.size else 1.0


@register_method(BudgetedProblem, "GA", category="heuristic")
def genetic_algorithm(
    problem: BudgetedProblem,
    seed: int | np.random.Generator | None = 0,
    population: int = 120,
    generations: int = 350,
    crossover_rate: float = 0.9,
    mutation_rate: float = 0.1,
    penalty: float = 10.0,
    time_limit: float | None = None,
    memetic: str = "penalised",
) -> Solution:
    """The memetic GA of §2.5 with a penalty for violated limits.

    Chapter 2's GA (:func:`taopt.heuristics.ga_routing.genetic_algorithm`, operator set
    "memetic": vehicle markers, binary tournament, OX1, inversion / swap / slide mutation,
    elitism, local search on the 2 best distinct children) run on the *penalised* fitness
    :func:`penalised_cost`: ``f + penalty × violation``.

    A penalty for the population, a repair in the memetic step. Why: the GA's crossover,
    mutations and local search work on the whole chromosome and price moves by their exact
    O(1) change of (2.2); repairing every child would re-insert targets after every
    crossover with a rule of its own and shrink the search to the feasible region, while a
    penalty keeps every operator unchanged and lets infeasible chromosomes carry good genes
    across a tight limit. But a penalty alone rarely *reaches* the feasible region when the
    limits bite (with ``Q_k = n / m`` exactly, random chromosomes almost never have the
    right route lengths: none in 100 generations on a drift n50m10 scenario), and chapter
    2's local search, which minimises (2.2) and ignores the limits, walks straight out of
    it. So the memetic step (``memetic="penalised"``, the default) polishes each of the 2
    best distinct children with the **penalised local search**
    (:class:`~taopt.heuristics.ga_penalised_search.PenalisedSearch`: chapter 2's moves that
    keep the route starts in place, each priced by its exact change of the penalised
    fitness), then, if a limit is still broken, :func:`repair` (cut each route to its
    longest prefix within limits, re-insert the rest by the limit-aware cheapest
    insertion), then :func:`~taopt.heuristics.budgeted.descent.limited_local_search` (relocations and exchanges that keep every
    limit); the result replaces the child when the *penalised* fitness improves. The
    population is kept free of clones (chapter 2's ``distinct`` option), without which it
    collapsed onto one infeasible chromosome on a 6-target instance. Without limits the
    memetic step is chapter 2's alone.

    ``memetic="chapter2"`` is the step this GA had first: two candidates per child, chapter
    2's local search (limits ignored) then the repair then the limit-aware descent, and the
    child itself repaired then the descent; the better one is kept. Measured on the drift
    n50m10 scenario of seed 7 with ``Q = 5``: 8279 with the penalty and repair only, 7518
    with the limit-aware descent after the repair, 6630 with both candidates (PyVRP, 2 s:
    6139). The penalised search replaced it (2026-11-26) because chapter 2's search spent
    most of the time walking to the unconstrained optimum that the repair then cut back:
    on the chapter-6 study's n50m10 scenarios 0–4 (study seeds, same run) it gives answers
    0.5–2.3 % lower on average at Q2–Q1 and T0.6 and within 0.2 % at T1–T0.8, in less time
    at every level (``docs/reproduction/chapter6.md``). The answer is the best *feasible*
    chromosome ever seen (not the best penalised one).

    Parameters
    ----------
    problem : BudgetedProblem
    seed : int or numpy.random.Generator
        Same seed, same result.
    population, generations, crossover_rate, mutation_rate
        As chapter 2's GA (thesis: 120, 350, 0.9, 0.1).
    penalty : float
        λ, time units of penalty per time unit of excess; a target over a capacity counts
        as :func:`capacity_unit` (``info["unit"]``, the median travel time between targets,
        always positive) of excess.
    time_limit : float, optional
        Wall-clock seconds; the run stops after the generation during which it expires
        (``info["stopped_by"] = "time_limit"``).
    memetic : {"penalised", "chapter2"}
        The memetic step under limits (above); ``info["memetic"]``.

    Returns
    -------
    Solution
        The best feasible chromosome, decoded; status "no_solution" and ``objective = inf`` when
        no chromosome ever kept every limit (not a proof of infeasibility). ``info``:
        ``history`` (best feasible cost per generation, ``inf`` until one is found),
        ``first_feasible`` (generation of the first feasible chromosome), ``evaluations``,
        ``moves``, ``repairs`` (repairs tried), ``repaired`` (repairs that succeeded),
        ``penalty``, ``unit``, ``memetic``.

    Raises
    ------
    InstanceError
        population < 2, generations < 0, a rate outside [0, 1], a negative penalty, or an
        unknown memetic step.

    Notes
    -----
    O(generations × population × (n + m)) numpy work plus the local search
    (O((n + m)^2) per move), as chapter 2's GA. With limits the memetic step is a
    deterministic function of the chromosome, so its answer is memoised per chromosome
    (``info["memo_hits"]``): the elite, polished again generation after generation, costs
    nothing after the first time (same answers, about half the local searches at n50m10).
    The repair and the limit-aware descent are remembered per input routes as well
    (``info["route_memo_hits"]``): different chromosomes often reach the same routes, and
    about half of those calls repeat an earlier input at n50m10 Q1–Q1.5 (same answers;
    ``moves`` counts the moves actually searched).

    Example
    -------
    >>> import numpy as np
    >>> from taopt.budgeted import BudgetedProblem
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = BudgetedProblem(abs(x[:, None] - x[None, :]), 3, capacity=[1, 2])
    >>> genetic_algorithm(p, seed=0, population=10, generations=20).objective
    4.0

    References
    ----------
    Thesis §2.5 (the GA), §6.2.
    """
    _check_options(population, generations, crossover_rate, mutation_rate, penalty, memetic)
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    ops = OPERATOR_SETS["memetic"]
    rng = np.random.default_rng(seed)
    n, m = problem.n, problem.m
    length = n + m - 1
    unit = capacity_unit(problem)
    matrix = path_matrix(problem.routing)
    descent = LimitedDescent(problem)
    penalised = PenalisedSearch(problem, penalty, unit) if memetic == "penalised" else None
    counters = {
        "moves": 0,
        "move_evaluations": 0,
        "repairs": 0,
        "repaired": 0,
        "memo_hits": 0,
        "route_memo_hits": 0,
    }
    # polished chromosome -> its memetic step's best candidate; and ("repair" | "descent",
    # routes) -> that step's answer (different chromosomes often reach the same routes)
    memo: dict[Any, Any] = {}
    # clone fingerprints, as chapter 2's GA (fixed weights: they draw nothing from ``rng``)
    weights = np.random.default_rng(0x6A).integers(1, 2**62, size=length, dtype=np.int64)

    genes = rng.permuted(np.tile(np.arange(length), (population, 1)), axis=1)
    fitness, plain, violation = penalised_cost(problem, genes, penalty, unit)
    best = _BestFeasible()
    best.keep(genes, plain, violation, 0)
    history = [best.cost]
    elite = genes[int(np.argmin(fitness))].copy()
    done = 0
    for generation in range(1, generations + 1):
        if deadline.limited and deadline.expired():
            break
        done += 1
        genes = _breed(genes, fitness, elite, ops, (crossover_rate, mutation_rate), weights, rng)
        fitness, plain, violation = penalised_cost(problem, genes, penalty, unit)
        _polish(
            problem, (matrix, descent, penalised), genes, fitness, plain, violation, penalty,
            unit, ops, counters, memo, deadline,
        )  # fmt: skip
        elite = genes[int(np.argmin(fitness))].copy()
        best.keep(genes, plain, violation, generation)
        history.append(best.cost)
    info: dict[str, Any] = {
        "history": history,
        "first_feasible": best.generation,
        "population": population,
        "generations": generations,
        "evaluations": population * (done + 1),
        "penalty": penalty,
        "unit": unit,
        "memetic": memetic,
        **counters,
    }
    if done < generations:
        info.update(stopped_by="time_limit", generations_done=done)
    if best.genes is None:
        info["error"] = (
            "GA met no chromosome that keeps every capacity and maximum travel time (a "
            "heuristic's failure, not a proof that the instance is infeasible)"
        )
        return _answer(problem, None, "GA", seed, start, info)
    routes = decode(problem.routing, best.genes, "vehicle")
    return _answer(problem, routes, "GA", seed, start, info)


def _check_options(
    population: int,
    generations: int,
    crossover_rate: float,
    mutation_rate: float,
    penalty: float,
    memetic: str,
) -> None:
    """The InstanceErrors of :func:`genetic_algorithm`'s options, each naming the option."""
    if population < 2 or generations < 0:
        raise InstanceError(
            f"need population >= 2 and generations >= 0, got {population}, {generations}"
        )
    for label, rate in (("crossover_rate", crossover_rate), ("mutation_rate", mutation_rate)):
        if not 0.0 <= rate <= 1.0:
            raise InstanceError(f"{label} must be in [0, 1], got {rate}")
    if not (math.isfinite(penalty) and penalty >= 0):
        raise InstanceError(f"penalty must be a number >= 0, got {penalty}")
    if memetic not in MEMETIC_STEPS:
        raise InstanceError(f"memetic must be one of {MEMETIC_STEPS}, got {memetic!r}")


@dataclass
class _BestFeasible:
    """The best chromosome that keeps every limit seen so far, its total travel time and
    the generation of the first feasible chromosome (None until one is met)."""

    genes: np.ndarray | None = None
    cost: float = math.inf
    generation: int | None = None

    def keep(
        self, genes: np.ndarray, plain: np.ndarray, violation: np.ndarray, generation: int
    ) -> None:
        """Take the population's best feasible chromosome if it beats the one kept."""
        ok = violation == 0
        if ok.any():
            row = int(np.flatnonzero(ok)[np.argmin(plain[ok])])
            if plain[row] < self.cost:
                self.genes, self.cost = genes[row].copy(), float(plain[row])
            if self.generation is None:
                self.generation = generation


def _breed(
    genes: np.ndarray,
    fitness: np.ndarray,
    elite: np.ndarray,
    ops: Any,
    rates: tuple[float, float],
    weights: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """One generation's children, as chapter 2's GA: binary tournaments on the penalised
    ``fitness``, OX1 with probability ``rates[0]``, mutation with ``rates[1]``, the
    ``elite`` kept in row 0 and clones separated (``weights``: their fingerprints)."""
    population = len(genes)
    crossover_rate, mutation_rate = rates
    half = (population + 1) // 2
    contenders = rng.integers(0, population, size=(2 * half, ops.tournament))
    winners = contenders[np.arange(2 * half), np.argmin(fitness[contenders], axis=1)]
    mothers, fathers = genes[winners[:half]], genes[winners[half:]]
    cross = rng.random(half) < crossover_rate
    children = np.concatenate([mothers, fathers])
    if cross.any():
        children[:half][cross] = order_crossover(mothers[cross], fathers[cross], rng)
        children[half:][cross] = order_crossover(fathers[cross], mothers[cross], rng)
    children = _mutate(children[:population], ops, mutation_rate, rng)
    children[0] = elite  # elitism on the penalised fitness
    _separate_clones(children, weights, ops, rng)  # keep the population diverse
    return children


def _polish(
    problem: BudgetedProblem,
    searches: tuple[np.ndarray, LimitedDescent, PenalisedSearch | None],
    genes: np.ndarray,
    fitness: np.ndarray,
    plain: np.ndarray,
    violation: np.ndarray,
    penalty: float,
    unit: float,
    ops: Any,
    counters: dict[str, int],
    memo: dict[Any, Any],
    deadline: Deadline | None = None,
) -> None:
    """On the best distinct children, in place, where the penalised fitness improves; once
    ``deadline`` has expired no further child is polished and the searches stop early.

    With ``memetic="penalised"`` (``searches[2]`` set): the penalised local search
    (:class:`~taopt.heuristics.ga_penalised_search.PenalisedSearch`), then :func:`repair`
    if a limit is still broken, then :func:`~taopt.heuristics.budgeted.descent.limited_local_search`. With "chapter2": the
    better of two candidates, chapter 2's local search then :func:`repair` then
    :func:`~taopt.heuristics.budgeted.descent.limited_local_search`, and the child itself repaired then
    :func:`~taopt.heuristics.budgeted.descent.limited_local_search`. Without limits: chapter 2's local search only.
    ``searches``: the path matrix, the run's :class:`LimitedDescent` and its
    :class:`~taopt.heuristics.ga_penalised_search.PenalisedSearch` (or None)."""
    matrix, descent, penalised = searches
    values, first = np.unique(fitness, return_index=True)
    limited = problem.has_capacity or problem.has_max_time
    for row in [int(r) for r in first[: ops.polish]]:
        if deadline is not None and deadline.expired():
            return
        key = genes[row].tobytes()
        if limited and key in memo:  # polished before (often the elite): same answer
            counters["memo_hits"] += 1
            best = memo[key]
            if best is not None and best[1] < fitness[row]:
                genes[row] = best[0]
                fitness[row], plain[row], violation[row] = best[1], best[2], best[3]
            continue
        path = path_nodes(problem.routing, genes[row])[0]
        if limited and penalised is not None:  # one candidate: the penalised search's
            nodes, moves = penalised.run(matrix, path, ops.max_moves, deadline)
            starts: tuple[np.ndarray, ...] = (nodes_to_genes(problem.routing, nodes),)
        else:
            nodes, moves, evaluations = local_search(
                matrix, path, ops.max_moves, ops.neighbourhood, deadline
            )
            counters["move_evaluations"] += evaluations
            starts = (nodes_to_genes(problem.routing, nodes), genes[row]) if limited else ()
        counters["moves"] += moves
        best = None
        if not limited:  # no limit: chapter 2's memetic step exactly
            candidate = nodes_to_genes(problem.routing, nodes)
            value, total, over = penalised_cost(problem, candidate, penalty, unit)
            best = (candidate, value[0], total[0], over[0])
        for start in starts:
            candidate = start
            value, total, over = penalised_cost(problem, candidate, penalty, unit)
            routes = decode(problem.routing, candidate, "vehicle")
            if over[0] > 0:
                counters["repairs"] += 1
                routes = _remembered(memo, "repair", routes, counters, lambda r: repair(problem, r))
                if routes is None:
                    if best is None or value[0] < best[1]:
                        best = (candidate, value[0], total[0], over[0])
                    continue
                counters["repaired"] += 1
            routes = _remembered(
                memo,
                "descent",
                routes,
                counters,
                lambda r: _descend(descent, r, ops, counters, deadline),
            )
            candidate = encode(problem.routing, routes)
            value, total, over = penalised_cost(problem, candidate, penalty, unit)
            if best is None or value[0] < best[1]:
                best = (candidate, value[0], total[0], over[0])
        if limited:
            memo[key] = None if best is None else (best[0].copy(), *best[1:])
        if best is not None and best[1] < fitness[row]:
            genes[row] = best[0]
            fitness[row], plain[row], violation[row] = best[1], best[2], best[3]


def _descend(
    descent: LimitedDescent,
    routes: list[list[int]],
    ops: Any,
    counters: dict[str, int],
    deadline: Deadline | None = None,
) -> list[list[int]]:
    """:func:`~taopt.heuristics.budgeted.descent.limited_local_search` (the run's ``descent``) with its moves counted."""
    routes, moves = descent.run(routes, ops.max_moves, deadline)
    counters["moves"] += moves
    return routes


def _remembered(
    memo: dict[Any, Any],
    step: str,
    routes: list[list[int]],
    counters: dict[str, int],
    compute: Any,
) -> Any:
    """``compute(routes)``, remembered per (step, routes): :func:`repair` and
    :func:`~taopt.heuristics.budgeted.descent.limited_local_search` are deterministic functions of the routes, and about half
    of their calls in a run repeat an earlier input (n50m10 at Q1 and Q1.5). Returns a
    fresh copy of the routes (or None), so callers may change them."""
    key = (step, tuple(tuple(route) for route in routes))
    if key in memo:
        counters["route_memo_hits"] += 1
    else:
        memo[key] = compute([list(route) for route in routes])
    found = memo[key]
    return None if found is None else [list(route) for route in found]
