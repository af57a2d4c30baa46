"""The coupled problem of one split: the fleet's optimum over the plans that serve each customer
by a given truck (or its drones), with the cross-truck precedences.

Three methods. :func:`coupled_dp` (below): several trucks with one drone each, drone-only
customers, a joint DP over the trucks' sortie sequences. :func:`leader_search`: two trucks,
any drones, cross pairs one way (exact: a search over the leading truck's part, the other
priced by its optimum under the leader's service times as releases) or both ways (a
relaxation, a bound, which :func:`taopt.fleet.twoway.two_way_search` makes exact by
splitting boxes of the follower's times). :func:`coupled_search`: any split, the label
search's joint states, each label also bounded by every truck's own part (exact; slower than
the leader search where that applies). Proofs in their docstrings.

:func:`taopt.fleet.sorties.split_dp` bounds each split (X_1, ..., X_K) by its trucks' parts
solved apart; where cross-truck precedences make the combined plan wait, the optimum restricted
to the split lies between that bound and the combined plan. :func:`coupled_dp` computes it.

*Shape.* One drone per truck, every customer drone-only (the split DP's shape): truck k's plan
is a sequence of sorties over X_k, each a sequence σ = (j_1, ..., j_m), m <= c, launched at a
stop w_1 and recovered at w_2 (module docstring of :mod:`taopt.fleet.sorties`). With waits,
``t_{j_1} = max(L + ft(w_1, j_1) + τ, W_{j_1})``, ``t_{j_{i+1}} = max(t_{j_i} + ft(j_i,
j_{i+1}) + τ, W_{j_{i+1}})`` and ``R' = max(t_{j_m} + ft(j_m, w_2), L + tt(w_1, w_2)) + τ``,
``L = R + tt(w, w_1)``, ``W_j`` the latest service of j's predecessors on other trucks (its own
truck's are served before, by the same drone).

*Joint states.* A label is (S, w_k, R_k per truck, the last service M, the service times of
the customers served so far that have a successor on another truck); a transition adds one
sortie of one truck whose customers' predecessors are all served (S, or earlier in σ). This
enumerates every plan of the split whose sorties can be ordered so that each comes after the
sorties serving its customers' other-truck predecessors — every plan when c = 1 and τ > 0
(order the sorties by their customer's service time: a cross pair has ``t_r <= t_j`` and a
truck's next customer is served strictly later), or when the trucks' cross pairs form no
cycle between trucks (their sorties' order relation then has none) — :func:`coupled_applies`.
Every time is non-decreasing in every other, so a label whose vector is no smaller
componentwise than another's of the same (S, stops) is dropped, and so is a recovery at w_2'
when the same launch recovers at w_2 with ``R'(w_2) + tt(w_2, w_2') <= R'(w_2')`` (the truck
could drive on; tt is a shortest-path metric).

*Bound.* ``max(M, max_k R_k + g_k(S ∩ X_k, w_k))`` with g_k the least time truck k needs from
stop w with its drone aboard to finish X_k with no waits (a backward sortie DP over the ideals
of X_k; waits only delay): a valid bound of every completion. Labels are expanded best-first;
the run stops at the first complete label (its value is the optimum), when every label is at
least ``cutoff`` (no plan below it: the bound returned is ``cutoff``), or at the limit with the
least open label's bound (proven).
"""

from __future__ import annotations

import heapq
import math
from operator import le
from typing import Any

import numpy as np

from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.fleet.search import next_flight, trace
from taopt.runtime import Deadline

INF = math.inf

#: Most labels the joint DP keeps (memory guard): it then stops like a time limit, with the
#: least open label's bound.
MAX_LABELS = 500_000


def _owner(problem: FleetProblem, split: tuple[int, ...]) -> list[int]:
    owner = [0] * problem.n
    for k, mask in enumerate(split):
        for j in range(problem.n):
            if mask >> j & 1:
                owner[j] = k
    return owner


def coupled_applies(problem: FleetProblem, split: tuple[int, ...]) -> bool:
    """The joint DP enumerates every plan of the split (module docstring): one drone per truck,
    drone-only customers, and c = 1 with τ > 0 or no cycle among the trucks' cross pairs."""
    import networkx as nx

    if any(d != 1 for d in problem.drones) or any(m != "drone" for m in problem.service):
        return False
    if problem.capacity == 1 and problem.service_time > 0:
        return True
    owner = _owner(problem, split)
    trucks = nx.DiGraph()
    trucks.add_nodes_from(range(problem.K))
    trucks.add_edges_from(
        (owner[r], owner[j]) for r, j in problem.precedences if owner[r] != owner[j]
    )
    return bool(nx.is_directed_acyclic_graph(trucks))


