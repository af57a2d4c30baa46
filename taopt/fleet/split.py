"""Several trucks, any drones per truck: exact by splitting the customers over the trucks.

:func:`split_search` generalises :func:`taopt.fleet.sorties.split_dp` (one drone per truck,
drone-only customers) to any fleet with K >= 2: any D_k, any service modes, either objective.

*Split.* A plan assigns every customer to one truck k (served by the truck itself or by one of
its drones); the sets (X_1, ..., X_K) are its *split*. The optimum is the least, over the
splits, of the optimum restricted to that split.

*Bound of a split.* Drop, from the plans with split X, every precedence pair (r, j) with r
and j on different trucks, and keep, for each truck, the pairs of the transitive closure of
G^p inside X_k. What is left is K independent one-truck problems: truck k with its own D_k
drones serving exactly X_k (:func:`sub_problem`). Every pair kept still holds in each plan
of split X: a closure pair r ->* j is a chain r -> m_1 -> ... -> j of G^p's pairs, each with
``t <= t'``, so ``t_r <= t_j`` whichever trucks serve the m_i. Restricted to truck k, a plan's
event times satisfy every constraint of truck k's sub-problem (the same travel, flight,
range, capacity and service rules, and only pairs the plan satisfies), and the sub-problem's
earliest schedule has the least times satisfying them (a system of ``t >= t' + const``
and ``t >= max(...)`` constraints), so truck k's part of the objective is at least
``opt_k(X_k)`` — the last service among X_k (``"last_service"``) or truck k back home with
its drones (``"return"``). The plan's objective is the maximum over the trucks, so

``f(plan) >= max_k opt_k(X_k)`` for every plan of split X,

and the least such bound over the splits left is a bound on the optimum. Any valid lower
bound ``lb_k(X_k) <= opt_k(X_k)`` may replace ``opt_k``; three are used, cheapest first (each
lifted to the supersets, *Monotonicity* below):

0. ``max_{j in X} e_j`` (:func:`taopt.fleet.bounds.earliest_service`, the fastest any of truck
   k's vehicles can serve j; a truck without drones only by itself) and the drone work
   ``(Σ_{j in X drone-only} a_j + max(0, ceil(m / c) - D_k) ρ) / D_k``: a drone-only customer j
   costs the drone serving it at least ``a_j`` (its shortest in-leg, from a stop or, when
   c > 1, another customer, and τ), m such customers need at least ``ceil(m / c)`` sorties,
   hence at least ``ceil(m / c) - D_k`` recoveries before the drones' last services, each at
   least ρ (the shortest flight customer -> stop and τ); these intervals are disjoint on each
   drone's timeline from 0, so some drone's last service is at least the mean (the proof of
   :func:`taopt.fleet.bounds.work_bound`). Computed for every X at once;
1. :func:`taopt.fleet.bounds.fleet_lower` and the sortie-walk bound
   :func:`taopt.fleet.cover.fleet_cover_bound` of the sub-problem (bisected up to the best
   plan's value: a part that cannot beat it is priced at it);
2. ``opt_k(X_k)`` itself, by the label search (:func:`taopt.fleet.search.label_search`) of the
   sub-problem, cut off at the best plan's value; cached per (X_k, D_k). The dropped
   cross-truck pairs come back as *releases* (:func:`_releases`): for a closure pair (r, j)
   with r on another truck, every plan has ``t_j >= t_r >= e'_r`` (``e'`` the earliest
   service raised along G^p, :func:`_earliest`), so the part is solved with ``t_j >= e'_r``
   added — still a relaxation of every plan of the split. Its part plans then allow for the
   waits, and combine into better plans: on the shipped example a plan of 120.0, the root
   bound, certified in seconds (without releases: 121.16 [120] after 600 s). The releases
   depend on X_k alone, so the cache key is unchanged. The solve runs in doubling time
   slices (:data:`PART_SLICE`) so other splits get a turn; a slice that stops leaves its open
   search in the part's memo and the next slice continues it (``memo`` of
   :func:`~taopt.fleet.search.label_search`: valid under the lower cutoff and higher floor
   it then gets), up to :data:`PART_MEMO_LABELS` labels kept over all parts.

*Monotonicity.* For one truck with its drones (a part, with or without releases), dropping a
customer never raises the optimum: take an optimal plan of the part and remove customer j.
If the truck served j, the truck keeps its walk and skips that service; if a drone served j,
its sortie flies straight from j's predecessor in the sortie (or the launch stop) to j's
successor (or the recovery stop), no longer than through j (Euclidean flights: the triangle
inequality), so it stays within the range, and a sortie left empty is dropped. Every event
time of the earliest schedule is a maximum of sums of nonnegative terms over the events
before it (travel, flight, τ, the releases, the precedence pairs); the edit removes terms or
shortens them, and the pairs and releases left are those of the smaller part, so no event is
later, and neither is the last service or the return. Hence, for parts Y ⊆ X with the same
drones and releases ``r_X(j) >= r_Y(j)`` on Y (:func:`_releases`: the latest earliest service of
j's closure predecessors outside the part, which holds when no predecessor in X \\ Y is later
than those outside X), ``opt(Y) <= opt(X)``: a lower bound proven for Y is one for X. Bounds of
the part without releases (the set bounds, :func:`taopt.fleet.bounds.fleet_lower`, the
sortie-walk bound) lift to every superset; the label search's bounds (with releases) to the
supersets that keep Y's releases. :func:`_subset_max` closes the set bounds this way, and each
refinement is lifted into the cache at once.

*Drone split bound.* Level 0 also holds :func:`_drone_split_bounds`: the part's drone-only
customers split over its drones, each drone with its own copy of the truck, priced by the
one-drone table :func:`taopt.fleet.cover.one_drone_table` (on fleet10, K2D2c2, it raises the
least split bound before any part is refined from about 140 to 199-247).

*Repair* (two trucks, a split whose combined plan waits, first): each part in turn is solved
again with the other part's service times in that plan as releases (and its own), cut off at
the best value, and combined with the other part's plan; a plan, not a bound. On fleet10
seed 0 the combined plan was 232.34 against the split's bound 232.16; the repaired plan is
232.16, which certified the run at 240 s (no other plan or bound had closed it in 600 s).

*Topological releases* (a split whose combined plan waits, before its coupled search): in
a topological order of G^p, ``L_j`` is the larger of ``early[j]``, ``L_r`` for every closure
predecessor r on another truck, and the last-service optimum (label search, at most
:data:`CHAIN_SECONDS`, its proven bound when stopped) of j's own truck with its drones serving
exactly j and its closure predecessors on that truck under the releases L. Every plan of the
split has ``t_j >= L_j``, by induction: ``t_j >= t_r >= L_r``; and j's truck's plan with its
other customers dropped is a plan of that sub-problem meeting the releases L on its members
(its earliest schedule is no later than the plan's own times, which meet them), in which
every member is served by t_j. Each part is then solved again with releases L (L is at least
:func:`_releases`, so the part's cached bound is a valid floor); the larger of the split's key
and the parts' values bounds every plan of the split, and the split goes back to the heap
with it (once per split).

*Search.* The splits are kept in a heap by their current bound (the maximum of their parts'
current bounds); identical trucks (same drone count) make splits that differ by a
permutation of those trucks the same, so each is listed once. The least split is refined:
its cheapest unrefined part moves one level up, and the split is pushed back with its new
bound. When every part is exact, the parts' plans are combined into one fleet plan and
scored by :func:`taopt.fleet.evaluate.evaluate_fleet` (the cross-truck precedences may make a
vehicle wait, or deadlock). If its value equals the split's bound, the split is solved;
otherwise the coupled problem restricted to the split is solved, the split's bound as a
floor and the best value as a cutoff, in doubling time slices like the parts' (the split
goes back to the heap with the bound each slice proves): with two trucks whose cross pairs
go one way, by :func:`taopt.fleet.coupled.leader_search` (exact; :data:`LEADER_SHARE` of the
time left at its first try); with pairs both ways, by
:func:`taopt.fleet.twoway.two_way_search` (exact: a box search over the times of the
follower's cross predecessors, each box bounded by the leader search with releases and
follower deadlines; fleet10 seed 2's open split closed in 84 s); with more trucks, by the
label search with ``truck_of`` (each customer only on its truck) and the split's topological
releases (met by every plan of the split, so the optimum over the split is the same). A box
search certified within :data:`CERTIFY` returns its proven bound, and the split goes back to
the heap with it. The run stops when the best plan is no worse than the least bound of the
splits left (certified), or at the wall-clock limit with the best plan and that least bound
(proven). Unbalanced splits are never solved: their cheap bound stays above the optimum.
The part solves run without the label search's beam pass (they are cut off at the best
plan; the beam took 40-65 % of a 5-customer part's time). With two trucks, a part that
becomes exact is paired at once with its complement when that one is exact too, and the
combined plan scored (an incumbent before the split reaches the top of the heap).

*Which part of a split first.* The cheap levels first; among the parts that need a label
search, the one with the fewest slices stopped so far, then the highest bound, then the
fewest customers. A split is closed as soon as *one* part's bound reaches the best plan, and
the parts' costs differ by orders of magnitude (K2D3c1: one 4-customer part needed 14k labels,
17 s at load 6, to reach 160.76, its complement 105 labels, 0.4 s): after a stopped slice the
other part gets its turn, so the cheaper proof is found within about twice its own cost.
Any order is exact: every part bound is proven, and a split's key is their maximum.

*Eager complement* (two trucks, a primal step). When a part becomes exact with a plan below
the best one and its complement is open with a bound below the best, the complement is
solved at once (up to :data:`EAGER_SLICES` doubling slices while its bound stays below the
best plan: the same cached, lifted solve its split would run), the two plans combined, and a
combined plan that waits repaired (*Repair*, once per split). Good plans then appear before
their split reaches the top of the heap, and every later part search is cut off lower. It
changes no bound.

The result's ``trace`` records, with seconds since the start, each rise of the least bound
(``"least"``), each better plan (``"best"``, ``"paired"``, ``"repaired"``), each exact part
solve (``"part"``: customers, seconds, how it stopped, the bound before, the bound proved,
the split's key), each eager complement solve (``"eager"``: the complement's mask) and each
coupled search (``"coupled"``).
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError
from taopt.fleet.evaluate import best_of, evaluate_fleet
from taopt.fleet.operations import _submasks
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.runtime import Deadline

#: Most customers (the per-set bounds are arrays over the 2^n customer sets).
SPLIT_MAX_N = 16

#: Most splits listed (after identical trucks are merged).
SPLIT_MAX_SPLITS = 400_000

#: Share of the time left that a repair, a tightening or (three or more trucks) a coupled
#: search's first slice may take (doubled at each retry of a coupled search).
SLICE = 0.1

#: Share of the time left that a part's first exact solve may take, at least
#: :data:`PART_SLICE_MIN` seconds (doubled at each retry, its search resumed from its memo):
#: short first slices let the two parts of a split race (module docstring, *Which part of a
#: split first*), and a resumed slice costs about what one run does.
PART_SLICE = 0.02

#: Least seconds of a part's first exact slice (:data:`PART_SLICE`).
PART_SLICE_MIN = 0.25

#: Most slices of one eager complement solve (module docstring, *Eager complement*; each
#: slice doubles, so about 15 first slices in all).
EAGER_SLICES = 4

#: Most labels the split search keeps in its parts' label-search memos (about 1 KB each, so
#: about 0.5 GB at most):
#: a part stopped by its time slice keeps its open search for its next slice
#: (:func:`~taopt.fleet.search.label_search`, ``memo``); past this total the least recently
#: solved parts' memos are dropped (those parts then restart from scratch).
PART_MEMO_LABELS = 500_000

#: Share of the time left that the drone-split set bounds (:func:`_drone_split_bounds`) may take.
DRONE_SPLIT_SHARE = 0.25

#: Share of the time left that one leader search (:func:`taopt.fleet.coupled.leader_search`,
#: a split whose cross pairs go one way) may take at its first try (doubled at each retry).
LEADER_SHARE = 0.5

#: Most seconds of one exact chain solve (:func:`split_search`'s ``exact_chain``: the other
#: truck's last service over a cross predecessor and its ancestors there).
CHAIN_SECONDS = 1.0

#: Relative tolerance of the stop rule (best <= bound (1 + CERTIFY)), as the fleet's exact
#: method uses for its root bound.
CERTIFY = 1e-6

INF = math.inf


def count_splits(problem: FleetProblem) -> int:
    """The number of splits :func:`split_search` lists: customer assignments to the trucks,
    those differing by a permutation of trucks with equal drone counts taken once (an upper
    estimate, ``K^n / Π g!`` over the groups g, rounded up)."""
    groups: dict[int, int] = {}
    for d in problem.drones:
        groups[d] = groups.get(d, 0) + 1
    denominator = math.prod(math.factorial(g) for g in groups.values())
    return -(-(problem.K**problem.n) // denominator)


def split_applies(problem: FleetProblem) -> bool:
    """Several trucks, at most :data:`SPLIT_MAX_N` customers and about
    :data:`SPLIT_MAX_SPLITS` splits (:func:`count_splits`)."""
    return problem.K >= 2 and problem.n <= SPLIT_MAX_N and count_splits(problem) <= SPLIT_MAX_SPLITS


def _closure(problem: FleetProblem) -> list[tuple[int, int]]:
    import networkx as nx

    return sorted(
        (int(r), int(j)) for r, j in nx.transitive_closure_dag(problem.precedence_graph).edges
    )


def sub_problem(
    problem: FleetProblem,
    members: list[int],
    drones: int,
    closure: list[tuple[int, int]] | None = None,
) -> FleetProblem:
    """One truck with ``drones`` drones serving exactly the customers ``members`` (their
    order gives the sub-problem's indices), under the pairs of the transitive closure of
    G^p inside ``members`` (module docstring: why that is valid); everything else as in
    ``problem``."""
    pairs = _closure(problem) if closure is None else closure
    index = {j: i for i, j in enumerate(members)}
    return FleetProblem(
        customers=problem.customers[members],
        stops=problem.stops,
        graph=problem.graph,
        depot=problem.depot,
        drones=[drones],
        capacity=problem.capacity,
        flight_range=problem.flight_range,
        v_truck=problem.v_truck,
        v_drone=problem.v_drone,
        service=[problem.service[j] for j in members],
        customer_stop=[problem.customer_stop[j] for j in members],
        precedences=[(index[r], index[j]) for r, j in pairs if r in index and j in index],
        service_time=problem.service_time,
        objective=problem.objective,
        name=f"{problem.name} part {members}",
    )


def _set_bounds(problem: FleetProblem, drones: int) -> np.ndarray:
    """Level 0 (module docstring): for every customer set X (bit mask), a lower bound on the
    optimum of one truck with ``drones`` drones serving exactly X (inf when it cannot)."""
    from taopt.fleet.bounds import _earliest_by_mode

    n = problem.n
    truck_e, drone_e = _earliest_by_mode(problem)
    e = truck_e.copy()
    drone_ok = [problem.drone_servable(j) for j in range(n)]
    only_drone = [drone_ok[j] and not problem.truck_servable(j) for j in range(n)]
    if drones > 0:
        e = np.minimum(e, drone_e)
    fs, fc = problem.flight_stop, problem.flight_customer
    limit, vd, tau, c = (
        problem.flight_limit,
        problem.v_drone,
        problem.service_time,
        problem.capacity,
    )
    a = np.zeros(n)
    for j in range(n):
        if not only_drone[j]:
            continue
        legs = fs[j][fs[j] <= limit]
        shortest = float(legs.min()) if legs.size else INF
        if c > 1:
            others = [float(fc[i, j]) for i in range(n) if i != j and drone_ok[i]]
            shortest = min([shortest, *others])
        a[j] = shortest / vd + tau
    rho = float(fs.min() / vd + tau)
    size = 1 << n
    reach = np.zeros(size)
    work = np.zeros(size)
    count = np.zeros(size, dtype=np.int64)
    for j in range(n):
        bit = 1 << j
        lo = np.arange(bit)
        for start in range(bit, size, 2 * bit):
            idx = start + lo
            reach[idx] = np.maximum(reach[idx - bit], e[j])
            work[idx] = work[idx - bit] + a[j]
            count[idx] = count[idx - bit] + int(only_drone[j])
    if drones == 0:
        return np.where(count > 0, INF, reach)
    sorties = -(-count // c)
    work = work + np.maximum(0, sorties - drones) * rho
    return np.maximum(reach, work / drones)


def _subset_max(values: np.ndarray) -> np.ndarray:
    """``out[X] = max_{Y ⊆ X} values[Y]`` (a superset-closed copy), by one pass per bit.

    A bound of a part lifts to every superset part by monotonicity (module docstring,
    *Monotonicity*): this makes any per-set bound table monotone, so a set never gets less
    than what one of its subsets already proves."""
    out = np.array(values, dtype=float, copy=True)
    size = out.shape[0]
    bit = 1
    while bit < size:
        view = out.reshape(-1, 2 * bit)
        np.maximum(view[:, bit:], view[:, :bit], out=view[:, bit:])
        bit <<= 1
    return out


def _drone_split_bounds(
    problem: FleetProblem,
    closure: list[tuple[int, int]],
    drone_counts: set[int],
    deadline: Deadline,
) -> dict[int, np.ndarray]:
    """For every customer set X (bit mask) and drone count D in ``drone_counts``, a lower
    bound on the optimum of one truck with D drones serving exactly X (the part of
    :func:`sub_problem`, with or without releases): the drones' sets split over their own
    copies of the truck,

    ``B_1[X] = V[depot, X ∩ O]``, ``B_D[X] = min_{A ⊆ X} max(B_1[A], B_{D-1}[X \\ A])``,

    ``V`` the one-drone table :func:`taopt.fleet.cover.one_drone_table` of ``problem`` with the
    precedence closure as its pairs, O the drone-only customers.

    *Proof.* Let P be a plan of the part. Dropping its customers outside O never raises its
    objective (module docstring, *Monotonicity*), so ``f(P) >= opt(X ∩ O)``, and it is enough
    to bound a plan P' serving exactly X ∩ O, all by drones. Let A_1, ..., A_D be the sets
    its D drones serve (a partition of X ∩ O). For each drone d, give it its own copy of the
    truck (same stops in the same order, waiting only for drone d): no service and no return
    of drone d is later (the one-drone relaxation's argument,
    :func:`taopt.fleet.cover.one_drone_table`), and the copy is a one-truck, one-drone plan of
    A_d that respects every closure pair inside A_d (a closure pair holds in every plan of the
    part, :func:`sub_problem`; one drone serves its customers in time order), so drone d's
    last service (or its copy's return under ``"return"``) is at least ``V[depot, A_d]``.
    The part's objective is at least the maximum over its drones, hence at least
    ``max_d V[depot, A_d] >= B_D[X]`` (the recursion takes the least such maximum over every
    split of X into D sets, empty ones included, ``V[depot, ∅] = 0``). Releases only delay
    the part, so the bound holds with them.

    Zeros (no bound) when the table exceeds its work cap or the deadline passes, or n > 14
    (the min-max convolution is ``3^n`` steps)."""
    from taopt.fleet.cover import one_drone_table

    n = problem.n
    size = 1 << n
    zero = {d: np.zeros(size) for d in drone_counts}
    if n > 14 or max(drone_counts, default=0) == 0:
        return zero
    table = one_drone_table(problem.replace(precedences=closure), deadline)
    if table is None:
        return zero
    only = sum(
        1 << j for j in range(n) if problem.drone_servable(j) and not problem.truck_servable(j)
    )
    one = np.asarray(table[problem.depot], dtype=float)[np.arange(size) & only]
    out = {1: one}
    for D in range(2, max(drone_counts) + 1):
        prev = out[D - 1]
        cur = np.empty(size)
        for X in range(size):
            if X & 255 == 0 and deadline.expired():
                return zero
            A = _submasks(X, empty=True)
            cur[X] = np.min(np.maximum(one[A], prev[X ^ A]))
        out[D] = cur
    return {d: (out[d] if d > 0 else np.zeros(size)) for d in drone_counts}


def _chain_tables(
    problem: FleetProblem,
    closure: list[tuple[int, int]],
    drone_counts: set[int],
    deadline: Deadline,
) -> dict[int, np.ndarray]:
    """Per drone count D and customer set A, a release-free lower bound on the *last service*
    of one truck with D drones serving exactly A: :func:`_set_bounds` and
    :func:`_drone_split_bounds` of the problem under ``"last_service"``, closed over subsets
    (:func:`_subset_max`); the ``chain`` of :func:`_releases`."""
    ls = problem.replace(objective="last_service")
    split = _drone_split_bounds(ls, closure, drone_counts, deadline)
    return {d: _subset_max(np.maximum(_set_bounds(ls, d), split[d])) for d in drone_counts}


def _splits(problem: FleetProblem) -> list[tuple[int, ...]]:
    """Every split (one mask per truck), identical trucks' permutations once."""
    n, K = problem.n, problem.K
    seen: set[tuple[int, ...]] = set()
    out: list[tuple[int, ...]] = []
    groups: dict[int, list[int]] = {}
    for k, d in enumerate(problem.drones):
        groups.setdefault(d, []).append(k)
    for assign in itertools.product(range(K), repeat=n):
        masks = [0] * K
        for j, k in enumerate(assign):
            masks[k] |= 1 << j
        for ks in groups.values():
            if len(ks) > 1:
                ordered = sorted((masks[k] for k in ks), reverse=True)
                for k, m in zip(ks, ordered, strict=True):
                    masks[k] = m
        key = tuple(masks)
        if key in seen:
            continue
        seen.add(key)
        out.append(key)
    return out


class _Part:
    """One truck's part (mask, drone count): its bound, level and, when exact, its plan."""

    __slots__ = ("attempts", "bound", "level", "plan")

    def __init__(self, bound: float) -> None:
        self.bound = bound
        self.level = 0
        self.plan: FleetPlan | None = None
        self.attempts = 0  # exact solves stopped by their time slice


def _members(mask: int) -> list[int]:
    return [j for j in range(mask.bit_length()) if mask >> j & 1]


def _lift(plan: FleetPlan, members: list[int]) -> tuple[list[int], list[tuple[int, int]], Any]:
    """A one-truck sub-plan's route, truck services and sorties in the full indices."""
    served = [(p, members[j]) for p, j in plan.truck_service[0]]
    sorties = [
        [Sortie(s.launch, tuple(members[j] for j in s.customers), s.recovery) for s in drone]
        for drone in plan.sorties[0]
    ]
    return list(plan.routes[0]), served, sorties


def _restrict(
    problem: FleetProblem, plan: FleetPlan | None, mask: int, drones: int
) -> FleetPlan | None:
    """The part of ``plan`` flown by a truck with ``drones`` drones serving exactly the
    customers of ``mask``, as a plan of that part's sub-problem (an incumbent for its
    search: feasible there, the sub-problem having only fewer constraints), or None."""
    if plan is None:
        return None
    members = _members(mask)
    index = {j: i for i, j in enumerate(members)}
    for k in range(problem.K):
        if problem.drones[k] != drones:
            continue
        mine = {j for _, j in plan.truck_service[k]} | {
            j for drone in plan.sorties[k] for sortie in drone for j in sortie.customers
        }
        if mine != set(members):
            continue
        return FleetPlan(
            [plan.routes[k]],
            [[(p, index[j]) for p, j in plan.truck_service[k]]],
            [
                [
                    [
                        Sortie(s.launch, tuple(index[j] for j in s.customers), s.recovery)
                        for s in drone
                    ]
                    for drone in plan.sorties[k]
                ]
            ],
        )
    return None


def _earliest(problem: FleetProblem) -> np.ndarray:
    """A time before which no plan serves customer j:
    :func:`~taopt.fleet.bounds.earliest_service`, raised along the precedences (t_j >= t_r
    for r -> j)."""
    import networkx as nx

    from taopt.fleet.bounds import earliest_service

    early = earliest_service(problem)
    for j in nx.topological_sort(problem.precedence_graph):
        for r in problem.precedence_graph.predecessors(j):
            early[j] = max(early[j], early[r])
    return early


def _releases(
    closure: list[tuple[int, int]],
    early: np.ndarray,
    mask: int,
    members: list[int],
    chain: np.ndarray | None = None,
) -> list[float]:
    """Per member of a part (in the part's numbering), the latest :func:`_earliest` of its
    predecessors served by other trucks (0 without one).

    Valid for the split's bound: in every plan, a closure pair (r, j) with r outside the part
    gives t_j >= t_r >= early[r], so truck k's part of any plan of the split is a plan of its
    sub-problem that also meets these releases, and its objective there is at least the
    optimum with them (the earliest schedule only moves later when a release is added).

    ``chain`` (two trucks): per customer set A, a lower bound on the *last service* of one
    truck with the other truck's drones serving exactly A (release-free: :func:`_set_bounds`
    and :func:`_drone_split_bounds` under ``"last_service"``). With two trucks the other
    truck serves exactly the complement O of the part, so for a closure pair (r, j) with r in
    O, ``t_r >= chain[A_r]``, ``A_r = {r} ∪ (r's closure predecessors in O)``: the other
    truck's plan with every customer outside A_r dropped serves A_r no later (*Monotonicity*,
    module docstring) and keeps the pairs inside A_r, and in it every member of A_r is
    served by t_r (they precede r), so its last service, at least ``chain[A_r]``, is at most
    t_r. The release of j is then the larger of ``early[r]`` and that."""
    where = {j: i for i, j in enumerate(members)}
    out = [0.0] * len(members)
    ancestors: dict[int, int] = {}
    if chain is not None:
        for r, j in closure:
            ancestors[j] = ancestors.get(j, 0) | 1 << r
    other = ~mask & ((1 << len(early)) - 1)
    for r, j in closure:
        if j in where and not mask >> r & 1:
            value = float(early[r])
            if chain is not None:
                value = max(value, float(chain[(ancestors.get(r, 0) & other) | 1 << r]))
            out[where[j]] = max(out[where[j]], value)
    return out


def _lead(problem: FleetProblem, owner: list[int]) -> int:
    """Two trucks, cross pairs both ways: the truck with more cross closure pairs leaving it
    (the default leader of :func:`taopt.fleet.coupled.leader_search`'s relaxation)."""
    ways = [0, 0]
    for r, j in _closure(problem):
        if owner[r] != owner[j]:
            ways[owner[r]] += 1
    return 0 if ways[0] >= ways[1] else 1


def _dominates(outer: dict[int, float], inner: dict[int, float], mask: int) -> bool:
    """Whether the releases ``outer`` (customer -> release, of a superset part) are no earlier
    than ``inner`` (of the part ``mask``) on every member of ``mask``: the condition of
    *Monotonicity* (module docstring) for lifting a bound proven with releases."""
    return all(outer.get(j, 0.0) >= inner.get(j, 0.0) - 1e-12 for j in _members(mask))


def _split_releases(
    problem: FleetProblem,
    owner: list[int],
    closure: list[tuple[int, int]],
    early: np.ndarray,
    deadline: Deadline,
) -> list[float]:
    """The *topological releases* ``L_j`` of the split ``owner`` (customer -> truck; module
    docstring: every plan of that split has ``t_j >= L_j``)."""
    import networkx as nx

    from taopt.fleet.search import label_search

    last_service = problem.replace(objective="last_service")
    preds: list[list[int]] = [[] for _ in range(problem.n)]
    for r, j in closure:
        preds[j].append(r)
    L = [float(x) for x in early]
    for j in nx.topological_sort(problem.precedence_graph):
        k = owner[j]
        for r in preds[j]:
            if owner[r] != k:
                L[j] = max(L[j], L[r])
        own = sorted({r for r in preds[j] if owner[r] == k} | {j})
        if len(own) >= 2 and not deadline.expired():
            left = deadline.remaining()
            found = label_search(
                sub_problem(last_service, own, problem.drones[k], closure),
                time_limit=CHAIN_SECONDS if left is None else min(left, CHAIN_SECONDS),
                floor=L[j],
                release=[L[a] for a in own],
                beam=0,
            )
            if found["stopped_by"] == "optimal" and found["plan"] is not None:
                L[j] = max(L[j], float(found["value"]))
            elif found["stopped_by"] == "time_limit":
                L[j] = max(L[j], float(found["bound"]))
    return L


def split_search(
    problem: FleetProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    max_labels: int | None = None,
    floor: float = 0.0,
) -> dict[str, Any]:
    """Exact by splitting (module docstring); K >= 2 (:func:`split_applies`).

    ``floor``: a known lower bound on the optimum (e.g. the root sortie-walk bound): the run
    also stops when the best plan reaches it, and the bound returned is at least it.

    Returns a dict like :func:`taopt.fleet.search.label_search`'s: ``plan``, ``value``,
    ``bound`` (proven), ``stopped_by`` ("optimal", "time_limit", "infeasible"), and the
    counters ``splits`` (examined: popped at least once), ``of_splits`` (listed),
    ``solved_splits`` (closed by their parts' plans), ``coupled`` (coupled searches run),
    ``parts`` (exact part solves) and ``part_seconds`` (the slowest part solves, as
    ``(customers, drones, seconds)``).
    """

    from taopt.fleet.bounds import fleet_lower
    from taopt.fleet.coupled import leader_of, leader_search
    from taopt.fleet.cover import fleet_cover_bound
    from taopt.fleet.search import _simple_plan, label_search
    from taopt.fleet.twoway import two_way_search

    deadline = Deadline(time_limit)
    deadline_start = time.perf_counter()
    closure = _closure(problem)
    early = _earliest(problem)
    best, best_plan = best_of(problem, (incumbent, _simple_plan(problem)))
    counts = set(problem.drones)
    left = deadline.remaining()
    split_bounds = _drone_split_bounds(
        problem, closure, counts, Deadline(None if left is None else DRONE_SPLIT_SHARE * left)
    )
    level0 = {d: _subset_max(np.maximum(_set_bounds(problem, d), split_bounds[d])) for d in counts}
    full = (1 << problem.n) - 1
    chain: dict[int, np.ndarray | None] = {d: None for d in counts}
    if problem.K == 2:  # the other truck's last-service bounds (:func:`_releases`)
        if problem.objective == "last_service":
            chain = {d: level0[d].copy() for d in counts}
        else:
            left = deadline.remaining()
            tables = _chain_tables(
                problem,
                closure,
                counts,
                Deadline(None if left is None else DRONE_SPLIT_SHARE * left),
            )
            chain = {d: tables[d] for d in counts}
    released_at: dict[tuple[int, int], dict[int, float]] = {}
    ancestors: dict[int, int] = {}
    for r, j in closure:
        ancestors[j] = ancestors.get(j, 0) | 1 << r
    chained: set[tuple[int, int]] = set()
    last_service = problem.replace(objective="last_service")

    def exact_chain(A: int, d: int, table: np.ndarray) -> None:
        """Raise ``table[A]`` (a chain bound, :func:`_releases`) to the last-service optimum
        of one truck with ``d`` drones serving exactly A (the label search, release-free, at
        most :data:`CHAIN_SECONDS`; its proven bound when stopped): still a lower bound on
        that last service, so the chain's argument holds. Sets of two or more customers,
        once each."""
        if A & (A - 1) == 0 or (A, d) in chained or deadline.expired():
            return
        chained.add((A, d))
        left = deadline.remaining()
        sub = sub_problem(last_service, _members(A), d, closure)
        found = label_search(
            sub,
            time_limit=CHAIN_SECONDS if left is None else min(left, CHAIN_SECONDS),
            floor=float(table[A]),
            beam=0,
        )
        if found["stopped_by"] == "optimal":
            table[A] = max(float(table[A]), float(found["value"]))
        elif found["stopped_by"] == "time_limit":
            table[A] = max(float(table[A]), float(found["bound"]))

    def release_of(mask: int, d: int) -> dict[int, float]:
        """The part's releases (:func:`_releases`, with the other truck's chain bound when
        K = 2), per customer; cached."""
        got = released_at.get((mask, d))
        if got is None:
            members = _members(mask)
            other = problem.drones[1] if problem.drones[0] == d else problem.drones[0]
            table = chain[other] if problem.K == 2 else None
            if table is not None:
                for r, j in closure:
                    if mask >> j & 1 and not mask >> r & 1:
                        exact_chain((ancestors.get(r, 0) & ~mask & full) | 1 << r, other, table)
            values = _releases(closure, early, mask, members, table)
            got = released_at[(mask, d)] = dict(zip(members, values, strict=True))
        return got

    splits = _splits(problem)
    parts: dict[tuple[int, int], _Part] = {}
    lifts = 0

    def lift(mask: int, d: int, bound: float, released: bool) -> None:
        """Monotonicity (module docstring): ``bound`` proven for the part ``mask`` (with its
        releases when ``released``) bounds every superset part with the same drones (whose
        releases are no earlier on ``mask``'s members, when ``released``)."""
        nonlocal lifts
        table = level0[d]
        for outer in (full ^ _submasks(full ^ mask, empty=True)).tolist():
            if outer == mask or table[outer] >= bound:
                continue
            if released and not _dominates(release_of(outer, d), release_of(mask, d), mask):
                continue
            table[outer] = bound
            got = parts.get((outer, d))
            if got is not None and got.level < 3 and got.bound < bound:
                got.bound = bound
                lifts += 1

    def part(mask: int, d: int) -> _Part:
        got = parts.get((mask, d))
        if got is None:
            got = parts[(mask, d)] = _Part(float(level0[d][mask]))
            if mask == 0:
                got.level, got.bound = 3, 0.0
                got.plan = FleetPlan([[problem.depot]], [[]], [[[] for _ in range(d)]])
        return got

    def combine(split: tuple[int, ...]) -> tuple[FleetPlan, float]:
        """The fleet plan of a split whose parts are all exact, and its value (inf when the
        cross-truck precedences deadlock it)."""
        routes, served, flights = [], [], []
        for k, m in enumerate(split):
            sub_plan = part(m, problem.drones[k]).plan
            assert sub_plan is not None
            route, truck_served, sorties = _lift(sub_plan, _members(m))
            routes.append(route)
            served.append(truck_served)
            flights.append(sorties)
        plan = FleetPlan(routes, served, flights)
        try:
            value = evaluate_fleet(problem, plan)
        except FeasibilityError:
            value = INF
        return plan, value

    def partner(mask: int, d: int) -> tuple[FleetPlan, float, tuple[int, ...]] | None:
        """Two trucks: the part ``mask`` just became exact; when the other part of its split
        is exact too, their combined plan (an incumbent found as soon as possible, not when
        the split reaches the top of the heap), its value and the split."""
        if problem.K != 2:
            return None
        for k in range(2):
            other = parts.get((full ^ mask, problem.drones[1 - k]))
            if problem.drones[k] == d and other is not None and other.plan is not None:
                split = (mask, full ^ mask) if k == 0 else (full ^ mask, mask)
                return (*combine(split), split)
        return None

    def key_of(split: tuple[int, ...]) -> float:
        return max(part(m, problem.drones[k]).bound for k, m in enumerate(split))

    heap = [(key_of(sp), i) for i, sp in enumerate(splits)]
    heapq.heapify(heap)
    popped: set[int] = set()
    coupled_tries: dict[int, int] = {}
    tightened: set[int] = set()
    preds: list[list[int]] = [[] for _ in range(problem.n)]
    for r, j in closure:
        preds[j].append(r)

    def solved_value(found: dict[str, Any], cap: float) -> float:
        """What a label search run proves: its optimum (below ``cap``), ``cap`` when it
        found none below it, or its bound when stopped."""
        if found["stopped_by"] == "optimal":
            if found["plan"] is not None and found["value"] < cap:
                return float(found["value"])
            return cap
        if found["stopped_by"] == "infeasible":
            return INF
        return float(found["bound"])

    def repair(
        split: tuple[int, ...], plan: FleetPlan, value: float
    ) -> tuple[FleetPlan, float] | None:
        """Two trucks, a combined plan that waits: each part in turn re-solved (cut off at the
        best plan) with the other part's service times in that plan as releases, and combined
        with the other part's plan; the better plan (scored by
        :func:`~taopt.fleet.evaluate.evaluate_fleet`, a primal step: it proves nothing)."""
        from taopt.fleet.evaluate import schedule

        if problem.K != 2 or not math.isfinite(value):
            return None
        times = schedule(problem, plan).service
        found_best: tuple[FleetPlan, float] | None = None
        for k in range(2):
            m, d = split[k], problem.drones[k]
            if not m or deadline.expired():
                continue
            members = _members(m)
            cached = release_of(m, d)
            waits = [
                max([cached[j]] + [float(times[r]) for r in preds[j] if not m >> r & 1])
                for j in members
            ]
            left = deadline.remaining()
            found = label_search(
                sub_problem(problem, members, d, closure),
                time_limit=None if left is None else min(left, max(1.0, SLICE * left)),
                floor=part(m, d).bound,
                cutoff=min(best, value),
                release=waits,
                beam=0,
            )
            if found["stopped_by"] != "optimal" or found["plan"] is None:
                continue
            sub_plan = found["plan"]
            route, truck_served, sorties = _lift(sub_plan, members)
            other = split[1 - k]
            other_plan = part(other, problem.drones[1 - k]).plan
            assert other_plan is not None
            o_route, o_served, o_sorties = _lift(other_plan, _members(other))
            pieces = [(route, truck_served, sorties), (o_route, o_served, o_sorties)]
            if k == 1:
                pieces.reverse()
            candidate = FleetPlan(
                [p[0] for p in pieces], [p[1] for p in pieces], [p[2] for p in pieces]
            )
            try:
                score = evaluate_fleet(problem, candidate)
            except FeasibilityError:
                continue
            if found_best is None or score < found_best[1]:
                found_best = (candidate, score)
        return found_best

    def keep_memo(mask: int, d: int, memo: dict[str, Any], found: dict[str, Any]) -> None:
        """Keep a part's label-search memo for its next slice when its search was stopped
        (a finished one has nothing to continue), the most recent last; drop the least
        recent ones past :data:`PART_MEMO_LABELS` labels in all."""
        if "state" not in memo or found["labels"] > PART_MEMO_LABELS:
            return
        part_memo[(mask, d)] = (memo, int(found["labels"]))
        total = sum(size for _, size in part_memo.values())
        while total > PART_MEMO_LABELS:
            oldest = next(iter(part_memo))
            total -= part_memo.pop(oldest)[1]

    solves = 0  # exact part solves

    def exact_part(mask: int, d: int, key: float, eager: bool = True) -> str:
        """One exact solve (a time slice) of the part ``mask`` with ``d`` drones by the label
        search (cut off at the best plan, its releases, its memo); the part's bound, level
        and plan updated and lifted (*Monotonicity*). When it becomes exact with a plan below
        the best one (two trucks) and ``eager``, its complement is solved at once too
        (:func:`eager_pair`). Returns how the search stopped."""
        nonlocal best, best_plan, solves
        item = part(mask, d)
        members = _members(mask)
        sub = sub_problem(problem, members, d, closure)
        started = time.perf_counter()
        left = deadline.remaining()
        if left is not None:  # a slice, doubled at each retry, so other splits get a turn
            left = min(left, max(PART_SLICE_MIN, PART_SLICE * left) * 2**item.attempts)
        memo = part_memo.pop((mask, d), ({}, 0))[0]
        found = label_search(
            sub,
            incumbent=_restrict(problem, best_plan, mask, d),
            time_limit=left,
            max_labels=max_labels,
            floor=item.bound,
            cutoff=best,
            release=list(release_of(mask, d).values()),
            beam=0,  # cut off at the best plan: a beam incumbent only costs (40-65 %)
            memo=memo,
        )
        keep_memo(mask, d, memo, found)
        solves += 1
        seconds = time.perf_counter() - started
        timings.append((len(members), d, seconds))
        trace.append(
            (
                "part",
                round(time.perf_counter() - deadline_start, 3),
                len(members),
                round(seconds, 3),
                found["stopped_by"],
                round(item.bound, 3),
                round(float(found["bound"]), 3),
                round(key, 3),
            )
        )
        item.bound = max(item.bound, float(found["bound"]))
        status = str(found["stopped_by"])
        if status == "infeasible":
            item.bound, item.level = INF, 3
        elif status == "optimal":
            if found["plan"] is not None and found["value"] < best:
                item.plan = found["plan"]
                item.bound = float(found["value"])
                item.level = 3
                paired = partner(mask, d)
                if paired is not None and paired[1] < best:
                    best, best_plan = paired[1], paired[0]
                    trace.append(("paired", round(time.perf_counter() - deadline_start, 3), best))
                if eager and status == "optimal":
                    status = eager_pair(mask, d, paired)
            else:
                item.bound = max(item.bound, best)  # cannot beat the best plan
                item.level = 2
        elif status != "size":  # stopped by its slice or the clock: the bound it proved is kept
            item.attempts += 1
        lift(mask, d, item.bound, released=True)
        return status

    def eager_pair(
        mask: int, d: int, paired: tuple[FleetPlan, float, tuple[int, ...]] | None
    ) -> str:
        """Two trucks: the part ``mask`` just became exact below the best plan. Its
        complement (the other truck's part of the same split) is solved at once (up to
        :data:`EAGER_SLICES` slices of :func:`exact_part`, without recursion) when its bound is
        below the best plan, and a
        combined plan that waits is repaired (:func:`repair`, once per split): a primal step
        that finds good plans before their split reaches the top of the heap, so every later
        part search is cut off lower. It proves nothing by itself (the complement's solve is
        the one the split would run, cached and lifted the same way). Returns how the
        complement's search stopped ("optimal" when there was none to run)."""
        nonlocal best, best_plan
        if problem.K != 2 or deadline.expired():
            return "optimal"
        k = problem.drones.index(d)
        if paired is None:
            other = part(full ^ mask, problem.drones[1 - k])
            if other.level >= 2 or other.bound >= best or not math.isfinite(best):
                return "optimal"
            trace.append(("eager", round(time.perf_counter() - deadline_start, 3), full ^ mask))
            status = "time_limit"
            for _ in range(EAGER_SLICES):  # doubling slices, while it may still beat the best
                status = exact_part(full ^ mask, problem.drones[1 - k], other.bound, eager=False)
                if status != "time_limit" or other.bound >= best or deadline.expired():
                    break
            if status != "optimal" or other.plan is None:
                return status
            paired = partner(mask, d)
            if paired is None:
                return status
            if paired[1] < best:
                best, best_plan = paired[1], paired[0]
                trace.append(("paired", round(time.perf_counter() - deadline_start, 3), best))
        plan, value, split = paired
        if problem.drones[0] == problem.drones[1]:  # identical trucks: the split listed once
            split = (max(split), min(split))
        if split in eager_repaired or not math.isfinite(value):
            return "optimal"
        eager_repaired.add(split)
        key = max(part(m, problem.drones[kk]).bound for kk, m in enumerate(split))
        if value > key * (1 + CERTIFY):
            repaired = repair(split, plan, value)
            if repaired is not None and repaired[1] < best:
                best, best_plan = repaired[1], repaired[0]
                trace.append(("repaired", round(time.perf_counter() - deadline_start, 3), best))
        return "optimal"

    topological: dict[tuple[int, ...], list[float]] = {}  # a split's releases L
    eager_repaired: set[tuple[int, ...]] = set()  # splits repaired by eager_pair
    leader_memo: dict[tuple[tuple[int, ...], int], dict[str, Any]] = {}  # follower solves

    def tighten(split: tuple[int, ...], owner: list[int], key: float) -> float:
        """The split's *topological releases* (module docstring) and its parts re-solved
        with them: a bound on every plan of the split, at least ``key``."""
        L = topological[split] = _split_releases(problem, owner, closure, early, deadline)
        bound = key
        for k, m in enumerate(split):
            if not m or deadline.expired():
                continue
            members = _members(m)
            # the part's own releases hold in every plan of the split too: the larger is kept,
            # so its cached bound (proven with those) is a valid floor
            cached = release_of(m, problem.drones[k])
            left = deadline.remaining()
            found = label_search(
                sub_problem(problem, members, problem.drones[k], closure),
                time_limit=None if left is None else min(left, max(1.0, SLICE * left)),
                floor=part(m, problem.drones[k]).bound,
                cutoff=best,
                release=[max(L[j], cached[j]) for j in members],
                beam=0,
            )
            bound = max(bound, solved_value(found, best))
        return bound

    # per part (mask, d): its label search's memo across its slices, with its label count,
    # least recently solved first (PART_MEMO_LABELS)
    part_memo: dict[tuple[int, int], tuple[dict[str, Any], int]] = {}
    solved = coupled = 0
    timings: list[tuple[int, int, float]] = []
    trace: list[tuple[Any, ...]] = [("best", round(time.perf_counter() - deadline_start, 3), best)]
    stopped_by = "optimal"
    least = INF
    while heap:
        key, i = heap[0]
        if key > least or least == INF:
            trace.append(("least", round(time.perf_counter() - deadline_start, 3), key))
        least = key
        if best <= max(key, floor) * (1 + CERTIFY):
            break
        if key == INF:
            break
        if deadline.expired():
            stopped_by = "time_limit"
            break
        heapq.heappop(heap)
        split = splits[i]
        now = key_of(split)
        if now > key:
            heapq.heappush(heap, (now, i))
            continue
        popped.add(i)
        pending = [
            (
                part(m, problem.drones[k]).level,
                part(m, problem.drones[k]).attempts,
                -part(m, problem.drones[k]).bound,
                m.bit_count(),
                m,
                k,
            )
            for k, m in enumerate(split)
            if part(m, problem.drones[k]).level < 3
        ]
        if pending:
            # (module docstring, *Search*: the cheap levels first, then the part with the
            # fewest stopped slices, the highest bound and the fewest customers)
            level, _, _, _, mask, k = min(pending)
            d = problem.drones[k]
            item = part(mask, d)
            members = _members(mask)
            sub = sub_problem(problem, members, d, closure)
            if level == 0:
                lower = max(item.bound, fleet_lower(sub, "fast"))
                if lower < best and math.isfinite(best):
                    left = deadline.remaining()
                    sub_deadline = Deadline(None if left is None else min(left, 0.1 * left + 0.5))
                    lower = max(lower, fleet_cover_bound(sub, lower, best, sub_deadline))
                item.bound = max(item.bound, lower)
                item.level = 1 if not deadline.expired() else 0
                lift(mask, d, item.bound, released=False)
            else:
                status = exact_part(mask, d, key)
                if status == "size":
                    stopped_by = "size"  # the label cap: stop with the bound it proved
                    heapq.heappush(heap, (key_of(split), i))
                    least = heap[0][0]
                    break
            heapq.heappush(heap, (key_of(split), i))
            continue
        # every part exact: combine and score
        plan, value = combine(split)
        trace.append(
            ("combined", round(time.perf_counter() - deadline_start, 3), split, key, value)
        )
        if value < best:
            best, best_plan = value, plan
            trace.append(("best", round(time.perf_counter() - deadline_start, 3), best))
        if value <= key * (1 + CERTIFY):
            solved += 1
            continue
        # cross-truck precedences bind: the coupled problem restricted to this split
        owner = [0] * problem.n
        for k, m in enumerate(split):
            for j in _members(m):
                owner[j] = k
        if i not in tightened:
            tightened.add(i)
            repaired = repair(split, plan, value)
            if repaired is not None and repaired[1] < best:
                best, best_plan = repaired[1], repaired[0]
                trace.append(("repaired", round(time.perf_counter() - deadline_start, 3), best))
                if best <= key * (1 + CERTIFY):
                    solved += 1
                    continue
            raised = tighten(split, owner, key)
            trace.append(
                ("tight", round(time.perf_counter() - deadline_start, 3), split, key, raised)
            )
            if raised > key * (1 + CERTIFY):
                heapq.heappush(heap, (raised, i))
                continue
        coupled += 1
        left = deadline.remaining()
        # two trucks: one-way cross pairs, the leader search; both ways, the box search over
        # the follower's cross predecessors' times (both exact); more trucks: the label
        # search restricted to the split
        one_way = problem.K == 2 and leader_of(problem, owner) is not None
        leader = problem.K == 2
        if left is not None:  # a slice, doubled at each retry of this split, like the parts'
            tries = coupled_tries.get(i, 0)
            coupled_tries[i] = tries + 1
            share = LEADER_SHARE if leader else SLICE
            left = min(left, max(2.0, share * left) * 2**tries)
        L = topological.get(split)
        if L is None:
            L = topological[split] = _split_releases(problem, owner, closure, early, deadline)
        if leader and not one_way:  # both ways: the box search over the follower's times
            found = two_way_search(
                problem,
                owner,
                release=L,
                time_limit=left,
                incumbent=plan if value < INF else None,
                floor=key * (1 - 1e-9),
                cutoff=best,
                max_labels=max_labels,
                memo=leader_memo.setdefault((split, -1), {}),
            )
        elif leader:
            found = leader_search(
                problem,
                owner,
                release=L,
                time_limit=left,
                incumbent=plan if value < INF else None,
                floor=key * (1 - 1e-9),
                cutoff=best,
                max_labels=max_labels,
                memo=leader_memo.setdefault((split, 0), {}),
            )
        else:
            found = label_search(
                problem,
                time_limit=left,
                incumbent=plan if value < INF else None,
                max_labels=max_labels,
                truck_of=owner,
                floor=key * (1 - 1e-9),
                cutoff=best,
                release=L,  # met by every plan of the split: same optimum, stronger bounds
            )
        if found["plan"] is not None and found["value"] < best:
            try:
                scored = evaluate_fleet(problem, found["plan"])
            except FeasibilityError:
                scored = INF
            if scored < best:
                best, best_plan = scored, found["plan"]
                trace.append(("best", round(time.perf_counter() - deadline_start, 3), best))
        trace.append(
            (
                "coupled",
                round(time.perf_counter() - deadline_start, 3),
                split,
                found["stopped_by"],
                key,
                round(float(found["bound"]), 4),
            )
        )
        boxed = leader and not one_way
        if found["stopped_by"] != "optimal" or (
            boxed and float(found["bound"]) < best * (1 - 1e-12)
        ):
            # (a box search certified within CERTIFY keeps its proven bound: the split goes
            # back with it and ends the run when it is the least)
            heapq.heappush(heap, (max(key, float(found["bound"])), i))
            if found["stopped_by"] == "size":
                stopped_by = "size"
                least = heap[0][0]
                break
    else:
        least = INF
    if not heap:
        least = INF
    bound = min(best, max(least, floor))
    if best == INF and least == INF and stopped_by == "optimal":
        stopped_by = "infeasible"
    timings.sort(key=lambda x: -x[2])
    return {
        "plan": best_plan,
        "value": best,
        "bound": bound,
        "stopped_by": stopped_by,
        "splits": len(popped),
        "of_splits": len(splits),
        "solved_splits": solved,
        "coupled": coupled,
        "parts": solves,
        "part_seconds": [(m, d, round(s, 3)) for m, d, s in timings[:5]],
        "lifted": lifts,
        "trace": trace,
    }


__all__ = [
    "CERTIFY",
    "CHAIN_SECONDS",
    "DRONE_SPLIT_SHARE",
    "EAGER_SLICES",
    "LEADER_SHARE",
    "PART_MEMO_LABELS",
    "SPLIT_MAX_N",
    "SPLIT_MAX_SPLITS",
    "PART_SLICE",
    "PART_SLICE_MIN",
    "SLICE",
    "count_splits",
    "split_applies",
    "split_search",
    "sub_problem",
]
