"""The covering-walk bound of the fleet family: the trucks' routing, relaxed to deadlines.

For a trial objective value T, every customer j must be *covered* by some truck's walk: a truck
serving it stands at its stop no later than its deadline, and a drone serving it was launched
from a stop its truck stood at early enough. Relaxing everything else (the number of drones,
their capacity, the sorties' sharing of a drone, the range beyond one direct flight, the
precedences), the question "can K walks cover every customer by T" is a DP over (covered set,
last stop) per truck and an OR-convolution over the trucks; the least T that passes is a lower
bound on the optimum, found by bisection. See :func:`coverable` for the proof.

Timing conventions are those of :mod:`taopt.fleet.evaluate` (chapter 5's (5.1)–(5.7)): a
truck-served customer j at position p has ``t_j >= A[k, p]``; a sortie launched at position p
(stop w) has ``L >= A[k, p]`` and its i-th customer ``t_{c_i} >= L + ft(w, c_1) + τ + ...
>= L + ft(w, c_i) + τ`` (straight lines: the triangle inequality); under ``"return"`` the
truck carrying the drone is home no sooner than ``t_j + ft(j, q) + τ + tt(q, depot)`` for
the recovery stop q.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.fleet.problem import FleetProblem
from taopt.runtime import Deadline

INF = math.inf


class CoverTables:
    """Per-instance arrays of the covering-walk bound.

    Attributes
    ----------
    offset : dict bool -> (s, n) float array
        ``offset[has_drones][w, j]``: the least time from a truck standing at stop w to the
        objective's clock for customer j served from there (``inf`` when it cannot be): 0 for a
        truck-servable j at its own stop w (plus ``tt(w, depot)`` under ``"return"``);
        ``ft(w, j) + τ`` for a drone-servable j when the truck carries drones and some
        single-customer sortie w -> j -> q is within range (plus ``min_q ft(j, q) + τ +
        tt(q, depot)`` under ``"return"``); the minimum of the two.
    """

    def __init__(self, problem: FleetProblem) -> None:
        p = problem
        n, s = p.n, p.s
        self.n, self.s = n, s
        self.tt = np.asarray(p.truck_time, dtype=float)
        self.depot = p.depot
        self.ret = p.objective == "return"
        self.drones = list(p.drones)
        self.home_truck = self.tt[:, p.depot].copy()
        fs = p.flight_stop  # (n, s) distances
        ft = fs / p.v_drone
        tau = p.service_time
        # a sortie serving j from launch w and landing at q flies at least d(w, j) + d(j, q)
        reach = fs.T + fs.min(axis=1)[None, :]  # (s, n)
        drone = np.where(reach <= p.flight_limit, ft.T + tau, INF)
        if self.ret:
            home = (ft + tau + self.tt[:, p.depot][None, :]).min(axis=1)  # (n,)
            drone = drone + home[None, :]
        truck = np.full((s, n), INF)
        for j in range(n):
            if p.truck_servable(j):
                w = p.customer_stop[j]
                assert w is not None
                truck[w, j] = self.home_truck[w] if self.ret else 0.0
        no_drone = truck
        with_drone = np.minimum(
            truck, np.where([p.drone_servable(j) for j in range(n)], drone, INF)
        )
        self.offset = {False: no_drone, True: with_drone}
        self.ft_customer = p.flight_customer / p.v_drone
        self.home_drone = (ft + tau + self.tt[:, p.depot][None, :]).min(axis=1)
        self.tau = tau
        self.limit = p.flight_limit
        self.fs = fs
        self.fc = p.flight_customer
        self.near = fs.min(axis=1)
        self.v_drone = p.v_drone


def _reached(
    tab: CoverTables,
    off: np.ndarray,
    T: float,
    stop: int,
    arrival: float,
    leave: float,
    budget: int,
) -> np.ndarray | None:
    """The covered sets (bitmasks over the columns of ``off``) one truck's walks reach by
    ``T``: the truck stands at ``stop`` from ``arrival`` and may leave at ``leave``.

    Only maximal-enough sets matter (a subset of a reached set is covered too); each state
    (set, stop) keeps its earliest time, which covers a superset of any later one."""
    m = off.shape[1]
    weights = (1 << np.arange(m, dtype=np.int64)) if m else np.zeros(0, dtype=np.int64)
    slack = T - off  # (s, m): the latest arrival at w that still covers j
    tt = tab.tt
    home = tab.home_truck

    def cover(times: np.ndarray) -> np.ndarray:
        return ((slack >= times[:, None]) @ weights).astype(np.int64)  # (s,)

    start = int(cover(np.full(tab.s, arrival))[stop])
    if tab.ret and leave + home[stop] > T:
        return np.zeros(0, dtype=np.int64)
    best: dict[int, np.ndarray] = {}
    first = np.full(tab.s, INF)
    first[stop] = leave
    best[start] = first
    order = [start]
    import heapq

    heapq.heapify(order)
    out = []
    while order:
        S = heapq.heappop(order)
        dep = best[S]
        out.append(S)
        if len(best) > budget:
            return None
        arr = np.min(dep[:, None] + tt, axis=0)  # (s,)
        ok = arr <= T
        if tab.ret:
            ok &= arr + home <= T
        if not ok.any():
            continue
        cov = cover(np.where(ok, arr, INF))
        for w in np.flatnonzero(ok & ((cov | S) != S)):
            S2 = int(cov[w]) | S
            row = best.get(S2)
            if row is None:
                row = np.full(tab.s, INF)
                best[S2] = row
                heapq.heappush(order, S2)
            if arr[w] < row[w]:
                row[w] = arr[w]
    return np.unique(np.asarray(out, dtype=np.int64))


def coverable(
    tab: CoverTables,
    T: float,
    trucks: Sequence[tuple[int, float, float, int]],
    required: Sequence[int],
    budget: int = 1 << 16,
) -> bool:
    """Whether K truck walks can cover the ``required`` customers by ``T`` (relaxation).

    ``trucks``: per unfinished truck (stop, arrival, earliest departure, drones carried).

    Proof that a plan of objective ``<= T`` passes. Take its earliest schedule (module
    :mod:`taopt.fleet.evaluate`). Each customer j is served by (a) a truck at position p at
    stop ``customer_stop[j]`` with ``A[k, p] <= t_j <= T`` (under ``"return"`` the truck then
    drives home: ``A[k, p] + tt(w, depot) <= T``); or (b) a drone of a sortie launched at
    position p (stop w) of truck k: ``t_j >= L + ft(w, j) + τ >= A[k, p] + ft(w, j) + τ``
    (straight lines are shortest), the sortie flies at least ``d(w, j) + d(j, q)`` for its
    recovery stop q (so ``d(w, j) + min_q d(j, q) <= range``), and under ``"return"`` the
    truck is home no sooner than ``t_j + ft(j, q) + τ + tt(q, depot)``. Either way truck k
    stood at a stop w at a time ``A[k, p] <= T - offset[w, j]`` (:class:`CoverTables`). The
    truck's positions are a walk; its arrival times are at least the street shortest paths
    from its start between consecutive positions, so the DP's walk through the same stops,
    arriving earliest, covers j too (deadlines only: being earlier never hurts). Truck k's
    customers form a set reached by one truck's DP; the K sets cover every customer.
    """
    m = len(required)
    if m == 0:
        return True
    full = (1 << m) - 1
    family: np.ndarray | None = None
    for stop, arrival, leave, drones in trucks:
        off = tab.offset[drones > 0][:, list(required)]
        sets = _reached(tab, off, T, stop, arrival, leave, budget)
        if sets is None:
            return True  # too many sets to decide: nothing proven
        if len(sets) == 0:
            continue
        if np.any(sets == full):
            return True
        if family is None:
            family = sets
        else:
            union = np.unique(np.bitwise_or.outer(family, sets).ravel())
            if np.any(union == full):
                return True
            family = union
    return False


def cover_bound(
    problem: FleetProblem,
    lower: float,
    upper: float,
    trucks: Sequence[tuple[int, float, float, int]] | None = None,
    required: Sequence[int] | None = None,
    tables: CoverTables | None = None,
    deadline: Deadline | None = None,
    tolerance: float = 1e-7,
) -> float:
    """The covering-walk lower bound, by bisection between a valid bound and an upper value.

    Parameters
    ----------
    problem : FleetProblem
    lower : float
        A valid lower bound on the optimum (returned when nothing better is proven).
    upper : float
        A value to test first (an incumbent's): when even ``upper (1 - tolerance)`` is not
        coverable, that is returned, closing the gap within the tolerance.
    trucks : sequence of (stop, arrival, departure, drones), optional
        Default: every truck at the depot at time 0.
    required : sequence of int, optional
        The customers to cover (default: all).
    deadline : Deadline, optional
        Checked between trials; the best proven value is returned when it expires.

    Returns
    -------
    float
        ``max(lower, T)`` for the largest tested T no plan of objective ``<= T`` meets
        (:func:`coverable`): a valid lower bound.
    """
    tab = tables if tables is not None else CoverTables(problem)
    if trucks is None:
        trucks = [(problem.depot, 0.0, 0.0, d) for d in problem.drones]
    req = list(range(problem.n)) if required is None else list(required)
    if not math.isfinite(upper):
        return lower
    top = upper * (1.0 - tolerance)
    if top <= lower:
        return lower
    return _bisect(lambda T: coverable(tab, T, trucks, req), lower, top, tolerance, deadline)


def _bisect(
    test: Any, lower: float, top: float, tolerance: float, deadline: Deadline | None
) -> float:
    """The least trial value that passes ``test``, from below: ``top`` when it fails there
    (no plan is that fast, so ``top`` is a bound), else bisected over (lower, top] until the
    interval is within ``tolerance`` (relative) or the deadline passes; the last failing value
    is returned (a proven bound: ``test`` is monotone, a relaxation's feasibility)."""
    if not test(top):
        return top
    lo, hi = lower, top
    while hi - lo > tolerance * max(1.0, abs(hi)):
        if deadline is not None and deadline.expired():
            break
        mid = 0.5 * (lo + hi)
        if test(mid):
            hi = mid
        else:
            lo = mid
    return lo


# -- the sortie-walk relaxation: each drone with its own truck --------------------------------


class SortieTables:
    """Per-instance arrays of :func:`sortie_walks`: every ordered tuple of at most c distinct
    drone-servable customers (a possible sortie), its customer bitmask, its first and last
    customer, the flight time between its customers with the landings, and which launch and
    recovery stops keep it within range."""

    def __init__(self, problem: FleetProblem, required: Sequence[int]) -> None:
        p = problem
        import itertools

        self.required = list(required)
        col = {j: i for i, j in enumerate(self.required)}
        drone_ok = [j for j in self.required if p.drone_servable(j)]
        fs, fc = p.flight_stop, p.flight_customer
        vd, tau, limit = p.v_drone, p.service_time, p.flight_limit
        near = fs.min(axis=1)
        seqs = [
            seq
            for size in range(1, p.capacity + 1)
            for seq in itertools.permutations(drone_ok, size)
        ]
        self.count = len(seqs)
        self.size = p.capacity
        s = p.s
        self.mask = np.array([sum(1 << col[j] for j in seq) for seq in seqs], dtype=np.int64)
        self.first_leg = np.full((len(seqs), s), INF)  # ft(w, c_1) where the launch w is in range
        self.back_leg = np.full((len(seqs), s), INF)  # ft(c_m, q) where the recovery q is in range
        self.steps = np.full((len(seqs), p.capacity), -1, dtype=np.int64)  # columns, -1 padding
        self.gaps = np.zeros((len(seqs), p.capacity))  # ft(c_{i-1}, c_i) + τ (0 for i = 0)
        for i, seq in enumerate(seqs):
            inner = sum(float(fc[a, b]) for a, b in zip(seq[:-1], seq[1:], strict=False))
            launch_ok = fs[seq[0]] + inner + near[seq[-1]] <= limit
            self.first_leg[i, launch_ok] = fs[seq[0], launch_ok] / vd
            if launch_ok.any():
                out = float(fs[seq[0], launch_ok].min()) + inner
                back_ok = out + fs[seq[-1]] <= limit
                self.back_leg[i, back_ok] = fs[seq[-1], back_ok] / vd
            for pos, j in enumerate(seq):
                self.steps[i, pos] = col[j]
                if pos:
                    self.gaps[i, pos] = float(fc[seq[pos - 1], j]) / vd + tau
        self.tau = tau


def sortie_walks(
    tab: CoverTables,
    stab: SortieTables,
    T: float,
    stop: int,
    ready: float,
    release: np.ndarray,
    budget_sets: int = 1 << 16,
    deadline: Deadline | None = None,
) -> np.ndarray | None:
    """The customer sets (bitmasks over ``stab.required``) one drone can serve by ``T``
    (``"last_service"``; under ``"return"``: with every sortie recovered and its truck home by
    T), when it is aboard its truck at ``stop`` from ``ready``, its truck free to follow it.

    Relaxation of the plan's constraints on one drone's sorties σ_1, σ_2, ... (module
    :mod:`taopt.fleet.evaluate`): the launch of σ_{i+1} at stop w is no sooner than the
    recovery ``R_i`` at stop q plus the truck's drive ``tt(q, w)`` (the truck leaves position
    q no sooner than ``R_i``); its customers' times follow the flight legs and τ and are no
    earlier than their ``release`` (predecessors); its recovery at q' is
    ``max(B, A[q']) + τ`` with ``A[q'] >= min_q R_i[q] + tt(q, q')``; a sortie is within range
    only if its launch and recovery legs are (:class:`SortieTables`). The other drones of the
    truck and the truck's own service are dropped, so each drone gets a truck of its own: a
    relaxation. A DP over (served set, last recovery stop) keeping the earliest recovery.
    None (nothing proven) when there are more than ``budget_sets`` sets or the deadline
    expires first.
    """
    m = len(stab.required)
    size = 1 << m
    s = tab.s
    if size > budget_sets:
        return None
    R = np.full((size, s), INF)
    R[0, stop] = ready
    alive = np.zeros(size, dtype=bool)
    alive[0] = True
    done = np.zeros(size, dtype=bool)
    done[0] = True
    tt = tab.tt
    home = tab.home_truck
    ret = tab.ret
    rel_steps = np.where(stab.steps >= 0, release[np.maximum(stab.steps, 0)], -INF)
    valid_steps = stab.steps >= 0
    for S in range(size):
        if not alive[S]:
            continue
        if deadline is not None and S & 63 == 0 and deadline.expired():
            return None
        launch = np.min(R[S][:, None] + tt, axis=0)  # (s,): truck and drone at w
        free = (stab.mask & S) == 0
        if not free.any():
            continue
        first = np.min(launch[None, :] + stab.first_leg[free], axis=1) + stab.tau
        rel = rel_steps[free]
        gaps = stab.gaps[free]
        valid = valid_steps[free]
        t = np.maximum(first, rel[:, 0])
        for pos in range(1, stab.size):
            nxt = np.maximum(t + gaps[:, pos], rel[:, pos])
            t = np.where(valid[:, pos], nxt, t)
        masks = stab.mask[free] | S
        if ret:
            back = t[:, None] + stab.back_leg[free]
            rec = np.maximum(back, launch[None, :]) + stab.tau
            rec[rec + home[None, :] > T] = INF
            ok = np.isfinite(rec).any(axis=1)
        else:
            ok = t <= T
            back = t[:, None] + stab.back_leg[free]
            rec = np.maximum(back, launch[None, :]) + stab.tau
            rec[rec > T] = INF
        done[masks[ok]] = True
        more = np.isfinite(rec).any(axis=1)
        if more.any():
            idx = masks[more]
            np.minimum.at(R, idx, rec[more])
            alive[idx] = True
    return np.flatnonzero(done).astype(np.int64)


def _combine(families: list[np.ndarray], full: int) -> bool:
    """Whether one set from each family covers ``full`` (OR-convolution over bitmasks)."""
    families = sorted(families, key=len)
    acc: np.ndarray | None = None
    for fam in families:
        if len(fam) == 0:
            continue
        if np.any(fam == full):
            return True
        acc = fam if acc is None else np.unique(np.bitwise_or.outer(acc, fam).ravel())
        if np.any(acc == full):
            return True
    return False


def fleet_coverable(
    tab: CoverTables,
    stab: SortieTables,
    T: float,
    trucks: Sequence[tuple[int, float, float, int]],
    release: np.ndarray,
    budget: int = 1 << 16,
    deadline: Deadline | None = None,
) -> bool:
    """Whether the trucks' walks (truck service only, :func:`coverable`'s DP) and the drones'
    sortie walks (:func:`sortie_walks`, one per drone) can serve every customer of
    ``stab.required`` by ``T``. A plan of objective ``<= T`` passes: each customer is served by
    a truck (so that truck's walk covers it) or by a drone (so that drone's sorties serve it),
    and every constraint kept is one of the plan's."""
    req = stab.required
    m = len(req)
    if m == 0:
        return True
    if np.any(release[req] > T):
        return False
    full = (1 << m) - 1
    families: list[np.ndarray] = []
    off = tab.offset[False][:, req]
    has_truck_customers = bool(np.isfinite(off).any())
    memo: dict[tuple[Any, ...], np.ndarray | None] = {}  # identical starts, identical families
    for stop, arrival, leave, drones in trucks:
        if has_truck_customers:
            key: tuple[Any, ...] = ("truck", stop, arrival, leave)
            if key not in memo:
                memo[key] = _reached(tab, off, T, stop, arrival, leave, budget)
            sets = memo[key]
            if sets is None:
                return True
            families.append(sets)
        for _ in range(drones):
            key = ("drone", stop, arrival)
            if key not in memo:
                memo[key] = sortie_walks(
                    tab, stab, T, stop, arrival, release[req], budget, deadline
                )
            walks = memo[key]
            if walks is None:
                return True
            families.append(walks)
    return _combine(families, full)


def release_times(problem: FleetProblem) -> np.ndarray:
    """(n,) times no plan serves customer j before: :func:`taopt.fleet.bounds.earliest_service`
    raised along the precedences (``t_j >= t_r`` for every pair (r, j))."""
    import networkx as nx

    from taopt.fleet.bounds import earliest_service

    e = earliest_service(problem).astype(float)
    for j in nx.topological_sort(problem.precedence_graph):
        for r in problem.precedence_graph.predecessors(j):
            e[j] = max(e[j], e[r])
    return e


def fleet_cover_bound(
    problem: FleetProblem,
    lower: float,
    upper: float,
    deadline: Deadline | None = None,
    tolerance: float = 1e-7,
    resolution: float = 1e-4,
    settled: bool = False,
) -> float:
    """The root sortie-walk bound: the largest T (bisection between the valid ``lower`` and
    the incumbent value ``upper``, to a relative ``resolution``) for which
    :func:`fleet_coverable` fails, at least ``lower``; ``upper (1 - tolerance)`` when even that
    fails (the incumbent is then optimal within the tolerance). Only for n <= 14 (the DP is
    over customer subsets); ``lower`` otherwise, or when the deadline expires first.

    ``settled``: ``lower`` is a strong bound (the one-drone relaxation's) that the walks
    likely cannot beat: ``lower (1 + resolution)`` is tested first, and when it passes
    ``lower`` is returned (the bisection could return nothing larger)."""
    if not math.isfinite(upper) or problem.n > 14:
        return lower
    tab = CoverTables(problem)
    stab = SortieTables(problem, list(range(problem.n)))
    release = release_times(problem)
    trucks = [(problem.depot, 0.0, 0.0, d) for d in problem.drones]
    # identical drones give identical families: computed once per distinct truck start
    top = upper * (1.0 - tolerance)
    if top <= lower:
        return lower

    def test(T: float) -> bool:
        return fleet_coverable(tab, stab, T, trucks, release, deadline=deadline)

    if settled and test(min(lower * (1.0 + resolution), top)):
        # a stronger bound is already known (the one-drone relaxation): the walks pass just
        # above it, so the bisection could only return ``lower`` (one test instead of ~14)
        return lower
    return _bisect(test, lower, top, resolution, deadline)


# -- the truck-walk table of the label search -------------------------------------------------

#: Largest number of customers for which :func:`walk_table` builds its (2^n, s) table.
WALK_MAX_CUSTOMERS = 14


class WalkTable:
    """The least covering walk of one truck, per set of customers and per stop.

    Attributes
    ----------
    cover : list of int
        ``cover[w]``: bitmask of the customers a truck standing at stop w can serve or launch a
        drone toward (its own stop for a truck-servable customer; for a drone-servable one,
        when the truck carries drones, every stop w with ``d(w, j) + min_q d(j, q) <= range``).
    value : (2^n, s) float array
        ``value[R, w]`` (:func:`walk_table`): a lower bound on the time from a truck's departure
        from stop w until the objective's clock, when the customers of R are not coverable at
        w and must be covered by its later stops; ``value[0, w]`` is 0 (``"last_service"``)
        or ``tt(w, depot)`` (``"return"``).
    """

    def __init__(self, cover: list[int], value: np.ndarray) -> None:
        self.cover = cover
        self.value = value


def walk_table(
    problem: FleetProblem, drones: int, tables: CoverTables | None = None
) -> WalkTable | None:
    """The truck-walk table of :func:`taopt.fleet.search._walk_bound` (None above
    :data:`~taopt.fleet.cover.WALK_MAX_CUSTOMERS` customers).

    A backward DP over (R, w): R the customers not yet coverable, w the truck's stop::

        value[∅, w] = 0   (tt(w, depot) under "return")
        value[R, w] = min over q with R ∩ cover[q] ≠ ∅ of
                      tt(w, q) + max(end(R, q), value[R \\ cover[q], q])
        end(R, q)   = max(max_{j ∈ R} o[q, j], (W(R) + max(0, ceil(m(R) / c) - D) ρ) / D)
                      (and tt(q, depot) under "return")

    where ``o[q, j] = min_w tt(q, w) + offset[w, j]`` (:class:`CoverTables`: offset is the
    least time from a truck standing at w to the objective's clock for j served from there;
    o adds the drive from q to such a stop w), D the truck's drones (the second term only
    when D >= 1), m(R) the drone-only customers of R, W(R) the sum of their works (the
    shortest flight into j from a stop or, when c > 1, another customer, plus the landing
    τ) and ρ the least recovery (the shortest flight from a customer to a stop, plus τ).

    Proof that a truck leaving w at T, whose later positions serve (by itself or by a
    sortie launched there) every customer of R, ends the objective's clock no sooner than
    ``T + value[R, w]``. Let its positions after w be ``w_1, w_2, ...`` with arrivals
    ``A_1 >= T + tt(w, w_1)`` and ``A_{i+1} >= A_i + tt(w_i, w_{i+1})`` (street shortest
    paths; waiting only delays). A customer j is served from a position i whose stop is in
    its cover set, no sooner than ``A_i + offset[w_i, j]`` (a sortie's later customers are
    still within ``d(w, j) + min_q d(j, q)`` of its launch: straight lines). Let R_i be the
    customers of R not coverable by ``w_1..w_{i-1}``. Each is served from a position
    ``i' >= i``, no sooner than ``A_i + tt(w_i, w_i') + offset[w_i', j] >= A_i + o[w_i, j]``;
    the drone-only ones by sorties launched at positions ``>= i``, so after ``A_i``: each
    costs its drone an in-leg and τ, at least ``ceil(m(R_i) / c)`` such sorties are flown,
    and a drone flying ``n_d >= 1`` of them is recovered ``n_d - 1`` times between them;
    these intervals are disjoint on a drone's timeline, so the D drones end their last
    service no sooner than ``A_i + (W(R_i) + max(0, q - D) ρ) / D``. So the clock (at least
    the last service under both objectives; under ``"return"`` also at least the truck's
    return, ``A_i + tt(w_i, depot)``) is at least ``A_i + end(R_i, w_i)`` for every i with
    R_i ≠ ∅. Keep the positions that cover something new, ``q_1 = w_{i_1}, q_2, ...``: by
    the triangle inequality of tt, ``A_{i_l} >= T +`` the drives of the DP's path through
    them, whose value is the max over l of those drives plus ``end(R_{i_l}, q_l)`` (and,
    after the last, the way home under ``"return"``); the DP's minimum is no larger.
    Precedences and the drones' sharing between trucks are relaxed.

    Notes
    -----
    Time and memory ``O(2^n s^2)``, vectorised over the sets of one size (chunked).
    """
    if problem.n > WALK_MAX_CUSTOMERS:
        return None
    tab = tables if tables is not None else CoverTables(problem)
    n, s = problem.n, problem.s
    off = tab.offset[drones > 0]  # (s, n)
    weights = 1 << np.arange(n, dtype=np.int64)
    cover = (np.isfinite(off) @ weights).astype(np.int64)  # (s,)
    # o[q, j]: from the truck's arrival at q to j's clock, served from q or a later stop
    reach = np.min(tab.tt[:, :, None] + off[None, :, :], axis=1)  # (s, n)
    size = 1 << n
    # worst[R, q] = max_{j in R} o[q, j] (0 for the empty set), built bit by bit
    worst = np.zeros((size, s))
    for j in range(n):
        worst[1 << j : 2 << j] = np.maximum(worst[: 1 << j], reach[None, :, j])
    if drones > 0 and n:
        p = problem
        only = np.array([not p.truck_servable(j) for j in range(n)], dtype=bool)
        into = p.flight_stop.min(axis=1)
        if p.capacity > 1 and n > 1:
            into = np.minimum(
                into, np.where(np.eye(n, dtype=bool), INF, p.flight_customer).min(axis=1)
            )
        work = np.where(only, into / p.v_drone + p.service_time, 0.0)
        rho = float(p.flight_stop.min() / p.v_drone + p.service_time)
        total = np.zeros(size)
        many = np.zeros(size, dtype=np.int64)
        for j in range(n):
            total[1 << j : 2 << j] = total[: 1 << j] + work[j]
            many[1 << j : 2 << j] = many[: 1 << j] + int(only[j])
        sorties = -(-many // p.capacity)
        drone_work = (total + np.maximum(0, sorties - drones) * rho) / drones
        worst = np.maximum(worst, drone_work[:, None])
    home = tab.home_truck if tab.ret else np.zeros(s)
    value = np.full((size, s), INF)
    value[0] = home
    tt = tab.tt
    masks = np.arange(size, dtype=np.int64)
    count = np.zeros(size, dtype=np.int64)
    for j in range(n):
        count += (masks >> j) & 1
    stops = np.arange(s)
    chunk = max(1, (1 << 21) // max(1, s * s))
    for k in range(1, n + 1):
        layer = masks[count == k]
        for lo in range(0, len(layer), chunk):
            R = layer[lo : lo + chunk]
            rest = R[:, None] & ~cover[None, :]  # (L, s)
            val = value[rest, stops[None, :]]
            end = np.maximum(worst[R], home[None, :])
            val = np.where(rest == 0, end, val)
            val[rest == R[:, None]] = INF  # q covers nothing of R
            value[R] = np.min(tt[None, :, :] + val[:, None, :], axis=2)
    return WalkTable([int(x) for x in cover], value)


# -- the one-drone sortie-time table of the label search --------------------------------------

#: Largest work (sets x starts x sorties x stops) :func:`sortie_time_table` takes on.
SORTIE_TIME_MAX_WORK = 400_000_000


def sortie_time_table(problem: FleetProblem, deadline: Deadline | None = None) -> np.ndarray | None:
    """``F[w, X]``: a lower bound on the time, after a drone aboard a truck at stop w is ready,
    until the drone has served exactly the drone-servable customers of X (bitmask over all
    customers; ``inf`` where X holds another customer or cannot be served).

    The relaxation of :func:`sortie_walks` with the precedences dropped and the truck given to
    the drone alone: a DP over (served set, stop) keeping the earliest recovery, from
    (∅, w) at 0; a sortie launched at stop v leaves no sooner than the truck can be at v
    (recovery at q plus ``tt(q, v)``), serves its customers after the flight legs and τ, and
    is recovered at a stop in range after the back leg and τ, no sooner than the truck can be
    there. Without release times the DP is shift-invariant, so a drone ready at time a ends
    no sooner than ``a + F[w, X]``. None when the table would take more than
    :data:`~taopt.fleet.cover.SORTIE_TIME_MAX_WORK` steps or the deadline expires."""
    n, s = problem.n, problem.s
    stab = SortieTables(problem, list(range(n)))
    size = 1 << n
    if size * s * s * max(1, stab.count) > SORTIE_TIME_MAX_WORK:
        return None
    tab = CoverTables(problem)
    tt = tab.tt
    R = np.full((size, s, s), INF)  # R[S, start, q]
    R[0, np.arange(s), np.arange(s)] = 0.0
    F = np.full((size, s), INF)  # F[S, start]
    F[0] = 0.0
    alive = np.zeros(size, dtype=bool)
    alive[0] = True
    gaps, valid = stab.gaps, stab.steps >= 0
    for S in range(size):
        if not alive[S]:
            continue
        if deadline is not None and S & 15 == 0 and deadline.expired():
            return None
        free = (stab.mask & S) == 0
        if not free.any():
            continue
        launch = np.min(R[S][:, :, None] + tt[None, :, :], axis=1)  # (start, v)
        first = np.min(launch[:, None, :] + stab.first_leg[free][None, :, :], axis=2)  # (st, i)
        t = first + stab.tau
        g, ok = gaps[free], valid[free]
        for pos in range(1, stab.size):
            t = np.where(ok[None, :, pos], t + g[None, :, pos], t)
        masks = stab.mask[free] | S
        np.minimum.at(F, masks, t.T)  # F[mask_i, st] <- t[st, i]
        back = t[:, :, None] + stab.back_leg[free][None, :, :]  # (st, i, q)
        rec = np.maximum(back, launch[:, None, :]) + stab.tau
        more = np.isfinite(rec).any(axis=(0, 2))
        if more.any():
            idx = masks[more]
            np.minimum.at(R, idx, rec[:, more, :].transpose(1, 0, 2))
            alive[idx] = True
    return np.ascontiguousarray(F.T)


#: Largest work (sets x sorties x launch stops x recovery stops) :func:`one_drone_table` takes
#: on.
ONE_DRONE_MAX_WORK = 600_000_000


def one_drone_table(problem: FleetProblem, deadline: Deadline | None = None) -> np.ndarray | None:
    """``V[u, X]`` of :func:`one_drone_tables` (None when that is)."""
    got = one_drone_tables(problem, deadline)
    return None if got is None else got[0]


def one_drone_tables(
    problem: FleetProblem, deadline: Deadline | None = None
) -> tuple[np.ndarray, np.ndarray] | None:
    r"""``(V, H)``, both indexed ``[u, X]``: ``V[u, X]``: a lower bound on the objective's clock, counted from the moment a truck at
    stop u and one drone aboard it are both ready, for that truck and that drone alone to serve
    exactly the drone-only customers of X by sorties, the precedence pairs inside X kept (``inf``
    where X holds another customer, or no such plan exists): the time of X's last service
    (``"last_service"``), or of the truck and the drone back at the depot (``"return"``).

    A backward DP over (X, u), exact for the relaxed problem below::

        V[∅, u] = 0   (tt(u, depot) under "return")
        V[X, u] = min_v tt(u, v) + H[X, v]
        H[X, v] = min over the first sortie Q = (q_1, ..., q_m) ⊆ X (m <= c, launched at v,
                  every predecessor of q_i inside X among q_1, ..., q_{i-1}) and its recovery
                  stop q (d(v, q_1) + the legs + d(q_m, q) <= range) of
                  f(Q, v)                                       (Q = X, "last_service")
                  max(f(Q, v) + ft(q_m, q), tt(v, q)) + τ + V[X \ Q, q]   (otherwise)

    with ``f(Q, v) = ft(v, q_1) + τ + Σ_i (ft(q_{i-1}, q_i) + τ)`` the last service after the
    launch. Every time is a max-plus expression of the start with no release, so the DP is
    shift-invariant: a drone ready at a (its truck at u, leaving no sooner than a) ends no
    sooner than ``a + V[X, u]``.

    *Why the precedences inside X hold* (Chapter 6's multi-drone reading of the one-drone
    relaxation of :func:`taopt.models.fleet._one_drone_floor`): in any plan, one drone's
    services are strictly ordered in time (two of them are at least τ apart; with τ = 0 ties
    are reordered freely, changing no time), so a pair r -> j with both served by the same
    drone has r before j in that drone's sequence. Giving that drone its own copy of the truck
    (same stops in the same order, waiting only for this drone) makes no service and no return
    later. So the drone's copy is a one-truck, one-drone plan of X whose sequence respects the
    pairs inside X, and the DP over all such plans (with the truck's wait for a recovery only
    relaxed to ``tt(v, q)`` after the launch) is at most its objective. Pairs with one end
    outside X are dropped (a relaxation).

    ``H[v, X]`` is the same clock when the drone's first sortie is launched at v itself (the
    DP's ``H``; ``H[v, ∅] = V[v, ∅]``): a drone ready at a whose truck stands at v and which
    launches there ends no sooner than ``a + H[v, X]`` (and ``V[u, X] = min_v tt(u, v) +
    H[v, X]``). The label search uses it for a drone that launches before its truck leaves
    its stop (:func:`taopt.fleet.search._sortie_time_bound`).

    None when the table would take more than :data:`~taopt.fleet.cover.ONE_DRONE_MAX_WORK`
    steps or the deadline expires (checked every 16 sets)."""
    import itertools

    p = problem
    n, s = p.n, p.s
    only = [j for j in range(n) if p.drone_servable(j) and not p.truck_servable(j)]
    N = len(only)
    # Σ over sets X ⊆ only of the sorties inside X (N!/(N-m)! of m customers, each in
    # 2^(N-m) sets), times s^2, counted before any sortie is listed
    work = sum(math.perm(N, m) << (N - m) for m in range(1, min(p.capacity, N) + 1)) * s * s
    if work > ONE_DRONE_MAX_WORK:
        return None
    seqs = [q for m in range(1, p.capacity + 1) for q in itertools.permutations(only, m)]
    size = 1 << n
    count = len(seqs)
    allowed = sum(1 << j for j in only)
    tt = np.asarray(p.truck_time, dtype=float)
    fs, fc = p.flight_stop, p.flight_customer
    vd, tau, limit = p.v_drone, p.service_time, p.flight_limit
    pred = [0] * n
    for r, j in p.precedences:
        pred[j] |= 1 << r
    V = np.full((size, s), INF)
    V[0] = tt[:, p.depot] if p.objective == "return" else 0.0
    HX = np.full((size, s), INF)  # H per set (rows X, as V)
    HX[0] = V[0]
    if not seqs:
        return np.ascontiguousarray(V.T), np.ascontiguousarray(HX.T)
    mask = np.zeros(count, dtype=np.int64)
    bad = np.zeros(count, dtype=np.int64)
    f = np.full((count, s), INF)  # launch -> last service
    rec = np.full((count, s, s), INF)  # launch -> recovery done, per (launch v, recovery q)
    for i, q in enumerate(seqs):
        prefix = 0
        inner = 0.0
        t = tau
        for pos, j in enumerate(q):
            bad[i] |= pred[j] & ~prefix
            prefix |= 1 << j
            if pos:
                inner += float(fc[q[pos - 1], j])
                t += float(fc[q[pos - 1], j]) / vd + tau
        mask[i] = prefix
        dist = fs[q[0]][:, None] + inner + fs[q[-1]][None, :]  # (v, q)
        ok = dist <= limit
        last = fs[q[0]] / vd + t  # (v,)
        f[i] = np.where(ok.any(axis=1), last, INF)
        back = np.maximum(last[:, None] + fs[q[-1]][None, :] / vd, tt) + tau
        rec[i] = np.where(ok, back, INF)
    last_service = p.objective != "return"
    home = tt[:, p.depot]
    for X in range(1, size):
        if X & ~allowed:
            continue
        if deadline is not None and X & 15 == 0 and deadline.expired():
            return None
        idx = np.flatnonzero(((mask & ~X) == 0) & ((bad & X) == 0))
        if not len(idx):
            continue
        rest = X ^ mask[idx]
        final = rest == 0
        H = np.full(s, INF)
        if final.any():
            fi = idx[final]
            if last_service:
                H = np.min(f[fi], axis=0)
            else:
                H = np.min(rec[fi] + home[None, None, :], axis=(0, 2))
        more = ~final
        if more.any():
            mi = idx[more]
            cand = np.min(rec[mi] + V[rest[more]][:, None, :], axis=(0, 2))
            H = np.minimum(H, cand)
        HX[X] = H
        V[X] = np.min(tt + H[None, :], axis=1)
    return np.ascontiguousarray(V.T), np.ascontiguousarray(HX.T)


__all__ = [
    "WALK_MAX_CUSTOMERS",
    "CoverTables",
    "SortieTables",
    "WalkTable",
    "cover_bound",
    "coverable",
    "fleet_cover_bound",
    "one_drone_table",
    "one_drone_tables",
    "ONE_DRONE_MAX_WORK",
    "fleet_coverable",
    "release_times",
    "sortie_time_table",
    "sortie_walks",
    "walk_table",
]
