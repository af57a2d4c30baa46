"""Exact DP for one truck carrying one multi-parcel drone (K = D = 1, every customer
drone-only, any capacity c, either objective): chapter 5's DP over the order ideals of G^p
carried to sorties of up to c customers.

With one drone, its customers are served one after the other, so their order is a linear
extension of G^p (a later customer waits for no one: its predecessors were served earlier by
the same drone, and t_j grows along the order; an earlier one would deadlock), split into
sorties of at most c consecutive customers. The truck serves no one: it only carries the
drone from a recovery to the next launch. A *state* is (S, w): the served set S (an order
ideal of G^p) and the stop w where the drone was last recovered (the depot at the start); its
value R(S, w) is the earliest such recovery (0 at the depot for S = ∅).

A sortie σ = (j_1, ..., j_m), m <= c, is launched at a stop w_1 and recovered at w_2 (within
the range: ``d(w_1, j_1) + Σ d(j_i, j_{i+1}) + d(j_m, w_2) <= range``). Under
:mod:`taopt.fleet.evaluate`'s rules, from (S, w) at R: the truck drives w -> w_1 (or stays),
the drone is launched on arrival ``L = R + tt(w, w_1)``, serves ``t_{j_1} = L + ft(w_1, j_1)
+ τ``, ``t_{j_{i+1}} = t_{j_i} + ft(j_i, j_{i+1}) + τ``; the truck drives w_1 -> w_2 (arriving
``L + tt(w_1, w_2)``; a detour or an extra stop never arrives sooner, tt being shortest
paths) and recovers the drone at ``R' = max(t_{j_m} + ft(j_m, w_2), L + tt(w_1, w_2)) + τ``.
Every time is R plus a constant of (w, σ, w_1, w_2), so

``R(S ∪ σ, w_2) = min over (S, w), σ of R(S, w) + C_σ(w, w_2)``, with
``C_σ(w, w_2) = min_{w_1} tt(w, w_1) + max(a_σ(w_1) + ft(j_m, w_2), tt(w_1, w_2)) + τ``,
``a_σ(w_1) = ft(w_1, j_1) + Σ ft(j_i, j_{i+1}) + m τ``,

a shortest path over the states (every transition adds a customer, so the layers by |S| are
processed in order, each state final when its layer starts). The objective: ``"last_service"``
``f = min over the last sortie σ (S ∪ σ = N) of R(S, w) + min_{w_1} tt(w, w_1) +
a_σ(w_1)`` (w_1 with some recovery stop in range; the last recovery costs nothing);
``"return"`` ``f = min_w R(N, w) + tt(w, depot)``. Exact: every plan of this shape is a walk
through the states with the same times (earliest schedule), and every transition's times are
non-decreasing in R, so the least R of each state is the only one a best plan needs.

Work: the ideals of G^p times the sequences of at most c customers, each an (s, s) min-plus
step. The plan is rebuilt from parent pointers and re-scored by
:func:`taopt.fleet.evaluate.evaluate_fleet` (the two must agree).

References
----------
Thesis §5.3 (the DP over order ideals), §6.2 (multi-parcel drones); Bai et al., IEEE T-ITS
2023 (one truck, one drone with several parcels per flight; heuristics only).
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from taopt.errors import SolverError
from taopt.fleet.evaluate import best_of, evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.runtime import Deadline

#: Most (state, sortie) steps the DP takes before stopping like a time limit.
DEFAULT_MAX_STEPS = 5_000_000

#: Most states (S, ·) kept (memory guard: three arrays of s numbers each, ≈ 200 MB at s = 42).
MAX_STATES = 200_000

#: Largest fleet the split DP takes: at most this many customers and this many splits K^n
#: (its no-precedence DP keeps 2^n arrays of s numbers); beyond, the label search runs.
SPLIT_MAX_N = 12

#: Most splits K^n of the customers among the trucks the split DP examines.
SPLIT_MAX_SPLITS = 600_000

#: Relative agreement required between the DP's value and the scorer's.
MATCH_TOLERANCE = 1e-9


def applies(problem: FleetProblem) -> bool:
    """One truck, one drone, every customer drone-only (any capacity, either objective)."""
    return problem.drones == (1,) and all(mode == "drone" for mode in problem.service)


def _sequences(problem: Any, pairs: Any = None) -> list[tuple[int, ...]]:
    """Every sortie order of at most c distinct customers that respects G^p (or ``pairs``)
    within itself."""
    n, c = problem.n, min(problem.capacity, problem.n)
    pairs = problem.precedences if pairs is None else pairs
    before = {(int(r), int(j)) for r, j in pairs}
    out: list[tuple[int, ...]] = []
    for m in range(1, c + 1):
        for seq in itertools.permutations(range(n), m):
            if any((seq[b], seq[a]) in before for a in range(m) for b in range(a + 1, m)):
                continue
            out.append(seq)
    return out


def _table(problem: Any, seqs: list[tuple[int, ...]]) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Per sequence σ: its mask, C_σ (s, s) and the final cost F_σ (s,) (module docstring)."""
    tau, v, limit = problem.service_time, problem.v_drone, problem.flight_limit
    tt, fsd, fcd = problem.truck_time, problem.flight_stop, problem.flight_customer
    table: list[tuple[int, np.ndarray, np.ndarray]] = []
    for seq in seqs:
        inner = sum(float(fcd[seq[i], seq[i + 1]]) for i in range(len(seq) - 1))
        first, last = seq[0], seq[-1]
        reach = fsd[first] + inner  # (w_1,) distance flown up to the last customer
        ok = reach[:, None] + fsd[last][None, :] <= limit  # (w_1, w_2)
        a = reach / v + len(seq) * tau  # (w_1,)
        body = np.maximum(a[:, None] + fsd[last][None, :] / v, tt) + tau  # (w_1, w_2)
        body = np.where(ok, body, np.inf)
        cost = np.min(tt[:, :, None] + body[None, :, :], axis=1)  # (w, w_2)
        final = np.where(ok.any(axis=1), a, np.inf)
        final_cost = np.min(tt + final[None, :], axis=1)  # (w,)
        table.append((sum(1 << j for j in seq), cost, final_cost))
    return table


