"""Chapter 2 bounds: the thesis's Algorithm 1 ("MCGA"), a valid arborescence bound, f_da.

Which of these is a valid lower bound on the optimum f_o of (2.2)–(2.5)
(docs/architecture.md, invariant 3):

* :func:`arborescence_bound` — **valid** for every non-negative matrix. Every
  feasible solution (one open path per vehicle) plus zero-cost edges from a
  super-root to the vehicles is a spanning arborescence of the graph used, so
  the minimum-cost one (Edmonds' algorithm) is never above f_o.
* :func:`thesis_mcga` — Algorithm 1 exactly as printed: Prim-like growth from
  the vehicle set. On a symmetric matrix it is a minimum spanning forest
  rooted at the vehicles, hence valid (Lemma 2.4). On an asymmetric matrix
  Prim's greedy growth is *not* a minimum-cost arborescence, and its value can
  exceed f_o (Lemma 2.4 fails there; :mod:`taopt.orchestration.studies.routing_claims` finds such
  instances). Kept because the thesis's quality ratio q = f / f_a (2.26) uses it.
* :func:`f_da` — Lemma 2.5's upper bound: the MCGA with every edge duplicated
  in the opposite direction.
* :func:`lp_bound` — the LP relaxation of (2.2)–(2.5) with every DFJ row (valid; the
  ``"strong"`` bound of :func:`taopt.bounds.lower`).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np

from taopt.arborescence import min_arborescence
from taopt.errors import InstanceError
from taopt.routing.problem import AssignmentProblem


@dataclass(frozen=True)
class GrowthTree:
    """The tree grown by Algorithm 1 / the extended Voronoi clustering (2.12)–(2.14).

    Attributes
    ----------
    parent : (n,) int array
        ``parent[k]`` is the point (index into ``problem.cost``: a target
        ``0..n-1`` or a vehicle start ``n..n+m-1``) joined to target k.
    vehicle : (n,) int array
        ``vehicle[k]`` in ``0..m-1``: the vehicle whose subtree holds target k
        (the cluster of (2.14)).
    order : (n,) int array
        Targets in the order they were added (line 3 of Algorithm 1).
    weight : (n,) float array
        ``weight[k] = cost[parent[k], k]``, the edge weight added for target k.
    """

    parent: np.ndarray
    vehicle: np.ndarray
    order: np.ndarray
    weight: np.ndarray

    @property
    def value(self) -> float:
        """Sum of the edge weights, the thesis's f_a."""
        return float(self.weight.sum())


def mcga_tree(problem: AssignmentProblem) -> GrowthTree:
    """Grow Algorithm 1's tree ("MCGA") from the vehicle set, as printed.

    Line 1 puts every vehicle start in the tree; each pass of lines 3–5 adds
    the target ``p*`` and tree vertex ``j*`` minimising ``t(j, p)`` over
    (tree vertex, target not yet in the tree). This is also exactly the
    extended Voronoi clustering (2.12)–(2.14): ``T_j`` = the vehicle's start
    plus its subtree.

    Parameters
    ----------
    problem : AssignmentProblem

    Returns
    -------
    GrowthTree

    Notes
    -----
    The zero-cost vehicle–vehicle edges of §2.4.3 never matter: all vehicles
    are in the tree from line 1 and only targets are added, so no edge into a
    vehicle is ever chosen. Ties in the argmin: the lowest target index
    ``p``; among tree vertices at equal cost, the one that entered the tree
    first (vehicle starts in index order, then targets in the order added).
    Vectorised Prim: O(n (n + m)) time.

    References
    ----------
    Thesis §2.4.3, Algorithm 1; (2.12)–(2.14).
    """
    n = problem.n
    cost = problem.cost
    from_vehicles = cost[n:, :n]  # (m, n): t(p_j, k)
    source = np.argmin(from_vehicles, axis=0)  # lowest vehicle on ties
    best = from_vehicles[source, np.arange(n)].copy()
    parent = n + source
    vehicle = source.copy()
    open_ = np.ones(n, dtype=bool)
    order = np.empty(n, dtype=int)
    weight = np.empty(n, dtype=float)
    masked = best.copy()
    for step in range(n):
        k = int(np.argmin(masked))  # lowest target index on ties
        order[step] = k
        weight[k] = best[k]
        open_[k] = False
        masked[k] = np.inf
        # Target k joins the tree: it may now be the closest tree vertex of others.
        better = open_ & (cost[k, :n] < best)  # strict: earlier vertex wins ties
        best[better] = cost[k, :n][better]
        parent[better] = k
        vehicle[better] = vehicle[k]
        masked[better] = best[better]
    return GrowthTree(parent=parent, vehicle=vehicle, order=order, weight=weight)


def thesis_mcga(problem: AssignmentProblem) -> float:
    """The thesis's f_a: value of Algorithm 1's tree, as printed.

    Valid lower bound for symmetric matrices only (see the module notes): on
    asymmetric matrices it may exceed the optimum; use
    :func:`arborescence_bound` for a valid bound.

    Example
    -------
    One vehicle (point 2) and two targets where greedy growth is fooled:

    >>> import numpy as np
    >>> cost = np.array([[0, 10, 9], [0, 0, 9], [1, 10, 0]])
    >>> p = AssignmentProblem(cost, n_targets=2)
    >>> thesis_mcga(p), p.evaluate([[1, 0]])  # f_a = 1 + 10 > f_o = 10 + 0
    (11.0, 10.0)
    """
    return mcga_tree(problem).value


