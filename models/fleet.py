"""The fleet family's certified exact method, registered as ``"exact"`` for FleetProblem.

:func:`solve_fleet` picks the fastest exact algorithm that applies (each certified on its own):

1. no plan exists (a drone-only customer out of every drone's range, or no drone at all):
   status ``infeasible``, proven by :meth:`taopt.fleet.problem.FleetProblem.unservable`;
2. chapter 5's shape (K = D = c = 1, every customer drone-only, ``last_service``): chapter 5's
   DP over the order ideals of G^p (:func:`taopt.delivery.ideal_dp.ideal_dp`), its plan carried
   over by :meth:`taopt.fleet.problem.FleetPlan.from_delivery_plan`;
3. one truck with one drone, every customer drone-only, c > 1 or ``"return"``: the sortie DP
   over the order ideals (:func:`taopt.fleet.sorties.sortie_dp`, chapter 5's DP with
   multi-parcel sorties);
4. one drone per truck, c = 1 and no precedence (TSP-D and its multi-truck version): the
   operations DP over customer subsets (:func:`taopt.fleet.operations.operations_dp`);
5. several trucks with one drone each, every customer drone-only: the customers split over
   the trucks, each truck by the sortie DP, a bound over the splits
   (:func:`taopt.fleet.sorties.split_dp`: each part with split-dependent releases, then the
   joint DP of each split whose combined plan misses its bound,
   :func:`taopt.fleet.coupled.coupled_dp`);
6. any other fleet of K >= 2 trucks with at most 16 customers and 400,000 splits
   (:func:`taopt.fleet.split.split_applies`): the split search
   (:func:`taopt.fleet.split.split_search`: splits in increasing bound, each truck's part by
   the label search on its one-truck sub-problem, the coupled search where cross-truck
   precedences bind: exact by :func:`taopt.fleet.coupled.leader_search` when they all go
   one way), from the root sortie-walk bound;
7. anything else (one truck): the best-first label search with dominance
   (:mod:`taopt.fleet.search`).
"""

from __future__ import annotations

import time
from typing import Any

from taopt.errors import require
from taopt.fleet.evaluate import as_plan
from taopt.fleet.problem import FleetPlan, FleetProblem
from taopt.fleet.search import label_search
from taopt.fleet.sorties import applies as sorties_applies
from taopt.fleet.sorties import sortie_dp, split_applies, split_dp
from taopt.fleet.split import split_applies as search_split_applies
from taopt.fleet.split import split_search
from taopt.registry import register_method
from taopt.result import Solution, finish

#: Share of the time limit the label search gives the improver (the ILS) before searching.
IMPROVE_SHARE = 0.2

#: Cap on the improver's time per customer (seconds): at n <= 8 the ILS settles within a
#: second or two, and a fifth of a 60 s limit (12 s) was most of a run the search certifies
#: in seconds (one truck, two drones, n = 5).
IMPROVE_SECONDS_PER_CUSTOMER = 0.5

#: Share of the time limit the root sortie-walk bound may take (its bisection stops there).
COVER_SHARE = 0.2

#: Share of the time limit the one-drone relaxation's bound (:func:`_one_drone_floor`) may take
#: (one truck only). It ends when the relaxed problem is solved (0.6-2.7 s on fleet8's one-truck
#: rows, load 1-6), and it is their bound at 10 s: the search after it expands 1-8k labels
#: there and lifts no bound (certifying needs 33k or more). A fifth of 10 s cut it short at
#: load 7 (K1D3c2 242.58 instead of 248.50, K1D3c3 235.03 instead of 244.98).
RELAX_SHARE = 0.35

#: K >= 2 (the split search): the root sortie-walk bound takes at most this share of the time
#: the improver left (and at most :data:`COVER_SHARE` of the limit).
SPLIT_COVER_LEFT = 0.5


def _score_or_inf(problem: FleetProblem, plan: Any) -> float:
    from taopt.errors import FeasibilityError
    from taopt.fleet.evaluate import evaluate_fleet

    if plan is None:
        return float("inf")
    try:
        return evaluate_fleet(problem, plan)
    except FeasibilityError:
        return float("inf")


def _chapter5_shape(problem: FleetProblem) -> bool:
    return (
        problem.drones == (1,)
        and problem.capacity == 1
        and problem.objective == "last_service"
        and all(mode == "drone" for mode in problem.service)
    )


def _operations_shape(problem: FleetProblem) -> bool:
    return all(d == 1 for d in problem.drones) and problem.capacity == 1 and not problem.precedences


