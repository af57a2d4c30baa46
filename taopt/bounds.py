"""Lower bounds, each saying whether it is valid (DESIGN invariant 3).

Each bound is a ``functools.singledispatch`` function on the problem's class; families hook
their implementations in with :func:`taopt.registry.register_family`.

* :func:`arborescence` — valid. Chapter 2: Edmonds' min-cost arborescence with a super-root
  joined to every vehicle at zero cost. Chapter 3: the same per capability class. Chapter 5:
  Proposition 5.3's min-cost arborescence of G^d rooted at the depot. SOP: the arborescence
  rooted at the start node.
* :func:`thesis_mcga` — the thesis's Algorithm 1 ("MCGA") as printed (per class in chapter
  3, Theorem 3.4's f^a). Kept because Tables 2.1–2.2 and Figs. 3.4–3.6 are computed with it;
  NOT a valid lower bound on asymmetric matrices (it can exceed the optimum).
* :func:`doubled_arborescence` — Lemma 3.6's f^da, an upper bound on the optimum.
* :func:`mst` — Lemma 4.8's minimum-spanning-tree bound (chapter 4).
* :func:`lower` — the strongest valid lower bound each family has, at a chosen cost
  (``strength``): the one to quote a gap against.
"""

from __future__ import annotations

import functools
from typing import Any

from taopt.errors import InstanceError


def _generic(name: str, doc: str) -> Any:
    def unknown(problem: Any, *args: Any, **kwargs: Any) -> float:
        raise InstanceError(f"{name}() does not know problems of type {type(problem).__name__}")

    unknown.__name__ = name
    unknown.__qualname__ = name
    unknown.__doc__ = doc
    return functools.singledispatch(unknown)


arborescence = _generic(
    "arborescence", "Valid lower bound from a min-cost arborescence (Edmonds), per family."
)
thesis_mcga = _generic(
    "thesis_mcga",
    "The thesis's Algorithm 1 value f_a, as printed (not a valid bound on asymmetric costs).",
)
doubled_arborescence = _generic(
    "doubled_arborescence", "Lemma 3.6's f^da: every arborescence edge doubled (an upper bound)."
)
mst = _generic("mst", "Lemma 4.8's minimum-spanning-tree lower bound (chapter 4).")

#: Accepted values of ``strength`` in :func:`lower`.
STRENGTHS = ("fast", "auto", "strong")


def _routing_path_bound(problem: Any) -> float:
    """Chapter 2: the degree-penalised arborescence (targets out-degree <= 1, vehicles <= m).

    Validity: a feasible solution of (2.2)–(2.5) with the vehicles merged into one root
    (root -> target k costs min_j t(p_j, k), as in the dense arborescence bound) is a
    spanning arborescence in which every target has out-degree <= 1 and the root <= m, of
    weight <= f; the Lagrangian with π >= 0 on these rows is <= f
    (:mod:`taopt.delivery.relaxation`).
    """
    import numpy as np

    from taopt.delivery.relaxation import degree_penalised_arborescence

    n, m = problem.n, problem.m
    if n == 0:
        return 0.0
    weight = np.full((n + 1, n + 1), np.inf)
    weight[:n, :n] = problem.cost[:n, :n]
    weight[n, :n] = problem.cost[n:, :n].min(axis=0)
    capacity = np.r_[np.ones(n), float(m)]
    result = degree_penalised_arborescence(weight, n, capacity, np.zeros(n + 1, dtype=bool))
    return max(result.value, arborescence(problem))


def _sop_path_bound(problem: Any) -> float:
    """SOP: the degree-penalised arborescence (every node but ``end`` has out-degree 1).

    Validity: a feasible order is a Hamiltonian path start -> ... -> end, a spanning
    arborescence rooted at ``start`` on the usable arcs (those of
    :func:`taopt.delivery.sop.sop_arborescence_bound`) in which every node except ``end``
    has out-degree exactly 1; hence every L(π) is <= its cost.
    """
    import numpy as np

    from taopt.delivery.relaxation import degree_penalised_arborescence, greedy_path_weight

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
    return max(result.value, arborescence(problem))


def lower(problem: Any, strength: str = "auto") -> float:
    """The strongest valid lower bound on the optimum of ``problem`` at a given cost.

    Parameters
    ----------
    problem : AssignmentProblem, CapabilityProblem, CommProblem, DeliveryInstance or SopProblem
    strength : {"fast", "auto", "strong"}
        "fast": the family's Edmonds/MST bound (milliseconds). "auto" (default): the
        strongest bound that takes seconds at the thesis's sizes. "strong": "auto" plus
        the LP relaxations where the family has one (may take minutes).

    Returns
    -------
    float
        A valid lower bound (never above the optimum), always >= the "fast" bound.

    Raises
    ------
    InstanceError
        Unknown problem type or strength.

    Notes
    -----
    Which bound each family gets (all valid, proofs in the functions named):

    - AssignmentProblem (ch. 2): fast :func:`arborescence`; auto a degree-penalised
      arborescence (targets' out-degree <= 1); strong also ``taopt.models.lp_bound`` (the
      DFJ LP, needs cvxpy; the slowest by far).
    - CapabilityProblem (ch. 3): the sum over classes of the above.
    - CommProblem (ch. 4): :func:`mst` (Lemma 4.8) for every strength (no stronger bound
      yet).
    - DeliveryInstance (ch. 5): fast Proposition 5.3; auto the larger of
      ``decomposition_bound`` and ``path_bound`` of ``taopt.delivery.bounds`` (about 10 s at
      n = 120).
    - SopProblem: fast the arborescence from ``start``; auto a degree-penalised
      arborescence.

    "auto" returns the maximum of its bound and the "fast" one, so it is never weaker.

    Example
    -------
    >>> import taopt
    >>> inst = taopt.DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> lower(inst) >= arborescence(inst)
    True

    References
    ----------
    Thesis Prop. 5.3 (§5.3.2), §2.4.3, Lemma 4.8; Held and Karp (1970).
    """
    if strength not in STRENGTHS:
        raise InstanceError(f"strength must be one of {STRENGTHS}, got {strength!r}")
    return float(_lower(problem, strength))


# each family hooks its implementation in through register_family(bounds={"lower": ...})
_lower = _generic("lower", "The strongest valid lower bound at a cost ``strength``, per family.")
lower.register = _lower.register  # type: ignore[attr-defined]


def routing_lower(problem: Any, strength: str) -> float:
    """:func:`lower` for chapter 2: the degree-penalised arborescence; "strong" adds the LP."""
    if strength == "fast":
        return float(arborescence(problem))
    value = _routing_path_bound(problem)
    if strength == "strong":  # the DFJ LP is an exact-model relaxation: it lives in taopt.models
        from taopt.models import lp_bound

        value = max(value, float(lp_bound(problem)))
    return float(value)


def capability_lower(problem: Any, strength: str) -> float:
    """:func:`lower` for chapter 3: the arborescence, or the sum of the classes' bounds."""
    if strength == "fast":
        return float(arborescence(problem))
    return float(sum(lower(c.problem, strength) for c in problem.classes if c.problem is not None))


def sop_lower(problem: Any, strength: str) -> float:
    """:func:`lower` for the SOP: the arborescence, or the degree-penalised one."""
    return float(arborescence(problem) if strength == "fast" else _sop_path_bound(problem))


def comm_lower(problem: Any, strength: str) -> float:
    """:func:`lower` for chapter 4: Lemma 4.8's MST bound at every strength."""
    return float(mst(problem))


__all__ = ["arborescence", "thesis_mcga", "doubled_arborescence", "mst", "lower", "STRENGTHS"]
