"""Separation of the rows of chapter 2's model: lifted cycles and blossoms (heuristic).

The exact separation of the subtour rows (2.5) (:func:`separate_subtours`, :func:`cut_rows`)
is core code, shared with the DFJ LP bound: :mod:`taopt.routing.subtours`, re-exported here.
These serve the DFJ loop (:mod:`taopt.models.routing.dfj`).

References
----------
Thesis (2.5); Padberg and Rinaldi's exact separation of subtour constraints.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from taopt.routing.problem import AssignmentProblem
from taopt.routing.subtours import CUT_TOLERANCE, cut_rows, separate_subtours


def lifted_cycle_arcs(kind: str, sequence: tuple[int, ...]) -> list[tuple[int, int, int]]:
    """Arcs and coefficients of the lifted cycle inequality ``D_k^+`` or ``D_k^-`` of ``sequence``.

    For a sequence ``s_0, …, s_{k-1}`` of distinct targets, ``D_k^+`` (Grötschel and
    Padberg) reads::

        Σ_{h<k-1} σ(s_h, s_{h+1}) + σ(s_{k-1}, s_0)        (the cycle, coefficient 1)
        + 2 Σ_{2≤h≤k-1} σ(s_0, s_h)                        (chords out of s_0)
        + Σ_{2≤j<h≤k-1} σ(s_h, s_j)                        (backward arcs among s_2..)
        ≤ k − 1.

    ``D_k^-`` of a sequence t is ``D_k^+`` of t with every arc reversed (the same
    inequality on the reversed digraph). Both are valid for chapter 2's model: they hold
    for every tour of an ATSP on more than k points, so for every set of vertex-disjoint
    paths on ``{s_h}`` (each extends to such a tour), and the arcs of any solution of
    (2.2)–(2.5) between targets are such paths ((2.3), (2.4) and (2.5)); reversing all
    paths keeps them paths. ``kind`` is ``"+"`` or ``"-"``; returns ``(tail, head,
    coefficient)`` triples, the right-hand side being ``k − 1``.

    References
    ----------
    Grötschel and Padberg (1985), the ``D_k`` inequalities of the ATSP; Fischetti and
    Toth (1997), their heuristic separation.
    """
    s = [int(v) for v in sequence]
    k = len(s)
    arcs = [(s[h], s[h + 1], 1) for h in range(k - 1)] + [(s[k - 1], s[0], 1)]
    arcs += [(s[0], s[h], 2) for h in range(2, k)]
    arcs += [(s[h], s[j], 1) for h in range(3, k) for j in range(2, h)]
    if kind == "-":
        arcs = [(head, tail, c) for tail, head, c in arcs]
    return arcs


def separate_lifted_cycles(
    problem: AssignmentProblem,
    tails: np.ndarray,
    heads: np.ndarray,
    values: np.ndarray,
    tolerance: float = 1e-3,
    limit: int = 50,
) -> list[tuple[str, tuple[int, ...]]]:
    """``D_k^+`` / ``D_k^-`` inequalities violated by σ = ``values``, found greedily.

    Heuristic separation (the problem is NP-hard in general): from every arc
    ``s_0 -> s_1`` between targets with ``σ > 0``, the sequence is extended one target at
    a time by the target that raises the left-hand side of
    :func:`lifted_cycle_arcs` most, and the prefix of largest violation is kept; ``D_k^-``
    the same on the transposed σ. Returns at most ``limit`` ``(kind, sequence)`` pairs,
    most violated first, each violated by more than ``tolerance``.

    Notes
    -----
    Appending v to ``s_0..s_{k-1}`` changes the ``D^+`` left-hand side by
    ``−σ(s_{k-1}, s_0) + σ(s_{k-1}, v) + σ(v, s_0) + 2σ(s_0, v) + Σ_{j≥2} σ(v, s_j)``
    and the right-hand side by 1: O(n) per step with numpy, O(n) steps per start and
    one start per support arc, so O(n^2 |support|) at worst (the extension stops after
    a few steps without a better prefix).
    """
    n = problem.n
    dense = np.zeros((n, n))
    inner = tails < n
    dense[tails[inner], heads[inner]] = np.asarray(values, dtype=float)[inner]
    found: dict[tuple[str, tuple[int, ...]], float] = {}
    for kind, matrix in (("+", dense), ("-", dense.T)):
        for first, second in zip(*np.nonzero(matrix > 1e-6), strict=True):
            sequence, violation = _grow_lifted(matrix, int(first), int(second))
            if sequence is not None and violation > tolerance:
                found[(kind, sequence)] = max(violation, found.get((kind, sequence), 0.0))
    ranked = sorted(found, key=lambda key: -found[key])
    return ranked[:limit]


def blossom_arcs(
    handle: tuple[int, ...], teeth: tuple[tuple[int, int], ...]
) -> tuple[list[tuple[int, int, int]], float]:
    """Arcs, coefficients and right-hand side of a 2-matching (blossom) inequality.

    With ``y_{ij} = σ_ij + σ_ji`` the undirected use of a pair, the inequality over a
    handle H and t odd teeth (pairs with exactly one end in H) reads
    ``y(E(H)) + Σ_teeth y_e ≤ |H| + (t − 1) / 2``. It is valid for chapter 2's model:
    every point has at most two arcs (a target one in by (2.3), at most one out by (2.4);
    a start point at most one out), and ``y_e ≤ 1`` on a tooth (a 2-cycle of targets is
    a (2.5) row; a start point is never entered); summing the degrees over H with the
    teeth's ``y_e ≤ 1`` gives ``2 y(E(H)) + 2 Σ_teeth y_e ≤ 2|H| + t``, and rounding down
    (Chvátal–Gomory) the inequality. Returns ``(tail, head, 1)`` triples (both directions
    of every pair; arcs into a start point do not exist and are left to the caller) and
    the right-hand side.

    References
    ----------
    Edmonds (1965), 2-matching inequalities; Padberg and Rao (1982); their use on the
    ATSP through ``y = σ + σ^T`` (Fischetti, Lodi and Toth 2003).
    """
    inside = [int(v) for v in handle]
    arcs = [(a, b, 1) for a in inside for b in inside if a != b]
    for a, b in teeth:
        arcs += [(int(a), int(b), 1), (int(b), int(a), 1)]
    return arcs, len(inside) + (len(teeth) - 1) / 2


def separate_blossoms(
    problem: AssignmentProblem,
    tails: np.ndarray,
    heads: np.ndarray,
    values: np.ndarray,
    tolerance: float = 1e-3,
) -> list[tuple[str, tuple[int, ...], tuple[tuple[int, int], ...]]]:
    """Blossom inequalities (:func:`blossom_arcs`) violated by σ = ``values``, found greedily.

    The usual fast heuristic: every connected component of the pairs with fractional
    ``0 < y < 1`` is a handle; its teeth are the pairs leaving it with ``y > 1/2``, one
    dropped or added (the one that costs least) when their number is even. Returns
    ``("blossom", handle, teeth)`` triples, each violated by more than ``tolerance``.

    Notes
    -----
    O((n + m)^2) with numpy and one connected-components call.
    """
    size = problem.n + problem.m
    y = np.zeros((size, size))
    y[tails, heads] = np.asarray(values, dtype=float)
    y = y + y.T
    fractional = (y > 1e-6) & (y < 1 - 1e-6)
    count, label = connected_components(sp.csr_matrix(fractional), directed=False)
    found = []
    for component in range(count):
        members = np.flatnonzero(label == component)
        if len(members) < 3:
            continue
        inside = np.zeros(size, dtype=bool)
        inside[members] = True
        inner = y[np.ix_(members, members)].sum() / 2
        outside = np.flatnonzero(~inside)
        leaving = y[np.ix_(members, outside)]
        rows, columns = np.nonzero(leaving > 1e-6)
        weights = leaving[rows, columns]
        order = np.argsort(-weights)
        rows, columns, weights = rows[order], columns[order], weights[order]
        t = int((weights > 0.5).sum())
        if t % 2 == 0:
            # drop the weakest tooth or add the best non-tooth: whichever loses less
            drop = 2 * weights[t - 1] - 1 if t else np.inf
            add = 1 - 2 * weights[t] if t < len(weights) else np.inf
            if not np.isfinite(min(drop, add)):
                continue
            t = t - 1 if drop <= add else t + 1
        if t < 1:
            continue
        violation = inner + weights[:t].sum() - len(members) - (t - 1) / 2
        if violation > tolerance:
            teeth = tuple(
                (int(members[r]), int(outside[c]))
                for r, c in zip(rows[:t], columns[:t], strict=True)
            )
            found.append(("blossom", tuple(int(v) for v in members), teeth))
    return found


def _grow_lifted(
    matrix: np.ndarray, first: int, second: int, patience: int = 3
) -> tuple[tuple[int, ...] | None, float]:
    """Greedy ``D^+`` sequence from ``first -> second`` on σ = ``matrix``: best prefix, violation."""
    n = matrix.shape[0]
    free = np.ones(n, dtype=bool)
    free[[first, second]] = False
    sequence = [first, second]
    lhs = matrix[first, second] + matrix[second, first]
    backward = np.zeros(n)  # Σ_{j>=2} σ(v, s_j) for every v
    best, best_length, waited = lhs - 1.0, 2, 0
    while free.any() and waited < patience:
        last = sequence[-1]
        gain = matrix[last] + matrix[:, first] + 2.0 * matrix[first] + backward
        gain = np.where(free, gain, -np.inf)
        v = int(np.argmax(gain))
        lhs += gain[v] - matrix[last, first]
        sequence.append(v)
        free[v] = False
        backward += matrix[:, v]
        violation = lhs - (len(sequence) - 1)
        if violation > best + 1e-12:
            best, best_length, waited = violation, len(sequence), 0
        else:
            waited += 1
    if best_length < 3:
        return None, best  # a 2-cycle is a (2.5) row: left to the exact separation
    return tuple(sequence[:best_length]), best


__all__ = [
    "CUT_TOLERANCE",
    "cut_rows",
    "blossom_arcs",
    "lifted_cycle_arcs",
    "separate_blossoms",
    "separate_lifted_cycles",
    "separate_subtours",
]
