"""Genetic algorithm with topological-sort chromosomes, the baseline of thesis §5.5.

The thesis compares NIA/MMA/SMMA with "the GA for the precedence-constrained assignment
problem [82]" (an improved version of the topological-sort GA of [56]) with population 20,
2000 generations, crossover rate 0.5 and mutation rate 0.05. The thesis does not print
[82]'s operators, so this module documents its own choice, which keeps the one property
the thesis stresses: *every chromosome decodes to a precedence-feasible order*.

Operators
---------
* **Chromosome**: random keys, one priority in [0, 1) per node to order.
* **Decoding** (the topological sorting technique of §5.4.1): start from the start node;
  repeatedly append, among the viable nodes (no un-placed predecessor), the one with the
  smallest key (lowest index on ties); a forced end node is appended last. Every key vector
  gives a precedence-feasible order, and every feasible order is reachable. When some arcs
  are forbidden (infinite cost, as in TSPLIB SOP files), a viable node reached from the
  last placed one by a usable arc is preferred; an order that still needs a forbidden arc
  costs inf, and if the best order found does, :func:`ga_search` raises ``SolverError``
  rather than return it; the registered methods then take the backtracking repair's order
  (:func:`~taopt.heuristics.sequencing.backtrack_order`) or answer status "no_solution".
* **Normalisation** (Lamarckian): after decoding, each node's key is reset to its rank in
  the decoded order divided by the number of nodes, so keys carry positions.
* **Selection**: binary tournament (lower path cost wins, the first drawn on ties);
  the best chromosome is copied unchanged into the next generation (elitism).
* **Crossover** (probability ``crossover`` per child): parametrised-uniform key crossover;
  each gene comes from either parent with probability 1/2. Otherwise the child copies its
  first parent.
* **Mutation** (probability ``mutation`` per gene): the key is redrawn uniformly in [0, 1),
  i.e. the node is moved to a random position (as early as its predecessors allow).
* **Fitness**: the path cost on the cost matrix (t* of (5.11) for the delivery problem),
  evaluated for the whole population in one array op; the decoding is also vectorised
  over the population.

The registered delivery method "GA" builds the order on t* with the depot as start and
scores the best order with the exact scheduler :func:`taopt.schedule`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError, SolverError
from taopt.heuristics.sequencing import (
    REPAIR_BUDGET,
    _validate,
    backtrack_order,
    delivery_cost_matrix,
    no_order_solution,
    path_cost,
    schedule_order,
)
from taopt.registry import register_method
from taopt.result import FEASIBLE, Order, Solution, make_solution
from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem

__all__ = ["ga_order", "ga_search"]


def _decode(
    keys: np.ndarray,
    successors: np.ndarray,
    waiting0: np.ndarray,
    usable: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Topological sort of every chromosome: the viable node with the smallest key first.

    ``keys`` (P, m); ``successors[a, b] = 1`` when a precedes b; ``waiting0`` the number of
    predecessors of each node. ``usable`` (first, next), when some arcs are forbidden:
    ``first[b]`` the arc start -> b is usable, ``next[a, b]`` the arc a -> b is; a viable
    node reached by a usable arc is then preferred (the smallest key among those), and
    only when none is left does the decoder take any viable node (that order uses a
    forbidden arc and costs inf). Returns (P, m) orders of node positions 0..m-1.
    """
    population, m = keys.shape
    rows = np.arange(population)
    waiting = np.broadcast_to(waiting0, (population, m)).copy()
    orders = np.empty((population, m), dtype=np.int64)
    placed = np.int64(m + 1)  # a placed node never returns to 0 waiting predecessors
    for step in range(m):
        viable = waiting == 0
        if usable is not None:
            reach = usable[0][None, :] if step == 0 else usable[1][orders[:, step - 1]]
            preferred = viable & reach
            viable = np.where(preferred.any(axis=1)[:, None], preferred, viable)
        choice = np.where(viable, keys, np.inf).argmin(axis=1)
        orders[:, step] = choice
        waiting[rows, choice] = placed
        waiting -= successors[choice]
    return orders


