"""Lemma 4.8's lower bound f_MST: a minimum spanning tree per attribute class.

For each attribute a, the graph G_a holds the targets of attribute a and the start points
of the vehicles of ability a, with Euclidean edge weights and zero-weight edges between
every two vehicles (Algorithm 7 grows it from all the vehicles at once, as Prim's algorithm
does). Any routes serving class a, joined by the zero-weight vehicle edges, form a spanning
connected subgraph of G_a, so ``f_MST = Σ_a MST(G_a) <= f_o`` (Lemma 4.8): valid for every
instance of the family.

Contracting the zero-weight vehicle edges gives the same tree weight: one root node joined
to each target at its distance from the nearest vehicle of the class. That is what is
computed, with :func:`scipy.sparse.csgraph.minimum_spanning_tree` on a sparse matrix that
lists every edge explicitly (a dense matrix would read a zero distance — coincident points —
as "no edge").
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree

from taopt.comm.problem import CommProblem


def class_mst(problem: CommProblem, code: int) -> float:
    """MST weight of G_a for the attribute with index ``code`` (0 when it has no target)."""
    targets = np.flatnonzero(problem.target_code == code)
    vehicles = np.flatnonzero(problem.vehicle_code == code)
    if targets.size == 0:
        return 0.0
    n = problem.n
    dist = problem.distances
    size = targets.size + 1
    weights = np.zeros((size, size))
    weights[0, 1:] = dist[np.ix_(n + vehicles, targets)].min(axis=0)
    weights[1:, 1:] = dist[np.ix_(targets, targets)]
    rows, cols = np.triu_indices(size, k=1)
    edges = coo_matrix((weights[rows, cols], (rows, cols)), shape=(size, size)).tocsr()
    return float(minimum_spanning_tree(edges).sum())


def mst_bound(problem: CommProblem) -> float:
    """Lemma 4.8: ``f_MST = Σ_a MST(G_a)``, a valid lower bound on the optimum f_o of (4.1).

    Example
    -------
    >>> p = CommProblem([[1, 0], [3, 0]], [[0, 0]], ["a", "a"], ["a"], comm_range=1)
    >>> mst_bound(p)
    3.0
    """
    return float(sum(class_mst(problem, code) for code in range(len(problem.attributes))))


def comm_lower(problem: CommProblem, strength: str) -> float:
    """:func:`taopt.bounds.lower` for chapter 4: Lemma 4.8's MST bound at every strength."""
    return float(mst_bound(problem))


__all__ = ["mst_bound", "class_mst", "comm_lower"]
