"""Executable checks of chapter 2's claims (docs/architecture.md, invariant 5).

Each claim with a checkable inequality is tested over random instances of
several classes; the result says how often it held and keeps the smallest
counterexample found (fewest targets, then fewest vehicles) as a JSON file
that :meth:`AssignmentProblem.load` reloads.

Claims checked (f_a = :func:`~taopt.routing.bounds.thesis_mcga`, Algorithm 1;
f_da = :func:`~taopt.routing.bounds.f_da`; f_o the exact optimum):

* Lemma 2.3 — the matrix satisfies ``t(i, k) <= t(i, j) + t(j, k)``.
* Lemma 2.4 — ``f_a <= f_o``.
* Lemma 2.5 — ``f_o <= f_da``; and ``f_da = 2 f_a`` on symmetric matrices.
* Theorem 2.6 — ``f_EVM / f_o <= f_da / f_a``.
* Theorem 2.7 — ``f_MC <= f_EVM``.

Instance classes (points uniform in a square of side 100 m, vehicle speed 1):

* "euclidean": symmetric, ``t = distance``.
* "uniform-drift": the uniform current equal to the thesis field (scale
  1e-2) at the square's centre, (0.25, 0.05) m/s: straight lines are time
  optimal and ``t = d / v_net`` with v_net from (3.4) (closed form).
* "drift": the thesis field ``1e-2 [0.3x + 0.2y, -0.2x + 0.3y]`` (Fig. 2.1's
  scale) with minimum times from ``taopt.navigation.travel_time_matrix``
  (direct collocation); instances are sub-matrices of pooled matrices
  (:class:`InstanceSampler`) because each ordered pair is a small NLP.
* "metric": random asymmetric costs uniform in [1, 100], closed under
  shortest paths (scipy ``shortest_path``), so Lemma 2.3 holds by
  construction — the general asymmetric setting the lemmas are stated for.

What the checks found (``check_claims(samples=300, seed=0)``, n 2..7, m 1..3):
Lemma 2.4 fails on every asymmetric class (12-26 % of instances, smallest
n = 2, m = 1: Algorithm 1's greedy growth is not a minimum arborescence);
Theorem 2.7 fails on every class, Euclidean included (1-4 %; a 3-target
Euclidean case is worked by hand in ``tests/routing/test_claims.py``); Theorem 2.6
fails rarely on "metric" (2 of 1500 in ``check_claims(1500, seed=1,
classes=("euclidean", "uniform-drift", "metric"), n_range=(2, 5))``, n = 3). Lemmas 2.3 and 2.5
held on every sample.

The exact optimum comes from :func:`exact_optimum`: a Held–Karp style
dynamic programme over subsets (independent of any solver), used for n <= 10.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from taopt.errors import InstanceError, SolverError
from taopt.orchestration.pipeline import solve
from taopt.routing.bounds import f_da, thesis_mcga
from taopt.routing.problem import AssignmentProblem

# -- exact optimum by dynamic programming ---------------------------------------------


def exact_optimum(problem: AssignmentProblem) -> tuple[float, list[list[int]]]:
    """Optimal value and routes of (2.2)–(2.5) by dynamic programming (n <= 12).

    ``path[j, S, e]`` = cheapest open path from vehicle j's start through
    exactly the target set S, ending at e (Held–Karp); ``best[j, S]`` its min
    over e; then the targets are split among vehicles by
    ``split[j, S] = min_{T ⊆ S} split[j-1, S \\ T] + best[j, T]``.
    O(m 2^n n^2 + m 4^n) numpy work: fine up to n ~ 10.

    Raises
    ------
    InstanceError
        n > 12.
    """
    n, m = problem.n, problem.m
    if n > 12:
        raise InstanceError(f"exact_optimum enumerates subsets: n={n} > 12 targets is too many")
    cost = problem.cost
    full = 1 << n
    path = np.full((m, full, n), np.inf)
    came = np.full((m, full, n), -1, dtype=int)
    for e in range(n):
        path[:, 1 << e, e] = cost[n:, e]
    for subset in range(1, full):
        members = [e for e in range(n) if subset >> e & 1]
        if len(members) < 2:
            continue
        for e in members:
            prev = subset & ~(1 << e)
            options = path[:, prev, :] + cost[:n, e][None, :]  # (m, n) over last f
            came[:, subset, e] = np.argmin(options, axis=1)
            path[:, subset, e] = options[np.arange(m), came[:, subset, e]]
    best = path.min(axis=2)
    best[:, 0] = 0.0
    masks = np.arange(full)
    split = np.empty((m, full))
    choice = np.zeros((m, full), dtype=int)  # T given to vehicle j
    split[0] = best[0]
    choice[0] = masks
    for j in range(1, m):
        for subset in range(full):
            subs = masks[(masks & subset) == masks]
            totals = split[j - 1, subset & ~subs] + best[j, subs]
            pick = int(np.argmin(totals))
            split[j, subset] = totals[pick]
            choice[j, subset] = subs[pick]
    # Decode: peel off each vehicle's subset, then walk its path backwards.
    routes: list[list[int]] = [[] for _ in range(m)]
    remaining = full - 1
    for j in range(m - 1, -1, -1):
        mine = int(choice[j, remaining])
        remaining &= ~mine
        if mine:
            e = int(np.argmin(path[j, mine]))
            route = []
            subset = mine
            while subset:
                route.append(e)
                f = int(came[j, subset, e])
                subset &= ~(1 << e)
                e = f
            routes[j] = route[::-1]
    return float(split[m - 1, full - 1]), routes


def optimum(problem: AssignmentProblem, method: str = "auto") -> float:
    """f_o: :func:`exact_optimum` (dp) or ``taopt.models.solve_routing`` (milp).

    "auto" uses the DP for n <= 10 and the MILP beyond; a MILP result must be
    certified optimal.
    """
    if method not in ("auto", "dp", "milp"):
        raise InstanceError(f"exact must be 'auto', 'dp' or 'milp', got {method!r}")
    if method == "dp" or (method == "auto" and problem.n <= 10):
        return exact_optimum(problem)[0]
    result = solve(problem, "exact")
    if result.status != "optimal":
        raise SolverError(f"solve_routing did not prove optimality (status {result.status!r})")
    return float(result.objective)


# -- instance classes -----------------------------------------------------------------


def _points(rng: np.random.Generator, count: int, side: float) -> np.ndarray:
    return rng.uniform(0.0, side, size=(count, 2))


def euclidean_costs(points: np.ndarray) -> np.ndarray:
    """Symmetric straight-line times at speed 1."""
    return np.linalg.norm(points[:, None, :] - points[None, :, :], axis=2)


DRIFT_SCALE = 1e-2
SIDE = 100.0


def drift_field() -> Any:
    """The thesis field at Fig. 2.1's scale, ``1e-2 [0.3x + 0.2y, -0.2x + 0.3y]``."""
    from taopt.fields import thesis_field

    return thesis_field(DRIFT_SCALE)