def solve_fleet(
    problem: FleetProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    max_labels: int | None = None,
    algorithm: str = "auto",
    improve: Any = None,
) -> Solution:
    """Certified optimum of a fleet problem (module docstring for the algorithm used).

    Parameters
    ----------
    problem : FleetProblem
    time_limit : float, optional
        Wall-clock seconds, everything included; when reached the result has status
        ``time_limit``, the best plan found (or none, objective inf) and a proven bound.
    incumbent : FleetPlan or Solution, optional
        A feasible plan used to prune (``taopt.solve`` passes the warm-start heuristics').
    max_labels : int, optional
        Memory guard of the label search (:data:`taopt.fleet.search.DEFAULT_MAX_LABELS`): the
        run stops like a time limit (``info["stopped_by"] == "size"``).
    algorithm : {"auto", "search", "operations", "ideal_dp", "sortie_dp", "split_dp", "split"}
        Force one algorithm (``"auto"``: the fastest that applies; for measurements;
        ``"split"`` needs K >= 2).
    improve : callable, optional
        ``improve(problem, plan, time_limit) -> plan``, never worse (:func:`taopt.solve` passes
        :func:`taopt.heuristics.fleet_search.improve_fleet`, an ILS): called on the incumbent
        before the label search and the split search only (the DPs need no incumbent), with
        :data:`~taopt.models.fleet.IMPROVE_SHARE` of the time limit, at most
        :data:`~taopt.models.fleet.IMPROVE_SECONDS_PER_CUSTOMER` per customer.

    Returns
    -------
    Solution
        ``status`` "optimal" (objective == bound), "infeasible" (no plan exists) or
        "time_limit"; ``info["algorithm"]`` names the algorithm, plus its counters.
    """
    require(problem, FleetProblem, "solve_fleet")
    start = time.perf_counter()
    unservable = problem.unservable()
    if unservable:
        j = unservable[0]
        why = (
            "no truck carries a drone"
            if problem.D == 0
            else f"its nearest stop is {float(problem.flight_stop[j].min()):.6g} away, so the "
            f"shortest sortie is longer than the range {problem.flight_range:.6g}"
        )
        return finish(
            problem,
            None,
            method="exact",
            stop="infeasible",
            bound=float("inf"),
            runtime=time.perf_counter() - start,
            info={"reason": f"customer {j} is drone-only and cannot be served: {why}"},
        )
    choice = algorithm
    if choice == "auto":
        if _chapter5_shape(problem):
            choice = "ideal_dp"
        elif sorties_applies(problem):
            choice = "sortie_dp"
        elif _operations_shape(problem):
            choice = "operations"
        elif split_applies(problem):
            choice = "split_dp"
        elif search_split_applies(problem):
            choice = "split"
        else:
            choice = "search"
    if choice == "ideal_dp":
        from taopt.delivery.ideal_dp import ideal_dp

        inner = ideal_dp(problem.to_delivery(), time_limit=time_limit)
        plan = (
            FleetPlan.from_delivery_plan(inner.solution, problem.depot)
            if inner.solution is not None
            else None
        )
        info = {"algorithm": "ideal_dp", **inner.info}
        bound = inner.bound
        if plan is None:  # stopped before any plan: the sequential one, with the DP's bound
            from taopt.fleet.search import _simple_plan

            plan = _simple_plan(problem)
        return finish(
            problem,
            plan,
            method="exact",
            stop="optimal" if inner.status == "optimal" else "time_limit",
            bound=bound,
            runtime=time.perf_counter() - start,
            info=info,
        )
    if choice == "operations":
        from taopt.fleet.operations import operations_dp

        result = operations_dp(problem, time_limit=time_limit)
    elif choice == "sortie_dp":
        from taopt.fleet.bounds import fleet_lower
        from taopt.fleet.search import _simple_plan

        result = sortie_dp(problem, time_limit=time_limit, max_steps=max_labels)
        result["bound"] = result["value"]
        if result["plan"] is None:  # stopped: the incumbent (or a simple plan), a proven bound
            result["bound"] = fleet_lower(problem)
            result["plan"] = _simple_plan(problem)
            if incumbent is not None:
                result["plan"] = min(
                    (result["plan"], as_plan(incumbent)),
                    key=lambda plan: _score_or_inf(problem, plan),
                )
    elif choice == "split":
        if improve is not None:
            share = _improve_share(problem, time_limit)
            incumbent = improve(problem, incumbent, share)
        # (the one-drone relaxation is left out here: on fleet8's K2D2 rows it gave the split
        # search's own bound, 197.06 / 190.43 / 184.97, for 1-2 s of its limit)
        cover_limit = time_limit
        if time_limit is not None:
            # the root bound gets COVER_SHARE of the limit, but never more than
            # SPLIT_COVER_LEFT of what the improver left (under load the improver may run
            # late; the limit is wall-clock for every phase)
            spare = max(time_limit - (time.perf_counter() - start), 0.0)
            cover_limit = min(time_limit, SPLIT_COVER_LEFT * spare / COVER_SHARE)
        floor, incumbent = _root_cover(problem, incumbent, cover_limit)
        left = None if time_limit is None else max(time_limit - (time.perf_counter() - start), 0)
        result = split_search(
            problem, time_limit=left, incumbent=incumbent, max_labels=max_labels, floor=floor
        )
        result["root_cover_bound"] = floor
    elif choice == "split_dp":
        from taopt.fleet.search import _simple_plan

        result = split_dp(problem, time_limit=time_limit)
        candidates = [result["plan"], _simple_plan(problem)]
        if incumbent is not None:
            candidates.append(as_plan(incumbent))
        result["plan"] = min(candidates, key=lambda plan: _score_or_inf(problem, plan))
        left = None if time_limit is None else time_limit - (time.perf_counter() - start)
        if result["stopped_by"] == "gap" and (left is None or left > 0):
            # not closed by the splits (cross-truck waits): the sortie-walk bound, then the
            # label search from the split's plan for the time left; every bound is valid, so
            # the largest is kept
            floor, _ = _root_cover(problem, result["plan"], left)
            result["bound"] = max(result["bound"], floor)
            result["root_cover_bound"] = floor
            left = None if time_limit is None else time_limit - (time.perf_counter() - start)
            if _score_or_inf(problem, result["plan"]) <= floor * (1 + 1e-6):
                left = 0.0  # certified by the bound: no search
            searched = label_search(
                problem, time_limit=left, incumbent=result["plan"], max_labels=max_labels
            )
            bound = max(result["bound"], searched["bound"])
            plan = result["plan"]
            if searched["plan"] is not None:
                plan = min((plan, searched["plan"]), key=lambda p: _score_or_inf(problem, p))
            value = _score_or_inf(problem, plan)
            closed = searched["stopped_by"] == "optimal" or value <= bound * (1 + 1e-12)
            result.update(
                plan=plan,
                value=value,
                bound=min(bound, value),
                stopped_by="optimal" if closed else searched["stopped_by"],
                searched_labels=searched["labels"],
            )
    else:
        left = time_limit
        # where the wall-clock goes before the label search (info["phase_seconds"])
        phases: dict[str, float] = {}
        mark = time.perf_counter()
        if improve is not None:
            share = _improve_share(problem, time_limit)
            incumbent = improve(problem, incumbent, share)
            if time_limit is not None:
                left = max(time_limit - (time.perf_counter() - start), 0.0)
        phases["improve"] = round(time.perf_counter() - mark, 4)
        mark = time.perf_counter()
        # the one-drone relaxation first (one truck, several drones: exact in 0.7-2.7 s at
        # n = 8 and above the sortie-walk bound on all six fleet8 rows), then the sortie-walk
        # bound from it (one covering test when it cannot do better)
        relaxed = _one_drone_floor(problem, time_limit)
        phases["relaxation"] = round(time.perf_counter() - mark, 4)
        mark = time.perf_counter()
        floor, incumbent = _root_cover(problem, incumbent, time_limit, relaxed)
        floor = max(floor, relaxed)
        phases["cover"] = round(time.perf_counter() - mark, 4)
        value = _score_or_inf(problem, incumbent)
        if value <= floor * (1 + 1e-6):
            # the sortie-walk bound meets the incumbent: certified without searching
            result = {
                "plan": as_plan(incumbent),
                "value": value,
                "bound": floor,
                "stopped_by": "optimal",
                "root_cover_bound": floor,
                "one_drone_bound": relaxed,
                "phase_seconds": phases,
            }
        else:
            if time_limit is not None:
                left = max(time_limit - (time.perf_counter() - start), 0.0)
            result = label_search(
                problem, time_limit=left, incumbent=incumbent, max_labels=max_labels, floor=floor
            )
            result["root_cover_bound"] = floor
            result["one_drone_bound"] = relaxed
            result["phase_seconds"] = phases
            if result["stopped_by"] != "optimal":
                result["bound"] = min(max(result["bound"], floor), result["value"])
    info = {
        "algorithm": choice,
        **{k: v for k, v in result.items() if k not in ("plan", "value", "bound")},
    }
    stopped = result["stopped_by"]
    # the label search / operations DP stop: "optimal" (proven), "time_limit" or "size"
    stop = stopped if stopped in ("optimal", "time_limit", "size", "infeasible") else "solver_limit"
    return finish(
        problem,
        result["plan"],
        method="exact",
        stop=stop,
        bound=result["value"] if stop == "optimal" else result["bound"],
        runtime=time.perf_counter() - start,
        info=info,
    )


