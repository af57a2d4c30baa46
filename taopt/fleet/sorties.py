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
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.runtime import Deadline

#: Most (state, sortie) steps the DP takes before stopping like a time limit (memory guard).
DEFAULT_MAX_STEPS = 5_000_000

#: Relative agreement required between the DP's value and the scorer's.
MATCH_TOLERANCE = 1e-9


def applies(problem: FleetProblem) -> bool:
    """One truck, one drone, every customer drone-only (any capacity, either objective)."""
    return problem.drones == (1,) and all(mode == "drone" for mode in problem.service)


def _sequences(problem: FleetProblem) -> list[tuple[int, ...]]:
    """Every sortie order of at most c distinct customers that respects G^p within itself."""
    n, c = problem.n, min(problem.capacity, problem.n)
    before = {(int(r), int(j)) for r, j in problem.precedences}
    out: list[tuple[int, ...]] = []
    for m in range(1, c + 1):
        for seq in itertools.permutations(range(n), m):
            if any((seq[b], seq[a]) in before for a in range(m) for b in range(a + 1, m)):
                continue
            out.append(seq)
    return out


def sortie_dp(
    problem: FleetProblem, time_limit: float | None = None, max_steps: int | None = None
) -> dict[str, Any]:
    """Run the DP (module docstring); a dict like :func:`taopt.fleet.search.label_search`'s:
    ``plan`` (None when stopped), ``value`` (inf when stopped), ``stopped_by`` ("optimal",
    "time_limit" or "size") and counters (``states``, ``steps``)."""
    if not applies(problem):
        raise SolverError("sortie_dp: needs one truck with one drone and drone-only customers")
    deadline = Deadline(time_limit)
    cap = DEFAULT_MAX_STEPS if max_steps is None else int(max_steps)
    n, s, tau = problem.n, problem.s, problem.service_time
    depot = problem.depot
    ret = problem.objective == "return"
    tt = problem.truck_time
    fsd, fcd = problem.flight_stop, problem.flight_customer
    v = problem.v_drone
    limit = problem.flight_limit
    need = [0] * n
    for r, j in problem.precedences:
        need[int(j)] |= 1 << int(r)
    seqs = _sequences(problem)
    # per sequence: its mask, C_σ (s, s) and the final cost F_σ (s,)
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
        mask = sum(1 << j for j in seq)
        table.append((mask, cost, final_cost))
    full = (1 << n) - 1
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
            if steps > cap:
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
                    if ends[w] < best:
                        best, best_end = float(ends[w]), (S, q, w)
                    continue
                cand = R[:, None] + cost  # (w, w_2)
                arg = np.argmin(cand, axis=0)
                new = cand[arg, np.arange(s)]
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
    scored = evaluate_fleet(problem, plan)
    if abs(scored - best) > MATCH_TOLERANCE * max(1.0, abs(best)):
        raise SolverError(f"fleet sortie DP: the plan scores {scored!r} but the DP says {best!r}")
    result.update(plan=plan, value=scored)
    return result


def _launch_recovery(
    problem: FleetProblem, seq: tuple[int, ...], w: int, w2: int | None
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
    problem: FleetProblem,
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


__all__ = ["DEFAULT_MAX_STEPS", "applies", "sortie_dp"]
