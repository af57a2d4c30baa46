"""The genetic algorithm baseline of thesis §2.5 for the chapter 2 problem.

Encoding (§2.5): a chromosome is a permutation of the n target genes
``0..n-1`` and m - 1 marker genes ``n..n+m-2``. Reading left to right, the
markers split the targets into m routes: targets before the first marker are
vehicle 0's route, between the first and second markers vehicle 1's, and so
on (the marker's own value does not matter, only its position).

The thesis names tournament selection, crossover rate 0.9, mutation rate 0.1,
population 120 and 350 generations, but not its operators. Chosen here
(standard permutation operators):

* selection: tournament of size 4 (four individuals drawn uniformly with
  replacement; the one with the smallest total travel time wins). Size 4
  rather than 2 because binary tournaments left the GA far from converged
  after 350 generations (n120m10 Euclidean, q = f / f_a: 4.8 with size 2,
  3.1-3.3 with sizes 3-8; the thesis reports q = 2.0 for its GA);
* crossover: order crossover OX1 (Davis): with probability 0.9 per pair, copy
  a random slice from parent 1 and fill the other positions, starting after
  the slice and wrapping around, with parent 2's remaining genes in parent 2's
  order from the same point; otherwise the children are copies of the parents;
* mutation: inversion (reverse a random slice), with probability 0.1 per child;
* elitism: the best individual of each generation replaces the first child of
  the next, so the best objective never gets worse;
* initial population: uniform random permutations.

Fitness is vectorised over the whole population: the predecessor of every
target gene is the previous gene if that is a target, else the start of the
vehicle whose segment the gene is in; the objective (2.2) is the sum of
``cost[predecessor, gene]`` over target genes.
"""

from __future__ import annotations

import time

import numpy as np

from taopt.errors import InstanceError
from taopt.registry import register_method
from taopt.result import FEASIBLE, Routes, Solution
from taopt.routing.problem import AssignmentProblem, evaluate_routes


def population_cost(problem: AssignmentProblem, genes: np.ndarray) -> np.ndarray:
    """Total travel time (2.2) of every chromosome in ``genes`` (P, n + m - 1), vectorised."""
    n = problem.n
    is_marker = genes >= n
    vehicle = np.cumsum(is_marker, axis=1)  # at a target gene: the number of markers before it
    previous = np.empty_like(genes)
    previous[:, 0] = n  # sentinel: treated as a marker (start of vehicle 0)
    previous[:, 1:] = genes[:, :-1]
    from_start = previous >= n
    from_start[:, 0] = True
    predecessor = np.where(from_start, n + vehicle, previous)
    step = problem.cost[predecessor, np.where(is_marker, 0, genes)]
    return np.where(is_marker, 0.0, step).sum(axis=1)


def decode(problem: AssignmentProblem, chromosome: np.ndarray) -> list[list[int]]:
    """Split one chromosome at its markers into m routes."""
    routes: list[list[int]] = [[]]
    for gene in chromosome:
        if gene >= problem.n:
            routes.append([])
        else:
            routes[-1].append(int(gene))
    return routes


