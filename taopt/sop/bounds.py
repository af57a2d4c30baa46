"""Bounds of the sequential ordering problem: the arborescence from ``start`` (in
:mod:`taopt.sop.problem`) and a degree-penalised arborescence (valid, proofs below)."""

from __future__ import annotations

from taopt.sop.problem import SopProblem, sop_arborescence_bound


def path_bound(problem: SopProblem) -> float:
    """SOP: the degree-penalised arborescence (every node but ``end`` has out-degree 1).

    Validity: a feasible order is a Hamiltonian path start -> ... -> end, a spanning
    arborescence rooted at ``start`` on the usable arcs (those of
    :func:`taopt.sop.problem.sop_arborescence_bound`) in which every node except ``end``
    has out-degree exactly 1; hence every L(π) is <= its cost.
    """
    import numpy as np

    from taopt.arborescence import degree_penalised_arborescence, greedy_path_weight

    weights = np.array(problem.cost, dtype=float)
    closure = problem.closure
    for r, j in closure.edges:
        weights[j, r] = np.inf
    weights[problem.end, :] = np.inf
    n = problem.n
    capacity = np.ones(n)
    capacity[problem.end] = np.inf
    need = [set(closure.predecessors(v)) if v in closure else set() for v in range(n)]
    target = greedy_path_weight(weights, problem.start, need)
    result = degree_penalised_arborescence(
        weights, problem.start, capacity, np.ones(n, dtype=bool), target=target
    )
    return max(result.value, sop_arborescence_bound(problem))


def sop_lower(problem: SopProblem, strength: str) -> float:
    """:func:`taopt.bounds.lower` for the SOP: the arborescence ("fast"), or
    :func:`path_bound`."""
    return float(sop_arborescence_bound(problem) if strength == "fast" else path_bound(problem))


__all__ = ["path_bound", "sop_lower", "sop_arborescence_bound"]
