"""Executable checks of chapter 3's claims (docs/architecture.md, invariant 5).

Each checkable statement is evaluated on random instances of several classes; the result
says how often it held and keeps the smallest counterexample (fewest targets, then vehicles,
then capabilities) as a JSON file that :meth:`CapabilityProblem.load` reloads.

Claims (per class q and summed; ``f^a`` = :func:`~taopt.capability.bounds.thesis_mcga`,
``f^da`` = :func:`~taopt.capability.bounds.doubled_arborescence`, ``f^o`` the optimum):

* Remark 3.1 — the matrix satisfies ``t(i, k) <= t(i, j) + t(j, k)``.
* Theorem 3.4 — ``f^a <= f^o``.
* Lemma 3.6 — ``f^o <= f^da``; and ``f^da <= 2 f^o`` on symmetric costs.
* Theorem 3.7 — ``f^DTAA <= f^da``.
* Theorem 3.5 — DTAA's assignment (Algorithm 2 on the communication graph) equals
  Algorithm 1's clusters per class, on a complete graph, a path and a random connected graph
  (checked together); and, beyond the thesis's "all connected topologies", what happens on a
  disconnected graph (two components): whether every demand is still served exactly once.

Instance classes (capabilities and demands drawn as in :mod:`taopt.capability.instances`):

* "euclidean": symmetric straight-line times, points uniform in a 100 m square.
* "metric": random asymmetric times in [1, 100] closed under shortest paths (Remark 3.1
  holds by construction): the general setting the statements are made for.
* "grid-drift": §3.7's scenarios (thesis field, the three obstacles, 1000 m square) with
  the grid planner's travel times (:func:`taopt.capability.instances.thesis_scenario`).

The optimum comes from :func:`exact_optimum`, chapter 2's Held–Karp subset DP on each class
(independent of any solver), or from the certified MILP (``exact="milp"``).

This is an orchestration module: it runs the heuristics and, on request, the MILP.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import networkx as nx
import numpy as np

from taopt.capability.bounds import doubled_arborescence, thesis_mcga
from taopt.capability.instances import random_demands, thesis_scenario
from taopt.capability.problem import CapabilityProblem
from taopt.errors import InstanceError, SolverError
from taopt.heuristics.dtaa import distributed_auction, dtaa
from taopt.models import solve_capability
from taopt.orchestration.studies.routing_claims import claims_table, euclidean_costs, metric_costs
from taopt.orchestration.studies.routing_claims import exact_optimum as routing_optimum
from taopt.routing.bounds import mcga_tree

#: The instance classes the claims are checked on.
CLASSES = ("euclidean", "metric", "grid-drift")
CLASS_NOTES = {
    "euclidean": "symmetric straight-line times, 100 m square",
    "metric": "random asymmetric in [1, 100], shortest-path closed",
    "grid-drift": "§3.7 scenario: thesis field, three obstacles, grid planner (10 m, 16 moves)",
}
GRAPHS = ("complete", "path", "random")

__all__ = [
    "CLASSES",
    "GRAPHS",
    "exact_optimum",
    "optimum",
    "random_problem",
    "communication_graphs",
    "split_graph",
    "claim_values",
    "check_claims",
    "triangle_excess",
    "still_violates",
]


# -- the optimum ----------------------------------------------------------------------------


def exact_optimum(problem: CapabilityProblem) -> tuple[float, list[list[int]]]:
    """Optimal value and routes by chapter 2's subset DP on each class (|T_q| <= 12)."""
    total = 0.0
    class_routes = {}
    for cls in problem.classes:
        if cls.problem is None:
            continue
        value, routes = routing_optimum(cls.problem)
        total += value
        class_routes[cls.capability] = routes
    return total, problem.join(class_routes)


def optimum(problem: CapabilityProblem, method: str = "auto") -> float:
    """f^o by the DP ("dp"), the certified corrected MILP ("milp"), or "auto" (DP when
    every class has at most 10 targets)."""
    if method not in ("auto", "dp", "milp"):
        raise InstanceError(f"exact must be 'auto', 'dp' or 'milp', got {method!r}")
    small = all(len(c.targets) <= 10 for c in problem.classes)
    if method == "dp" or (method == "auto" and small):
        return exact_optimum(problem)[0]

    result = solve_capability(problem, "corrected")
    if result.status != "optimal":
        raise SolverError(f"the corrected model did not prove optimality ({result.status})")
    return float(result.objective)


# -- random instances -----------------------------------------------------------------------


def _labels(rng: np.random.Generator, n: int, m: int, k: int) -> tuple[list[str], list[tuple]]:
    labels = [f"c{q}" for q in range(k)]
    capability = [labels[q] for q in rng.integers(0, k, size=m)]
    for q, vehicle in enumerate(rng.permutation(m)[:k]):
        capability[vehicle] = labels[q]
    return capability, random_demands(rng, n, labels)