def arborescence_graph(problem: AssignmentProblem) -> nx.DiGraph:
    """The digraph of the valid bound: super-root -> vehicles (0), vehicles/targets -> targets."""
    n, m = problem.n, problem.m
    cost = problem.cost
    graph = nx.DiGraph()
    root = "root"
    graph.add_node(root)
    graph.add_edges_from((root, n + j, {"weight": 0.0}) for j in range(m))
    sources, targets = np.nonzero(~np.eye(n + m, n, dtype=bool))
    graph.add_edges_from(
        (int(i), int(k), {"weight": float(cost[i, k])})
        for i, k in zip(sources, targets, strict=True)
    )
    return graph


def arborescence_bound(problem: AssignmentProblem, method: str = "dense") -> float:
    """Valid lower bound: minimum-cost spanning arborescence with a super-root.

    The graph has a super-root joined to every vehicle start at zero cost and
    the edges ``i -> k`` of weight ``t(i, k)`` from every point to every
    target (no edges into vehicles other than from the root). Any feasible
    solution of (2.2)–(2.5) plus the root edges is a spanning arborescence of
    it, so the minimum (Edmonds' algorithm) is <= f_o for every non-negative
    matrix, symmetric or not.

    Parameters
    ----------
    problem : AssignmentProblem
    method : {"dense", "networkx"}
        "dense" (default): :func:`taopt.arborescence.min_arborescence` on the graph with
        the vehicles merged into the super-root (the root's edge to target k
        costs ``min_j t(p_j, k)``; the same optimum, since root -> vehicle
        edges cost 0 and nothing else enters a vehicle). "networkx":
        ``networkx.minimum_spanning_arborescence`` on the graph as described
        (about 5 s for n=120, m=20, against milliseconds for "dense").

    Returns
    -------
    float
        The arborescence's weight; always <= :func:`thesis_mcga` (Algorithm
        1 builds one spanning arborescence of the same graph).

    References
    ----------
    Thesis §2.4.3 (the MCGA it intends); Edmonds (1967).
    """
    if method == "networkx":
        graph = arborescence_graph(problem)
        tree = nx.minimum_spanning_arborescence(graph, attr="weight", preserve_attrs=True)
        return float(sum(w for _, _, w in tree.edges(data="weight")))
    if method != "dense":
        raise InstanceError(f"method must be 'dense' or 'networkx', got {method!r}")
    n = problem.n
    weight = np.full((n + 1, n + 1), np.inf)
    weight[:n, :n] = problem.cost[:n, :n]
    weight[n, :n] = problem.cost[n:, :n].min(axis=0)
    return min_arborescence(weight, root=n)


def f_da(problem: AssignmentProblem, tree: str = "thesis") -> float:
    """Lemma 2.5's f_da: the MCGA with each edge duplicated in the opposite direction.

    Sums ``t(u, k) + t(k, u)`` over the edges ``u -> k`` of the tree (u a
    vehicle start or a target, k a target), i.e. over the n edges of each
    vehicle's arborescence after the zero-cost vehicle edges are removed.

    Parameters
    ----------
    problem : AssignmentProblem
    tree : {"thesis", "edmonds"}
        "thesis" (default, as in Lemma 2.5): Algorithm 1's tree
        (:func:`mcga_tree`). "edmonds": the minimum-cost arborescence of
        :func:`arborescence_bound`.

    Returns
    -------
    float
        When the matrix satisfies the triangle inequality (Lemma 2.3), an
        upper bound on f_o (a depth-first walk of the doubled tree,
        shortcut, is a feasible solution). For a symmetric matrix with
        ``tree="thesis"`` it equals ``2 * thesis_mcga(problem)``.

    References
    ----------
    Thesis Lemma 2.5.
    """
    cost = problem.cost
    n = problem.n
    if tree == "thesis":
        parent = mcga_tree(problem).parent
    elif tree == "edmonds":
        graph = arborescence_graph(problem)
        arb = nx.minimum_spanning_arborescence(graph, attr="weight")
        parent = np.empty(n, dtype=int)
        for u, k in arb.edges():
            if u != "root":
                parent[k] = u
    else:
        raise InstanceError(f"tree must be 'thesis' or 'edmonds', got {tree!r}")
    targets = np.arange(n)
    return float((cost[parent, targets] + cost[targets, parent]).sum())