def ga_search(
    cost: Any,
    precedences: Iterable[Sequence[int]] = (),
    start: int = 0,
    end: int | None = None,
    seed: int | np.random.Generator | None = 0,
    population: int = 20,
    generations: int = 2000,
    crossover: float = 0.5,
    mutation: float = 0.05,
    time_limit: float | None = None,
) -> tuple[list[int], float, np.ndarray]:
    """Run the GA; return the best full path, its cost and the best cost per generation.

    Parameters are those of :func:`ga_order`, and ``time_limit`` (wall-clock seconds: the
    run stops after the generation during which it expires, and ``history`` is shorter).
    ``history[g]`` is the best path cost after generation g (``history[0]``: the initial
    population), non-increasing by elitism.
    """
    deadline = Deadline(time_limit)
    matrix, nodes, pairs = _validate(cost, precedences, start, end)
    if int(population) != population or population < 2:
        raise InstanceError(f"population must be an integer >= 2, got {population!r}")
    if int(generations) != generations or generations < 0:
        raise InstanceError(f"generations must be an integer >= 0, got {generations!r}")
    for name, rate in (("crossover", crossover), ("mutation", mutation)):
        if not 0.0 <= rate <= 1.0:
            raise InstanceError(f"{name} rate must lie in [0, 1], got {rate!r}")
    population, generations = int(population), int(generations)
    rng = np.random.default_rng(seed)
    m = len(nodes)
    head = [int(start)]
    tail = [] if end is None else [int(end)]
    if m == 0:
        path = head + tail
        value = float(matrix[path[0], path[1]]) if len(path) == 2 else 0.0
        if not np.isfinite(value):
            raise SolverError(f"GA: the only order {path} uses the forbidden arc {path}")
        return path, value, np.full(generations + 1, value)

    local = {int(node): k for k, node in enumerate(nodes)}
    successors = np.zeros((m, m), dtype=np.int64)
    for before, after in set(pairs):
        successors[local[before], local[after]] = 1
    waiting0 = successors.sum(axis=0)
    inner = matrix[np.ix_(nodes, nodes)]
    from_start = matrix[start, nodes]
    to_end = matrix[nodes, end] if end is not None else np.zeros(m)
    rows = np.arange(population)
    ranks = np.arange(m) / m
    usable = None
    if not (np.isfinite(inner).all() and np.isfinite(from_start).all()):
        usable = (np.isfinite(from_start), np.isfinite(inner))

    def evaluate(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        orders = _decode(keys, successors, waiting0, usable)
        keys[rows[:, None], orders] = ranks[None, :]  # Lamarckian normalisation
        values = (
            from_start[orders[:, 0]]
            + inner[orders[:, :-1], orders[:, 1:]].sum(axis=1)
            + to_end[orders[:, -1]]
        )
        return orders, values

    keys = rng.random((population, m))
    orders, values = evaluate(keys)
    history = np.empty(generations + 1)
    history[0] = values.min()
    children = population - 1
    for generation in range(1, generations + 1):
        if deadline.limited and deadline.expired():
            history = history[:generation]
            break
        elite = int(np.argmin(values))
        drawn = rng.integers(population, size=(children, 2, 2))  # two tournaments per child
        winners = np.where(
            values[drawn[:, :, 0]] <= values[drawn[:, :, 1]], drawn[:, :, 0], drawn[:, :, 1]
        )
        first, second = keys[winners[:, 0]], keys[winners[:, 1]]
        mixed = rng.random((children, m)) < 0.5
        crossed = (rng.random(children) < crossover)[:, None]
        offspring = np.where(crossed & mixed, second, first)
        mutate = rng.random((children, m)) < mutation
        offspring = np.where(mutate, rng.random((children, m)), offspring)
        keys = np.vstack([keys[elite][None, :], offspring])
        orders, values = evaluate(keys)
        history[generation] = values.min()
    best = int(np.argmin(values))
    if not np.isfinite(values[best]):
        raise SolverError(
            f"GA found no feasible order in {generations} generations: every order it decoded "
            "uses a forbidden arc (infinite cost)"
        )
    path = head + [int(nodes[k]) for k in orders[best]] + tail
    return path, float(values[best]), history


def ga_order(
    cost: Any,
    precedences: Iterable[Sequence[int]] = (),
    start: int = 0,
    end: int | None = None,
    seed: int | np.random.Generator | None = 0,
    population: int = 20,
    generations: int = 2000,
    crossover: float = 0.5,
    mutation: float = 0.05,
) -> list[int]:
    """Genetic algorithm over topological-sort chromosomes (thesis §5.5, after [82]).

    Parameters
    ----------
    cost : (N, N) array_like
        Asymmetric costs (t* of (5.11) for the delivery problem); the fitness is the path cost.
    precedences : iterable of (before, after)
        The edges of G^p.
    start : int
        First node of every path (the depot w0; node 0 in TSPLIB SOP).
    end : int, optional
        A node forced last (TSPLIB SOP).
    seed : int or numpy.random.Generator
        Same seed, same result.
    population, generations : int
        Thesis §5.5: 20 and 2000.
    crossover : float
        Probability that a child is a uniform key crossover of its two parents (0.5).
    mutation : float
        Per-gene probability of redrawing a key (0.05).

    Returns
    -------
    list of int
        The best full path found (start first, end last when given), precedence-feasible.

    Raises
    ------
    InstanceError
        Bad matrix, indices, parameters or a precedence cycle.
    SolverError
        Every order decoded uses a forbidden (infinite-cost) arc.

    Examples
    --------
    >>> C = [[0, 6, 1, 9], [5, 0, 7, 3], [3, 6, 0, 9], [5, 1, 9, 0]]
    >>> ga_order(C, [(1, 2)], start=0, generations=50, seed=1)  # the optimum, cost 17
    [0, 3, 1, 2]

    Notes
    -----
    Cost per generation O(population · m) numpy work for each of the m decoding steps,
    O(generations · population · m^2) in all. The operators are described in the module
    docstring; they are ours, since the thesis does not print those of [82].

    References
    ----------
    Thesis §5.1 and §5.5; [56] Moon et al. (topological-sort GA), [82] its improved version.
    """
    path, _, _ = ga_search(
        cost, precedences, start, end, seed, population, generations, crossover, mutation
    )
    return path


def _searched_or_repaired(
    cost: Any, pairs: Any, start: int, end: int | None, seed: Any, **options: Any
) -> tuple[list[int] | None, float, np.ndarray | None, dict[str, Any]]:
    """:func:`ga_search`'s best path; when every order it decoded needs a forbidden arc, the
    backtracking repair's (:func:`~taopt.heuristics.sequencing.backtrack_order`); else None.

    Returns the path, its cost, the history (None when repaired) and the ``info`` to
    record (``repaired``/``dead_end``, or ``error``/``proved_infeasible`` with no path).
    """
    try:
        found, value, history = ga_search(cost, pairs, start, end, seed, **options)
        return found, value, history, {}
    except InstanceError:
        raise
    except SolverError as exc:
        dead_end = str(exc)
    path, proved = backtrack_order(cost, pairs, start, end)
    if path is not None:
        matrix = np.asarray(cost, dtype=float)
        return path, path_cost(matrix, path), None, {"repaired": True, "dead_end": dead_end}
    why = (
        "no feasible order exists (the backtracking repair searched every partial path)"
        if proved
        else f"the backtracking repair found none within {REPAIR_BUDGET} extensions"
    )
    info = {"error": f"GA found no order: {why}", "dead_end": dead_end}
    return None, math.inf, None, {**info, "proved_infeasible": proved}


@register_method(DeliveryInstance, "GA")
def ga_delivery(
    instance: Any, seed: int = 0, time_limit: float | None = None, **options: Any
) -> Solution:
    """GA order on t* (depot first), scheduled exactly by :func:`taopt.schedule`.

    Options are those of :func:`ga_order` (``population``, ``generations``, ``crossover``,
    ``mutation``). ``info["tstar_cost"]`` is the best path cost on t*,
    ``info["history"]`` the best t* cost per generation. ``time_limit`` (wall-clock
    seconds) stops the generations early (see :func:`ga_search`).
    """
    began = time.perf_counter()
    cost, start, pairs, customers = delivery_cost_matrix(instance)
    path, value, history, info = _searched_or_repaired(
        cost, pairs, start, None, seed, time_limit=time_limit, **options
    )
    if path is None:
        return no_order_solution(instance, "GA", seed, began, info)
    solution = schedule_order(instance, path, customers)
    if history is not None:
        info["history"] = history.tolist()
    return solution.replace(
        method="GA",
        seed=seed,
        runtime=time.perf_counter() - began,
        info={**solution.info, "tstar_cost": value, **info},
    )


@register_method(SopProblem, "GA")
def ga_sop(
    problem: SopProblem, seed: int = 0, time_limit: float | None = None, **options: Any
) -> Solution:
    """The topological-sort GA of :func:`ga_order` on the SOP's own cost matrix
    (``time_limit``: wall-clock seconds, see :func:`ga_search`). When every order it decoded
    needs a forbidden arc, the backtracking repair's order (``info["repaired"]``), or status
    "no_solution" with the reason in ``info["error"]``."""
    began = time.perf_counter()
    path, _, history, info = _searched_or_repaired(
        problem.cost,
        problem.precedences,
        problem.start,
        problem.end,
        seed,
        time_limit=time_limit,
        **options,
    )
    if path is None:
        return no_order_solution(problem, "GA", seed, began, info)
    if history is not None:
        info["history"] = history.tolist()
    return make_solution(
        problem,
        Order(path),
        method="GA",
        status=FEASIBLE,
        runtime=time.perf_counter() - began,
        seed=seed,
        info=info,
    )