def random_problem(
    kind: str, n: int, m: int, n_capabilities: int, rng: np.random.Generator
) -> CapabilityProblem:
    """One random instance of class ``kind`` (one of :data:`CLASSES`)."""
    if kind not in CLASSES:
        raise InstanceError(f"unknown instance class {kind!r}; choose from {CLASSES}")
    if kind == "grid-drift":
        seed = int(rng.integers(0, 2**31))
        return thesis_scenario(n, m, n_capabilities, seed).problem.replace(
            name=f"{kind}-n{n}m{m}A{n_capabilities}"
        )
    if kind == "euclidean":
        cost = euclidean_costs(rng.uniform(0.0, 100.0, size=(n + m, 2)))
    else:
        cost = metric_costs(rng, n + m)
    capability, demands = _labels(rng, n, m, n_capabilities)
    return CapabilityProblem(
        cost,
        n,
        tuple(capability),
        tuple(frozenset(d) for d in demands),
        name=f"{kind}-n{n}m{m}A{n_capabilities}",
    )


def communication_graphs(m: int, rng: np.random.Generator) -> dict[str, nx.Graph]:
    """Connected graphs on ``m`` vehicles: complete, a path (index order), a random one.

    The random graph is a random tree (each vehicle, in a random order, joined to a random
    earlier one) plus every other pair with probability 0.3.
    """
    order = rng.permutation(m)
    tree = nx.Graph()
    tree.add_nodes_from(range(m))
    for position in range(1, m):
        tree.add_edge(int(order[position]), int(order[rng.integers(0, position)]))
    for i in range(m):
        for j in range(i + 1, m):
            if rng.random() < 0.3:
                tree.add_edge(i, j)
    return {"complete": nx.complete_graph(m), "path": nx.path_graph(m), "random": tree}


def split_graph(m: int) -> nx.Graph:
    """A disconnected graph: vehicles ``0..⌈m/2⌉-1`` and the rest, each half complete."""
    half = (m + 1) // 2
    graph = nx.complete_graph(half)
    graph.add_edges_from((i, j) for i in range(half, m) for j in range(i + 1, m))
    graph.add_nodes_from(range(m))
    return graph


# -- the claims -----------------------------------------------------------------------------


def triangle_excess(matrix: np.ndarray) -> float:
    """Largest ``t(i, k) - min_j (t(i, j) + t(j, k))`` (<= 0 iff Remark 3.1 holds).

    ``inf`` entries are kept as such: an unreachable ``(i, k)`` with a finite detour through
    some j gives ``inf`` (Remark 3.1 fails); ``inf`` against ``inf`` is no violation.
    """
    via = np.min(matrix[:, :, None] + matrix[None, :, :], axis=1)
    with np.errstate(invalid="ignore"):
        excess = matrix - via
    return float(np.max(np.where(np.isnan(excess), -np.inf, excess)))


def _leq(lhs: float, rhs: float, rtol: float) -> bool:
    return lhs <= rhs + rtol * max(1.0, abs(rhs))


def _algorithm1_clusters(problem: CapabilityProblem) -> dict[Any, dict[int, frozenset[int]]]:
    """Algorithm 1's clusters per class, in whole-problem indices, one set per vehicle."""
    out: dict[Any, dict[int, frozenset[int]]] = {}
    for cls in problem.classes:
        if cls.problem is None:
            continue
        tree = mcga_tree(cls.problem)
        out[cls.capability] = {
            vehicle: frozenset(cls.targets[t] for t in np.flatnonzero(tree.vehicle == local))
            for local, vehicle in enumerate(cls.vehicles)
        }
    return out


def _dtaa_clusters(auction: Any) -> dict[Any, dict[int, frozenset[int]]]:
    return {
        c.capability: {j: frozenset(t) for j, t in enumerate(c.assigned) if t}
        for c in auction.classes
    }


def _same_clusters(expected: dict, found: dict) -> bool:
    for cap, clusters in expected.items():
        mine = found.get(cap, {})
        for vehicle, targets in clusters.items():
            if mine.get(vehicle, frozenset()) != targets:
                return False
    return True