def path_bound(problem: AssignmentProblem) -> float:
    """Chapter 2: the degree-penalised arborescence (targets out-degree <= 1, vehicles <= m).

    Validity: a feasible solution of (2.2)–(2.5) with the vehicles merged into one root
    (root -> target k costs min_j t(p_j, k), as in the dense arborescence bound) is a
    spanning arborescence in which every target has out-degree <= 1 and the root <= m, of
    weight <= f; the Lagrangian with π >= 0 on these rows is <= f
    (:func:`taopt.arborescence.degree_penalised_arborescence`).
    """
    import numpy as np

    from taopt.arborescence import degree_penalised_arborescence

    n, m = problem.n, problem.m
    if n == 0:
        return 0.0
    weight = np.full((n + 1, n + 1), np.inf)
    weight[:n, :n] = problem.cost[:n, :n]
    weight[n, :n] = problem.cost[n:, :n].min(axis=0)
    capacity = np.r_[np.ones(n), float(m)]
    result = degree_penalised_arborescence(weight, n, capacity, np.zeros(n + 1, dtype=bool))
    return max(result.value, arborescence_bound(problem))


def lp_bound(problem: AssignmentProblem) -> float:
    """Valid lower bound: the LP relaxation of (2.2)–(2.5) with every DFJ row (2.5).

    The LP of (2.2)–(2.4) over ``0 <= σ <= 1`` is solved with scipy's HiGHS; the (2.5) rows a
    fractional σ violates are found by exact separation
    (:func:`taopt.routing.subtours.separate_subtours`) and added until none is left, so the
    last LP is the full DFJ relaxation (the value ``taopt.models.lp_bound`` computes with the
    exact model's own HiGHS loop). Every LP of the loop is a relaxation; the value returned is
    the largest Lagrangian value of their row duals, valid whatever the solver's tolerances.

    Returns
    -------
    float
        The DFJ LP bound (never above the optimum f_o); at least :func:`arborescence_bound`
        up to solver tolerances (the DFJ LP lies in the arborescence polytope).

    Notes
    -----
    For row duals y of (2.3) (free) and z <= 0 of the other rows (written ``A_ub σ <= b_ub``),
    ``L = 1·y + b_ub·z + Σ_a min(0, c_a − (A_eq^T y + A_ub^T z)_a) <= c·σ`` for every
    ``0 <= σ <= 1`` meeting the rows, hence <= f_o. One LP of ``(n + m) n`` columns per
    round; a few rounds at the thesis's sizes.

    Example
    -------
    >>> import numpy as np
    >>> cost = np.array([[0, 1, 9], [1, 0, 9], [5, 6, 0.0]])
    >>> round(lp_bound(AssignmentProblem(cost, 2)), 6)
    6.0

    References
    ----------
    Thesis (2.2)–(2.5); Dantzig, Fulkerson and Johnson (1954).
    """
    import scipy.sparse as sp
    from scipy.optimize import linprog

    from taopt.routing.subtours import arc_list, cut_rows, separate_subtours

    n, m = problem.n, problem.m
    if n == 0:
        return 0.0
    size = n + m
    tails, heads = arc_list(problem)
    arcs = np.arange(len(tails))
    cost = problem.cost[tails, heads]
    into = sp.csr_matrix((np.ones(len(arcs)), (heads, arcs)), shape=(n, len(arcs)))  # (2.3)
    out_of = sp.csr_matrix((np.ones(len(arcs)), (tails, arcs)), shape=(size, len(arcs)))  # (2.4)
    cuts: list[tuple[int, ...]] = []
    best = -np.inf
    while True:
        rows, lower, upper = cut_rows(problem, cuts, tails, heads)
        # a cut row reads lower <= row·σ <= upper with one side open: as A_ub σ <= b_ub
        sign = np.where(np.isfinite(upper), 1.0, -1.0)
        a_ub = sp.vstack([out_of, sp.diags(sign) @ rows]).tocsr()
        b_ub = np.concatenate([np.ones(size), np.where(sign > 0, upper, -lower)])
        result = linprog(
            cost,
            A_ub=a_ub,
            b_ub=b_ub,
            A_eq=into,
            b_eq=np.ones(n),
            bounds=(0.0, 1.0),
            method="highs",
        )
        if result.status != 0:
            raise InstanceError(
                f"the DFJ LP relaxation of {problem.name or 'the problem'} "
                f"ended with status {result.status}: {result.message}"
            )
        y = np.asarray(result.eqlin.marginals, dtype=float)
        z = np.minimum(np.asarray(result.ineqlin.marginals, dtype=float), 0.0)
        reduced = cost - into.T @ y - a_ub.T @ z
        best = max(best, float(y.sum() + b_ub @ z + np.minimum(reduced, 0.0).sum()))
        found = [s for s in separate_subtours(problem, tails, heads, result.x) if s not in cuts]
        if not found:
            return best
        cuts += found


def routing_lower(problem: AssignmentProblem, strength: str) -> float:
    """:func:`taopt.bounds.lower` for chapter 2: the arborescence ("fast"), :func:`path_bound`
    ("auto"), and the larger of that and the DFJ LP :func:`lp_bound` ("strong")."""
    if strength == "fast":
        return float(arborescence_bound(problem))
    if strength == "strong":
        return max(float(path_bound(problem)), lp_bound(problem))
    return float(path_bound(problem))


__all__ = [
    "GrowthTree",
    "mcga_tree",
    "thesis_mcga",
    "arborescence_bound",
    "arborescence_graph",
    "f_da",
    "path_bound",
    "lp_bound",
    "routing_lower",
]