def uniform_drift_costs(points: np.ndarray) -> np.ndarray:
    """Closed-form (3.4) times in the uniform current equal to :func:`drift_field` at the centre."""
    from taopt.fields import UniformField
    from taopt.navigation import travel_time_matrix

    vx, vy = drift_field().velocity(np.array([[SIDE / 2, SIDE / 2]]))[0]
    return np.asarray(travel_time_matrix(UniformField(vx, vy), points), dtype=float)


def drift_costs(points: np.ndarray, jobs: int | None = 1) -> np.ndarray:
    """Minimum times in :func:`drift_field` by ``taopt.navigation.travel_time_matrix``."""
    from taopt.navigation import travel_time_matrix

    return np.asarray(travel_time_matrix(drift_field(), points, jobs=jobs), dtype=float)


def metric_costs(rng: np.random.Generator, size: int) -> np.ndarray:
    """Random asymmetric costs in [1, 100], closed under shortest paths (metric)."""
    from scipy.sparse.csgraph import shortest_path

    raw = rng.uniform(1.0, 100.0, size=(size, size))
    np.fill_diagonal(raw, 0.0)
    return shortest_path(raw, method="FW", directed=True)


#: The instance classes the claims are checked on.
CLASSES = ("euclidean", "uniform-drift", "drift", "metric")
CLASS_NOTES = {
    "euclidean": "symmetric straight-line distances, 100 m square",
    "uniform-drift": "closed form (3.4), uniform current = thesis field (1e-2) at the centre",
    "drift": "thesis field 1e-2, 100 m square, navigation.travel_time_matrix (collocation), "
    "sub-matrices of a pooled matrix",
    "metric": "random asymmetric in [1, 100], shortest-path closed",
}