def coupled_dp(
    problem: FleetProblem,
    split: tuple[int, ...],
    pre: tuple[list[tuple[int, ...]], list[tuple[int, np.ndarray, np.ndarray]]],
    closure: Any,
    time_limit: float | None = None,
    cutoff: float = INF,
    order: Any = None,
    release: Any = None,
) -> dict[str, Any]:
    """Optimum of ``problem`` restricted to ``split`` (one mask per truck; module docstring),
    ``pre`` the split DP's sequences and cost tables (:func:`taopt.fleet.sorties._table`),
    ``closure`` G^p's transitive closure pairs. ``order`` (a permutation of the trucks): only
    the cross pairs from an earlier to a later truck of it are kept (a relaxation of the
    split, whose trucks then form no cycle, so the DP is exact for it: its optimum is a lower
    bound on the split's, and its plan may violate a dropped pair). ``release``: per customer
    a time no plan of the split serves it before (added as a wait; valid, so the optimum is
    unchanged and the relaxation only tighter). Returns ``plan`` (None when none below
    ``cutoff`` was found), ``value`` (the DP's), ``bound`` (proven; ``cutoff`` when no plan
    below it exists) and ``stopped_by`` ("optimal", "time_limit", "size": :data:`MAX_LABELS`)."""
    deadline = Deadline(time_limit)
    n, s, K = problem.n, problem.s, problem.K
    ret = problem.objective == "return"
    tau, v, limit, depot = (
        problem.service_time,
        problem.v_drone,
        problem.flight_limit,
        problem.depot,
    )
    tt = np.asarray(problem.truck_time, dtype=float)
    fst = problem.flight_stop / v
    fsd = problem.flight_stop
    fct = problem.flight_customer / v
    fcd = problem.flight_customer
    owner = _owner(problem, split)
    seqs, table = pre
    rank = list(range(K)) if order is None else [list(order).index(k) for k in range(K)]
    preds = [0] * n  # closure predecessors enforced (any truck)
    cross: list[list[int]] = [[] for _ in range(n)]
    within = [0] * n  # closure predecessors on the same truck
    for r, j in closure:
        if owner[r] == owner[j]:
            within[j] |= 1 << r
            preds[j] |= 1 << r
        elif order is None or rank[owner[r]] < rank[owner[j]]:
            preds[j] |= 1 << r
            cross[j].append(r)
    floor = [0.0] * n if release is None else [float(x) for x in release]
    needed = sorted({r for j in range(n) for r in cross[j]})
    pos = {r: i for i, r in enumerate(needed)}
    mine: list[list[int]] = [[] for _ in range(K)]
    for q, (mask, _, _) in enumerate(table):
        k = owner[seqs[q][0]]
        if mask & ~split[k] == 0:
            mine[k].append(q)
    geo: dict[int, tuple[np.ndarray, np.ndarray, float]] = {}

    def geometry(q: int) -> tuple[np.ndarray, np.ndarray, float]:
        got = geo.get(q)
        if got is None:
            seq = seqs[q]
            inner = sum(float(fcd[seq[i], seq[i + 1]]) for i in range(len(seq) - 1))
            ok = (fsd[seq[0]] + inner)[:, None] + fsd[seq[-1]][None, :] <= limit
            got = geo[q] = (ok, ok.any(axis=1), inner)
        return got

    # g_k(S, w): least time from w (drone aboard) to finish X_k without waits
    memo: list[dict[int, np.ndarray]] = [{} for _ in range(K)]

    def g(k: int, S: int) -> np.ndarray:
        got = memo[k].get(S)
        if got is not None:
            return got
        full = split[k]
        if S == full:
            out = tt[:, depot].copy() if ret else np.zeros(s)
        else:
            out = np.full(s, INF)
            for q in mine[k]:
                mask, cost, final_cost = table[q]
                if mask & S or any(within[j] & ~(S | mask) for j in seqs[q]):
                    continue
                if S | mask == full and not ret:
                    out = np.minimum(out, final_cost)
                else:
                    out = np.minimum(out, np.min(cost + g(k, S | mask)[None, :], axis=1))
        memo[k][S] = out
        return out

    def lower(S: int, ws: tuple, Rs: tuple, M: float) -> float:
        b = M
        for k in range(K):
            if ws[k] < 0:
                continue
            x = Rs[k] + float(g(k, S & split[k])[ws[k]])
            if x > b:
                b = x
        return b

    start_ws = tuple(-1 if (not ret and split[k] == 0) else depot for k in range(K))
    root = (0, start_ws, (0.0,) * K, 0.0, (0.0,) * len(needed))
    labels: list[tuple] = [root]
    parent = [-1]
    action: list[Any] = [None]
    dead = bytearray(1)
    store: dict[tuple, list[tuple[tuple, int]]] = {
        (0, start_ws): [((0.0,) * (K + 1 + len(needed)), 0)]
    }
    best = cutoff
    heap = [(lower(0, start_ws, root[2], 0.0), 0, 0)]
    full_mask = sum(split)
    stopped_by = "optimal"
    found = -1
    expanded = 0
    while heap:
        lb, _, i = heapq.heappop(heap)
        if dead[i]:
            continue
        if lb >= best * (1 - 1e-12):
            heap.clear()
            break
        if deadline.expired():
            heapq.heappush(heap, (lb, 0, i))
            stopped_by = "time_limit"
            break
        S, ws, Rs, M, tvec = labels[i]
        if S == full_mask:
            found, best = i, lb
            break
        if len(labels) > MAX_LABELS:
            heapq.heappush(heap, (lb, 0, i))
            stopped_by = "size"
            break
        expanded += 1
        for k in range(K):
            if ws[k] < 0 or (ret and S & split[k] == split[k]):
                continue
            w, R = ws[k], Rs[k]
            L = R + tt[w]
            others = M
            for k2 in range(K):
                if k2 != k and ws[k2] >= 0:
                    x = Rs[k2] + float(g(k2, S & split[k2])[ws[k2]])
                    if x > others:
                        others = x
            for q in mine[k]:
                mask = table[q][0]
                if mask & S:
                    continue
                seq = seqs[q]
                if any(preds[j] & ~(S | mask) or within[j] & ~(S | mask) for j in seq):
                    continue
                ok, ok_any, _ = geometry(q)
                t: np.ndarray = L + fst[seq[0]] + tau
                crit: list[np.ndarray] = []
                prev = -1
                for j in seq:
                    wait = max((tvec[pos[r]] for r in cross[j]), default=floor[j])
                    if floor[j] > wait:
                        wait = floor[j]
                    if prev >= 0:
                        t = t + float(fct[prev, j]) + tau
                    if wait > 0:
                        t = np.maximum(t, wait)
                    if j in pos:
                        crit.append(t)
                    prev = j
                last = seq[-1]
                Mp = np.maximum(t, M)
                done = (S | mask) & split[k] == split[k]
                S2 = S | mask
                if done and not ret:
                    keep = ok_any & (np.maximum(Mp, others) < best * (1 - 1e-12))
                    cols = np.flatnonzero(keep)
                    if cols.size == 0:
                        continue
                    vecs = np.stack([Mp[cols], *[c[cols] for c in crit]], axis=1)
                    for a in _pareto(vecs):
                        w1 = int(cols[a])
                        nws = ws[:k] + (-1,) + ws[k + 1 :]
                        nRs = Rs[:k] + (0.0,) + Rs[k + 1 :]
                        ntv = list(tvec)
                        for j, c in zip([j for j in seq if j in pos], crit, strict=True):
                            ntv[pos[j]] = float(c[w1])
                        child = (S2, nws, nRs, float(Mp[w1]), tuple(ntv))
                        _push(
                            child,
                            (k, q, w1, -1),
                            i,
                            labels,
                            parent,
                            action,
                            dead,
                            store,
                            heap,
                            lower,
                            best,
                        )
                    continue
                Rp = np.maximum(t[:, None] + fst[last][None, :], L[:, None] + tt) + tau
                Rp = np.where(ok, Rp, INF)
                gnext = g(k, S2 & split[k])
                lbm = np.maximum(Rp + gnext[None, :], np.maximum(Mp, others)[:, None])
                live = lbm < best * (1 - 1e-12)
                if not live.any():
                    continue
                rows = np.flatnonzero(live.any(axis=1))
                cols = np.flatnonzero(live.any(axis=0))
                sub = Rp[np.ix_(rows, cols)]
                sub = np.where(live[np.ix_(rows, cols)], sub, INF)
                # metric dominance across recovery stops, per launch stop
                via = sub[:, :, None] + tt[np.ix_(cols, cols)][None, :, :]  # (w1, w2, w2')
                idx = np.arange(len(cols))
                better = (via < sub[:, None, :]) | (
                    (via == sub[:, None, :]) & (idx[:, None] < idx[None, :])[None, :, :]
                )
                better &= ~np.eye(len(cols), dtype=bool)[None, :, :]
                metric_dead = better.any(axis=1)  # (w1, w2')
                extra = np.stack([Mp[rows], *[c[rows] for c in crit]], axis=1)
                for b, w2 in enumerate(cols):
                    col = sub[:, b]
                    alive = np.flatnonzero(np.isfinite(col) & ~metric_dead[:, b])
                    if alive.size == 0:
                        continue
                    vecs = np.concatenate([col[alive][:, None], extra[alive]], axis=1)
                    for a in _pareto(vecs):
                        r_i = int(alive[a])
                        w1 = int(rows[r_i])
                        nws = ws[:k] + (int(w2),) + ws[k + 1 :]
                        nRs = Rs[:k] + (float(col[r_i]),) + Rs[k + 1 :]
                        ntv = list(tvec)
                        for j, c in zip([j for j in seq if j in pos], crit, strict=True):
                            ntv[pos[j]] = float(c[w1])
                        child = (S2, nws, nRs, float(Mp[w1]) if not ret else 0.0, tuple(ntv))
                        _push(
                            child,
                            (k, q, w1, int(w2)),
                            i,
                            labels,
                            parent,
                            action,
                            dead,
                            store,
                            heap,
                            lower,
                            best,
                        )
    bound = best
    if stopped_by != "optimal":
        bound = min([b for b, _, j in heap if not dead[j]] + [best])
    result: dict[str, Any] = {
        "plan": None,
        "value": INF,
        "bound": bound,
        "stopped_by": stopped_by,
        "labels": len(labels),
        "expanded": expanded,
    }
    if found >= 0:
        acts = trace(parent, action, found)
        result["plan"] = _rebuild(problem, seqs, acts, geometry)
        result["value"] = best
    return result