def sortie_dp(
    problem: FleetProblem, time_limit: float | None = None, max_steps: int | None = None
) -> dict[str, Any]:
    """Run the DP (module docstring); a dict like :func:`taopt.fleet.search.label_search`'s:
    ``plan`` (None when stopped), ``value`` (inf when stopped), ``stopped_by`` ("optimal",
    "time_limit" or "size") and counters (``states``, ``steps``)."""
    if not applies(problem):
        raise SolverError("sortie_dp: needs one truck with one drone and drone-only customers")
    return _sortie_dp(problem, time_limit, max_steps, check=True)


def _sortie_dp(
    problem: FleetProblem,
    time_limit: float | None,
    max_steps: int | None,
    check: bool,
    members: int | None = None,
    pairs: Any = None,
    pre: tuple[list[tuple[int, ...]], list[tuple[int, np.ndarray, np.ndarray]]] | None = None,
    release: Any = None,
    objective: str | None = None,
) -> dict[str, Any]:
    """:func:`sortie_dp`, or one truck with one drone serving only the customers of the mask
    ``members`` under the precedence ``pairs`` among them (``pre``: the sequences and their
    costs, computed once for all; ``check``: re-score the plan).

    ``release``: per customer j (full numbering) a time before which it is not served; the
    DP then solves the problem with ``t_j >= release[j]`` added (:func:`_release_floors`:
    still exact, the value with the releases; the plan rebuilt is scored without them, so
    ``check`` must be False). ``objective`` overrides the problem's."""
    deadline = Deadline(time_limit)
    cap = DEFAULT_MAX_STEPS if max_steps is None else int(max_steps)
    n, s = problem.n, problem.s
    depot = problem.depot
    ret = (problem.objective if objective is None else objective) == "return"
    tt = problem.truck_time
    full = (1 << n) - 1 if members is None else members
    need = [0] * n
    for r, j in problem.precedences if pairs is None else pairs:
        if full >> int(r) & 1 and full >> int(j) & 1:
            need[int(j)] |= 1 << int(r)
    if pre is None:
        seqs = _sequences(problem)
        table = _table(problem, seqs)
    else:
        keep = [q for q, (mask, _, _) in enumerate(pre[1]) if not mask & ~full]
        seqs = [pre[0][q] for q in keep]
        table = [pre[1][q] for q in keep]
    floors = None if release is None else _release_floors(problem, seqs, release)
    start = np.full(s, np.inf)
    start[depot] = 0.0
    value: dict[int, np.ndarray] = {0: start}
    parent: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    layers: list[list[int]] = [[] for _ in range(n + 1)]
    layers[0].append(0)
    best = math.inf
    best_end: tuple[int, int, int] | None = None  # (S, sequence index, w)
    steps = 0
    stopped_by = "optimal"
    for size in range(n + 1):
        for S in layers[size]:
            if deadline.expired():
                stopped_by = "time_limit"
                break
            if steps > cap or len(value) > MAX_STATES:
                stopped_by = "size"
                break
            R = value[S]
            if ret and S == full:
                home = R + tt[:, depot]
                w = int(np.argmin(home))
                if home[w] < best:
                    best, best_end = float(home[w]), (S, -1, w)
                continue
            for q, (mask, cost, final_cost) in enumerate(table):
                if mask & S:
                    continue
                seq = seqs[q]
                got = S
                ok = True
                for j in seq:
                    if need[j] & ~got:
                        ok = False
                        break
                    got |= 1 << j
                if not ok:
                    continue
                steps += 1
                S2 = S | mask
                if S2 == full and not ret:
                    ends = R + final_cost
                    w = int(np.argmin(ends))
                    end = float(ends[w])
                    if floors is not None and floors[q][0] > end:
                        end = floors[q][0]
                    if end < best:
                        best, best_end = end, (S, q, w)
                    continue
                cand = R[:, None] + cost  # (w, w_2)
                arg = np.argmin(cand, axis=0)
                new = cand[arg, np.arange(s)]
                if floors is not None:
                    new = np.maximum(new, floors[q][1])
                old = value.get(S2)
                if old is None:
                    value[S2] = new
                    parent[S2] = (np.full(s, q), arg)
                    layers[S2.bit_count()].append(S2)
                else:
                    better = new < old
                    if better.any():
                        old[better] = new[better]
                        pq, pw = parent[S2]
                        pq[better] = q
                        pw[better] = arg[better]
            else:
                continue
            break
        if stopped_by != "optimal":
            break
    result: dict[str, Any] = {
        "states": len(value),
        "steps": steps,
        "sequences": len(seqs),
        "stopped_by": stopped_by,
    }
    if stopped_by != "optimal" or best_end is None:
        result.update(plan=None, value=math.inf)
        return result
    plan = _rebuild(problem, seqs, parent, best_end)
    if not check:
        result.update(plan=plan, value=best)
        return result
    scored = evaluate_fleet(problem, plan)
    if abs(scored - best) > MATCH_TOLERANCE * max(1.0, abs(best)):
        raise SolverError(f"fleet sortie DP: the plan scores {scored!r} but the DP says {best!r}")
    result.update(plan=plan, value=scored)
    return result