class InstanceSampler:
    """Random instances of one class; "drift" reuses a pooled travel-time matrix.

    Navigation solves are the expensive part (tens of ms per ordered pair), so
    for "drift" a matrix is computed for ``pool_size`` random points and each
    instance takes the sub-matrix of n + m of them (a sub-matrix of a matrix
    of minimum times is the matrix of minimum times of those points). The pool
    is redrawn every ``pool_reuse`` instances.
    """

    def __init__(
        self, kind: str, rng: np.random.Generator, pool_size: int = 12, pool_reuse: int = 5
    ) -> None:
        if kind not in CLASSES:
            raise InstanceError(f"unknown instance class {kind!r}; choose from {CLASSES}")
        self.kind, self.rng = kind, rng
        self.pool_size, self.pool_reuse = pool_size, pool_reuse
        self._pool: np.ndarray | None = None
        self._used = 0

    def __call__(self, n: int, m: int) -> AssignmentProblem:
        kind, rng = self.kind, self.rng
        if kind == "euclidean":
            cost = euclidean_costs(_points(rng, n + m, SIDE))
        elif kind == "uniform-drift":
            cost = uniform_drift_costs(_points(rng, n + m, SIDE))
        elif kind == "metric":
            cost = metric_costs(rng, n + m)
        else:
            if n + m > self.pool_size:
                raise InstanceError(f"drift pool has {self.pool_size} points, need {n + m}")
            if self._pool is None or self._used >= self.pool_reuse:
                self._pool = drift_costs(_points(rng, self.pool_size, SIDE))
                self._used = 0
            self._used += 1
            pick = rng.choice(self.pool_size, size=n + m, replace=False)
            cost = self._pool[np.ix_(pick, pick)]
        return AssignmentProblem(cost, n, name=f"{kind}-n{n}m{m}")


def random_problem(kind: str, n: int, m: int, rng: np.random.Generator) -> AssignmentProblem:
    """One random instance of class ``kind`` (one of :data:`CLASSES`)."""
    return InstanceSampler(kind, rng, pool_size=n + m, pool_reuse=1)(n, m)


# -- the claims -----------------------------------------------------------------------


def triangle_violation(cost: np.ndarray) -> float:
    """Largest ``t(i, k) - min_j (t(i, j) + t(j, k))`` (<= 0 iff Lemma 2.3 holds)."""
    via = (cost[:, :, None] + cost[None, :, :]).min(axis=1)
    return float((cost - via).max())


def _leq(lhs: float, rhs: float, rtol: float) -> bool:
    return lhs <= rhs + rtol * max(1.0, abs(rhs))


def claim_values(
    problem: AssignmentProblem,
    rtol: float = 1e-9,
    triangle_rtol: float = 1e-6,
    exact: str = "auto",
) -> dict[str, dict[str, Any]]:
    """Evaluate every claim on one instance.

    Parameters
    ----------
    problem : AssignmentProblem
    rtol : float
        Relative slack of every inequality (sums in a different order differ
        by rounding).
    triangle_rtol : float
        Slack of Lemma 2.3, relative to the largest entry: navigation matrices
        are numerical solutions (collocation), not exact minima.
    exact : {"auto", "dp", "milp"}
        How f_o is computed (:func:`optimum`).

    Returns
    -------
    dict
        claim name -> {"holds": bool or None (not applicable), "lhs", "rhs"}.
    """
    f_a = thesis_mcga(problem)
    f_double = f_da(problem)
    f_o = optimum(problem, exact)
    f_evm = solve(problem, "EVM").objective
    f_mc = solve(problem, "MC").objective
    tri = triangle_violation(problem.cost)
    scale = float(problem.cost.max()) or 1.0
    out: dict[str, dict[str, Any]] = {
        "Lemma 2.3 (triangle inequality)": {
            "holds": tri <= triangle_rtol * scale,
            "lhs": tri,
            "rhs": 0.0,
        },
        "Lemma 2.4 (f_a <= f_o)": {"holds": _leq(f_a, f_o, rtol), "lhs": f_a, "rhs": f_o},
        "Lemma 2.5 (f_o <= f_da)": {
            "holds": _leq(f_o, f_double, rtol),
            "lhs": f_o,
            "rhs": f_double,
        },
        "Lemma 2.5 (f_da = 2 f_a, symmetric)": {
            "holds": (
                math.isclose(f_double, 2 * f_a, rel_tol=1e-9, abs_tol=1e-9)
                if problem.is_symmetric
                else None
            ),
            "lhs": f_double,
            "rhs": 2 * f_a,
        },
        "Theorem 2.6 (f_EVM/f_o <= f_da/f_a)": {
            # Cross-multiplied: f_EVM * f_a <= f_da * f_o (all positive).
            "holds": _leq(f_evm * f_a, f_double * f_o, rtol),
            "lhs": f_evm / f_o if f_o > 0 else math.inf,
            "rhs": f_double / f_a if f_a > 0 else math.inf,
        },
        "Theorem 2.7 (f_MC <= f_EVM)": {
            "holds": _leq(f_mc, f_evm, rtol),
            "lhs": f_mc,
            "rhs": f_evm,
        },
    }
    return out