def _pareto(vecs: np.ndarray) -> list[int]:
    """Rows of ``vecs`` no other row is <= in every column (ties: the first kept)."""
    order = np.lexsort(vecs.T[::-1])
    kept: list[int] = []
    for a in order:
        row = vecs[a]
        if any(bool(np.all(vecs[b] <= row)) for b in kept):
            continue
        kept.append(int(a))
    return kept


def _push(
    child: tuple,
    act: Any,
    i: int,
    labels: list,
    parent: list,
    action: list,
    dead: bytearray,
    store: dict,
    heap: list,
    lower: Any,
    best: float,
) -> None:
    S, ws, Rs, M, tvec = child
    b = lower(S, ws, Rs, M)
    if b >= best * (1 - 1e-12):
        return
    key = (S, ws)
    vec = Rs + (M,) + tvec
    bucket = store.get(key)
    if bucket is None:
        bucket = store[key] = []
    for other, _ in bucket:
        if all(x <= y for x, y in zip(other, vec, strict=True)):
            return
    keep = []
    for other, oid in bucket:
        if all(x <= y for x, y in zip(vec, other, strict=True)):
            dead[oid] = 1
        else:
            keep.append((other, oid))
    cid = len(labels)
    keep.append((vec, cid))
    bucket[:] = keep
    labels.append(child)
    parent.append(i)
    action.append(act)
    dead.append(0)
    heapq.heappush(heap, (b, -S.bit_count(), cid))