def _release_floors(
    problem: Any, seqs: list[tuple[int, ...]], release: Any
) -> list[tuple[float, np.ndarray]]:
    """Per sequence σ = (j_1, ..., j_m): (b_σ, b_σ + ft(j_m, w_2) + τ per w_2), the release
    part of its last service and of its recovery.

    With releases, ``t_{j_1} = max(L + ft(w_1, j_1) + τ, rel_{j_1})`` and ``t_{j_{i+1}} =
    max(t_{j_i} + ft(j_i, j_{i+1}) + τ, rel_{j_{i+1}})`` (a drone early at a customer waits,
    as in :mod:`taopt.fleet.evaluate`), so by induction ``t_{j_m} = max(L + a_σ(w_1), b_σ)``
    with ``b_{j_1} = rel_{j_1}``, ``b_{j_{i+1}} = max(b_{j_i} + ft(j_i, j_{i+1}) + τ,
    rel_{j_{i+1}})``. The recovery is then ``R' = max(L + max(a_σ(w_1) + ft(j_m, w_2),
    tt(w_1, w_2)) + τ, b_σ + ft(j_m, w_2) + τ)``; as ``max(x, b)`` is non-decreasing in x,
    the least over (w, w_1) of R' is ``max(min_{w, w_1}(...), b_σ + ft(j_m, w_2) + τ) =
    max(R(S, ·) ⊗ C_σ, b_σ + ft(j_m, ·) + τ)``, and the last service ``max(R ⊗ F_σ, b_σ)``.
    Every transition stays non-decreasing in R, so the DP stays exact."""
    tau, v = problem.service_time, problem.v_drone
    fct = problem.flight_customer / v
    fst = problem.flight_stop / v
    out: list[tuple[float, np.ndarray]] = []
    for seq in seqs:
        b = float(release[seq[0]])
        for i in range(1, len(seq)):
            b = max(b + float(fct[seq[i - 1], seq[i]]) + tau, float(release[seq[i]]))
        out.append((b, b + fst[seq[-1]] + tau))
    return out