def _one_drone_floor(problem: FleetProblem, time_limit: float | None) -> float:
    """A lower bound from the fleet's *one-drone relaxation*: every truck k carrying D_k drones
    replaced by D_k trucks with one drone each (when some D_k >= 2, every customer is
    drone-only and :func:`taopt.fleet.sorties.split_applies` takes the relaxed fleet; else 0),
    bounded by :func:`taopt.fleet.sorties.split_dp` with at most :data:`RELAX_SHARE` of the
    limit (a stopped run's bound is still proven); used before the label search (the split
    search's parts are bounded on their own).

    Valid: from any plan, let each of truck k's drones ride its own copy of truck k, which
    drives the same stops in the same order and launches and recovers that drone's sorties at
    the same positions. The copy's earliest schedule is subject to a subset of the original
    truck's constraints (it waits only for its own drone's launches and recoveries) and to
    the same flights, ranges, capacities and precedence pairs, so every service and every
    return home is no later: the relaxed optimum is at most every plan's objective, under
    ``"last_service"`` and ``"return"`` alike. On fleet8 it lifts the one-truck rows' root
    bound, e.g. K1D2c1 367.43 -> 401.96 (the K2D1c1 optimum)."""
    from taopt.runtime import Deadline

    if max(problem.drones, default=0) < 2 or any(m != "drone" for m in problem.service):
        return 0.0
    relaxed = problem.replace(drones=[1] * sum(problem.drones))
    if not split_applies(relaxed):
        return 0.0
    deadline = Deadline(None if time_limit is None else RELAX_SHARE * time_limit)
    found = split_dp(relaxed, time_limit=deadline.remaining())
    return float(found["bound"])