class _Labels:
    """The labels of one best-first label search of :func:`coupled_search` or
    :func:`leader_search` (as in :func:`taopt.fleet.search.label_search`): each label's
    parent and action (for :func:`taopt.fleet.search.trace`), a dead flag, and the
    dominance store: per discrete key the metric vectors kept, a vector dominated when
    another of its key is no larger everywhere. A new label that dominates kept ones marks
    them dead; the search skips dead labels when they are popped."""

    def __init__(self, root: tuple, key: tuple, vec: tuple) -> None:
        self.labels: list[tuple] = [root]
        self.parent: list[int] = [-1]
        self.action: list[Any] = [None]
        self.dead = bytearray(1)
        self.store: dict[tuple, list[tuple[tuple, int]]] = {key: [(vec, 0)]}

    def dominated(self, key: tuple, vec: tuple) -> bool:
        """Whether a kept label of the same key is no larger than ``vec`` everywhere."""
        bucket = self.store.get(key)
        return bucket is not None and any(all(map(le, other, vec)) for other, _ in bucket)

    def add(self, child: tuple, act: Any, parent: int, key: tuple, vec: tuple) -> int:
        """Keep ``child`` (not dominated, :meth:`dominated`), mark the kept labels it
        dominates dead; returns its index."""
        bucket = self.store.get(key)
        if bucket is not None:
            keep = []
            for other, oid in bucket:
                if all(map(le, vec, other)):
                    self.dead[oid] = 1
                else:
                    keep.append((other, oid))
            bucket[:] = keep
        else:
            bucket = self.store[key] = []
        cid = len(self.labels)
        self.labels.append(child)
        self.parent.append(parent)
        self.action.append(act)
        self.dead.append(0)
        bucket.append((vec, cid))
        return cid


def _rebuild(
    problem: FleetProblem, seqs: list[tuple[int, ...]], acts: list[Any], geometry: Any
) -> FleetPlan:
    """The plan of the actions (truck, sequence, launch stop, recovery stop or -1)."""
    routes = [[problem.depot] for _ in range(problem.K)]
    sorties: list[list[Sortie]] = [[] for _ in range(problem.K)]
    for k, q, w1, w2 in acts:
        route = routes[k]
        if route[-1] != w1:
            route.append(w1)
        launch = len(route) - 1
        if w2 < 0:  # the last sortie under last_service: any recovery in range
            ok = geometry(q)[0]
            w2 = w1 if ok[w1, w1] else int(np.flatnonzero(ok[w1])[0])
        if route[-1] != w2:
            route.append(w2)
        sorties[k].append(Sortie(launch, seqs[q], len(route) - 1))
    return FleetPlan(routes, [[] for _ in range(problem.K)], [[sorts] for sorts in sorties])


def _project(label: tuple, k: int, index: dict[int, int], members: list[int]) -> tuple:
    """Truck k's part of a coupled label, in its part's numbering (:func:`coupled_search`):
    the customers served among ``members``, their times, the label's last service and truck
    k's state alone, every airborne drone made *fresh* (free to take any customer in range
    next: a relaxation, the argument in :func:`coupled_search`)."""
    S, M, svc, trucks = label
    S_k = 0
    seen_of: dict[int, int] = {}
    for i, j in enumerate(members):
        if S >> j & 1:
            S_k |= 1 << i
    w, A, T, ev, fin, F, drones = trucks[k]
    out = []
    for dr in drones:
        if dr[0] != 1:
            out.append(dr)
            continue
        o = dr[1]
        if o >= 0:
            o = index[o]
        seen = seen_of.get(dr[7])
        if seen is None:
            seen = seen_of[dr[7]] = sum(1 << i for i, j in enumerate(members) if dr[7] >> j & 1)
        out.append((1, o, dr[2], dr[3], dr[4], dr[5], True, seen))
    return (S_k, M, tuple(svc[j] for j in members), ((w, A, T, ev, fin, F, tuple(out)),))


def _airborne(tab: Any, S: int, trucks: tuple) -> list[float]:
    """Per customer, the least time an airborne drone with room (of an unfinished truck) can
    serve it next, every such drone allowed any unserved customer within range (more than
    the label search's append rule allows: a lower bound), ``inf`` where none can: the
    ``air`` argument of :func:`taopt.fleet.search._earliest_services`."""
    air = [INF] * tab.n
    c, tau = tab.c, tab.tau
    for _w, _A, _T, _ev, fin, _F, drones in trucks:
        if fin:
            continue
        for dr in drones:
            if not (dr[0] == 1 and dr[5] and dr[2] < c):
                continue
            for j in range(tab.n):
                if S >> j & 1 or not tab.drone_ok[j]:
                    continue
                fly = next_flight(tab, dr, j)
                if fly is not None:
                    v = dr[3] + fly + tau
                    if v < air[j]:
                        air[j] = v
    return air