def _launch_recovery(
    problem: Any, seq: tuple[int, ...], w: int, w2: int | None
) -> tuple[int, int | None]:
    """The launch stop w_1 (and recovery w_2 when given) attaining C_σ(w, w_2), or F_σ(w)."""
    tt, fsd, fcd = problem.truck_time, problem.flight_stop, problem.flight_customer
    v, tau, limit = problem.v_drone, problem.service_time, problem.flight_limit
    inner = sum(float(fcd[seq[i], seq[i + 1]]) for i in range(len(seq) - 1))
    reach = fsd[seq[0]] + inner
    a = reach / v + len(seq) * tau
    last = seq[-1]
    if w2 is None:
        ok = (reach[:, None] + fsd[last][None, :] <= limit).any(axis=1)
        w1 = int(np.argmin(np.where(ok, tt[w] + a, np.inf)))
        back = np.where(reach[w1] + fsd[last] <= limit, fsd[last], np.inf)
        return w1, None if not np.isfinite(back).any() else int(np.argmin(back))
    body = np.maximum(a + fsd[last][w2] / v, tt[:, w2]) + tau
    body = np.where(reach + fsd[last][w2] <= limit, body, np.inf)
    return int(np.argmin(tt[w] + body)), w2


def _rebuild(
    problem: Any,
    seqs: list[tuple[int, ...]],
    parent: dict[int, tuple[np.ndarray, np.ndarray]],
    end: tuple[int, int, int],
) -> FleetPlan:
    """The plan of the best end state: its sorties back to the root, as a truck walk."""
    S, q, w = end
    steps: list[tuple[int, int, int | None]] = []  # (sequence, from stop, to stop or None)
    if q >= 0:
        steps.append((q, w, None))
    while S:
        pq, pw = parent[S]
        q2, w_prev = int(pq[w]), int(pw[w])
        steps.append((q2, w_prev, w))
        S &= ~sum(1 << j for j in seqs[q2])
        w = w_prev
    steps.reverse()
    route = [problem.depot]
    sorties: list[Sortie] = []
    for q2, w_from, w_to in steps:
        seq = seqs[q2]
        w1, w2 = _launch_recovery(problem, seq, w_from, w_to)
        if route[-1] != w1:
            route.append(w1)
        launch = len(route) - 1
        assert w2 is not None  # a range-feasible recovery exists (C_σ / F_σ finite)
        if route[-1] != w2:
            route.append(w2)
        sorties.append(Sortie(launch, seq, len(route) - 1))
    return FleetPlan([route], [[]], [[sorties]])


# -- several trucks, one drone each: split the customers, each truck by the sortie DP -----------


def split_applies(problem: FleetProblem) -> bool:
    """Several trucks, one drone each, every customer drone-only (any capacity, objective),
    at most :data:`~taopt.fleet.sorties.SPLIT_MAX_N` customers and
    :data:`~taopt.fleet.sorties.SPLIT_MAX_SPLITS` splits."""
    return (
        problem.K > 1
        and problem.n <= SPLIT_MAX_N
        and problem.K**problem.n <= SPLIT_MAX_SPLITS
        and all(d == 1 for d in problem.drones)
        and all(mode == "drone" for mode in problem.service)
    )