def check_claims(
    samples: int = 200,
    seed: int | np.random.Generator | None = 0,
    out_dir: str | Path | None = None,
    classes: tuple[str, ...] = CLASSES,
    n_range: tuple[int, int] = (2, 7),
    m_range: tuple[int, int] = (1, 3),
    progress: Callable[[int], None] | None = None,
    pool_size: int = 12,
    pool_reuse: int = 5,
    exact: str = "auto",
) -> Any:
    """Test chapter 2's claims on random instances; keep the smallest counterexamples.

    Parameters
    ----------
    samples : int
        Instances per class. Sizes are drawn uniformly: n in ``n_range``,
        m in ``m_range`` (both inclusive, m <= n).
    seed : int or numpy.random.Generator
    out_dir : path, optional
        Where to save each smallest counterexample as
        ``<claim>-<class>.json`` (reload with ``AssignmentProblem.load``).
    classes : tuple of str
        Subset of :data:`CLASSES` ("euclidean", "uniform-drift", "drift", "metric").
    pool_size, pool_reuse : int
        For "drift": points per navigation matrix, instances per matrix
        (see :class:`InstanceSampler`); ``pool_size >= n_range[1] + m_range[1]``.
    exact : {"auto", "dp", "milp"}
        How f_o is computed: the subset DP (default for n <= 10, independent of
        any solver) or ``taopt.models.solve_routing`` (certified optimal).

    Returns
    -------
    pandas.DataFrame
        One row per (claim, instance class): ``holds`` and ``total`` (the
        number of instances where the claim applies), ``smallest_n``,
        ``smallest_m``, ``lhs``/``rhs`` of that counterexample, ``path`` of
        its JSON (None without ``out_dir``), ``instance`` (the problem
        itself), and ``costs`` (how the matrices were made).
    """

    rng = np.random.default_rng(seed)
    rows: dict[tuple[str, str], dict[str, Any]] = {}
    for kind in classes:
        sampler = InstanceSampler(kind, rng, pool_size, pool_reuse)
        for sample in range(samples):
            n = int(rng.integers(n_range[0], n_range[1] + 1))
            m = int(rng.integers(m_range[0], min(m_range[1], n) + 1))
            problem = sampler(n, m)
            for claim, value in claim_values(problem, exact=exact).items():
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
                size = (n, m)
                if row["instance"] is None or size < (row["smallest_n"], row["smallest_m"]):
                    row.update(
                        smallest_n=n,
                        smallest_m=m,
                        lhs=value["lhs"],
                        rhs=value["rhs"],
                        instance=problem.replace(name=f"{claim} counterexample ({kind})"),
                    )
            if progress is not None:
                progress(sample)
    # Rows whose claim never applied (f_da = 2 f_a on asymmetric classes) are dropped.
    return claims_table(rows, out_dir)


def claims_table(rows: dict[Any, dict[str, Any]], out_dir: str | Path | None) -> Any:
    """The claims' DataFrame (rows that applied at least once), after saving each row's
    smallest counterexample to ``out_dir`` as ``<claim-slug>[-<instance_class>].json``
    (the path goes in the row's ``path``). Shared by the chapter 2, 3 and 4 claim checks."""
    import pandas as pd

    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        for row in rows.values():
            if row["instance"] is not None:
                suffix = f"-{row['instance_class']}" if "instance_class" in row else ""
                path = out / f"{_slug(row['claim'])}{suffix}.json"
                row["instance"].save(path)
                row["path"] = str(path)
    return pd.DataFrame([row for row in rows.values() if row["total"] > 0])


def _slug(claim: str) -> str:
    """ "Lemma 2.4 (f_a <= f_o)" -> "lemma-2-4-f-a-f-o"."""
    words = "".join(c if c.isalnum() else "-" for c in claim.lower())
    return "-".join(w for w in words.split("-") if w)[:60]


def still_violates(problem: AssignmentProblem, claim: str, exact: str = "auto") -> bool:
    """True if ``claim`` (a name from :func:`claim_values`) fails on ``problem``."""
    return claim_values(problem, exact=exact)[claim]["holds"] is False


__all__ = [
    "exact_optimum",
    "optimum",
    "claim_values",
    "check_claims",
    "still_violates",
    "random_problem",
    "triangle_violation",
    "euclidean_costs",
    "metric_costs",
    "drift_costs",
    "uniform_drift_costs",
    "InstanceSampler",
    "CLASSES",
]
