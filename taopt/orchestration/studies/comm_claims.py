"""Chapter 4's claims checked (docs/architecture.md, invariant 5), and Remark 4.6's search.

Each claim is evaluated on random scenarios (:func:`claim_values` on one problem,
:func:`check_claims` over many); the table says how often it held and keeps the smallest
counterexample found (fewest targets, then fewest vehicles) as a JSON file that
:meth:`CommProblem.load` reloads. The optimum f_o is the certified one of
``taopt.solve(problem, "exact")`` (claims needing it are skipped when it is not certified).

Claims checked
--------------
* Lemma 4.3(i) — every unvisited target stays on some able vehicle's route (checked by the
  engine after every event, for CAA, DAA and HDA).
* Proposition 4.4 — every run ends with all targets visited.
* Theorem 4.5(i) — DAA's assignment equals CAA's for every newly connected group (the whole
  trajectories are compared).
* Theorem 4.5(ii) — at most ``n + 3m + nm`` synchronous rounds per newly connected group
  (where n > m, as §4.2 assumes).
* Lemma 4.7 — the projected total distance never grows at an update (CAA, DAA, HDA).
* Lemma 4.8 — ``f_MST <= f_o``.
* Theorem 4.9 — ``f_DAA <= 2 f_o`` when the vehicles are initially connected.
* Proposition 4.10 — ``f_DAA <= Σ_j d(o_j(0))``.
* §4.4.2 — HDA and DAA give the same total when ``r = 1 m`` or ``|A| = m``.
* f_o <= f for every algorithm (no simulation beats the full-information optimum).

Remark 4.6 ("a longer range does not necessarily give a shorter total") is an existence
claim: :func:`search_remark_4_6` looks for instances where it shows and keeps the smallest.

This module is orchestration (it runs the registered methods through :func:`taopt.solve`).

Example
-------
>>> from taopt.orchestration.studies.comm_claims import check_claims
>>> table = check_claims(samples=2, seed=0, n_range=(2, 4), m_range=(1, 2))
>>> bool((table["holds"] <= table["total"]).all()), "Lemma 4.8" in " ".join(table["claim"])
(True, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from taopt.comm.bounds import mst_bound
from taopt.comm.engine import components, initially_connected
from taopt.comm.problem import CommProblem, random_problem
from taopt.errors import ConvergenceError, InstanceError
from taopt.orchestration.pipeline import solve
from taopt.orchestration.studies.routing_claims import claims_table

ALGORITHMS = ("CAA", "DAA", "HDA")


def _leq(lhs: float, rhs: float, rtol: float = 1e-9) -> bool:
    return lhs <= rhs + rtol * max(1.0, abs(rhs))


def claim_values(
    problem: CommProblem, *, seed: int = 0, time_limit: float | None = 60.0
) -> dict[str, dict[str, Any]]:
    """Evaluate every claim on one problem.

    Returns
    -------
    dict
        claim name -> {"holds": bool or None (not applicable), "lhs", "rhs"}.
    """
    runs: dict[str, Any] = {}
    stuck: dict[str, str] = {}
    for name in ALGORITHMS:
        try:
            runs[name] = solve(problem, name, seed=seed)
        except ConvergenceError as exc:
            stuck[name] = str(exc)
    n, m = problem.n, problem.m
    out: dict[str, dict[str, Any]] = {}
    out["Proposition 4.4 (all targets visited)"] = {
        "holds": not stuck,
        "lhs": len(stuck),
        "rhs": 0,
    }
    if stuck:
        return out
    daa, caa, hda = runs["DAA"], runs["CAA"], runs["HDA"]
    violations = sum(r.info["invariant_violations"] for r in runs.values())
    out["Lemma 4.3 (every target stays assigned)"] = {
        "holds": violations == 0,
        "lhs": violations,
        "rhs": 0,
    }
    out["Theorem 4.5(i) (DAA = CAA)"] = {
        "holds": daa.solution == caa.solution,
        "lhs": daa.objective,
        "rhs": caa.objective,
    }
    budget = n + 3 * m + n * m
    out["Theorem 4.5(ii) (rounds <= n + 3m + nm)"] = {
        # the theorem, like §4.2, assumes n > m (Phase 1 floods n rounds)
        "holds": daa.info["max_group_rounds"] <= budget if n > m else None,
        "lhs": daa.info["max_group_rounds"],
        "rhs": budget,
    }
    increases = sum(r.info["projected_increases"] for r in runs.values())
    out["Lemma 4.7 (projected total non-increasing)"] = {
        "holds": increases == 0,
        "lhs": increases,
        "rhs": 0,
    }
    out["Proposition 4.10 (f_DAA <= sum d(o_j(0)))"] = {
        "holds": _leq(daa.objective, daa.info["initial_total"]),
        "lhs": daa.objective,
        "rhs": daa.info["initial_total"],
    }
    same = problem.comm_range <= 1.0 or len(set(problem.vehicle_ability)) == m
    out["4.4.2 (f_HDA = f_DAA when r = 1 m or |A| = m)"] = {
        "holds": math.isclose(hda.objective, daa.objective, rel_tol=1e-9) if same else None,
        "lhs": hda.objective,
        "rhs": daa.objective,
    }
    exact = solve(problem, "exact", time_limit=time_limit, incumbent=daa.solution)
    certified = exact.is_optimal
    f_o = exact.objective
    f_mst = mst_bound(problem)
    out["Lemma 4.8 (f_MST <= f_o)"] = {
        "holds": _leq(f_mst, f_o) if certified else None,
        "lhs": f_mst,
        "rhs": f_o,
    }
    out["Theorem 4.9 (f_DAA <= 2 f_o, initially connected)"] = {
        "holds": _leq(daa.objective, 2 * f_o)
        if certified and initially_connected(problem)
        else None,
        "lhs": daa.objective,
        "rhs": 2 * f_o,
    }
    best = min(r.objective for r in runs.values())
    out["f_o <= f (no algorithm beats the optimum)"] = {
        "holds": _leq(f_o, best) if certified else None,
        "lhs": f_o,
        "rhs": best,
    }
    return out


def sample_problem(
    rng: np.random.Generator,
    n_range: tuple[int, int] = (2, 12),
    m_range: tuple[int, int] = (1, 5),
    side: float = 1000.0,
    r_range: tuple[float, float] = (1.0, 600.0),
) -> CommProblem:
    """A random scenario: n, m, |A| and r uniform in their ranges (r log-uniform)."""
    n = int(rng.integers(n_range[0], n_range[1] + 1))
    m = int(rng.integers(m_range[0], min(m_range[1], n) + 1))
    attributes = int(rng.integers(1, m + 1))
    r = float(np.exp(rng.uniform(np.log(r_range[0]), np.log(r_range[1]))))
    if rng.random() < 0.15:  # keep some scenarios initially connected (Theorem 4.9)
        r = side * math.sqrt(2.0)
    return random_problem(n, m, attributes, r, seed=rng, side=side, name=f"n{n}m{m}")


def check_claims(
    samples: int = 100,
    seed: int = 0,
    out_dir: str | Path | None = None,
    n_range: tuple[int, int] = (2, 12),
    m_range: tuple[int, int] = (1, 5),
    time_limit: float | None = 60.0,
    progress: Callable[[int], None] | None = None,
) -> Any:
    """Check every claim on ``samples`` random scenarios; a DataFrame, one row per claim.

    Columns: claim, holds, total (scenarios where it applied), smallest_n, smallest_m, lhs,
    rhs (of the smallest counterexample), path (its JSON file when ``out_dir`` is given).
    """

    rng = np.random.default_rng(seed)
    rows: dict[str, dict[str, Any]] = {}
    for sample in range(samples):
        problem = sample_problem(rng, n_range, m_range)
        for claim, value in claim_values(problem, seed=seed, time_limit=time_limit).items():
            row = rows.setdefault(
                claim,
                {
                    "claim": claim,
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
            size = (problem.n, problem.m)
            if row["instance"] is None or size < (row["smallest_n"], row["smallest_m"]):
                row.update(
                    smallest_n=problem.n,
                    smallest_m=problem.m,
                    lhs=value["lhs"],
                    rhs=value["rhs"],
                    instance=problem.replace(name=f"{claim} counterexample"),
                )
        if progress is not None:
            progress(sample)
    return claims_table(rows, out_dir)


# -- Remark 4.6 --------------------------------------------------------------------------------


def range_effect(
    problem: CommProblem, ranges: Sequence[float], algorithm: str = "DAA", seed: int = 0
) -> list[float]:
    """(4.1) of ``algorithm`` on ``problem`` at each communication range."""
    return [solve(problem.replace(comm_range=r), algorithm, seed=seed).objective for r in ranges]


def search_remark_4_6(
    samples: int = 2000,
    seed: int = 0,
    n_range: tuple[int, int] = (2, 6),
    m_range: tuple[int, int] = (2, 4),
    side: float = 100.0,
    ranges: Sequence[float] = (10.0, 20.0, 30.0, 40.0, 50.0, 60.0),
    algorithms: Sequence[str] = ("DAA",),
    homogeneous: bool = True,
) -> list[dict[str, Any]]:
    """Search random instances for Remark 4.6: ``r1 < r2`` with ``f(r2) > f(r1)``.

    Instances have integer coordinates in a ``side`` square (the thesis's Figs. 4.3–4.4 use
    100 m, homogeneous vehicles); each is run at every range in ``ranges``. Returns every
    hit as a dict (problem at r1, r1, r2, f1, f2, algorithm), smallest first (targets +
    vehicles, then the relative increase, largest first).
    """
    rng = np.random.default_rng(seed)
    hits: list[dict[str, Any]] = []
    for _ in range(samples):
        n = int(rng.integers(n_range[0], n_range[1] + 1))
        m = int(rng.integers(m_range[0], m_range[1] + 1))
        k = 1 if homogeneous else int(rng.integers(1, min(n, m) + 1))
        problem = random_problem(n, m, k, ranges[0], seed=rng, side=side)
        problem = CommProblem(
            np.round(problem.targets),
            np.round(problem.vehicles),
            problem.target_attribute,
            problem.vehicle_ability,
            ranges[0],
        )
        for algorithm in algorithms:
            totals = range_effect(problem, ranges, algorithm)
            for a in range(len(ranges)):
                for b in range(a + 1, len(ranges)):
                    if totals[b] > totals[a] * (1 + 1e-9) + 1e-9:
                        hits.append(
                            {
                                "problem": problem.replace(comm_range=ranges[a]),
                                "r1": ranges[a],
                                "r2": ranges[b],
                                "f1": totals[a],
                                "f2": totals[b],
                                "algorithm": algorithm,
                            }
                        )
    hits.sort(key=lambda h: (h["problem"].n + h["problem"].m, -(h["f2"] / h["f1"])))
    return hits


def save_remark_4_6(hit: dict[str, Any], out_dir: str | Path) -> tuple[Path, Path]:
    """Write a Remark 4.6 instance at both ranges (``remark-4-6-short/long.json``)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    label = (
        f"Remark 4.6: {hit['algorithm']} drives {hit['f1']:.1f} m at r = {hit['r1']:g} m "
        f"but {hit['f2']:.1f} m at r = {hit['r2']:g} m"
    )
    short = out / "remark-4-6-short.json"
    long = out / "remark-4-6-long.json"
    hit["problem"].replace(comm_range=hit["r1"], name=label).save(short)
    hit["problem"].replace(comm_range=hit["r2"], name=label).save(long)
    return short, long


