"""The genetic algorithm baseline of thesis §2.5 for the chapter 2 problem.

The thesis fixes the encoding (the n targets as genes plus m - 1 marker genes),
tournament selection, crossover rate 0.9, mutation rate 0.1, population 120 and
350 generations, and names no operators. Two operator sets are offered (see
:data:`OPERATOR_SETS`): a competent default and the first version; the choice
and the measurements behind it are in ``docs/ga-operators.md``
(``benchmarks/ga_sweep.py`` regenerates them).

Encoding
--------
A chromosome is a permutation of the target genes ``0..n-1`` and the marker
genes ``n..n+m-2``. Two readings of the markers are used:

* ``markers="position"`` (the first version): the markers split the targets
  into m routes by position -- targets before the first marker are vehicle 0's
  route, between the first and second markers vehicle 1's, and so on; a
  marker's value does not matter.
* ``markers="vehicle"``: marker gene ``n + k - 1`` *is* vehicle k's start
  (k = 1..m-1); targets before the first marker belong to vehicle 0, and the
  targets after marker ``n + k - 1`` (up to the next marker) to vehicle k.
  The chromosome is then a path through the points of the cost matrix from
  vehicle 0's start in which every arc into a vehicle start costs 0 (the
  vehicles do not return), so the total travel time (2.2) is a plain path
  length and every permutation move (reversal, relocation, exchange) has an
  exact O(1) cost change. This is the usual reduction of the multiple
  travelling salesman problem to a single one.

Operator sets
-------------
``"memetic"`` (the default; a genetic algorithm whose best children get a
local search, as in the memetic algorithms for vehicle routing):

* selection: binary tournament (``tournament=2``: two individuals drawn with
  replacement, the smaller total travel time wins);
* crossover: order crossover OX1 (Davis) with probability ``crossover_rate``
  per pair, otherwise copies of the parents;
* mutation: with probability ``mutation_rate`` per child one of inversion
  (reverse a random slice), swap (exchange two genes) or slide (move one gene
  to another position), chosen uniformly;
* elitism: the best individual found so far is copied into every generation;
* local improvement: each generation the ``polish = 2`` best new children with
  distinct costs are improved by best-improvement local search on the path
  (:func:`local_search`): segment reversal (2-opt, the reversed segment
  re-priced exactly since the costs are asymmetric), relocation of 1-3
  consecutive genes (or-opt; moves targets within and between vehicles),
  exchange of two genes, and exchange of two routes' tails (2-opt*), until no
  move improves or ``max_moves`` moves were made;
* initial population: uniform random permutations.

On the sweep's instances it is within 0.3 % of the optimum on average at
n50m10 and n120m20 (q = f / f_a about 1.05-1.07) and 6-9 % better than MC.

``"ox-inversion"`` (the first version, kept so earlier results stay
reproducible bit for bit): position markers, OX1, inversion mutation,
tournament of 4, elitism, no local search. It is a weak baseline: q = f / f_a
about 2.2 at n50m10 and 4.3-4.6 at n120m20 where MC has about 1.15.

The measurements behind these choices (operator sets, tournament sizes, local
search on or off, its neighbourhood and how many children get it) are in
``docs/ga-operators.md``.

Budget
------
``population * (generations + 1)`` chromosomes are evaluated in full (42 120
with the thesis's 120 and 350), whatever the operator set. Local search adds
no full evaluation: it prices candidate moves by their O(1) cost change,
about ``4.5 L**2`` candidates per move made for a chromosome of
``L = n + m - 1`` genes, on ``polish`` chromosomes per generation; ``info``
reports ``moves`` (moves made) and ``move_evaluations`` (candidates priced),
so runs with and without it can be compared on work done as well as on time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from taopt.errors import InstanceError

# the local search (and its NEIGHBOURHOOD) lives in taopt.heuristics.ga_local_search;
# re-exported here, where it was defined before
from taopt.heuristics.ga_local_search import NEIGHBOURHOOD, local_search
from taopt.registry import register_improver, register_method
from taopt.result import FEASIBLE, Routes, Solution, make_solution
from taopt.routing.problem import AssignmentProblem
from taopt.runtime import Deadline

MARKERS = ("position", "vehicle")
CROSSOVERS = ("ox", "obx")
MUTATIONS = ("inversion", "swap", "slide")


@dataclass(frozen=True)
class OperatorSet:
    """The operators of one GA variant (see the module docstring).

    Attributes
    ----------
    markers : {"position", "vehicle"}
        How marker genes are read.
    crossover : {"ox", "obx"}
        Order crossover OX1, or order-based crossover (OBX: a random half of
        parent 2's positions is chosen, and parent 1's genes found there are
        put back into parent 1's positions of those genes in parent 2's order).
    mutations : tuple of {"inversion", "swap", "slide"}
        A mutated child gets one of these, chosen uniformly.
    polish : int
        Best distinct children improved by local search per generation (0: none).
    max_moves : int
        Cap on local-search moves per improved chromosome.
    distinct : bool
        A child identical to an earlier chromosome of its generation is mutated
        (by one of ``mutations``) before it is evaluated, so the population does
        not collapse onto copies of its best member.
    tournament : int
        Tournament size used when :func:`genetic_algorithm` is not given one.
    neighbourhood : tuple of {"reverse", "relocate", "tails", "exchange"}
        Local-search moves (see :func:`local_search`).
    """

    markers: str = "vehicle"
    crossover: str = "ox"
    mutations: tuple[str, ...] = MUTATIONS
    polish: int = 2
    max_moves: int = 1000
    distinct: bool = False
    tournament: int = 2
    neighbourhood: tuple[str, ...] = NEIGHBOURHOOD

    def __post_init__(self) -> None:
        if self.markers not in MARKERS:
            raise InstanceError(f"markers must be one of {MARKERS}, got {self.markers!r}")
        if self.crossover not in CROSSOVERS:
            raise InstanceError(f"crossover must be one of {CROSSOVERS}, got {self.crossover!r}")
        unknown = [name for name in self.mutations if name not in MUTATIONS]
        if unknown or not self.mutations:
            raise InstanceError(
                f"mutations must be a non-empty subset of {MUTATIONS}, got {self.mutations!r}"
            )
        if self.polish < 0 or self.max_moves < 0:
            raise InstanceError(
                f"polish and max_moves must be >= 0, got {self.polish}, {self.max_moves}"
            )
        unknown = [name for name in self.neighbourhood if name not in NEIGHBOURHOOD]
        if unknown:
            raise InstanceError(
                f"neighbourhood must be a subset of {NEIGHBOURHOOD}, got {self.neighbourhood!r}"
            )
        if self.tournament < 1:
            raise InstanceError(f"tournament must be >= 1, got {self.tournament}")
        if self.polish and self.markers != "vehicle":
            raise InstanceError('local search (polish > 0) needs markers="vehicle"')


#: The GA's operator sets, by name.
OPERATOR_SETS: dict[str, OperatorSet] = {
    "memetic": OperatorSet(),
    "ox-inversion": OperatorSet(
        markers="position", mutations=("inversion",), polish=0, distinct=False, tournament=4
    ),
}


# -- encoding ---------------------------------------------------------------------------


def path_matrix(problem: AssignmentProblem) -> np.ndarray:
    """Arc costs of the single-path reading (``markers="vehicle"``), with an end point.

    Rows and columns ``0..n+m-1`` are the problem's points and ``n + m`` an end
    point closing the path. Every arc into a vehicle start or into the end
    costs 0, because the routes are open (2.2); the other arcs are ``cost``.
    """
    n, m = problem.n, problem.m
    matrix = np.zeros((n + m + 1, n + m + 1))
    matrix[: n + m, :n] = problem.cost[:, :n]
    return matrix


def path_nodes(problem: AssignmentProblem, genes: np.ndarray) -> np.ndarray:
    """Points visited by chromosomes ``genes`` (P, L) read with vehicle markers: (P, L + 2).

    Column 0 is vehicle 0's start ``n``, a marker gene ``g`` is vehicle
    ``g - n + 1``'s start point ``g + 1``, and the last column is the end point.
    """
    n = problem.n
    genes = np.atleast_2d(genes)
    nodes = np.empty((genes.shape[0], genes.shape[1] + 2), dtype=np.intp)
    nodes[:, 0] = n
    nodes[:, 1:-1] = np.where(genes < n, genes, genes + 1)
    nodes[:, -1] = n + problem.m
    return nodes


def population_cost(
    problem: AssignmentProblem, genes: np.ndarray, markers: str = "position"
) -> np.ndarray:
    """Total travel time (2.2) of every chromosome in ``genes`` (P, n + m - 1), vectorised.

    With position markers the predecessor of a target gene is the previous gene
    if that is a target, else the start of the vehicle whose segment the gene is
    in; with vehicle markers it is the path length in :func:`path_matrix`.
    """
    n = problem.n
    genes = np.atleast_2d(genes)
    if markers == "vehicle":
        nodes = path_nodes(problem, genes)
        targets = nodes[:, 1:-1]
        step = problem.cost[nodes[:, :-2], np.where(targets < n, targets, 0)]
        return np.where(targets < n, step, 0.0).sum(axis=1)
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


def decode(
    problem: AssignmentProblem, chromosome: np.ndarray, markers: str = "position"
) -> list[list[int]]:
    """Split one chromosome at its markers into m routes (see the module docstring)."""
    n = problem.n
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    vehicle = 0
    for gene in chromosome:
        if gene >= n:
            vehicle = int(gene) - n + 1 if markers == "vehicle" else vehicle + 1
        else:
            routes[vehicle].append(int(gene))
    return routes


def encode(problem: AssignmentProblem, routes: list[list[int]]) -> np.ndarray:
    """Chromosome with vehicle markers of ``routes`` (the inverse of :func:`decode`)."""
    genes: list[int] = list(routes[0])
    for vehicle in range(1, problem.m):
        genes.append(problem.n + vehicle - 1)
        genes.extend(routes[vehicle])
    return np.asarray(genes, dtype=np.intp)


#: Improving moves :func:`improve_routes` makes at most (about 7.5 ms each at n400m50).
IMPROVE_MAX_MOVES = 100


@register_improver(AssignmentProblem)
def improve_routes(
    problem: AssignmentProblem, routes: list[list[int]], max_moves: int = IMPROVE_MAX_MOVES
) -> list[list[int]]:
    """``routes`` after the memetic GA's local search (:func:`local_search`, every move).

    The improver of the exact DFJ loop: :func:`taopt.solve` passes it to
    :func:`taopt.models.solve_routing` as ``improve``, which calls it on the patched answer of
    each MIP round (the exact model imports no heuristic). Never worse than ``routes``.

    Example
    -------
    >>> import numpy as np, taopt
    >>> problem = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), 2)
    >>> improve_routes(problem, [[0, 1]])
    [[1, 0]]
    """
    nodes = path_nodes(problem, encode(problem, routes))[0]
    improved, _, _ = local_search(path_matrix(problem), nodes, max_moves)
    return decode(problem, nodes_to_genes(problem, improved), "vehicle")


# -- crossover and mutation (vectorised over rows) --------------------------------------


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


def order_based_crossover(
    first: np.ndarray, second: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Order-based crossover (OBX, Syswerda) of row pairs, vectorised over the rows.

    Each position of ``second[i]`` is chosen with probability 1/2; the genes at
    the chosen positions keep their places in ``first[i]``'s set of positions
    but are reordered as in ``second[i]``; the other genes stay where they are.
    """
    pairs, length = first.shape
    rows = np.arange(pairs)[:, None]
    chosen = rng.random((pairs, length)) < 0.5
    gene_chosen = np.zeros((pairs, length), dtype=bool)
    gene_chosen[rows, second] = chosen
    child = first.copy()
    # Row-major boolean indexing visits both masks row by row, left to right, and
    # each row has as many chosen genes in ``first`` as chosen positions in ``second``.
    child[gene_chosen[rows, first]] = second[chosen]
    return child