def claim_values(
    problem: CapabilityProblem,
    rng: np.random.Generator | None = None,
    rtol: float = 1e-9,
    triangle_rtol: float = 1e-9,
    exact: str = "auto",
) -> dict[str, dict[str, Any]]:
    """Evaluate every claim on one instance.

    Parameters
    ----------
    problem : CapabilityProblem
    rng : numpy.random.Generator, optional
        Draws the random communication graph (default: seed 0).
    rtol : float
        Relative slack of every inequality (sums in a different order differ by rounding).
    triangle_rtol : float
        Slack of Remark 3.1, relative to the largest finite entry.
    exact : {"auto", "dp", "milp"}
        How f^o is computed (:func:`optimum`).

    Returns
    -------
    dict
        claim name -> {"holds": bool or None (not applicable), "lhs", "rhs"}.
    """

    rng = np.random.default_rng(0) if rng is None else rng
    f_a = thesis_mcga(problem)
    f_da = doubled_arborescence(problem)
    f_o = optimum(problem, exact)
    f_dtaa = dtaa(problem).objective
    violation = 0.0
    scale = 1.0
    symmetric = True
    for cap in problem.capabilities:
        matrix = problem.cost_for(cap)
        finite = np.where(np.isfinite(matrix), matrix, np.nan)
        scale = max(scale, float(np.nanmax(finite)))
        violation = max(violation, triangle_excess(matrix))
        symmetric &= bool(np.allclose(matrix, matrix.T, equal_nan=False))
    expected = _algorithm1_clusters(problem)
    mismatched = [
        name
        for name, graph in communication_graphs(problem.m, rng).items()
        if not _same_clusters(expected, _dtaa_clusters(distributed_auction(problem, graph)))
    ]
    split = distributed_auction(problem, split_graph(problem.m))
    served = split.served()
    demanded = problem.demand_pairs()
    once = len(served) == demanded and all(len(who) == 1 for who in served.values())
    return {
        "Remark 3.1 (triangle inequality)": {
            "holds": violation <= triangle_rtol * scale,
            "lhs": violation,
            "rhs": 0.0,
        },
        "Theorem 3.4 (f^a <= f^o)": {"holds": _leq(f_a, f_o, rtol), "lhs": f_a, "rhs": f_o},
        "Lemma 3.6 (f^o <= f^da)": {"holds": _leq(f_o, f_da, rtol), "lhs": f_o, "rhs": f_da},
        "Lemma 3.6 (f^da <= 2 f^o, symmetric)": {
            "holds": _leq(f_da, 2 * f_o, rtol) if symmetric else None,
            "lhs": f_da,
            "rhs": 2 * f_o,
        },
        "Theorem 3.7 (f^DTAA <= f^da)": {
            "holds": _leq(f_dtaa, f_da, rtol),
            "lhs": f_dtaa,
            "rhs": f_da,
        },
        "Theorem 3.5 (DTAA = Algorithm 1, connected graphs)": {
            "holds": not mismatched,
            "lhs": len(mismatched),
            "rhs": 0,
        },
        "Theorem 3.5 on a disconnected graph (each demand served once)": {
            "holds": once if problem.m > 1 else None,
            "lhs": sum(len(w) for w in served.values()),
            "rhs": demanded,
        },
    }


def check_claims(
    samples: int = 100,
    seed: int | np.random.Generator | None = 0,
    out_dir: str | Path | None = None,
    classes: tuple[str, ...] = CLASSES,
    n_range: tuple[int, int] = (2, 7),
    m_range: tuple[int, int] = (1, 4),
    capability_range: tuple[int, int] = (1, 3),
    exact: str = "auto",
    progress: Callable[[int], None] | None = None,
) -> Any:
    """Test chapter 3's claims on random instances; keep the smallest counterexamples.

    Parameters
    ----------
    samples : int
        Instances per class; n, m and |A| uniform in their ranges (inclusive; m <= n is not
        required, |A| <= m).
    seed : int or numpy.random.Generator
    out_dir : path, optional
        Where to save each smallest counterexample as ``<claim>-<class>.json``.
    classes : tuple of str
        Subset of :data:`CLASSES`.
    exact : {"auto", "dp", "milp"}

    Returns
    -------
    pandas.DataFrame
        One row per (claim, class): ``holds``, ``total`` (instances where it applies),
        ``smallest_n``, ``smallest_m``, ``smallest_A``, ``lhs``, ``rhs``, ``path``,
        ``instance``, ``costs``.
    """

    rng = np.random.default_rng(seed)
    rows: dict[tuple[str, str], dict[str, Any]] = {}
    for kind in classes:
        for sample in range(samples):
            n = int(rng.integers(n_range[0], n_range[1] + 1))
            m = int(rng.integers(m_range[0], m_range[1] + 1))
            k = int(rng.integers(capability_range[0], min(capability_range[1], m) + 1))
            problem = random_problem(kind, n, m, k, rng)
            for claim, value in claim_values(problem, rng=rng, exact=exact).items():
                row = rows.setdefault(
                    (claim, kind),
                    {
                        "claim": claim,
                        "instance_class": kind,
                        "costs": CLASS_NOTES[kind],
                        "holds": 0,
                        "total": 0,
                        "smallest_n": None,
                        "smallest_m": None,
                        "smallest_A": None,
                        "lhs": None,
                        "rhs": None,
                        "instance": None,
                        "path": None,
                    },
                )
                if value["holds"] is None:
                    continue
                row["total"] += 1
                if value["holds"]:
                    row["holds"] += 1
                    continue
                size = (n, m, k)
                if row["instance"] is None or size < (
                    row["smallest_n"],
                    row["smallest_m"],
                    row["smallest_A"],
                ):
                    row.update(
                        smallest_n=n,
                        smallest_m=m,
                        smallest_A=k,
                        lhs=value["lhs"],
                        rhs=value["rhs"],
                        instance=problem.replace(name=f"{claim} counterexample ({kind})"),
                    )
            if progress is not None:
                progress(sample)
    return claims_table(rows, out_dir)


def still_violates(problem: CapabilityProblem, claim: str, exact: str = "auto") -> bool:
    """True if ``claim`` (a name from :func:`claim_values`) fails on ``problem``."""
    value = claim_values(problem, exact=exact)[claim]["holds"]
    return value is False
