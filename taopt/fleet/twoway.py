"""Two trucks whose cross-truck precedences go both ways: the optimum of one split, exact, by a
branch and bound over the times of the follower's cross-truck predecessors.

:func:`taopt.fleet.coupled.leader_search` is exact for a split whose cross pairs all leave one
truck. With pairs both ways it is a relaxation: a follower -> leader pair enters only through
the caller's releases. :func:`two_way_search` closes that gap.

*Boxes.* Fix the leader l and the follower f (:func:`taopt.fleet.split._lead`), and let R be
the follower's customers with a closure successor on the leader. For a plan P of the split
let ``ψ(P) = (t_r(P))_{r in R}`` (its earliest schedule). A *box* is a product of intervals
``[lo_r, hi_r]``; it holds the plans with ``ψ(P)`` inside. The root box ``[L_r, inf)`` holds
every plan of the split (``L`` the caller's releases, met by every plan of the split).

*Bound of a box.* Let ``G(box)`` be the value :func:`~taopt.fleet.coupled.leader_search`
computes with the releases ``max(L_j, lo_r)`` on the leader's j for every closure pair
(r, j), r in R (and ``lo_r`` on r itself), and the deadlines ``hi_r`` on the follower's r
(its ``due``). For a plan P in the box:

- each closure pair (r, j) has ``t_j >= t_r >= lo_r``, so P meets every release, and its
  follower meets every deadline;
- P's leader sub-plan scheduled with those releases alone (the follower's events dropped)
  has times no later than P's (a subset of P's constraints: the earliest schedule is the
  least solution), so its objective and its interface times θ' are at most P's;
- P's follower sub-plan scheduled with the releases θ(P) (the leader's times) has P's times
  (adding releases P meets leaves the least solution unchanged), which meet the deadlines:
  it is one of the plans ``h`` ranges over, so ``f(P) >= h(θ(P)) >= h(θ')`` (``h`` is
  non-decreasing in θ).

So ``f(P) >= max(f_l(P_l'), h(θ')) >= G(box)``: ``G`` bounds every plan in the box. When the
search's plan (combined and scored with every pair by :func:`taopt.fleet.evaluate.evaluate_fleet`)
reaches ``G`` (``stopped_by == "optimal"``), no plan of the box is below that plan: the box is
closed; so it is when the relaxed plan scores within :data:`taopt.fleet.split.CERTIFY` of ``G``
(the split search's tolerance; that ``G`` stays in the returned bound). Otherwise
(``"relaxed"``) the box is *split* on one r at a point m with ``lo_r < m < hi_r``:
``[lo_r, m]`` and ``[m, hi_r]`` cover it, each child's bound is at least its parent's (a
smaller box), and a child's follower solves may start from its parent's (their lower bounds
stay lower bounds: tighter deadlines and higher releases never lower ``h``).

*Split point.* Any m in the interval keeps the search exact; the choice is for speed. The
relaxation's own times (``relaxed_times``: the leader's under the box's releases, the
follower's under the leader's times) violate some pair (r, j), ``t_r > t_j`` (if none did,
those times would meet every constraint of the combined plan, which would then score no more
than ``G``). For the most violated pair, m is just below t_r (``t_r (1 -`` :data:`SPLIT_BELOW`
``)``): the lower child's deadline excludes that follower plan; in the upper child the
leader's j is released to m, so if the follower keeps its plan the pair is met up to
``t_r - m`` and every time of the combined plan is within that of the relaxation (a max-plus
schedule: delaying one release by δ delays no event by more), which closes the box within
the tolerance. Without such a pair the widest interval (capped at the best value) is halved.
On tiny two-way splits this closes in 3 boxes; the midpoint of (t_j, t_r), tried first, only
converged geometrically (thousands of boxes, bound and optimum equal to 1e-5).

*Search.* Each truck leads in turn with boxes of its own (the argument above holds for either
leader; which relaxation is tighter depends on the split: on fleet10 seed 3's open split the
second leader's root box is exact, on seed 2's the first's needs six box searches). The
leader with fewer sources (fewer pairs met only through the boxes: seed 3's exact leader has
2 against 3; seed 2's tie keeps :func:`taopt.fleet.split._lead`'s) goes first and gets
:data:`LEAD_TURNS` turns for each of the other's; either order is exact. Per
leader, best first over the boxes by their bounds; a box's leader search runs in doubling
slices (:data:`BOX_SHARE` of the time left at first; its memo kept). The split's optimum is
proven when every open box of one leader has a bound at the best plan's value (within
``CERTIFY``); at the clock, the larger of the two leaders' least open bounds is the split's
proven bound. Every plan found is scored with
every pair before it is kept.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

from taopt.errors import FeasibilityError
from taopt.fleet.problem import FleetProblem
from taopt.runtime import Deadline

INF = math.inf

#: Share of the time left that a box's first leader search may take (doubled at each retry).
BOX_SHARE = 0.25

#: Narrowest interval a box is halved on (seconds) when no violated pair says where to split.
BOX_MIN_WIDTH = 1e-3

#: Turns the first leader (the one with fewer sources, :func:`two_way_search`) gets for each
#: turn of the second.
LEAD_TURNS = 2

#: A box split at a violated pair (r, j) is split at ``t_r (1 - SPLIT_BELOW)`` (module
#: docstring, *Split point*).
SPLIT_BELOW = 1e-7


def two_way_search(
    problem: FleetProblem,
    owner: list[int],
    release: list[float] | None = None,
    time_limit: float | None = None,
    incumbent: Any = None,
    floor: float = 0.0,
    cutoff: float = INF,
    max_labels: int | None = None,
    memo: dict[str, Any] | None = None,
    leading: int | None = None,
) -> dict[str, Any]:
    """The optimum of a two-truck ``problem`` over the plans of one split (customer j served
    by truck ``owner[j]`` or its drones), cross pairs any way: the box search of the module
    docstring (exact; with pairs one way the root box's leader search is already exact).

    Parameters
    ----------
    release : list of float, optional
        Per customer a time no plan of the split serves it before (the split search's
        topological releases): the root box's lower ends and the leader's releases.
    incumbent, cutoff : optional
        A plan (scored) and a value: only plans below both are sought.
    floor : float
        A proven bound of the split (the boxes' bounds start there).
    memo : dict, optional
        Kept by the caller between runs on the same split with the same ``release`` (the
        split search's slices): the open boxes and their leader searches' memos.
    leading : int, optional
        Only this truck leads. By default both trucks lead in turn, each with its own boxes
        (:func:`taopt.fleet.split._lead`'s first): each truck's boxes bound the split, so
        the larger of their least bounds is proven and either truck's closing proves it.

    Returns
    -------
    dict
        ``plan``, ``value`` (the best plan found, scored with every pair, or the incumbent),
        ``bound`` (proven: the least open box's bound, at most ``value``), ``stopped_by``
        (``"optimal"``, ``"time_limit"``, ``"size"``), and the counters ``boxes`` (opened)
        and ``box_searches``.
    """
    from taopt.fleet.coupled import leader_of, leader_search
    from taopt.fleet.evaluate import evaluate_fleet
    from taopt.fleet.split import CERTIFY, _closure, _lead

    if problem.K != 2:
        raise ValueError("two_way_search needs two trucks")
    deadline = Deadline(time_limit)
    n = problem.n
    rel = [0.0] * n if release is None else [float(r) for r in release]
    plan_value, best_plan = INF, None
    if incumbent is not None:
        try:
            plan_value, best_plan = evaluate_fleet(problem, incumbent), incumbent
        except FeasibilityError:
            pass
    best = min(plan_value, cutoff)
    one_way = leader_of(problem, owner) is not None
    first = _lead(problem, owner)
    if one_way:
        leaders = [first]
    elif leading is not None:
        leaders = [int(leading)]
    else:
        closure = _closure(problem)
        leaders = sorted([first, 1 - first], key=lambda x: _source_count(closure, owner, x))
    memo = {} if memo is None else memo
    states: dict[int, dict[str, Any]] = memo.setdefault("leaders", {})
    for leader in leaders:
        if leader not in states:
            pairs = [
                (r, j)
                for r, j in _closure(problem)
                if owner[r] == 1 - leader and owner[j] == leader
            ]
            sources = sorted({r for r, _ in pairs})
            # box: (bound, id, lo, hi, tries); memos[id]: its leader search's memo
            states[leader] = {
                "pairs": pairs,
                "sources": sources,
                "boxes": [(floor, 0, tuple(rel[r] for r in sources), (INF,) * len(sources), 0)],
                "memos": {0: {}},
                "next": 1,
                "closed": INF,
                "searches": 0,
            }

    def least(state: dict[str, Any]) -> float:
        """A proven bound of the split from one leader's boxes."""
        return min(min((b for b, *_ in state["boxes"]), default=INF), state["closed"])

    searches = 0
    stopped_by = "optimal"
    while True:
        if any(best <= least(states[x]) * (1 + CERTIFY) for x in leaders):
            break  # one leader's boxes prove the split
        if deadline.expired():
            stopped_by = "time_limit"
            break
        # the leaders take turns (either may be the one whose boxes close first), the first
        # (fewer sources) LEAD_TURNS turns for each of the second's
        leader = min(
            leaders, key=lambda x: states[x]["searches"] * (1 if x == leaders[0] else LEAD_TURNS)
        )
        state = states[leader]
        boxes, memos = state["boxes"], state["memos"]
        pairs, sources = state["pairs"], state["sources"]
        bound, bid, lo, hi, tries = heapq.heappop(boxes)
        box_release = rel[:]
        due = [INF] * n
        for r, a, b in zip(sources, lo, hi, strict=True):
            box_release[r] = max(box_release[r], a)
            due[r] = b
        for r, j in pairs:
            box_release[j] = max(box_release[j], lo[sources.index(r)])
        left = deadline.remaining()
        if left is not None:
            left = min(left, max(1.0, BOX_SHARE * left) * 2**tries)
        found = leader_search(
            problem,
            owner,
            release=box_release,
            time_limit=left,
            floor=bound,
            cutoff=best,
            max_labels=max_labels,
            memo=memos[bid],
            leading=leader,
            due=None if one_way else due,
        )
        searches += 1
        state["searches"] += 1
        relaxed_value = INF
        for plan in (found.get("plan"), found.get("relaxed_plan")):
            if plan is None:
                continue
            try:
                scored = evaluate_fleet(problem, plan)
            except FeasibilityError:
                scored = INF
            if plan is found.get("relaxed_plan"):
                relaxed_value = scored
            if scored < plan_value:
                plan_value, best_plan = scored, plan
                best = min(best, scored)
        raised = max(bound, float(found["bound"]))
        if found["stopped_by"] == "optimal":
            memos.pop(bid, None)  # closed: no plan in it below the best
            continue
        if found["stopped_by"] in ("time_limit", "size"):
            heapq.heappush(boxes, (raised, bid, lo, hi, tries + 1))
            if found["stopped_by"] == "size":
                stopped_by = "size"
                break
            continue
        # relaxed: split the box
        if relaxed_value <= raised * (1 + CERTIFY):  # its plan is within the tolerance
            memos.pop(bid, None)
            state["closed"] = min(state["closed"], raised)
            continue
        cut = _split_point(pairs, found.get("relaxed_times"), sources, lo, hi, best)
        if cut is None:  # nowhere to split: keep the box open with its bound
            heapq.heappush(boxes, (raised, bid, lo, hi, tries + 1))
            stopped_by = "time_limit"
            break
        i, m = cut
        parent = memos.pop(bid, {})
        for a, b in ((lo[i], m), (m, hi[i])):
            child = state["next"]
            state["next"] += 1
            new_lo = lo[:i] + (a,) + lo[i + 1 :]
            new_hi = hi[:i] + (b,) + hi[i + 1 :]
            # the parent's follower lower bounds stay lower bounds in the child
            memos[child] = {"cache": list(parent.get("cache", []))}
            heapq.heappush(boxes, (raised, child, new_lo, new_hi, 0))
    proven = max(least(states[x]) for x in leaders)  # each leader's boxes bound the split
    return {
        "plan": best_plan,
        "value": plan_value,
        "bound": min(best, max(proven, floor)),
        "stopped_by": stopped_by,
        "boxes": sum(states[x]["next"] for x in leaders),
        "box_searches": searches,
        "open_boxes": sum(len(states[x]["boxes"]) for x in leaders),
    }


def _source_count(closure: list[tuple[int, int]], owner: list[int], leader: int) -> int:
    """How many follower customers have a ``closure`` successor on ``leader`` (the box
    dimensions when it leads: the pairs its relaxation meets only through the boxes)."""
    return len({r for r, j in closure if owner[r] == 1 - leader and owner[j] == leader})


def _split_point(
    pairs: list[tuple[int, int]],
    times: list[float] | None,
    sources: list[int],
    lo: tuple[float, ...],
    hi: tuple[float, ...],
    best: float,
) -> tuple[int, float] | None:
    """Where to split a box (module docstring): (index into ``sources``, point)."""
    if times is not None:
        worst = max(((times[r] - times[j], r) for r, j in pairs), default=(0.0, -1))
        if worst[0] > 0:
            r = worst[1]
            i = sources.index(r)
            m = times[r] - SPLIT_BELOW * max(1.0, abs(times[r]))
            if lo[i] < m < hi[i]:
                return i, m
    top = [min(b, best) for b in hi]
    widths = [b - a for a, b in zip(lo, top, strict=True)]
    if not widths:
        return None
    i = max(range(len(widths)), key=lambda x: widths[x])
    if not math.isfinite(widths[i]) or widths[i] < 2 * BOX_MIN_WIDTH:
        return None
    return i, lo[i] + 0.5 * widths[i]


__all__ = ["BOX_MIN_WIDTH", "BOX_SHARE", "LEAD_TURNS", "SPLIT_BELOW", "two_way_search"]