def _cuts(rng: np.random.Generator, rows: int, length: int) -> tuple[np.ndarray, np.ndarray]:
    cuts = np.sort(rng.integers(0, length + 1, size=(rows, 2)), axis=1)
    return cuts[:, :1], cuts[:, 1:]


def inversion_mutation(genes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Reverse a random slice of each row."""
    pairs, length = genes.shape
    low, high = _cuts(rng, pairs, length)
    position = np.arange(length)[None, :]
    inside = (position >= low) & (position < high)
    source = np.where(inside, low + high - 1 - position, position)
    return np.take_along_axis(genes, source, axis=1)


def swap_mutation(genes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Exchange two random genes of each row (possibly the same one: no change)."""
    rows, length = genes.shape
    picks = rng.integers(0, length, size=(rows, 2))
    out = genes.copy()
    index = np.arange(rows)
    out[index, picks[:, 0]] = genes[index, picks[:, 1]]
    out[index, picks[:, 1]] = genes[index, picks[:, 0]]
    return out


def slide_mutation(genes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Move one gene of each row to another position (rotate a random slice by one).

    The slice ``[a, b)`` is rotated left (its first gene moves to its end) or
    right (its last gene moves to its front), each with probability 1/2.
    """
    rows, length = genes.shape
    low, high = _cuts(rng, rows, length)
    width = np.maximum(high - low, 1)
    shift = np.where(rng.random((rows, 1)) < 0.5, 1, -1)
    position = np.arange(length)[None, :]
    inside = (position >= low) & (position < high)
    source = np.where(inside, low + (position - low + shift) % width, position)
    return np.take_along_axis(genes, source, axis=1)


CROSSOVER = {"ox": order_crossover, "obx": order_based_crossover}
MUTATION = {"inversion": inversion_mutation, "swap": swap_mutation, "slide": slide_mutation}


def nodes_to_genes(problem: AssignmentProblem, nodes: np.ndarray) -> np.ndarray:
    """Chromosome (vehicle markers) of a path from :func:`path_nodes` / :func:`local_search`."""
    inner = nodes[1:-1]
    return np.where(inner < problem.n, inner, inner - 1)


# -- the algorithm ----------------------------------------------------------------------


def _operator_set(operators: str | OperatorSet) -> OperatorSet:
    if isinstance(operators, OperatorSet):
        return operators
    if operators not in OPERATOR_SETS:
        raise InstanceError(
            f"unknown GA operator set {operators!r}; choose from {sorted(OPERATOR_SETS)}"
        )
    return OPERATOR_SETS[operators]


def _mutate(
    children: np.ndarray, ops: OperatorSet, rate: float, rng: np.random.Generator
) -> np.ndarray:
    mutate = rng.random(len(children)) < rate
    if not mutate.any():
        return children
    if len(ops.mutations) == 1:  # no draw for the choice: keeps "ox-inversion" as it was
        children[mutate] = MUTATION[ops.mutations[0]](children[mutate], rng)
        return children
    which = rng.integers(0, len(ops.mutations), size=children.shape[0])
    for index, name in enumerate(ops.mutations):
        rows = mutate & (which == index)
        if rows.any():
            children[rows] = MUTATION[name](children[rows], rng)
    return children


def _separate_clones(
    children: np.ndarray, weights: np.ndarray, ops: OperatorSet, rng: np.random.Generator
) -> None:
    """Mutate (in place) every row equal to an earlier row; row 0, the elite, is kept.

    Rows are compared by a fingerprint, their dot product with fixed random 64-bit
    ``weights`` (wrapping); two different rows sharing one is astronomically rare
    and would only cost one extra mutation.
    """
    _, first = np.unique(children @ weights, return_index=True)
    clone = np.ones(children.shape[0], dtype=bool)
    clone[first] = False
    if clone.any():
        children[clone] = _mutate(children[clone], ops, 1.0, rng)


def _polish(
    problem: AssignmentProblem,
    matrix: np.ndarray,
    genes: np.ndarray,
    fitness: np.ndarray,
    ops: OperatorSet,
    skip: float,
    counters: dict[str, int],
    deadline: Deadline | None = None,
) -> None:
    """Local search on the ``ops.polish`` best children with distinct costs (in place),
    stopped (each chromosome as improved so far) once ``deadline`` has expired."""
    values, first = np.unique(fitness, return_index=True)  # sorted, one row per value
    chosen = [int(row) for value, row in zip(values, first, strict=True) if value != skip]
    for row in chosen[: ops.polish]:
        if deadline is not None and deadline.expired():
            break
        nodes, moves, evaluations = local_search(
            matrix, path_nodes(problem, genes[row])[0], ops.max_moves, ops.neighbourhood, deadline
        )
        counters["moves"] += moves
        counters["move_evaluations"] += evaluations
        if moves:
            genes[row] = nodes_to_genes(problem, nodes)
            fitness[row] = population_cost(problem, genes[row], "vehicle")[0]


@register_method(AssignmentProblem, "GA", style=("-.", "h"))
def genetic_algorithm(
    problem: AssignmentProblem,
    seed: int | np.random.Generator | None = 0,
    population: int = 120,
    generations: int = 350,
    crossover_rate: float = 0.9,
    mutation_rate: float = 0.1,
    tournament: int | None = None,
    operators: str | OperatorSet = "memetic",
    time_limit: float | None = None,
) -> Solution:
    """GA of §2.5 with marker-gene encoding (operators in the module docstring).

    Works on any chapter 2 problem (any n >= 1, m >= 1), so chapter 3 can run
    it per capability class on a sub-problem.

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
    tournament : int, optional
        Tournament size (the thesis does not give it); default: the operator
        set's (``OperatorSet.tournament``).
    operators : str or OperatorSet
        A name from :data:`OPERATOR_SETS` -- "memetic" (default) or
        "ox-inversion" (the first version) -- or an :class:`OperatorSet`.
    time_limit : float, optional
        Wall-clock seconds: the run stops at the first check after it expires (before each
        generation and each local-search move) and returns the best chromosome so far (``info["stopped_by"] == "time_limit"``,
        ``info["generations_done"]`` fewer than ``generations``). A run stopped by time is
        not reproducible; tests stop on ``generations``.

    Returns
    -------
    Solution
        The best chromosome ever seen, decoded; ``info`` has the best
        objective after each generation (``"history"``, never increasing),
        ``"evaluations"`` (chromosomes evaluated in full), ``"moves"`` and
        ``"move_evaluations"`` (local search), and the operator set.

    Raises
    ------
    InstanceError
        population < 2, generations < 0, tournament < 1, a rate outside [0, 1]
        or an unknown operator set.

    Notes
    -----
    O(generations * population * (n + m)) numpy work for the genetic part,
    plus O((n + m)^2) per local-search move.

    Example
    -------
    >>> import numpy as np, taopt
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = taopt.AssignmentProblem(abs(x[:, None] - x[None, :]), 3)
    >>> genetic_algorithm(p, seed=0, population=10, generations=20).objective
    3.0

    References
    ----------
    Thesis §2.5 (population 120, rates 0.9 / 0.1, 350 generations).
    """
    ops = _operator_set(operators)
    if tournament is None:
        tournament = ops.tournament
    if population < 2 or generations < 0 or tournament < 1:
        raise InstanceError(
            "need population >= 2, generations >= 0 and tournament >= 1, "
            f"got {population}, {generations}, {tournament}"
        )
    for label, rate in (("crossover_rate", crossover_rate), ("mutation_rate", mutation_rate)):
        if not 0.0 <= rate <= 1.0:
            raise InstanceError(f"{label} must be in [0, 1], got {rate}")
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    rng = np.random.default_rng(seed)
    length = problem.n + problem.m - 1
    matrix = path_matrix(problem) if ops.polish else None
    counters = {"moves": 0, "move_evaluations": 0}
    # Fingerprint weights for clone detection: fixed, so they draw nothing from ``rng``.
    weights = np.random.default_rng(0x6A).integers(1, 2**62, size=length, dtype=np.int64)
    genes = rng.permuted(np.tile(np.arange(length), (population, 1)), axis=1)
    fitness = population_cost(problem, genes, ops.markers)
    best = int(np.argmin(fitness))
    best_genes, best_cost = genes[best].copy(), float(fitness[best])
    history = [best_cost]
    half = (population + 1) // 2
    crossover = CROSSOVER[ops.crossover]
    done = 0
    for _ in range(generations):
        if deadline.limited and deadline.expired():
            break
        done += 1
        # Tournament selection of 2 * half parents.
        contenders = rng.integers(0, population, size=(2 * half, tournament))
        winners = contenders[np.arange(2 * half), np.argmin(fitness[contenders], axis=1)]
        mothers, fathers = genes[winners[:half]], genes[winners[half:]]
        cross = rng.random(half) < crossover_rate
        children = np.concatenate([mothers, fathers])
        if cross.any():
            children[:half][cross] = crossover(mothers[cross], fathers[cross], rng)
            children[half:][cross] = crossover(fathers[cross], mothers[cross], rng)
        children = _mutate(children[:population], ops, mutation_rate, rng)
        children[0] = best_genes  # elitism
        if ops.distinct:
            _separate_clones(children, weights, ops, rng)
        genes = children
        fitness = population_cost(problem, genes, ops.markers)
        if ops.polish and matrix is not None:
            _polish(problem, matrix, genes, fitness, ops, best_cost, counters, deadline)
        best = int(np.argmin(fitness))
        if fitness[best] < best_cost:
            best_genes, best_cost = genes[best].copy(), float(fitness[best])
        history.append(best_cost)
    routes = decode(problem, best_genes, ops.markers)
    info = {
        "history": history,
        "population": population,
        "generations": generations,
        "tournament": tournament,
        "operators": operators if isinstance(operators, str) else repr(operators),
        "evaluations": population * (done + 1),
        **counters,
    }
    if done < generations:
        info.update(stopped_by="time_limit", generations_done=done)
    return make_solution(
        problem,
        Routes(routes),
        method="GA",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
        info=info,
    )


__all__ = [
    "genetic_algorithm",
    "OperatorSet",
    "OPERATOR_SETS",
    "population_cost",
    "path_matrix",
    "path_nodes",
    "decode",
    "encode",
    "order_crossover",
    "order_based_crossover",
    "inversion_mutation",
    "swap_mutation",
    "slide_mutation",
    "local_search",
    "improve_routes",
    "IMPROVE_MAX_MOVES",
]