def _improve_share(problem: FleetProblem, time_limit: float | None) -> float | None:
    """The improver's time: :data:`IMPROVE_SHARE` of the limit, at most
    :data:`IMPROVE_SECONDS_PER_CUSTOMER` per customer (None without a limit); when some truck
    carries two or more drones, half as much again for the interleaved-sortie search that
    follows the ILS (:func:`taopt.heuristics.fleet_search.improve_fleet` gives the ILS
    two thirds of it, the time it had alone)."""
    if time_limit is None:
        return None
    share = min(IMPROVE_SHARE * time_limit, IMPROVE_SECONDS_PER_CUSTOMER * max(problem.n, 1))
    if max(problem.drones, default=0) >= 2:
        share *= 1.5
    return share


def _root_cover(
    problem: FleetProblem, incumbent: Any, time_limit: float | None, known: float = 0.0
) -> tuple[float, Any]:
    """The root sortie-walk bound (:func:`taopt.fleet.cover.fleet_cover_bound`) between
    :func:`taopt.fleet.bounds.fleet_lower` (or ``known``, a proven bound, when larger) and the
    incumbent's value (the incumbent, or the simple sequential plan when it is better or
    missing), with at most :data:`COVER_SHARE` of the time limit; returns (bound,
    incumbent)."""
    from taopt.fleet.bounds import fleet_lower
    from taopt.fleet.cover import fleet_cover_bound
    from taopt.fleet.search import _simple_plan
    from taopt.runtime import Deadline

    candidates = [_simple_plan(problem)]
    if incumbent is not None:
        candidates.append(as_plan(incumbent))
    incumbent = min(candidates, key=lambda plan: _score_or_inf(problem, plan))
    lower = max(fleet_lower(problem, "fast"), known)
    deadline = Deadline(None if time_limit is None else COVER_SHARE * time_limit)
    value = _score_or_inf(problem, incumbent)
    bound = fleet_cover_bound(problem, lower, value, deadline, settled=known > 0.0)
    return bound, incumbent


def _affordable(problem: FleetProblem) -> bool:
    """Where the exact method typically certifies within a minute (measured, see
    docs/families/fleet.md): chapter 5's shape, the operations DP up to 12 customers (the
    geometric TSP-D's sparse DP up to 16), the
    sortie DP (one truck, one drone) up to 10, the label search up to 5 customers."""
    if _chapter5_shape(problem):
        return True
    if sorties_applies(problem):
        return problem.n <= 10
    if _operations_shape(problem):
        from taopt.fleet.tspd_dp import tspd_applies

        return problem.n <= (16 if tspd_applies(problem) else 12)
    return problem.n <= 5


register_method(
    FleetProblem,
    "exact",
    category="exact",
    warm_start=("SMMA",),
    certifies=_affordable,
    style=("-", "*"),
)(solve_fleet)

__all__ = [
    "COVER_SHARE",
    "IMPROVE_SECONDS_PER_CUSTOMER",
    "IMPROVE_SHARE",
    "RELAX_SHARE",
    "SPLIT_COVER_LEFT",
    "solve_fleet",
]