def search_one_metre(
    samples: int = 2000,
    seed: int = 0,
    n_range: tuple[int, int] = (2, 6),
    m_range: tuple[int, int] = (2, 3),
    side: float = 100.0,
) -> dict[str, Any] | None:
    """Search for §4.4.2's "HDA = DAA when r = 1 m" failing; the smallest hit (n + m, then n).

    Instances have integer coordinates in a ``side`` square and fewer abilities than vehicles
    (|A| = m is the other case of the statement, which holds by construction). Returns
    {"problem", "daa", "hda"} or None.
    """
    rng = np.random.default_rng(seed)
    best: dict[str, Any] | None = None
    for _ in range(samples):
        n = int(rng.integers(n_range[0], n_range[1] + 1))
        m = int(rng.integers(m_range[0], m_range[1] + 1))
        k = int(rng.integers(1, min(n, m - 1) + 1)) if m > 1 else 1
        drawn = random_problem(n, m, k, 1.0, seed=rng, side=side)
        problem = CommProblem(
            np.round(drawn.targets),
            np.round(drawn.vehicles),
            drawn.target_attribute,
            drawn.vehicle_ability,
            1.0,
        )
        daa = solve(problem, "DAA").objective
        hda = solve(problem, "HDA").objective
        if math.isclose(daa, hda, rel_tol=1e-9):
            continue
        if best is None or (n + m, n) < (best["problem"].n + best["problem"].m, best["problem"].n):
            best = {"problem": problem, "daa": daa, "hda": hda}
    return best