def coupled_search(
    problem: FleetProblem,
    owner: list[int],
    release: list[float] | None = None,
    time_limit: float | None = None,
    incumbent: Any = None,
    floor: float = 0.0,
    cutoff: float = INF,
    max_labels: int | None = None,
    due: list[float] | None = None,
) -> dict[str, Any]:
    """The optimum of ``problem`` over the plans of one split (customer j served by truck
    ``owner[j]`` or its drones), any drones per truck: the label search of
    :func:`taopt.fleet.search.label_search` over the trucks' joint states, each label also
    bounded by every truck's *own part* (proof below).

    ``release``: per customer a time no plan of the split serves it before (for example the
    split search's topological releases, :func:`taopt.fleet.split._split_releases`); added as
    releases they remove no plan of the split (each plan's earliest schedule meets them
    already), so the optimum is unchanged, and they strengthen every bound.

    *Per-truck bound.* Let λ be a label of the joint search and P a completion of λ (a plan of
    the split whose first actions are λ's). Restrict P to truck k: its route, its drones'
    sorties and its truck services, all over X_k = {j : owner[j] = k}. That is a plan of
    :func:`taopt.fleet.split.sub_problem` (truck k alone with its D_k drones serving exactly
    X_k, the closure pairs inside X_k) with the releases added: it meets every pair kept (P
    does) and every release (P's times are at least them). The sub-problem's earliest
    schedule of the same actions is no later than P's (it has a subset of P's constraints),
    so the sub-problem's objective of that plan, and of every completion of λ's projection
    (:func:`_project`: truck k's state and the services among X_k, the times λ fixed), is at
    most P's objective restricted to X_k, which is at most P's. The projection makes every
    airborne drone *fresh*: it may take any customer in range next, which only adds
    completions (the canonical-append rule of :func:`taopt.fleet.search._appendable` loses no
    plan's times, so the projected completion's times are reached by some sequence the
    sub-problem's search allows). The label search's bound of the projection (a valid lower
    bound on its completions in the sub-problem, :func:`taopt.fleet.search._bound`) is then
    at most ``f(P)``; so is the joint label's own bound and the maximum of them all. Trucks
    are not interchangeable here (``owner``), as with ``truck_of``.

    ``due``: per customer a time by which it must be served (``inf``: none); the search is
    then over the plans of the split whose earliest schedule meets them (the deadlines of
    :func:`taopt.fleet.twoway.two_way_search`'s boxes). A label's service times are final
    (its earliest schedule's), so a child serving j after ``due[j]`` has no such completion
    and is dropped; so is a label with an unserved j whose earliest service
    (:func:`taopt.fleet.search._earliest_services`, with every airborne drone allowed any
    customer in range: :func:`_airborne`) is after ``due[j]``: a lower bound of t_j in each
    completion. Dominance keeps its proof: a completion of a dominated label is matched by
    one of the dominating label whose every later event is no later, so it meets the
    deadlines too. The per-truck bound holds as above (a plan meeting the deadlines is a
    plan). ``incumbent`` is then only a cutoff (the caller's).

    Returns the dict of :func:`taopt.fleet.search.label_search` (``plan``, ``value``,
    ``bound``, ``stopped_by``, ``labels``, ``expanded``; with a plan found, its service times
    under the releases, ``times``): ``"optimal"`` when the optimum over
    the split's plans is proven (the value; or, with no plan below ``cutoff``, the bound
    ``min(cutoff, incumbent)``), else the least open label's bound (proven)."""
    from taopt.errors import FeasibilityError, SolverError
    from taopt.fleet.evaluate import evaluate_fleet
    from taopt.fleet.search import (
        DEFAULT_MAX_LABELS,
        _bound,
        _children,
        _complete,
        _earliest_services,
        _rebuild,
        _signature,
        _Tables,
    )
    from taopt.fleet.split import _closure, sub_problem

    deadline = Deadline(time_limit)
    cap = DEFAULT_MAX_LABELS if max_labels is None else int(max_labels)
    n = problem.n
    rel = [0.0] * n if release is None else [float(r) for r in release]
    tab = _Tables(problem)
    tab.owner = [int(k) for k in owner]
    tab.groups = [[k] for k in range(problem.K)]
    tab.release = rel
    closure = _closure(problem)
    parts = []
    for k in range(problem.K if problem.K > 1 else 0):  # one truck: its part is the problem
        members = [j for j in range(n) if owner[j] == k]
        if not members:
            continue
        sub_tab = _Tables(sub_problem(problem, members, problem.drones[k], closure))
        sub_tab.release = [rel[j] for j in members]
        parts.append((k, sub_tab, {j: i for i, j in enumerate(members)}, members))

    dues = [] if due is None else [(j, float(d) + 1e-9) for j, d in enumerate(due) if d < INF]

    def late(label: tuple) -> bool:
        """Whether a deadline is missed: by a service, or by an unserved customer's
        earliest service (``due``)."""
        S, _M, svc, trucks = label
        if any(S >> j & 1 and svc[j] > d for j, d in dues):
            return True
        if all(S >> j & 1 for j, _ in dues):
            return False
        est = _earliest_services(tab, S, svc, trucks, _airborne(tab, S, trucks))
        return any(est[j] > d for j, d in dues)

    def bound(label: tuple, cut: float) -> float:
        if dues and late(label):
            return INF
        b = _bound(tab, label, cut)
        for k, sub_tab, index, members in parts:
            if b >= cut:
                return b
            v = _bound(sub_tab, _project(label, k, index, members), cut)
            if v > b:
                b = v
        return b

    best_plan: Any = None
    best = INF
    if incumbent is not None:
        try:
            best, best_plan = evaluate_fleet(problem, incumbent), incumbent
        except FeasibilityError:
            pass
    planned = best
    best = min(best, cutoff)
    root_trucks = tuple(
        (problem.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d)))
        for d in problem.drones
    )
    root = (0, 0.0, (-1.0,) * n, root_trucks)
    kept = _Labels(root, *_signature(tab, root))
    labels, dead = kept.labels, kept.dead
    slack = 1e-12
    cut = best * (1 - slack)
    heap: list[tuple[float, int, int]] = [(max(bound(root, cut), floor), 0, 0)]
    expanded = 0
    stopped_by = "optimal"
    found = -1
    while heap:
        lb, _, i = heapq.heappop(heap)
        if dead[i]:
            continue
        if lb >= cut:
            heap.clear()
            break
        if deadline.expired():
            heapq.heappush(heap, (lb, 0, i))
            stopped_by = "time_limit"
            break
        label = labels[i]
        if _complete(tab, label):
            found = i
            best = lb
            break
        expanded += 1
        for child, act in _children(tab, label):
            key, vec = _signature(tab, child)
            if kept.dominated(key, vec):
                continue
            b = max(bound(child, cut), lb, floor)
            if b >= cut:
                continue
            cid = kept.add(child, act, i, key, vec)
            heapq.heappush(heap, (b, -bin(child[0]).count("1"), cid))
        if len(labels) > cap:
            stopped_by = "size"
            break
    result: dict[str, Any] = {"labels": len(labels), "expanded": expanded, "stopped_by": stopped_by}
    value = planned
    if found >= 0:
        plan = _rebuild(problem, tab, trace(kept.parent, kept.action, found), labels[found])
        # the search's value (with the releases); the scorer, which has none, may only say less
        scored = evaluate_fleet(problem, plan)
        if scored > lb * (1 + 1e-9) + 1e-9:
            raise SolverError(
                f"coupled search: the plan found scores {scored!r} above the search's {lb!r}"
            )
        result.update(plan=plan, value=lb, bound=lb, times=list(labels[found][2]))
        return result
    bound_value = best
    if stopped_by != "optimal":
        live = [b for b, _, j in heap if not dead[j]]
        bound_value = min(min(live, default=best), best)
    result.update(plan=best_plan, value=value, bound=bound_value)
    return result