def order_crossover(first: np.ndarray, second: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """OX1 children of row pairs (first[i], second[i]), vectorised over the rows.

    Each child keeps ``first[i, a:b]`` in place and receives the other genes in
    the order they appear in ``second[i]`` read from position b (wrapping), laid
    into the free positions from b onwards (wrapping).
    """
    pairs, length = first.shape
    cuts = np.sort(rng.integers(0, length + 1, size=(pairs, 2)), axis=1)
    low, high = cuts[:, :1], cuts[:, 1:]
    position = np.arange(length)[None, :]
    in_slice = (position >= low) & (position < high)
    rows = np.arange(pairs)[:, None]
    gene_in_slice = np.zeros((pairs, length), dtype=bool)
    gene_in_slice[rows, first] = in_slice
    rotated = (position + high) % length  # positions read from b, wrapping
    donor = second[rows, rotated]
    keep = ~gene_in_slice[rows, donor]
    free = ~in_slice[rows, rotated]
    # Stable sort puts kept donor genes / free positions first, in their order.
    donor_sorted = np.take_along_axis(donor, np.argsort(~keep, axis=1, kind="stable"), axis=1)
    free_sorted = np.take_along_axis(rotated, np.argsort(~free, axis=1, kind="stable"), axis=1)
    child = np.where(in_slice, first, -1)
    count = length - (high - low)
    fill = position < count
    child[np.broadcast_to(rows, fill.shape)[fill], free_sorted[fill]] = donor_sorted[fill]
    return child


def inversion_mutation(genes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Reverse a random slice of each row."""
    pairs, length = genes.shape
    cuts = np.sort(rng.integers(0, length + 1, size=(pairs, 2)), axis=1)
    low, high = cuts[:, :1], cuts[:, 1:]
    position = np.arange(length)[None, :]
    inside = (position >= low) & (position < high)
    source = np.where(inside, low + high - 1 - position, position)
    return np.take_along_axis(genes, source, axis=1)


@register_method(AssignmentProblem, "GA")
def genetic_algorithm(
    problem: AssignmentProblem,
    seed: int | np.random.Generator | None = 0,
    population: int = 120,
    generations: int = 350,
    crossover_rate: float = 0.9,
    mutation_rate: float = 0.1,
    tournament: int = 4,
) -> Solution:
    """GA of §2.5 with marker-gene encoding (operators in the module docstring).

    Parameters
    ----------
    problem : AssignmentProblem
    seed : int or numpy.random.Generator
        Same seed, same result.
    population : int
        Chromosomes per generation (thesis: 120); at least 2.
    generations : int
        Iterations (thesis: 350); the run stops on this count, not on time.
    crossover_rate, mutation_rate : float
        Per pair / per child probabilities (thesis: 0.9 and 0.1).
    tournament : int
        Tournament size (the thesis does not give it).

    Returns
    -------
    Solution
        The best chromosome ever seen, decoded; ``info`` has the best
        objective after each generation (``"history"``).

    Notes
    -----
    O(generations * population * (n + m)) numpy work.

    References
    ----------
    Thesis §2.5 (population 120, rates 0.9 / 0.1, 350 generations).
    """
    if population < 2 or generations < 0 or tournament < 1:
        raise InstanceError(
            "need population >= 2, generations >= 0 and tournament >= 1, "
            f"got {population}, {generations}, {tournament}"
        )
    for label, rate in (("crossover_rate", crossover_rate), ("mutation_rate", mutation_rate)):
        if not 0.0 <= rate <= 1.0:
            raise InstanceError(f"{label} must be in [0, 1], got {rate}")
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    length = problem.n + problem.m - 1
    genes = rng.permuted(np.tile(np.arange(length), (population, 1)), axis=1)
    fitness = population_cost(problem, genes)
    best = int(np.argmin(fitness))
    best_genes, best_cost = genes[best].copy(), float(fitness[best])
    history = [best_cost]
    half = (population + 1) // 2
    for _ in range(generations):
        # Tournament selection of 2 * half parents.
        contenders = rng.integers(0, population, size=(2 * half, tournament))
        winners = contenders[np.arange(2 * half), np.argmin(fitness[contenders], axis=1)]
        mothers, fathers = genes[winners[:half]], genes[winners[half:]]
        cross = rng.random(half) < crossover_rate
        children = np.concatenate([mothers, fathers])
        if cross.any():
            children[:half][cross] = order_crossover(mothers[cross], fathers[cross], rng)
            children[half:][cross] = order_crossover(fathers[cross], mothers[cross], rng)
        children = children[:population]
        mutate = rng.random(population) < mutation_rate
        if mutate.any():
            children[mutate] = inversion_mutation(children[mutate], rng)
        children[0] = best_genes  # elitism
        genes = children
        fitness = population_cost(problem, genes)
        best = int(np.argmin(fitness))
        if fitness[best] < best_cost:
            best_genes, best_cost = genes[best].copy(), float(fitness[best])
        history.append(best_cost)
    routes = decode(problem, best_genes)
    objective = evaluate_routes(problem, routes)
    return Solution(
        objective=objective,
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        method="GA",
        seed=seed,
        solution=Routes(routes),
        info={"history": history, "population": population, "generations": generations},
    )


__all__ = [
    "genetic_algorithm",
    "population_cost",
    "decode",
    "order_crossover",
    "inversion_mutation",
]