def _set_values(problem: FleetProblem, deadline: Deadline) -> list[float] | None:
    """A lower bound per customer set X on one truck with one drone serving exactly X from
    the depot: :func:`taopt.fleet.cover.one_drone_table`'s (the precedence pairs inside X
    kept, so at least :func:`_free_values`'s, and exact for one truck and one drone), checked
    against the deadline (None once it passes); :func:`_free_values` when that table is over
    its work cap."""
    from taopt.fleet.cover import one_drone_table

    table = one_drone_table(problem, deadline)
    if table is not None:
        return [float(v) for v in table[problem.depot]]
    if deadline.expired():
        return None
    return _free_values(problem)


def _free_values(problem: FleetProblem) -> list[float]:
    """``opt_free(X)`` for every customer set X (bit mask): the optimum of one truck with one
    drone serving exactly X with no precedence at all — the sortie DP over all subsets."""
    n, depot = problem.n, problem.depot
    ret = problem.objective == "return"
    tt = problem.truck_time
    free = problem.replace(precedences=())
    table = _table(free, _sequences(free))
    start = np.full(problem.s, np.inf)
    start[depot] = 0.0
    value: list[np.ndarray | None] = [None] * (1 << n)
    value[0] = start
    out = [math.inf] * (1 << n)
    out[0] = 0.0
    for S in sorted(range(1 << n), key=int.bit_count):
        R = value[S]
        if R is None:
            continue
        if ret:
            out[S] = float(np.min(R + tt[:, depot]))
        for mask, cost, final_cost in table:
            if mask & S:
                continue
            S2 = S | mask
            if not ret:
                out[S2] = min(out[S2], float(np.min(R + final_cost)))
            new = np.min(R[:, None] + cost, axis=0)
            old = value[S2]
            value[S2] = new if old is None else np.minimum(old, new)
    return out