def write_counterexamples(
    out_dir: str | Path, samples: int = 1500, seed: int = 0
) -> dict[str, Path]:
    """Search and save the chapter 4 instances shipped in docs/reproduction/counterexamples/chapter4.

    * ``remark-4-6-short.json`` / ``remark-4-6-long.json``: the smallest Remark 4.6 instance
      found by :func:`search_remark_4_6` (of its hits on that instance, the closest ranges);
    * ``section-4-4-2-hda-daa-one-metre.json``: the smallest instance where HDA and DAA
      drive different totals at r = 1 m (:func:`search_one_metre`).
    """
    out = Path(out_dir)
    written: dict[str, Path] = {}
    hits = search_remark_4_6(samples=samples, seed=seed)
    if hits:
        first = hits[0]["problem"].replace(comm_range=0.0).to_dict()
        same = [h for h in hits if h["problem"].replace(comm_range=0.0).to_dict() == first]
        hit = min(same, key=lambda h: (h["r2"] - h["r1"], -h["r1"]))
        written["remark-4-6-short"], written["remark-4-6-long"] = save_remark_4_6(hit, out)
    one = search_one_metre(samples=samples, seed=seed)
    if one is not None:
        path = out / "section-4-4-2-hda-daa-one-metre.json"
        label = (
            f"4.4.2: at r = 1 m DAA drives {one['daa']:.4f} m but HDA {one['hda']:.4f} m "
            "(the thesis: identical)"
        )
        one["problem"].replace(name=label).save(path)
        written["section-4-4-2-hda-daa-one-metre"] = path
    return written


def connectivity_probability(
    m: int, comm_range: float, samples: int = 100_000, seed: int = 0, side: float = 1000.0
) -> float:
    """Monte Carlo probability that m uniform vehicles in the square are connected at r.

    The thesis takes r_c with probability 0.99 ([65]): 712.8 m for m = 4, 600 m for m = 6,
    482 m for m = 10.
    """
    if m < 1 or samples < 1:
        raise InstanceError(f"need m >= 1 and samples >= 1, got m={m}, samples={samples}")
    rng = np.random.default_rng(seed)
    connected = 0
    chunk = 5000
    done = 0
    while done < samples:
        size = min(chunk, samples - done)
        points = rng.uniform(0.0, side, size=(size, m, 2))
        gap = points[:, :, None, :] - points[:, None, :, :]
        linked = np.hypot(gap[..., 0], gap[..., 1]) <= comm_range
        for sample in linked:
            connected += int((components(sample) == 0).all())
        done += size
    return connected / samples


__all__ = [
    "ALGORITHMS",
    "claim_values",
    "check_claims",
    "sample_problem",
    "initially_connected",
    "range_effect",
    "search_remark_4_6",
    "save_remark_4_6",
    "connectivity_probability",
    "search_one_metre",
    "write_counterexamples",
]