#: Grid (seconds) to which :func:`leader_search` rounds the leader's interface times down
#: before pricing the follower at them (fewer follower solves; rounding down keeps the bound).
LEADER_GRID = 2.0


def leader_of(problem: FleetProblem, owner: list[int]) -> int | None:
    """Two trucks whose cross-truck closure pairs all go one way: the truck they leave (the
    *leader*, which never waits for the other), else None (:func:`leader_search`)."""
    from taopt.fleet.split import _closure

    if problem.K != 2:
        return None
    ways = {owner[r] for r, j in _closure(problem) if owner[r] != owner[j]}
    return ways.pop() if len(ways) == 1 else None


def leader_search(
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
    due: list[float] | None = None,
) -> dict[str, Any]:
    """The optimum of a two-truck ``problem`` over the plans of one split (customer j served
    by truck ``owner[j]`` or its drones) whose cross-truck precedences all go from one truck,
    the *leader* (:func:`leader_of`), to the other, the *follower*; any drones per truck.
    With pairs both ways, a bound of it (*Both ways* below).

    A label search over the leader's part alone, each leader label priced also by the
    follower's optimum at the leader's interface times (a follower solve, cached).

    *Decomposition.* Let ``X_l``, ``X_f`` be the two parts, ``I`` the leader's customers with
    a closure successor in ``X_f`` and, for a vector θ over I, ``h(θ)`` the optimum of the
    follower's part (:func:`taopt.fleet.split.sub_problem`) with the releases
    ``max(release_j, θ_r for closure pairs (r, j), r in I)``. In a plan P of the split no
    leader event waits for a follower event (no pair goes that way), so the leader's times are
    those of its own sub-plan P_l alone (with ``release``: every plan of the split meets it,
    so it changes no earliest schedule). The follower's sub-plan P_f is then scheduled with
    every cross pair (r, j) as ``t_j >= t_r``: exactly the follower's part with the releases
    θ(P_l) (the leader's times on I; again ``release`` changes nothing). So
    ``f(P) = max(f_l(P_l), f_f(P_f; θ(P_l)))`` and, over the follower's sub-plans,
    ``min f(P) = max(f_l(P_l), h(θ(P_l)))``. The split's optimum is the least of that over the
    leader's plans.

    *Monotone.* Raising a release never lowers the follower's optimum (each plan's earliest
    schedule is a maximum of sums of nonnegative terms and the releases), so ``h`` is
    non-decreasing in every component. For a leader label λ and each r in I, ``e_r(λ)``,
    its service time when λ served it, else the least time λ's truck and drones can serve it
    (:func:`taopt.fleet.search._earliest_services`, with the airborne drones allowed any
    customer in range), is at most r's time in every completion; so every completion of λ
    costs at least ``max(b_l(λ), h(e(λ)))``, ``b_l`` the label search's bound of λ in the
    leader's part (:func:`taopt.fleet.search._bound`). The search prices labels with the
    largest cached follower value at a point ``<= e(λ)`` (a lower bound of ``h(e(λ))``); a
    label popped with a price below the cutoff has the follower solved at ``e(λ)`` rounded
    down to :data:`LEADER_GRID` (still ``<= e(λ)``; its own point when λ is complete) and is
    pushed back when its price rose. The follower is solved by :func:`coupled_search` (its
    optimum under the releases; the label search's incumbents are priced without them, so
    its value may be only a bound), and not at all for an incomplete label when a point
    ``>= e(λ)`` solved exactly has ``h`` at most the label's price (h there is no larger:
    the price could not rise). A complete label popped at its exact price is optimal:
    every other label's price is a lower bound of its completions. Dominance compares the
    leader labels as the label search does, with the interface times added to the compared
    times (a label later on I is no better for the follower).

    *Both ways* (no leader: :func:`leader_of` is None). The truck with more cross pairs
    leaving it leads, and the same search is a relaxation: a follower -> leader pair is kept
    only through ``release`` (the caller's lower bounds of those times, e.g. the topological
    releases). In a plan P of the split, the leader's sub-plan under ``release`` alone has
    times no later than P's (fewer constraints), so its objective and its interface times θ'
    are at most P's, and the follower's part of P meets the releases ``max(release, θ')``
    (its times are at least those of P's leader events), so ``f(P) >= max(f_l(P_l; release),
    h(θ'))``: the least of that over the leader's plans, what the search computes, bounds
    the split's optimum. When the plan it ends on scores that value (``evaluate``, with every
    pair) it is the optimum; else the run ends with ``stopped_by == "relaxed"``, that value as
    ``bound`` and the plan as a candidate (kept when it scores below the incumbent).

    ``leading``: with pairs both ways, the truck that leads the relaxation (default: the one
    with more cross pairs leaving it); ignored when the pairs go one way.

    ``due``: per follower customer a time by which it must be served (``inf``: none), passed
    to each follower solve (:func:`coupled_search`'s ``due``): ``h`` is then the follower's
    optimum over its plans meeting them, still non-decreasing in the releases, and the search
    is over the split's plans whose follower meets them (every argument above holds with
    those plans; :func:`taopt.fleet.twoway.two_way_search`'s boxes). A relaxed run also
    returns its plan as ``relaxed_plan`` and its service times (the leader's under
    ``release``, the follower's under the leader's times) as ``relaxed_times``.

    ``memo``: a dict kept by the caller between runs on the same split with the same
    ``release`` and a cutoff that never rises (the split search's slices): the follower
    solves are kept there and reused (each cached value stays a lower bound of h, and an
    exact one stays exact).

    Returns the dict of :func:`taopt.fleet.search.label_search` (``plan``, ``value``,
    ``bound``, ``stopped_by``) with the counters ``labels``, ``expanded`` and
    ``follower_solves``."""
    from taopt.errors import FeasibilityError
    from taopt.fleet.evaluate import evaluate_fleet
    from taopt.fleet.search import (
        DEFAULT_MAX_LABELS,
        _bound,
        _children,
        _complete,
        _earliest_services,
        _signature,
        _Tables,
    )
    from taopt.fleet.search import _rebuild as rebuild_label
    from taopt.fleet.split import _closure, _lift, sub_problem

    if problem.K != 2:
        raise ValueError("leader_search needs two trucks")
    leader = leader_of(problem, owner)
    one_way = leader is not None
    if leader is None:  # both ways (or none): the relaxation, led by the truck with more
        ways = [0, 0]
        for r, j in _closure(problem):
            if owner[r] != owner[j]:
                ways[owner[r]] += 1
        leader = (0 if ways[0] >= ways[1] else 1) if leading is None else int(leading)
    follower = 1 - leader
    deadline = Deadline(time_limit)
    cap = DEFAULT_MAX_LABELS if max_labels is None else int(max_labels)
    n = problem.n
    rel = [0.0] * n if release is None else [float(r) for r in release]
    closure = _closure(problem)
    lead = [j for j in range(n) if owner[j] == leader]
    foll = [j for j in range(n) if owner[j] == follower]
    li = {j: i for i, j in enumerate(lead)}
    sub_l = sub_problem(problem, lead, problem.drones[leader], closure)
    sub_f = sub_problem(problem, foll, problem.drones[follower], closure)
    tab = _Tables(sub_l)
    tab.release = [rel[j] for j in lead]
    cross = [(r, j) for r, j in closure if owner[r] == leader and owner[j] == follower]
    inter = sorted({r for r, _ in cross})
    inter_l = [li[r] for r in inter]  # in the leader's numbering
    succ_of = {r: [foll.index(j) for rr, j in cross if rr == r] for r in inter}
    base_f = [rel[j] for j in foll]
    due_f = None if due is None else [float(due[j]) for j in foll]

    best_plan: Any = None
    best = INF
    if incumbent is not None:
        try:
            best, best_plan = evaluate_fleet(problem, incumbent), incumbent
        except FeasibilityError:
            pass
    planned = best
    best = min(best, cutoff)
    cut = best * (1 - 1e-12)
    memo = {} if memo is None else memo
    # (θ, a lower bound of h(θ)); θ -> (h(θ) or >= the cutoff then, plan, its times);
    # points solved once without an exact answer
    cache: list[tuple[tuple[float, ...], float]] = memo.setdefault("cache", [])
    exact: dict[tuple[float, ...], tuple[float, Any, Any]] = memo.setdefault("exact", {})
    tried: set[tuple[float, ...]] = memo.setdefault("tried", set())
    solves = 0

    def h_low(theta: tuple[float, ...]) -> float:
        v = 0.0
        for point, value in cache:
            if value > v and all(map(le, point, theta)):
                v = value
        return v

    def solve(theta: tuple[float, ...], limit: float | None) -> float:
        """h(θ) with its plan (:func:`coupled_search`, which takes no incumbent priced
        without the releases), or a lower bound of it (cut when no follower plan is below
        it, the bound of a stopped solve), cached."""
        nonlocal solves
        releases = base_f[:]
        for r, t in zip(inter, theta, strict=True):
            for i in succ_of[r]:
                if t > releases[i]:
                    releases[i] = t
        solves += 1
        found = coupled_search(
            sub_f,
            [0] * len(foll),
            release=releases,
            time_limit=limit,
            floor=h_low(theta),
            cutoff=best,
            due=due_f,
        )
        if found["stopped_by"] == "optimal":
            if found["plan"] is not None and found["value"] < best:
                value = float(found["value"])
                exact[theta] = (value, found["plan"], found.get("times"))
            else:
                value = best
                exact[theta] = (value, None, None)
        else:
            value = float(found["bound"])
        cache.append((theta, value))
        return value

    def known_below(theta: tuple[float, ...], price: float) -> bool:
        """Whether some point solved exactly at or above θ has ``h <= price`` (then
        ``h(θ) <= price`` by monotonicity: solving at θ cannot raise the label's price)."""
        return any(
            value[0] <= price and all(map(le, theta, point)) for point, value in exact.items()
        )

    def interface(label: tuple) -> tuple[float, ...]:
        S, _M, svc, trucks = label
        if all(S >> i & 1 for i in inter_l):
            return tuple(svc[i] for i in inter_l)
        est = _earliest_services(tab, S, svc, trucks, _airborne(tab, S, trucks))
        return tuple(
            svc[i]
            if S >> i & 1
            else (math.floor(est[i] / LEADER_GRID) * LEADER_GRID if est[i] < INF else INF)
            for i in inter_l
        )

    def price(label: tuple, theta: tuple[float, ...]) -> float:
        if INF in theta:
            return INF  # an interface customer it can no longer serve
        b = _bound(tab, label, cut)
        if b >= cut:
            return b
        return max(b, h_low(theta))

    def signature(label: tuple) -> tuple[tuple, tuple]:
        key, vec = _signature(tab, label)
        svc = label[2]
        return key, vec + tuple(svc[i] for i in inter_l)

    if not cache:
        solve(tuple(rel[r] for r in inter), deadline.remaining())
    root_trucks = ((sub_l.depot, 0.0, 0.0, True, False, 0.0, ((0, 0.0),) * sub_l.drones[0]),)
    root = (0, 0.0, (-1.0,) * tab.n, root_trucks)
    kept = _Labels(root, *signature(root))
    labels, dead = kept.labels, kept.dead
    thetas: list[tuple[float, ...]] = [interface(root)]
    heap: list[tuple[float, int, int]] = [(max(price(root, thetas[0]), floor), 0, 0)]
    expanded = 0
    stopped_by = "optimal"
    found = -1
    while heap:
        lb, _, i = heapq.heappop(heap)
        if dead[i]:
            continue
        if lb >= cut:
            heap.clear()
            break
        if deadline.expired():
            heapq.heappush(heap, (lb, 0, i))
            stopped_by = "time_limit"
            break
        label, theta = labels[i], thetas[i]
        done = _complete(tab, label)
        if theta not in exact and (done or theta not in tried):
            tried.add(theta)
            left = deadline.remaining()
            if done or not known_below(theta, lb):
                solve(theta, left if done or left is None else min(left, max(1.0, 0.1 * left)))
            now = max(lb, price(label, theta))
            if now > lb:
                if now < cut:
                    heapq.heappush(heap, (now, -bin(label[0]).count("1"), i))
                continue
        if done and theta not in exact:  # its follower solve stopped: the clock (or size)
            heapq.heappush(heap, (lb, 0, i))
            stopped_by = "time_limit" if deadline.expired() else "size"
            break
        if done:
            now = max(lb, exact[theta][0])
            if now > lb:
                if now < cut:
                    heapq.heappush(heap, (now, -bin(label[0]).count("1"), i))
                continue
            found = i
            break
        expanded += 1
        for child, act in _children(tab, label):
            key, vec = signature(child)
            if kept.dominated(key, vec):
                continue
            theta_c = interface(child)
            b = max(price(child, theta_c), lb, floor)
            if b >= cut:
                continue
            cid = kept.add(child, act, i, key, vec)
            thetas.append(theta_c)
            heapq.heappush(heap, (b, -bin(child[0]).count("1"), cid))
        if len(labels) > cap:
            stopped_by = "size"
            break
    result: dict[str, Any] = {
        "labels": len(labels),
        "expanded": expanded,
        "stopped_by": stopped_by,
        "follower_solves": solves,
    }
    if found >= 0:
        lead_plan = rebuild_label(sub_l, tab, trace(kept.parent, kept.action, found), labels[found])
        foll_plan = exact[thetas[found]][1]
        assert foll_plan is not None  # priced below the cutoff: a follower plan exists
        pieces = [_lift(lead_plan, lead), _lift(foll_plan, foll)]
        if leader == 1:
            pieces.reverse()
        plan = FleetPlan([x[0] for x in pieces], [x[1] for x in pieces], [x[2] for x in pieces])
        try:
            value = evaluate_fleet(problem, plan)  # the coupled schedule: no later (see above)
        except FeasibilityError:  # both ways: the relaxation's plan may deadlock
            value = INF
        if not one_way and value > lb * (1 + 1e-9):
            # the relaxation's optimum: a bound of the split, its plan (when it scores) no proof
            result.update(stopped_by="relaxed", bound=lb, relaxed_plan=plan)
            foll_times = exact[thetas[found]][2]
            if foll_times is not None:
                times = [INF] * n
                for i, j in enumerate(lead):
                    times[j] = float(labels[found][2][i])
                for i, j in enumerate(foll):
                    times[j] = float(foll_times[i])
                result["relaxed_times"] = times
            if value < planned:
                result.update(plan=plan, value=value)
            else:
                result.update(plan=best_plan, value=planned)
            return result
        result.update(plan=plan, value=value, bound=min(lb, value))
        return result
    bound_value = best
    if stopped_by != "optimal":
        live = [b for b, _, j in heap if not dead[j]]
        bound_value = min(min(live, default=best), best)
    result.update(plan=best_plan, value=planned, bound=bound_value)
    return result


__all__ = [
    "LEADER_GRID",
    "MAX_LABELS",
    "coupled_applies",
    "coupled_dp",
    "coupled_search",
    "leader_of",
    "leader_search",
]