def split_dp(
    problem: FleetProblem, time_limit: float | None = None, trace: list[Any] | None = None
) -> dict[str, Any]:
    """Several trucks with one drone each (:func:`split_applies`): exact by splitting.

    *Bound.* Dropping the precedence pairs between customers of different trucks leaves one
    independent one-truck, one-drone problem per truck, so for every split (X_1, ..., X_K) of
    the customers over the trucks the optimum with that split is at least ``max_k
    opt(X_k)``, ``opt`` the sortie DP's optimum of X_k with the precedence closure's pairs
    inside X_k (each still holds: t_r <= t_m <= t_j through any chain), and at least ``max_k
    opt_set(X_k)`` (one DP over every subset with only the direct pairs inside each set,
    :func:`_set_values`; stopped by the deadline, the run returns at once with bound 0). The
    optimum is the least over the splits, hence at least the least of these bounds.

    *Releases* (split-dependent, valid in every plan of the split): let ``anc(j)`` be j's
    ancestors in the closure and ``L_j`` a time before which no plan of the split serves j,
    computed in a topological order: ``L_j`` starts at the earliest service raised along G^p
    (:func:`taopt.fleet.split._earliest`); then, for each truck k (j's own truck last), with
    ``Y = anc(j) ∩ X_k`` (plus j on its own truck), ``L_j >= opt_last(Y; L)``, the sortie DP's
    optimum of truck k serving exactly Y under ``"last_service"`` with the releases ``L`` of
    Y's members (:func:`_release_floors`). Valid: in a plan of the split, every member of Y is
    served by ``t_j`` (an ancestor, through a chain of pairs; or j itself); truck k's plan with
    every customer outside Y dropped (a sortie losing a customer flies straight on, which the
    triangle inequality of the Euclidean flights makes no longer, and an emptied sortie is
    removed) is a plan of Y whose earliest schedule is no later (fewer and weaker ``t >= t' +
    const`` constraints), and it meets the releases of Y's members (ancestors of j, so earlier
    in the order: induction); so ``t_j >= max_{Y} t >= opt_last(Y; L)``. Each truck's part is
    then solved with the releases ``L`` of its members, still a relaxation of every plan of
    the split. On fleet8's K2D1c1 row the least split bound rises from 348.9 to 391.2.

    *Search.* Splits in increasing ``max_k opt_set`` (identical trucks: each split once);
    for each, the sortie DP per truck gives the split's bound and plans, combined into one
    plan and scored by :func:`taopt.fleet.evaluate.evaluate_fleet` (the cross-truck
    precedences may make a drone wait, or deadlock: then no plan from that split). The run
    stops when the best plan is no worse than the least bound of the splits left (certified
    optimal), or at the time limit with the best plan and that least bound (proven).

    Returns a dict like :func:`sortie_dp`'s plus ``bound`` and ``splits`` (examined).
    ``trace``: when given, one ``(bound, value, split, releases)`` per split examined is
    appended (for tests and measurements).
    """
    import itertools

    import networkx as nx

    from taopt.errors import FeasibilityError

    deadline = Deadline(time_limit)
    n, K = problem.n, problem.K
    free = _set_values(problem, deadline)
    if free is None:  # the deadline passed while tabling the sets: nothing examined
        return {
            "plan": None,
            "value": math.inf,
            "bound": 0.0,
            "stopped_by": "time_limit",
            "splits": 0,
            "of_splits": 0,
            "coupled": 0,
        }
    closure = {
        (int(r), int(j)) for r, j in nx.transitive_closure_dag(problem.precedence_graph).edges
    }
    seqs = _sequences(problem, closure)
    pre = (seqs, _table(problem, seqs))
    from taopt.fleet.split import _earliest

    early = [float(e) for e in _earliest(problem)]
    ancestors = [0] * n
    for r, j in closure:
        ancestors[j] |= 1 << r
    topo = [int(j) for j in nx.topological_sort(problem.precedence_graph)]
    seen: set[tuple[int, ...]] = set()
    splits: list[tuple[float, tuple[int, ...]]] = []
    for assign in itertools.product(range(K), repeat=n):
        masks = [0] * K
        for j, k in enumerate(assign):
            masks[k] |= 1 << j
        key = tuple(sorted(masks))  # the trucks are identical (one drone each, same depot)
        if key in seen:
            continue
        seen.add(key)
        splits.append((max(free[m] for m in key), key))
    splits.sort()
    best, best_plan = math.inf, None
    bound_done = math.inf  # least bound over the splits examined
    examined = 0
    stopped_by = "optimal"
    cache: dict[tuple[int, tuple[float, ...], str], dict[str, Any]] = {}

    def solve(mask: int, release: list[float], objective: str) -> dict[str, Any] | None:
        """One truck's sortie DP over ``mask`` with ``release`` (cached; None: stopped)."""
        if not mask:
            return {"value": 0.0, "plan": None}
        key = (mask, tuple(release[j] for j in range(n) if mask >> j & 1), objective)
        got = cache.get(key)
        if got is None:
            got = _sortie_dp(
                problem,
                deadline.remaining(),
                None,
                False,
                mask,
                closure,
                pre,
                release=release,
                objective=objective,
            )
            if got["stopped_by"] != "optimal":
                return None
            cache[key] = got
        return got

    def releases(key: tuple[int, ...]) -> list[float] | None:
        """Per customer a time before which no plan of the split ``key`` serves it
        (:func:`split_releases`'s argument; None: stopped on the clock)."""
        owner = [0] * n
        for k, mask in enumerate(key):
            for j in range(n):
                if mask >> j & 1:
                    owner[j] = k
        out = early[:]
        for j in topo:
            if not ancestors[j]:
                continue
            mine = owner[j]
            order = [k for k in range(K) if k != mine] + [mine]
            for k in order:
                Y = ancestors[j] & key[k]
                if k == mine:
                    Y |= 1 << j
                    if Y == 1 << j:
                        continue
                if not Y:
                    continue
                found = solve(Y, out, "last_service")
                if found is None:
                    return None
                out[j] = max(out[j], float(found["value"]))
        return out

    done: list[list[Any]] = []  # [bound, split, releases] per split examined
    stop_at = len(splits)  # the first split not examined
    for at, (lower, key) in enumerate(splits):
        stop_at = at
        if best <= min(lower, bound_done) * (1 + MATCH_TOLERANCE):
            break
        if deadline.expired():
            stopped_by = "time_limit"
            break
        parts = []
        release = releases(key)
        for mask in key if release is not None else ():
            found = solve(mask, release, problem.objective)  # type: ignore[arg-type]
            if found is None:
                break
            parts.append(found)
        if len(parts) < len(key):  # a truck's DP stopped on the clock: this split not examined
            stopped_by = "time_limit"
            break
        examined += 1
        bound_done = min(bound_done, max(part["value"] for part in parts))
        done.append([max(part["value"] for part in parts), key, release])
        routes: list[list[int]] = []
        sorties: list[list[list[Sortie]]] = []
        for part in parts:
            if part["plan"] is None:
                routes.append([problem.depot])
                sorties.append([[]])
                continue
            routes.append(list(part["plan"].routes[0]))
            sorties.append([list(part["plan"].sorties[0][0])])
        plan = FleetPlan(routes, [[] for _ in range(K)], sorties)
        try:
            value = evaluate_fleet(problem, plan)
        except FeasibilityError:
            continue
        if value < best:
            best, best_plan = value, plan
        if trace is not None:
            trace.append((max(part["value"] for part in parts), value, key, release))
    else:
        stop_at = len(splits)
    left = min((lo for lo, _ in splits[stop_at:]), default=math.inf)
    # the splits whose parts' plans do not combine into a plan meeting their bound: the
    # coupled problem of each, by the joint DP (exact, or the best of its relaxations)
    coupled = 0
    for entry in sorted(done, key=lambda e: e[0]):
        if best <= min(entry[0], left) * (1 + MATCH_TOLERANCE) or deadline.expired():
            break
        coupled += 1
        closed, plans = _couple(problem, entry[1], entry[2], pre, closure, deadline, best)
        entry[0] = max(entry[0], closed)
        value, joint = best_of(problem, plans)
        if joint is not None and value < best:
            best, best_plan = value, joint
    bound_done = min((e[0] for e in done), default=math.inf)
    bound = min(best, bound_done, left)
    if stopped_by == "optimal" and best > bound * (1 + MATCH_TOLERANCE):
        stopped_by = "gap"  # every split examined, cross-truck waits keep a gap
    return {
        "plan": best_plan,
        "value": best,
        "bound": bound,
        "stopped_by": stopped_by,
        "splits": examined,
        "of_splits": len(seen),
        "coupled": coupled,
    }


def _couple(
    problem: FleetProblem,
    split: tuple[int, ...],
    release: list[float],
    pre: Any,
    closure: Any,
    deadline: Deadline,
    cutoff: float,
) -> tuple[float, list[FleetPlan]]:
    """A lower bound on the optimum restricted to ``split`` (at least ``cutoff`` when no plan of
    the split is below it) and the plans found: :func:`taopt.fleet.coupled.coupled_dp`, exact
    where :func:`~taopt.fleet.coupled.coupled_applies`, else the largest bound of its
    relaxations over the truck orders (each keeps the cross pairs going forward)."""
    import itertools

    from taopt.fleet.coupled import coupled_applies, coupled_dp

    orders: list[Any] = (
        [None]
        if coupled_applies(problem, split)
        else list(itertools.permutations(range(problem.K)))
    )
    bound = 0.0
    plans: list[FleetPlan] = []
    for order in orders:
        if deadline.expired():
            break
        got = coupled_dp(
            problem,
            split,
            pre,
            closure,
            time_limit=deadline.remaining(),
            cutoff=cutoff,
            order=order,
            release=release,
        )
        bound = max(bound, float(got["bound"]))
        if got["plan"] is not None:
            plans.append(got["plan"])
        if bound >= cutoff:
            break
    return bound, plans


__all__ = [
    "DEFAULT_MAX_STEPS",
    "MAX_STATES",
    "SPLIT_MAX_N",
    "SPLIT_MAX_SPLITS",
    "applies",
    "sortie_dp",
    "split_applies",
    "split_dp",
]
