"""The fleet family's certified exact method: best-first label search with dominance.

A *label* is a partial plan seen from its end: the served set S (every customer whose
service is fixed), its service times, and per truck its current stop w, its arrival time A
there, the earliest time T it may leave (every event at this position done), whether it
has finished, and per drone either *aboard* (with its last recovery time ρ) or *airborne*
(the last customer ℓ it served, or its launch stop while it has served none, the number m of
customers of the sortie so far, the time t it left ℓ or was launched, the distance δ flown).

Actions (each adds constraints of :mod:`taopt.fleet.evaluate` to the plan, never changes
earlier ones, so every time is final once computed and later times are monotone in earlier
ones):

* *serve* a truck-servable customer j at the truck's stop: ``t_j = max(A, t_r for r -> j)``;
* *launch* an aboard drone: ``L = max(A, ρ)``;
* *append* customer j to an airborne drone's sortie (m < c, within range):
  ``t_j = max(t + ft(ℓ, j) + τ, t_r for r -> j)``;
* *recover* an airborne drone (m >= 1) at the truck's stop:
  ``R = max(t + ft(ℓ, w), A) + τ``;
* *move* the truck to another stop (only after an event at this position: a position
  without an event, or two consecutive at the same stop, never helps; see
  :mod:`taopt.fleet.brute`);
* *finish* the truck (drones aboard; under ``"return"`` it drives home).

A customer is served only once its predecessors are (their times are then known). Without
precedences a sortie's customers are all chosen right after its launch (a drone *fills*
until another action is taken); with precedences a customer may be appended to an airborne
sortie at any later action, so a predecessor served meanwhile by any vehicle is waited for:
every feasible plan is reached this way (a plan's events can be committed in an order where
each customer follows its predecessors — the order of the acyclic constraint graph). Such a
late append is only taken when it could not have come earlier: while the drone is *fresh*
(no other action since its last launch or append) or when one of the customer's
predecessors was served since then (:func:`_appendable`, with the proof that every plan's
times are still reached); a drone launched with no customer that can take none any more ends
its label (bound ``inf``).

*Search.* Labels are expanded best-first by a valid lower bound on the final objective (the
largest of: the least time each unserved customer can be served from the label, over the
fleet, raised along precedences, under ``"return"`` plus the least way home; the drones'
shared work (:func:`_water_fill`); the trucks' covering walks (:func:`_walk_bound`, a truck
must bring its drones within reach of every customer no airborne drone can still take); the
drones' sortie times (:func:`_sortie_time_bound`, each drone with a truck of its own, one
launched with no customer yet recovered only after its first, :func:`_first_recoveries`;
two airborne drones of one truck recovered by that one truck, :func:`_shared_recoveries`;
the first recoveries of several airborne drones of one truck one after another on its
timeline, :func:`_chained_recoveries`);
and the parent's bound; taken cheapest first and cut off at the incumbent,
:func:`_bound`), so the first complete label popped is optimal. *Dominance*: two labels with the same served set and discrete state (stops,
flags, each drone's ℓ or launch stop and m, identical drones and identical trucks taken as
interchangeable) where one's times and distances are all <= the other's: the other is
dropped; so is a label dominated by one the bound pruned (it has no completion below the
cut either; per key up to :data:`~taopt.fleet.search.PRUNED_PER_KEY` pruned vectors none <=
another are kept for this, :func:`_remember`). An incumbent (the caller's, or a simple sequential plan) prunes labels whose bound
reaches it. A wall-clock limit and a label cap stop the search with the incumbent and the
least open bound, proven.
"""

from __future__ import annotations

import functools
import gc
import heapq
import itertools
import math
import time
from collections.abc import Callable, Sequence
from operator import le
from typing import Any, TypeVar, cast

import numpy as np

from taopt.errors import FeasibilityError, SolverError
from taopt.fleet.cover import (
    WALK_MAX_CUSTOMERS,
    CoverTables,
    WalkTable,
    one_drone_tables,
    sortie_time_table,
    walk_table,
)
from taopt.fleet.evaluate import best_of, evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.fleet.synced import synced_applies, synced_plan
from taopt.runtime import Deadline

#: Default cap on the labels kept (about 1 KB each with their bookkeeping).
DEFAULT_MAX_LABELS = 3_000_000

#: Share of the time limit the synchronised-operations incumbent (:mod:`taopt.fleet.synced`)
#: may take.
SYNCED_SHARE = 0.1

#: Up to this many customers the sortie-time term splits them exactly over three or more
#: drones (3^m pairs per drone, :func:`_least_largest`).
PARTITION_MAX_CUSTOMERS = 9

#: Per dominance key, how many labels pruned by the bound the label search remembers to
#: drop the labels they dominate without a bound (:func:`_remember`). Measured at K1D2c1's
#: optimum cut (the shipped residential n = 8): 8 per key skipped 87,674 bounds, 16 92,869,
#: 32 95,221 (with the dominated vectors dropped), any number 95,420 (the largest key then
#: held 75 vectors, the median 2); the memo's vectors are at most the labels pruned.
PRUNED_PER_KEY = 32

#: The shared-recovery term (:func:`_shared_recoveries`) is computed only for labels whose
#: independent sortie-time term is at least this share of the cutoff (a label further below
#: is seldom pruned by it; skipping a term leaves a valid, lower bound).
SHARED_FROM = 0.95

#: The chained-recovery term (:func:`_chained_recoveries`) is computed only for the airborne
#: drones of a truck carrying at least this many drones (with two, it cut K1D2c1's and
#: K1D2c2's expansions by 14-18 % for the same CPU) and labels whose independent split is at
#: least this share of the cutoff (skipping a term leaves a valid, lower bound).
CHAIN_MIN_DRONES = 3
CHAIN_FROM = 0.85

#: The release term (:func:`_release_term`) is computed for at most this many drones left
#: and this many assignments of the unserved customers to them.
RELEASE_MAX_DRONES = 3
RELEASE_MAX_ROWS = 6561

#: ... and only for labels whose independent sortie-time term is at least this share of the
#: cutoff (skipping a term leaves a valid, lower bound).
RELEASE_FROM = 0.8

#: The release term orders each part under its releases (:func:`_sequence_end`) for at most
#: this many assignments below the cutoff, and parts of at most this many customers.
RELEASE_MAX_EXACT = 256
RELEASE_MAX_SEQUENCE = 8

#: Relative agreement required between the search's value and the scorer's.
MATCH_TOLERANCE = 1e-9

INF = math.inf

#: ``np.minimum.reduce``: ``ndarray.min`` without its Python wrapper (the same values; the
#: bound takes several per label on arrays of tens of entries).
_least = np.minimum.reduce

_F = TypeVar("_F", bound=Callable[..., Any])


class _Tables:
    """Per-instance arrays (plain Python lists, read in the inner loops)."""

    def __init__(
        self, p: FleetProblem, walk: bool = True, deadline: Deadline | None = None
    ) -> None:
        n, s = p.n, p.s
        self.n, self.s, self.K = n, s, p.K
        self.depot = p.depot
        self.c = p.capacity
        self.tau = p.service_time
        self.limit = p.flight_limit
        self.tt = p.truck_time.tolist()
        self.fsd = p.flight_stop.tolist()  # distances
        self.fcd = p.flight_customer.tolist()
        self.fst = (p.flight_stop / p.v_drone).tolist()  # times
        self.fct = (p.flight_customer / p.v_drone).tolist()
        self.near = p.flight_stop.min(axis=1).tolist()
        self.truck_ok = [p.truck_servable(j) for j in range(n)]
        self.drone_ok = [p.drone_servable(j) and p.D > 0 for j in range(n)]
        self.cstop: list[int | None] = list(p.customer_stop)
        self.preds: list[list[int]] = [[] for _ in range(n)]
        self.pred_mask = [0] * n
        self.succ_mask = [0] * n
        for r, j in p.precedences:
            self.preds[j].append(r)
            self.pred_mask[j] |= 1 << r
            self.succ_mask[r] |= 1 << j
        import networkx as nx

        self.topo = list(nx.topological_sort(p.precedence_graph))
        self.lazy = bool(p.precedences)
        # a drone launched later from a truck now at w serves j no sooner than A + G[w][j] + τ
        tt = p.truck_time
        ft = p.flight_stop / p.v_drone
        ok = (p.flight_stop + p.flight_stop.min(axis=1)[:, None]) <= self.limit  # (n, s)
        G = np.full((s, n), INF)
        for j in range(n):
            if ok[j].any():
                G[:, j] = np.min(tt[:, ok[j]] + ft[j, ok[j]][None, :], axis=1)
        self.G = G.tolist()
        self.Gnp = G
        # F[w, j]: a sortie launched at w itself reaches j after ft(w, j) (inf when out of range)
        self.Fnp = np.where(ok.T, ft.T, INF)
        self.tt_np = np.asarray(tt, dtype=float)
        # tt between different stops (inf on the diagonal): :func:`_shared_recoveries`
        self.tt_apart = self.tt_np.copy()
        np.fill_diagonal(self.tt_apart, INF)
        # tt + τ between different stops, 0 at the same stop: :func:`_chained_recoveries`
        self.chain_step = self.tt_np + p.service_time
        np.fill_diagonal(self.chain_step, 0.0)
        self.fst_np = np.asarray(ft, dtype=float)  # (n, s) flight times customer -> stop
        self.fsd_np = np.asarray(p.flight_stop, dtype=float)
        home = ft + p.service_time + tt[:, p.depot][None, :]  # (n, s)
        self.home = home.min(axis=1).tolist()  # drone at customer j: recovery and drive home
        back = self.home[:]
        for j in range(n):
            if self.truck_ok[j]:
                back[j] = min(
                    back[j] if self.drone_ok[j] else INF, float(tt[p.customer_stop[j], p.depot])
                )
        self.back = back
        self.ret = p.objective == "return"
        # work[j]: drone time serving a drone-only customer costs at least (landing τ and the
        # shortest leg into it, from a stop or, when c > 1, another customer); 0 for
        # truck-servable ones
        into = p.flight_stop.min(axis=1)
        if p.capacity > 1 and n > 1:
            into = np.minimum(
                into, np.where(np.eye(n, dtype=bool), INF, p.flight_customer).min(axis=1)
            )
        self.work = [
            0.0 if self.truck_ok[j] else float(into[j] / p.v_drone + p.service_time)
            for j in range(n)
        ]
        # rec: a recovery costs its drone at least the shortest flight from a customer to a stop
        # and the landing τ
        self.rec = float(p.flight_stop.min() / p.v_drone + p.service_time) if n else 0.0
        self.full = (1 << n) - 1
        # launch_ok[w]: customers a sortie launched at w can serve first (and still land)
        self.launch_ok = [
            sum(1 << j for j in range(n) if self.drone_ok[j] and ok[j, w]) for w in range(s)
        ]
        self.drones = list(p.drones)
        groups: dict[int, list[int]] = {}
        for k, d in enumerate(p.drones):
            groups.setdefault(d, []).append(k)
        self.groups = list(groups.values())
        # the truck-walk term (:func:`_walk_bound`): per number of drones carried, the
        # covering-walk table
        self.walk: dict[int, WalkTable] = {}
        if walk:
            ctab = CoverTables(p)
            for count in sorted(set(p.drones)):
                table = walk_table(p, count, ctab)
                if table is not None:
                    self.walk[count] = table
        # the drones' sortie-time term (:func:`_sortie_time_bound`): one drone's least time per
        # start stop and served set
        self.sortie_time: np.ndarray | None = None
        self.one_drone = False  # sortie_time is one_drone_table's (the objective's clock)
        # launched here: the one-drone table's H (the first sortie launched at the start stop)
        self.launch_here: np.ndarray | None = None
        self.drone_only = sum(1 << j for j in range(n) if not self.truck_ok[j] and self.drone_ok[j])
        if walk and n <= WALK_MAX_CUSTOMERS and self.drone_only:
            # the one-drone table (precedences inside the set, the objective's own clock) where
            # it fits, else the weaker precedence-free sortie-time table
            tables = one_drone_tables(p, deadline)
            if tables is None:
                self.sortie_time = sortie_time_table(p, deadline)
            else:
                self.sortie_time, self.launch_here = tables
                self.one_drone = True
        self.masks = np.arange(1 << n, dtype=np.int64) if self.walk else np.zeros(0, np.int64)
        self._subs: dict[int, np.ndarray] = {}
        self.popcount = np.zeros(len(self.masks), dtype=np.int64)
        for j in range(n if self.walk else 0):
            self.popcount += (self.masks >> j) & 1
        # owner[j]: the only truck that (or whose drones) may serve j (``truck_of``), or None
        self.owner: list[int] | None = None
        # release[j]: a time before which j is not served (``release``), 0 by default
        self.release = [0.0] * n
        # per-label work, memoised on what it depends on (the inner loops' plain lists and
        # caches; each cache is cleared when it grows past its cap)
        self._watch: dict[int, tuple[int, tuple[int, ...], int]] = {}  # _watched
        self._cols: dict[int, np.ndarray] = {}  # _columns
        self._here: dict[int, np.ndarray] = {}  # _columns of launch_here
        self._cols_size = 0
        self._legs: dict[int, np.ndarray] = {}  # _first_recoveries
        self._firsts: dict[tuple, np.ndarray] = {}
        self._first_cands: dict[tuple, tuple] = {}  # _first_candidates
        self._reach: dict[tuple, tuple[int, int, int, list[tuple[int, float]]]] = {}  # _air_reach
        self.nowhere = np.full(s, INF)  # (read only)
        self._arrive_key: tuple[int, float, float] | None = None  # _arrivals
        self._arrive = self.nowhere
        self._release: dict[tuple[int, int, int, int], tuple | None] = {}  # _release_rows
        self._tail: tuple | None = None  # _tail_table
        self._kept: dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray]] = {}  # _kept_pairs
        self._kept_size = 0
        self._release_parts: dict[
            tuple[int, int, int, int], list[list[int]]
        ] = {}  # per row, the parts


def _submasks(tab: _Tables, U: int) -> np.ndarray:
    """The submasks of U in ascending order (cached per U)."""
    subs = tab._subs.get(U)
    if subs is None:
        if len(tab._subs) > 1 << 16:
            tab._subs.clear()
        subs = tab._subs[U] = tab.masks[(tab.masks & ~U) == 0]
    return subs


# label: (S, M, svc, trucks); truck: (w, A, T, ev, fin, F, drones)
# drone aboard: (0, rho); airborne: (1, origin, m, t, delta, open, fresh, seen) with
# origin = ℓ >= 0, or -(w_L + 1) before its first customer; fresh: no action other than an
# append since its last launch or append, seen: the served set at that event (_appendable)


def _water_fill(tab: _Tables, S: int, trucks: tuple) -> float:
    """The drones' shared work: a lower bound on the last drone service (``"last_service"``)
    or on the last recovery (``"return"``) of every completion.

    Every unserved drone-only customer j costs the drone serving it at least ``work[j]``: its
    in-leg (the shortest flight into j, from a stop or, when c > 1, another customer) and the
    landing τ. Recoveries cost ``rec`` each (the shortest flight from a customer to a stop and
    the recovery τ). Let m be the unserved drone-only customers, r the room left in the
    sorties still open (c - m_d for each airborne drone that may still take customers) and a
    the aboard drones: at least ``q = ceil(max(0, m - r) / c)`` new sorties are flown. A drone
    flying n_d >= 1 new sorties is recovered n_d - 1 times before its last service when it is
    aboard now, n_d times when it is airborne now (its current sortie first); so, summed over
    the drones, at least ``q - a`` recoveries happen before the drones' last services (under
    ``"return"`` every recovery counts: at least ``q`` plus one per airborne drone). These
    intervals (legs, landings, recoveries) are disjoint on a drone's timeline and start after
    its availability a_d (an aboard drone: launch no sooner than its truck's arrival A or its
    recovery ρ; an airborne one: its last time t). A drone with load L_d ends no sooner than
    ``a_d + L_d``, so the bounded time F satisfies ``Σ_d max(0, F - a_d) >= W`` (the total
    work): F is at least the water level that fills W over the availabilities. 0 when no
    drone-only customer is left."""
    W = 0.0
    m = 0
    for j in range(tab.n):
        if not S >> j & 1 and tab.work[j] > 0.0:
            W += tab.work[j]
            m += 1
    if m == 0:
        return 0.0
    avail = []
    room = aboard = airborne = 0
    c = tab.c
    for _w, A, _T, _ev, fin, _F, drones in trucks:
        if fin:
            continue
        for dr in drones:
            if dr[0] == 0:
                avail.append(dr[1] if dr[1] > A else A)
                aboard += 1
            else:
                avail.append(dr[3])
                airborne += 1
                if dr[5]:
                    room += c - dr[2]
    new = -(-(m - room) // c) if m > room else 0
    recoveries = new + airborne if tab.ret else new - aboard
    if recoveries > 0:
        W += recoveries * tab.rec
    if not avail:
        return INF
    avail.sort()
    total = 0.0
    for i, a in enumerate(avail):
        total += a
        level = (total + W) / (i + 1)
        if i + 1 == len(avail) or level <= avail[i + 1]:
            return level
    return INF  # not reached


def _arrivals(tab: _Tables, w: int, A: float, T: float) -> np.ndarray:
    """Per stop q, the earliest a truck at stop w (arrival A, departure bound T) is there: A
    at w, ``T + tt(w, q)`` elsewhere (read only; the last truck's kept: the drones of a
    label's truck and its terms ask for the same one in turn)."""
    key = (w, A, T)
    if tab._arrive_key == key:
        return tab._arrive
    arrive = T + tab.tt_np[w]
    arrive[w] = A
    arrive.flags.writeable = False
    tab._arrive_key, tab._arrive = key, arrive
    return arrive


def _recoveries(tab: _Tables, w: int, A: float, T: float, dr: tuple, arrive: Any) -> tuple:
    """Per stop q, the earliest an airborne drone ``dr`` of a truck at stop w (arrival A,
    departure bound T) can be recovered there and its τ done (``inf`` beyond its range; one
    that has served nobody yet is charged no flight), and the truck's arrival times per stop
    (``arrive``, :func:`_arrivals` when None)."""
    if arrive is None:
        arrive = _arrivals(tab, w, A, T)
    o = dr[1]
    if o >= 0:
        back = np.maximum(dr[3] + tab.fst_np[o], arrive) + tab.tau
        back[dr[4] + tab.fsd_np[o] > tab.limit] = INF
    else:
        back = np.maximum(dr[3], arrive) + tab.tau
    return back, arrive


def _first_recoveries(
    tab: _Tables,
    k: int,
    w: int,
    A: float,
    T: float,
    dr: tuple,
    S: int,
    svc: Sequence[float],
    times: Sequence[float] | None,
) -> np.ndarray:
    """Per stop q, the earliest a drone launched with no customer yet (``dr``: airborne,
    m = 0) of truck k at stop w (arrival A, departure bound T) can be recovered there and
    its τ done: :func:`_recoveries` for a drone that must first serve a customer.

    Such a drone is recovered only after it has served some customer j it may still take
    (unserved, drone-servable, on truck k's side under ``truck_of``, within range with a
    landing, and when it is stale one with a predecessor served since its launch:
    :func:`_appendable`; :func:`_complete` never ends a label with an empty sortie), no
    sooner than ``a_j = max(t + ft(w_L, j) + τ, t_r for r -> j, release_j)``, ``t_r`` the
    service time of a served predecessor or, with ``times``, the earliest service of an
    unserved one (``times[r]``, a lower bound on it in every completion; without ``times``
    an unserved predecessor is not counted). Its recovery at q, after any further customers
    of the sortie (straight lines: the triangle inequality), is no sooner than
    ``max(a_j + ft(j, q), arrival at q) + τ``, with ``d(w_L, j) + d(j, q)`` within the range
    left (``svc``: the label's service times). The least over j is a lower bound; ``inf`` everywhere when it can take no one
    (such a label has no completion)."""
    first = _first_legs(tab, k, dr, S, svc, times)
    back = np.maximum(first, _arrivals(tab, w, A, T))
    back += tab.tau
    return back


def _first_legs(
    tab: _Tables, k: int, dr: tuple, S: int, svc: Sequence[float], times: Sequence[float] | None
) -> np.ndarray:
    """Per stop q, ``min_j a_j + ft(j, q)`` over the customers j a drone launched with no
    customer yet may take first, within range (:func:`_first_recoveries`; ``inf`` everywhere
    when it can take no one)."""
    ws = -dr[1] - 1
    t, delta = dr[3], dr[4]
    tau, limit = tab.tau, tab.limit
    firsts, spent, cands = _first_candidates(tab, k, dr, S)
    if not firsts:
        return tab.nowhere
    value: list[float] = []
    for f, done, open_, rel in cands:
        a = t + f + tau
        for r in done:
            if svc[r] > a:
                a = svc[r]
        if times is not None:
            for r in open_:
                if times[r] > a:
                    a = times[r]
        if rel > a:
            a = rel
        value.append(a)
    key = (ws, delta, tuple(firsts), tuple(value))
    first = tab._firsts.get(key)  # per stop q: min_j a_j + ft(j, q), within range
    if first is None:
        if delta > 0.0:  # (a launched drone has flown nothing before its first customer)
            rows = tab.fst_np[list(firsts)] + np.asarray(value)[:, None]
            rows[tab.fsd_np[list(firsts)] + np.asarray(spent)[:, None] > limit] = INF
        else:
            legs = tab._legs.get(ws)
            if legs is None:  # ft(j, q), inf where d(w_s, j) + d(j, q) is beyond the range
                legs = tab._legs[ws] = np.where(
                    tab.fsd_np[:, ws : ws + 1] + tab.fsd_np > limit, INF, tab.fst_np
                )
            rows = legs[list(firsts)] + np.asarray(value)[:, None]
        first = _least(rows, axis=0)
        if len(tab._firsts) > 1 << 15:
            tab._firsts.clear()
        tab._firsts[key] = first
    return first


def _first_candidates(
    tab: _Tables, k: int, dr: tuple, S: int
) -> tuple[tuple[int, ...], list[float], list[tuple[float, list[int], list[int], float]]]:
    """The time-free part of :func:`_first_legs`: the customers j a drone launched with no
    customer yet (``dr``, of truck k, served set S) may take first (ascending), the distance
    flown on reaching each, and per j (ft(w_L, j), its served predecessors, its unserved
    ones, its release); memoised per (k, S, launch stop, distance, freshness)."""
    fresh = not tab.lazy or dr[6]
    key = (k, S, dr[1], dr[4], -1 if fresh else dr[7])
    got = tab._first_cands.get(key)
    if got is not None:
        return got
    owner, pred_mask, release = tab.owner, tab.pred_mask, tab.release
    ws = -dr[1] - 1
    delta, seen, limit = dr[4], dr[7], tab.limit
    firsts: list[int] = []
    spent: list[float] = []
    cands: list[tuple[float, list[int], list[int], float]] = []
    for j in range(tab.n):
        if S >> j & 1 or not tab.drone_ok[j] or (owner is not None and owner[j] != k):
            continue
        if not fresh and not pred_mask[j] & ~seen:
            continue
        dist = delta + tab.fsd[j][ws]
        if dist + tab.near[j] > limit:
            continue
        firsts.append(j)
        spent.append(dist)
        done = [r for r in tab.preds[j] if S >> r & 1]
        open_ = [r for r in tab.preds[j] if not S >> r & 1]
        cands.append((tab.fst[j][ws], done, open_, release[j]))
    got = (tuple(firsts), spent, cands)
    if len(tab._first_cands) > 1 << 16:
        tab._first_cands.clear()
    tab._first_cands[key] = got
    return got


def _fresh_sorties(
    tab: _Tables, trucks: tuple, S: int | None = None, svc: Sequence[float] = ()
) -> list[Any]:
    """Per truck, per customer j: the least time a sortie of that truck not yet launched
    serves j (``inf`` where none can). With the label's served set ``S`` and service times
    ``svc``, a drone launched with no customer yet is recovered only after its first
    customer (:func:`_first_recoveries`, unserved predecessors not counted).

    An aboard drone launches here no sooner than ``max(A, ρ)`` (only toward customers a sortie
    from this stop can reach and still land: ``F``), or at another stop after the truck leaves
    (no sooner than its departure bound T) and drives there (``T + G[w, j]``, G the least
    drive-and-fly time). An airborne drone must first be recovered at some stop q within its
    range: no sooner than ``max(t + ft(ℓ, q), arrival at q) + τ`` (the truck is at q at A if q is
    its stop, else no sooner than ``T + tt(w, q)``; a drone that has served nobody yet is
    charged no flight to q), then ``G[q, j]``. Then τ at j. Each is a relaxation of the
    actions of :func:`_children`, which only add constraints."""
    out: list[Any] = []
    tau = tab.tau
    for k, (w, A, T, _ev, fin, _F, drones) in enumerate(trucks):
        if fin or not drones:
            out.append(None)
            continue
        rho = INF
        for dr in drones:
            if dr[0] == 0 and dr[1] < rho:
                rho = dr[1]
        # the least recovery per stop over the airborne drones (then one drive-and-fly
        # step for all: fl(x + g) is monotone in x, so min_d (b_d + G) = min_d b_d + G)
        low = None
        for dr in drones:
            if dr[0] != 1:
                continue
            if dr[2] == 0 and S is not None:
                back = _first_recoveries(tab, k, w, A, T, dr, S, svc, None)
            else:
                back, _ = _recoveries(tab, w, A, T, dr, None)
            low = back if low is None else np.minimum(low, back)
        if low is None:
            best = np.minimum(tab.Fnp[w] + (rho if rho > A else A), tab.Gnp[w] + T)
        else:
            if rho < INF and T < low[w]:  # (an aboard drone driven on from w: T + G[w, j])
                low[w] = T
            best = _least(low[:, None] + tab.Gnp, axis=0)
            if rho < INF:
                best = np.minimum(tab.Fnp[w] + (rho if rho > A else A), best)
        best += tau
        out.append(best.tolist())
    return out


def _walk_bound(tab: _Tables, U: int, trucks: tuple, drop: int = 0, count: int = 0) -> float:
    """The trucks' covering walks: a lower bound on the objective of every completion in which
    the customers of ``U`` are served from the trucks' stops (each by the truck itself at its
    stop, or by a sortie launched from there).

    A truck k at stop w, leaving no sooner than T, that serves (or launches toward) the
    customers of a set ``U_k`` ends the objective's clock no sooner than
    ``T + value[U_k \\ cover[w], w]`` (:func:`taopt.fleet.cover.walk_table`: those coverable at w
    itself are relaxed out, the others need its later stops, reached after it leaves).
    Every customer of U is served from some truck's stop, so the objective is at least
    ``min`` over partitions (U_1, ..., U_K) of U among the unfinished trucks of
    ``max_k (T_k + value_k[U_k \\ cover_k[w_k], w_k])``: exact for one and two trucks (the
    partitions are the submasks of U). With three or more, some part holds at least
    ``ceil(|U| / K)`` customers, so the objective is at least the least
    ``T_k + value_k[X \\ cover_k[w_k], w_k]`` over trucks k and submasks X of U of that size
    or more. ``inf`` when no unfinished truck is left for a nonempty U; 0 when U is empty or
    there is no table. Under ``"last_service"`` a truck whose part is all coverable at its
    own stop need not leave it, so that part ends nothing (T bounds only a departure: the
    recoveries that set it may come after the last service).

    ``drop``, ``count``: customers of U of which at most ``count`` may be served by sorties
    already in the air: the least over U \\ Y, Y ⊆ ``drop``, ``|Y| <= count`` (one truck;
    with more, all of ``drop`` is left out, which is no more)."""
    drop &= U
    if drop and count > 0 and len(trucks) > 1:
        U &= ~drop
        drop = 0
    if not U or not tab.walk:
        return 0.0
    active: list[tuple[int, float, WalkTable]] = []
    for w, _A, T, _ev, fin, _F, drones in trucks:
        if not fin:
            table = tab.walk.get(len(drones))
            if table is None:
                return 0.0
            active.append((w, T, table))
    if not active:
        return INF
    ret = tab.ret
    if len(active) == 1:
        w, T, table = active[0]
        R = U & ~table.cover[w]
        least = T + float(table.value[R, w]) if R or ret else 0.0
        if drop and count > 0 and least > 0.0:
            bits = [1 << j for j in range(tab.n) if drop >> j & 1]
            for size in range(1, min(count, len(bits)) + 1):
                for Y in itertools.combinations(bits, size):
                    R = (U & ~sum(Y)) & ~table.cover[w]
                    v = T + float(table.value[R, w]) if R or ret else 0.0
                    if v < least:
                        least = v
        return least
    subs = _submasks(tab, U)

    def ends(X: np.ndarray, w: int, T: float, table: WalkTable) -> np.ndarray:
        R = X & ~table.cover[w]
        e = T + table.value[R, w]
        return e if ret else np.where(R == 0, 0.0, e)

    if len(active) == 2:
        (w1, T1, t1), (w2, T2, t2) = active
        one = ends(subs, w1, T1, t1)
        two = ends(U ^ subs, w2, T2, t2)
        return float(np.min(np.maximum(one, two)))
    size = -(-int(tab.popcount[U]) // len(active))
    big = subs[tab.popcount[subs] >= size]
    return float(min(np.min(ends(big, w, T, table)) for w, T, table in active))


def _sortie_time_bound(
    tab: _Tables,
    U: int,
    trucks: tuple,
    S: int | None = None,
    svc: Sequence[float] = (),
    times: Sequence[float] | None = None,
    drop: int = 0,
    count: int = 0,
    cutoff: float = INF,
) -> float:
    """The drones' sorties, the one-drone relaxation at a label: a lower bound on the
    objective of every completion in which the drone-only customers of ``U`` are served by
    sorties not yet launched.

    Each such customer is served by one drone of an unfinished truck. A drone aboard its
    truck at stop w, ready at ``a = max(A, ρ)`` (its truck leaves w no sooner), serving
    exactly the set X ends no sooner than ``a + F[w, X]``: :func:`taopt.fleet.cover.one_drone_table`
    (``tab.one_drone``; the drone with a copy of its truck of its own, the precedence pairs
    inside X kept, the objective's clock: the last service, or the drone and its truck home
    under ``"return"``), else :func:`taopt.fleet.cover.sortie_time_table` (precedences
    dropped, last service). With the one-drone table this is sharpened on the truck's
    timeline: the truck leaves w no sooner than T (every event at its position done, other
    drones' recoveries included), so the drone's next launch is either at this position, no
    sooner than a, from w itself, after which its copy of the truck ends no sooner than
    ``a + H[w, X]`` (:func:`taopt.fleet.cover.one_drone_tables`: the first sortie launched
    at the start stop; the copy relaxation started at that launch), or at a later position,
    at some stop v reached no sooner than ``T + tt(w, v)``, after which it ends no sooner
    than ``T + tt(w, v) + H[v, X] >= T + F[w, X]``; so no sooner than ``min(a + H[w, X],
    T + F[w, X])`` (equal to ``a + F[w, X]`` when T = a; a drone given nothing does not
    launch and ends no sooner than ``a + F[w, ∅]``, which ``H[w, ∅] = F[w, ∅]`` gives).
    An airborne one is first recovered at some stop q within its
    range, no sooner than ``r_q = max(t + ft(ℓ, q), arrival at q) + τ`` (as in
    :func:`_fresh_sorties`), then ends no sooner than ``min_q r_q + F[q, X]``. So the
    objective is at least the least, over the partitions of U among the drones, of the
    largest drone's end (a drone given no customer ends nothing under ``"last_service"``;
    under ``"return"`` with the one-drone table it still gets home, ``F[w, ∅] = tt(w,
    depot)``): exact over the submasks of U for one or two drones, and for more up to
    :data:`PARTITION_MAX_CUSTOMERS` customers (:func:`_least_largest`); above, some drone
    serves at least ``ceil(|U| / N)`` of them, so the least end over drones and subsets of
    that size or more. The pairs between different drones' parts are dropped, so at the root
    this is at most :func:`taopt.models.fleet._one_drone_floor` (which keeps them, and is the
    search's ``floor``). 0 without a table or customers; ``inf`` without a drone.

    ``drop``, ``count``: customers of U of which at most ``count`` may be served by sorties
    already in the air (and so need no new sortie): the least of the term over U \\ Y, Y ⊆
    ``drop`` with ``|Y| <= count`` (from the least-largest values of every subset of U, up to
    :data:`PARTITION_MAX_CUSTOMERS` customers; above, all of ``drop`` is left out, which is
    no more).

    The split over the drones is :func:`_split_term`'s (with the release term and the shared
    recoveries of two airborne drones); on a truck carrying :data:`CHAIN_MIN_DRONES` drones or
    more, two or more of them airborne, it is raised to :func:`_chained_recoveries` (their
    first recoveries one after another on the truck's timeline) on labels whose independent
    split is at least :data:`CHAIN_FROM` of the cutoff (skipping it leaves a valid bound)."""
    F = tab.sortie_time
    drop &= U
    if drop and count <= 0:
        drop = 0
    elif drop and int(tab.popcount[U]) > PARTITION_MAX_CUSTOMERS:
        U &= ~drop
        drop = 0
    if F is None or not U:
        return 0.0
    drones_left = [
        (k, w, A, T, dr)
        for k, (w, A, T, _ev, fin, _F, drones) in enumerate(trucks)
        if not fin
        for dr in drones
    ]
    if not drones_left:
        return INF

    def back_of(k: int, w: int, A: float, T: float, dr: tuple) -> np.ndarray:
        if dr[2] == 0 and S is not None:
            return _first_recoveries(tab, k, w, A, T, dr, S, svc, times)
        return cast(np.ndarray, _recoveries(tab, w, A, T, dr, None)[0])

    H = tab.launch_here
    if len(drones_left) == 1 and not drop:  # one drone serves all of U: one column
        k, w, A, T, dr = drones_left[0]
        if dr[0] == 0:
            a = dr[1] if dr[1] > A else A
            if T > a and H is not None:  # launched here from a, or after the truck leaves
                return min(a + float(H[w, U]), T + float(F[w, U]))
            return a + float(F[w, U])
        return float(_least(back_of(k, w, A, T, dr) + F[:, U]))
    cols = _columns(tab, U)
    ends: list[np.ndarray] = []
    backs: list[np.ndarray] = []
    air: list[int] = []  # per airborne drone, its index in drones_left (and ends)
    for k, w, A, T, dr in drones_left:
        if dr[0] == 0:
            a = dr[1] if dr[1] > A else A
            if T > a and H is not None:  # launched here from a, or after the truck leaves
                ends.append(np.minimum(_columns(tab, U, True)[w] + a, cols[w] + T))
            else:
                ends.append(cols[w] + a)
            continue
        back = back_of(k, w, A, T, dr)
        air.append(len(ends))
        backs.append(back)
        ends.append(_least(back[:, None] + cols, axis=0))
    if not tab.one_drone or not tab.ret:
        for e in ends:
            e[0] = 0.0  # column 0 is the empty set: a drone that serves no one more ends nothing
    # a truck with three drones or more, two or more of them airborne: their recoveries on
    # that truck's one timeline (:func:`_chained_recoveries`), before the release term (when
    # it prunes, the release term is not needed)
    chained, least = 0.0, None
    chain: list[int] = []  # the airborne drones of the truck with the most of them
    for k in {drones_left[i][0] for i in air}:
        of_k = [i for i in air if drones_left[i][0] == k]
        if len(of_k) > len(chain):
            chain = of_k
    m = int(tab.popcount[U])
    if (
        len(chain) >= 2
        and len(trucks[drones_left[chain[0]][0]][6]) >= CHAIN_MIN_DRONES
        and m <= PARTITION_MAX_CUSTOMERS
    ):
        pairs = _kept_pairs(tab, U, drop, count) if drop else None
        least = _least_largest_at(ends, m, pairs)
        if least < cutoff and (cutoff == INF or least >= CHAIN_FROM * cutoff):
            chained = _chained_recoveries(
                tab, m, cols, ends, [backs[air.index(i)] for i in chain], chain, pairs, cutoff
            )
            if chained >= cutoff:
                return chained
    v = _split_term(
        tab, U, cols, ends, backs, drones_left, S, svc, times, drop, count, cutoff, least
    )
    return v if v > chained else chained


def _split_term(
    tab: _Tables,
    U: int,
    cols: np.ndarray,
    ends: list[np.ndarray],
    backs: list[np.ndarray],
    drones_left: list,
    S: int | None,
    svc: Sequence[float],
    times: Sequence[float] | None,
    drop: int,
    count: int,
    cutoff: float,
    least: float | None = None,
) -> float:
    """:func:`_sortie_time_bound`'s split of U over two or more drones, from each drone's
    ends per submask of U (``ends``, column 0 set) and the airborne drones' recoveries per stop
    (``backs``): the release term (:func:`_release_term`) and the shared recoveries of two
    airborne drones (:func:`_shared_recoveries`) where they apply, else the least largest
    end. ``least``: the independent split's least largest end over the kept sets
    (``_least_largest_at(ends, m, _kept_pairs(...) if drop else None)``) when the caller has
    it already, else None."""
    # two airborne drones of one truck: recovered by that one truck (:func:`_shared_recoveries`)
    shared = len(backs) == 2 and len(ends) == 2 and drones_left[0][0] == drones_left[1][0]
    if (
        not drop
        and tab.lazy
        and not tab.ret
        and len(ends) <= RELEASE_MAX_DRONES
        and len(ends) ** int(tab.popcount[U]) <= RELEASE_MAX_ROWS
    ):
        # the releases across the drones' parts (:func:`_release_term`): only for labels
        # whose independent term is near the cutoff (skipping it leaves a valid bound)
        if least is None:
            least = _least_largest_at(ends, int(tab.popcount[U]))
        if least < cutoff and (cutoff == INF or least >= RELEASE_FROM * cutoff):
            v = _release_term(
                tab, U, ends, _plain_ends(tab, cols, drones_left, ends), S, svc, times, cutoff
            )
            if v > least:
                if v >= cutoff or not (shared and not drop):
                    return v
                return max(
                    v, _shared_recoveries(tab, cols, backs[0], backs[1], ends[0], ends[1], cutoff)
                )
    if shared and not drop:
        least = float(_least(np.maximum(ends[0], ends[1][::-1])))
        if least >= cutoff or (cutoff < INF and least < SHARED_FROM * cutoff):
            return least  # (already pruned, or too far below the cutoff to be pruned by it)
        return _shared_recoveries(tab, cols, backs[0], backs[1], ends[0], ends[1], cutoff)
    if drop:
        # per subset Z of U (local masks), the least largest end; then the least over the
        # sets U \ Y left to new sorties
        if least is None:
            least = _least_largest_at(ends, int(tab.popcount[U]), _kept_pairs(tab, U, drop, count))
        if (
            least < cutoff
            and least >= RELEASE_FROM * cutoff
            and tab.lazy
            and not tab.ret
            and len(ends) <= RELEASE_MAX_DRONES
        ):
            v = _release_term(
                tab,
                U,
                ends,
                _plain_ends(tab, cols, drones_left, ends),
                S,
                svc,
                times,
                cutoff,
                drop,
                count,
            )
            if v > least:
                least = v
        return least
    if len(ends) == 2:  # the columns ascend: U itself is last, the empty set first
        return float(_least(np.maximum(ends[0], ends[1][::-1])))
    m = int(tab.popcount[U])
    if m <= PARTITION_MAX_CUSTOMERS:
        return _least_largest_at(ends, m)
    size = -(-m // len(ends))
    big = tab.popcount[_submasks(tab, U)] >= size
    return float(min(np.min(e[big]) for e in ends))


def _shared_recoveries(
    tab: _Tables,
    cols: np.ndarray,
    back1: np.ndarray,
    back2: np.ndarray,
    ends1: np.ndarray,
    ends2: np.ndarray,
    cutoff: float = INF,
) -> float:
    r"""The sortie-time term of :func:`_sortie_time_bound` for two airborne drones of one
    truck, with their recoveries made by that one truck (a truck-timeline term: the copy of
    the truck each drone gets there never has to be at two stops).

    ``cols[q, X]``: the sortie-time table's columns over the submasks X of U (ascending, so
    X's complement in U is at the mirrored index); ``back_d[q]``: a lower bound on drone d's
    recovery at stop q with its τ done (:func:`_recoveries`, :func:`_first_recoveries`);
    ``ends_d[X] = min_q back_d[q] + cols[q, X]`` the independent ends (column 0 already
    set to 0 where a drone given nothing ends nothing).

    *Proof.* Take a completion in which drone d serves the set X_d of U by new sorties
    (X_1, X_2 split U: only these two drones fly new sorties, U holding no customer an
    airborne sortie may still take). A drone with X_d nonempty (under ``"return"`` with
    the one-drone table, every drone: it rides home) is first recovered, at a position
    p_d of the truck at stop q_d, at R_d >= back_d[q_d], and then ends no sooner than
    R_d + cols[q_d, X_d] (the relaxation of :func:`_sortie_time_bound` started at its
    recovery). Two cases:

    * q_1 = q_2 = q: the objective is at least
      ``same[X_1] = min_q max(back_1[q] + cols[q, X_1], back_2[q] + cols[q, X_2])``;
    * q_1 != q_2: the positions differ; if p_a < p_b the truck leaves p_a no sooner than
      R_a, reaches q_b no sooner than R_a + tt(q_a, q_b) (tt is a metric, so the stops in
      between only add) and R_b is τ after its arrival at the latest, so
      ``R_b >= g_a[q_b] = min_{q' != q_b} back_a[q'] + tt(q', q_b) + τ`` as well as
      ``back_b[q_b]``; the objective is at least
      ``max(ends_a[X_a], late_b[X_b])``, ``late_b[X] = min_q max(back_b[q], g_a[q]) +
      cols[q, X]``.

    So every completion is at least the least, over X_1, of the smallest of the three
    (the two orders and the same stop), and at least the independent
    ``max(ends_1[X_1], ends_2[X_2])`` pointwise (each case is), so this term is never below
    :func:`_sortie_time_bound`'s. A drone given nothing under ``"last_service"`` needs no
    recovery: that split keeps the independent value."""
    last = cols.shape[1] - 1
    indep = np.maximum(ends1, ends2[::-1])
    least = float(indep.min())  # the independent value
    ridden = tab.one_drone and tab.ret  # every drone is recovered, even one given nothing
    if cutoff < INF:
        # the term at the independent term's best split first (its same-stop part, then
        # the two orders): when one is below the cutoff so is the term (a least over the
        # splits), and the independent value is returned
        i = int(np.argmin(indep))
        if not ridden and i in (0, last):
            return least
        if float(np.maximum(back1 + cols[:, i], back2 + cols[:, last - i]).min()) < cutoff:
            return least
    # only the stops where a drone can be recovered (the other rows are inf throughout)
    at1 = np.flatnonzero(back1 < INF)
    at2 = np.flatnonzero(back2 < INF)
    if not len(at1) or not len(at2):
        return least  # (a drone never recovered)
    apart, tau = tab.tt_apart, tab.tau
    # max(back_d, g_d): drone d recovered after the other one, at another stop
    wait2 = np.maximum(back2[at2], (back1[at1, None] + apart[at1]).min(axis=0)[at2] + tau)
    wait1 = np.maximum(back1[at1], (back2[at2, None] + apart[at2]).min(axis=0)[at1] + tau)
    if cutoff < INF:
        v = max(float(ends1[i]), float((wait2 + cols[at2, last - i]).min()))
        if v < cutoff:
            return least
        v = max(float(ends2[last - i]), float((wait1 + cols[at1, i]).min()))
        if v < cutoff:
            return least
    late2 = (wait2[:, None] + cols[at2]).min(axis=0)
    late1 = (wait1[:, None] + cols[at1]).min(axis=0)
    J = np.minimum(np.maximum(ends1, late2[::-1]), np.maximum(late1, ends2[::-1]))
    both = np.flatnonzero((back1 < INF) & (back2 < INF))
    if len(both):
        same = np.maximum(back1[both, None] + cols[both], back2[both, None] + cols[both, ::-1])
        J = np.minimum(J, same.min(axis=0))
    if not ridden:
        J[0] = ends2[-1]  # a drone given nothing under "last_service" needs no recovery
        J[-1] = ends1[-1]
    return max(float(J.min()), least)


def _chained_recoveries(
    tab: _Tables,
    m: int,
    cols: np.ndarray,
    ends: list[np.ndarray],
    backs: list[np.ndarray],
    chain: list[int],
    pairs: tuple[np.ndarray, np.ndarray] | None = None,
    cutoff: float = INF,
) -> float:
    r"""The sortie-time term of :func:`_sortie_time_bound` with the first recoveries of the
    airborne drones ``chain`` (indices into ``ends``, two or more, all of one truck) made one
    after another on that truck's timeline: a lower bound on the objective of every completion
    (the same completions as :func:`_sortie_time_bound`'s: U's customers served by new
    sorties, save at most ``count`` of ``drop`` by the sorties in the air).

    ``m``: the number of customers in U; ``cols[q, X]``: the sortie-time table's columns over
    the submasks X of U; ``ends[i][X]``: drone i's independent end when it serves X by new
    sorties (column 0 already set); ``backs[c][q]``: a lower bound on the recovery at stop q,
    τ done, of drone ``chain[c]`` (:func:`_recoveries`, :func:`_first_recoveries`);
    ``pairs``: :func:`_kept_pairs` of the customers the sorties in the air may take (None:
    all of U is left to new sorties).

    *Proof.* Take a completion; every drone d of ``chain`` given new sorties (X_d nonempty;
    under ``"return"`` with the one-drone table every drone) is first recovered at a position
    p_d of the truck, at stop q_d, at time R_d >= back_d[q_d]. Order the drones of ``chain``
    by (p_d, R_d), those never recovered before the end last (under ``"last_service"`` only
    a drone given nothing may be: it ends nothing, ``ends[i][∅] = 0``). For consecutive
    recovered drones a, b of this order:

    * p_a = p_b: R_b >= R_a (the order);
    * p_a < p_b: the truck leaves p_a no sooner than R_a (every event at a position is done
      before it leaves), reaches q_b no sooner than ``R_a + tt(q_a, q_b)`` (tt is a metric:
      the stops in between only add) and R_b is at least τ after that arrival.

    So ``R_b >= max(back_b[q_b], R_a + step[q_a, q_b])`` with ``step = tt + τ`` between
    different stops and 0 at the same stop (a relaxation of both cases). By induction along
    the order, the i-th drone's ``R >= r_i[q_i]``, ``r_1 = back``, ``r_i[q] = max(back_i[q],
    min_{q'} r_{i-1}[q'] + step[q', q])``, and it ends no sooner than
    ``e_i[X] = min_q r_i[q] + cols[q, X]`` (the relaxation of :func:`_sortie_time_bound`
    started at its recovery). The other drones keep their ``ends``. So the completion's
    objective is at least the least largest end over the splits of U (the kept sets with
    ``pairs``, :func:`_least_largest_at`) for *its* order; the least over all orders of
    ``chain`` is a lower bound on every completion, and at least the independent split's
    (every order's ends are pointwise >= ``ends``: ``r_i >= back_i``). With a finite
    ``cutoff``, once an order's value is below it the term cannot prune and ``0.0`` is
    returned (a valid bound: the caller keeps its own term)."""
    step = tab.chain_step
    zero = not tab.one_drone or not tab.ret  # a drone given nothing ends nothing
    best = INF
    # the orders by their first drone's least recovery first (the likeliest least)
    first = sorted(range(len(chain)), key=lambda c: float(_least(backs[c])))
    prefixes: dict[tuple[int, ...], tuple[np.ndarray, np.ndarray]] = {}  # (r_i, e_i)
    width = cols.shape[1]
    for order in itertools.permutations(first):
        got = list(ends)
        r = backs[order[0]]
        for i in range(1, len(order)):
            hit = prefixes.get(order[: i + 1])
            if hit is None:
                at = np.flatnonzero(r < INF)
                reach = _least(r[at, None] + step[at], axis=0) if len(at) else tab.nowhere
                r = np.maximum(backs[order[i]], reach)
                at = np.flatnonzero(r < INF)
                e = _least(r[at, None] + cols[at], axis=0) if len(at) else np.full(width, INF)
                if zero:
                    e[0] = 0.0
                hit = prefixes[order[: i + 1]] = (r, e)
            r = hit[0]
            got[chain[order[i]]] = hit[1]
        v = _least_largest_at(got, m, pairs)
        if v < best:
            best = v
            if best < cutoff and cutoff < INF:
                return 0.0
    return best


def _kept_pairs(tab: _Tables, U: int, drop: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (Y, Z ^ Y), Y ⊆ Z, of local indices (among the submasks of U, ascending) over
    the kept sets Z = U \\ X, X ⊆ drop, |X| <= count: :func:`_least_largest_at`'s last step
    (cached per (U, drop, count), the cache cleared past 2^22 indices in all)."""
    key = (U, drop, count)
    got = tab._kept.get(key)
    if got is None:
        m = int(tab.popcount[U])
        local = [i for i, j in enumerate(j for j in range(tab.n) if U >> j & 1) if drop >> j & 1]
        top = (1 << m) - 1
        kept = [
            top ^ sum(1 << i for i in X)
            for size in range(min(count, len(local)) + 1)
            for X in itertools.combinations(local, size)
        ]
        full = np.arange(1 << m, dtype=np.int64)
        Y = np.concatenate([full[(full & ~Z) == 0] for Z in kept])
        Z = np.repeat(np.array(kept, dtype=np.int64), [1 << int(tab.popcount[Z]) for Z in kept])
        got = (Y, Z ^ Y)
        if tab._kept_size + 2 * len(Y) > 1 << 22:
            tab._kept.clear()
            tab._kept_size = 0
        tab._kept[key] = got
        tab._kept_size += 2 * len(Y)
    return got


def _plain_ends(tab: _Tables, cols: np.ndarray, drones_left: list, ends: list) -> list:
    """Per drone left, a lower bound on the time it has served all of each submask X of U by
    new sorties (:func:`_release_term`'s ``plain``): ``a + V[w, X]`` aboard (ready at a), its
    ``ends`` airborne; 0 for X = ∅."""
    plain = [
        cols[w] + (dr[1] if dr[1] > A else A) if dr[0] == 0 else e
        for (_k, w, A, _T, dr), e in zip(drones_left, ends, strict=True)
    ]
    for e in plain:
        e[0] = 0.0
    return plain


def _release_rows(tab: _Tables, U: int, N: int, drop: int = 0, count: int = 0) -> tuple | None:
    """The time-free part of :func:`_release_term` for the unserved set U and N drones,
    memoised per (U, N, drop, count): per assignment of U's customers to the drones, or to
    the sorties in the air (only customers of ``drop``, at most ``count`` of them; "owner"
    N), each drone's part (local indices of the submasks of U), and per customer j of U in a
    topological order: per drone d the local index of ``anc(j) ∩ X_d`` (with j itself on its
    own drone), ``Tail[j, desc(j) ∩ X_own]`` per row (0 in the air), and per predecessor r
    of j in U the least gap ``t_j - t_r`` (``hop(r, j)`` where one drone serves both by new
    sorties, else 0). None when the rows exceed :data:`RELEASE_MAX_ROWS`."""
    drop &= U
    if not drop or not count:
        drop = count = 0
    key = (U, N, drop, count)
    got = tab._release.get(key)
    if got is not None or key in tab._release:
        return got
    cust = [j for j in range(tab.n) if U >> j & 1]
    m = len(cust)
    base = [N + 1 if count and drop >> j & 1 else N for j in cust]
    if math.prod(base) > RELEASE_MAX_ROWS * (2 if count else 1):
        tab._release[key] = None
        return None
    if tab._tail is None:
        tab._tail = _tail_table(tab)
    hop, tail, anc, desc = tab._tail
    digits = np.arange(math.prod(base), dtype=np.int64)
    own = np.empty((m, len(digits)), dtype=np.int64)
    for i in range(m):
        own[i] = digits % base[i]
        digits //= base[i]
    if count:
        own = own[:, (own == N).sum(axis=0) <= count]
        if own.shape[1] > RELEASE_MAX_ROWS:
            tab._release[key] = None
            return None
    rows = own.shape[1]
    parts = np.zeros((N + 1, rows), dtype=np.int64)  # (the last: in the air)
    for i, j in enumerate(cust):
        for d in range(N + 1):
            parts[d] |= (own[i] == d).astype(np.int64) << j
    loc = np.zeros(1 << tab.n, dtype=np.int64)
    loc[_submasks(tab, U)] = np.arange(1 << m, dtype=np.int64)
    at = {j: i for i, j in enumerate(cust)}
    items = []
    every = np.arange(rows)
    for j in tab.topo:
        if j not in at:
            continue
        i = at[j]
        drones = parts[:N]
        mine = (drones >> j) & 1
        idx = loc[(drones & anc[j]) | (mine << j)]
        tj = np.where(own[i] < N, tail[j][parts[own[i], every] & desc[j]], 0.0)
        edges = [
            (r, np.where((own[at[r]] == own[i]) & (own[i] < N), hop[r][j], 0.0))
            for r in tab.preds[j]
            if r in at
        ]
        items.append((j, idx, tj, edges))
    # the same, stacked over the customers (their order kept): per drone the index arrays,
    # the tails, and per customer with predecessors in U their positions and gaps
    at_item = {j: i for i, (j, _idx, _tj, _edges) in enumerate(items)}
    got = (
        loc[parts[:N]],
        [j for j, _idx, _tj, _edges in items],
        np.stack([idx for _j, idx, _tj, _edges in items], axis=1),
        np.stack([tj for _j, _idx, tj, _edges in items]),
        [
            (i, [(at_item[r], add) for r, add in edges])
            for i, (_j, _idx, _tj, edges) in enumerate(items)
            if edges
        ],
    )
    if len(tab._release) > 1 << 12:
        tab._release.clear()
        tab._release_parts.clear()
    tab._release[key] = got
    tab._release_parts[key] = parts[:N].T.tolist()
    return got


def _tail_table(tab: _Tables) -> tuple[list[list[float]], np.ndarray, list[int], list[int]]:
    """(hop, tail, anc, desc): ``hop[a][b]`` a least time between a drone's services of a and
    then b (:func:`_release_term`), ``tail[j][Y]`` the least sum of hops of a path from j
    through every customer of Y (precedences dropped; 0 for Y = ∅), and per customer its
    ancestors and descendants along the precedences (masks)."""
    n, tau = tab.n, tab.tau
    fst = tab.fst_np  # (n, s)
    via = (fst[:, :, None] + tab.tt_np[None, :, :]).min(axis=1)  # (n, s): a -> stop -> stop v
    hopm = (via[:, None, :] + fst[None, :, :]).min(axis=2) + 2 * tau  # recovered between
    if tab.c > 1:
        hopm = np.minimum(hopm, np.asarray(tab.fct) + tau)  # one sortie on
    for k in range(n):  # the least over chains of hops (a lower bound kept)
        hopm = np.minimum(hopm, hopm[:, k : k + 1] + hopm[k : k + 1, :])
    size = 1 << n
    B = np.full((size, n), INF)  # B[Z, f]: a path from f through Z (f in Z)
    for f in range(n):
        B[1 << f, f] = 0.0
    for Z in range(1, size):
        if Z & (Z - 1) == 0:
            continue
        for f in range(n):
            if Z >> f & 1:
                R = Z ^ (1 << f)
                B[Z, f] = float(np.min(hopm[f] + B[R]))
    tail = np.minimum.reduce([hopm[:, f : f + 1] + B[:, f][None, :] for f in range(n)])
    tail[:, 0] = 0.0
    anc = [0] * n
    for j in tab.topo:
        for r in tab.preds[j]:
            anc[j] |= anc[r] | 1 << r
    desc = [0] * n
    for j in range(n):
        for k in range(n):
            if anc[k] >> j & 1:
                desc[j] |= 1 << k
    return hopm.tolist(), tail, anc, desc


def _release_term(
    tab: _Tables,
    U: int,
    ends: list[np.ndarray],
    plain: list[np.ndarray],
    S: int | None,
    svc: Sequence[float],
    times: Sequence[float] | None,
    cutoff: float = INF,
    drop: int = 0,
    count: int = 0,
) -> float:
    r"""The sortie-time term with the releases across the drones' parts (``"last_service"``
    with precedences): a lower bound on the objective of every completion in which the
    drone-only customers of U are served by sorties not yet launched, at least the least
    over the assignments of U to the drones of the largest ``ends[d][X_d]`` (the independent
    term of :func:`_sortie_time_bound`).

    ``ends[d][X]`` is that term's end of drone d serving exactly X; ``plain[d][X]`` a lower
    bound on the time drone d has served all of X (the one-drone table from its ready time
    a, ``a + V[w, X]``, for an aboard drone; its recovery bound plus ``V[q, X]`` for an
    airborne one; 0 for X = ∅).

    *Proof.* Take a completion, and let X_d be the customers of U drone d serves (by new
    sorties: U holds none an airborne sortie may still take). Its objective is at least
    ``ends[d][X_d]`` for every d (:func:`_sortie_time_bound`). For j in X_d and any drone e,
    let ``Y = anc(j) ∩ X_e`` (with j added when e = d): every member of Y is served by
    ``t_j`` (an ancestor through a chain of pairs ``t_j >= t_r``; or j itself). Drone e's
    new sorties with every customer outside Y dropped (a sortie losing a customer flies
    straight on, no longer by the triangle inequality; an emptied one removed) serve Y no
    later, from the same recovery or ready time, on its own copy of the truck (where a
    dropped first sortie moves the next launch to a later stop, so the one-drone table's
    ``V`` and not its launch-here ``H`` applies): so ``t_j >= plain[e][Y]``. Also ``t_j >=
    times[j]`` (a lower bound in every completion), ``t_j >=`` its release and its served
    predecessors' times, and ``t_j >= t_r`` for r -> j, ``t_j >= t_r + hop(r, j)`` when one
    drone serves both: between two services a then b of one drone it flies on from a to b
    (``ft(a, b) + τ``, c >= 2), or is recovered at a stop q (``ft(a, q) + τ``), carried to a
    launch stop v (``tt(q, v)``) and flies to b (``ft(v, b) + τ``); services in between add
    such gaps, so the least over chains of gaps (``hop``) is a lower bound. These give
    ``L_j <= t_j`` in a topological order. Drone d serves j's descendants in X_d after j, in
    some order, each after the one before by at least a hop: its last service is at least
    ``L_j + tail[j, desc(j) ∩ X_d]`` (the least path from j through them, precedences
    dropped). Finally drone d serves all of X_d in some order respecting the pairs inside
    X_d, each j no sooner than ``L_j`` and each after the one before by at least a hop, so
    its last service is at least :func:`_sequence_end` of X_d under the releases L. So the
    completion's objective is at least the row of its assignment: ``max(max_d
    ends[d][X_d], max_j L_j + tail_j, max_d sequence_end(X_d))``, and every completion at
    least the least row.

    With ``drop`` and ``count`` (customers of U of which at most ``count`` may be served by
    the sorties in the air, :func:`_sortie_time_bound`), the rows also put customers of
    ``drop``, at most ``count`` of them, in the air: such a customer is in no drone's part
    and adds no tail and no hop, but keeps its release (served after its ancestors, so
    ``t_j >= plain[e][anc(j) ∩ X_e]`` still, and ``t_j >= times[j]``); every completion is
    then at the row of the assignment it makes.

    *Cost.* The first two parts are taken for every row at once (numpy, the index arrays
    memoised per U by :func:`_release_rows`); the orders (a DP per part, in Python) only for
    the rows still below ``cutoff``, least first, at most :data:`RELEASE_MAX_EXACT` of them
    and parts of at most :data:`RELEASE_MAX_SEQUENCE` customers (a row or part skipped keeps
    its lower value), stopping at the first row that stays below the cutoff: the value
    returned is then the least of that row and the first two parts of the rows after it
    (no more than the least row, so still a lower bound)."""
    got = _release_rows(tab, U, len(ends), drop, count)
    if got is None:
        return 0.0
    drop &= U
    if not drop or not count:
        drop = count = 0
    key = (U, len(ends), drop, count)
    parts, cust, _idx, tails, _edges = got
    top = ends[0][parts[0]]
    for d in range(1, len(ends)):
        top = np.maximum(top, ends[d][parts[d]])
    L = _release_floors(tab, got, plain, S, svc, times)
    top = np.maximum(top, (L + tails).max(axis=0))
    least = float(_least(top))
    if least >= cutoff:
        return least
    # the rows below the cutoff, least first: each part's order under its releases
    cand = np.flatnonzero(top < cutoff)
    if len(cand) > RELEASE_MAX_EXACT:
        return least
    cand = cand[np.argsort(top[cand], kind="stable")]
    hop = tab._tail[0] if tab._tail is not None else []
    owners = tab._release_parts[key]
    rel = [0.0] * tab.n
    best = INF  # the least exact row so far
    for pos, r in enumerate(cand.tolist()):
        for j, v in zip(cust, L[:, r].tolist(), strict=True):
            rel[j] = v
        v = float(top[r])
        for X in owners[r]:
            if X and int(tab.popcount[X]) <= RELEASE_MAX_SEQUENCE:
                e = _sequence_end(tab, X, rel, hop, cutoff)
                if e > v:
                    v = e
                    if v >= cutoff:
                        break
        if v < best:
            best = v
        if v < cutoff:  # the rows not examined are no lower than their own terms
            after = float(top[cand[pos + 1]]) if pos + 1 < len(cand) else INF
            return min(best, after)
    rest = top[top >= cutoff]
    return min(best, float(rest.min()) if len(rest) else INF)


def _release_floors(
    tab: _Tables,
    rows: tuple,
    plain: list[np.ndarray],
    S: int | None,
    svc: Sequence[float],
    times: Sequence[float] | None,
) -> np.ndarray:
    """:func:`_release_term`'s releases: ``L[i, row]`` a lower bound on the service of the
    i-th customer of U (``rows``: :func:`_release_rows`) in every completion of that row's
    assignment: the largest ``plain[e][anc ∩ X_e]``, its release, ``times``, its served
    predecessors' times, and ``L[r] + gap`` over its predecessors r in U (a topological
    order). All customers at once (a maximum is exact in any order), then raised along the
    predecessors, each in turn."""
    _parts, cust, idx, _tails, edges = rows
    L = plain[0][idx[0]]
    for d in range(1, len(plain)):
        L = np.maximum(L, plain[d][idx[d]])
    pred_mask = tab.pred_mask
    floors = []
    for j in cust:
        rel = tab.release[j]
        if times is not None and times[j] > rel:
            rel = times[j]
        if S is not None and pred_mask[j] & S:
            for r in tab.preds[j]:
                if S >> r & 1 and svc[r] > rel:
                    rel = svc[r]
        floors.append(rel if rel > 0.0 else -INF)
    L = np.maximum(L, np.asarray(floors)[:, None])
    for i, gaps in edges:
        for r, add in gaps:
            np.maximum(L[i], L[r] + add, out=L[i])
    return L


def _sequence_end(
    tab: _Tables, X: int, rel: Sequence[float], hop: Sequence[Sequence[float]], cutoff: float
) -> float:
    """A lower bound on the last service of a drone serving the customers of X, each j no
    sooner than ``rel[j]``, two consecutive a then b at least ``hop[a][b]`` apart, a
    predecessor inside X before its successor: the least over such orders of ``t_last``, with
    ``t_first = rel[first]`` and ``t_b = max(t_a + hop[a][b], rel[b])`` (a DP over the served
    subset and the last customer; every time is non-decreasing in the one before, so the
    least time per state is the only one needed). Partial orders at or above ``cutoff`` are
    dropped (their ends are no lower), so the value is ``cutoff`` when every order reaches
    it."""
    pred_mask = tab.pred_mask
    cust = [j for j in range(tab.n) if X >> j & 1]
    cur: dict[tuple[int, int], float] = {}
    for j in cust:
        if not pred_mask[j] & X and rel[j] < cutoff:
            cur[(1 << j, j)] = rel[j]
    for _ in range(len(cust) - 1):
        nxt: dict[tuple[int, int], float] = {}
        for (Z, a), t in cur.items():
            row = hop[a]
            for b in cust:
                if Z >> b & 1 or pred_mask[b] & X & ~Z:
                    continue
                u = t + row[b]
                if rel[b] > u:
                    u = rel[b]
                if u >= cutoff:
                    continue
                key = (Z | 1 << b, b)
                if u < nxt.get(key, INF):
                    nxt[key] = u
        cur = nxt
        if not cur:
            return cutoff
    return min(cur.values()) if cur else cutoff


def _columns(tab: _Tables, U: int, here: bool = False) -> np.ndarray:
    """The sortie-time table's columns of the submasks of U, ascending (with ``here``, those
    of ``launch_here``; cached per U, the caches cleared past 2^23 entries in all)."""
    cache = tab._here if here else tab._cols
    got = cache.get(U)
    if got is None:
        table = tab.launch_here if here else tab.sortie_time
        assert table is not None
        got = np.ascontiguousarray(table[:, _submasks(tab, U)])
        if tab._cols_size + got.size > 1 << 23:
            tab._cols.clear()
            tab._here.clear()
            tab._cols_size = 0
        cache[U] = got
        tab._cols_size += got.size
    return got


@functools.cache
def _subset_pairs(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pair (Z, Y) of masks over m bits with Y ⊆ Z, sorted by Z: (Y, Z ^ Y, the index
    where each Z's pairs start)."""
    full = np.arange(1 << m, dtype=np.int64)
    Z, Y = np.nonzero((full[None, :] & ~full[:, None]) == 0)
    counts = np.bincount(Z, minlength=1 << m)
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    return Y.astype(np.int64), (Z ^ Y).astype(np.int64), starts.astype(np.int64)


def _least_largest(ends: list[np.ndarray], m: int) -> np.ndarray:
    """Per subset Z of m customers (local masks, ascending as the submasks of U), the least
    over the partitions of Z among the drones of the largest ``ends[i][part]``: the
    min-max subset convolution ``g_i[Z] = min_{Y ⊆ Z} max(ends[i][Y], g_{i-1}[Z \\ Y])``,
    3^m pairs per drone (exact, where the size argument of :func:`_sortie_time_bound` is
    not)."""
    Y, rest, starts = _subset_pairs(m)
    g = ends[0]
    for e in ends[1:]:
        g = np.minimum.reduceat(np.maximum(e[Y], g[rest]), starts)
    return g


def _least_largest_at(
    ends: list[np.ndarray], m: int, pairs: tuple[np.ndarray, np.ndarray] | None = None
) -> float:
    """The least, over the sets Z given by ``pairs`` (``(Y, Z ^ Y)`` for every Y ⊆ Z,
    :func:`_kept_pairs`; without it Z is all m customers), of :func:`_least_largest`'s
    ``g[Z]``: the same value, with the last drone's convolution taken only at those Z
    (``min_Z g[Z] = min_Z min_{Y ⊆ Z} max(ends[-1][Y], g'[Z \\ Y])``, g' the convolution of
    the other drones: one flat least over the pairs)."""
    if len(ends) == 1:
        e = ends[0]
        return float(e[-1] if pairs is None else e[pairs[0][pairs[1] == 0]].min())
    g = ends[0] if len(ends) == 2 else _least_largest(ends[:-1], m)
    if pairs is None:  # the submasks ascend: Z \ Y of Y is at the mirrored index
        return float(_least(np.maximum(ends[-1], g[::-1])))
    Y, rest = pairs
    return float(_least(np.maximum(ends[-1][Y], g[rest])))


def _bound(tab: _Tables, label: tuple, cutoff: float = INF) -> float:
    """A lower bound on the objective of every completion of ``label`` (module docstring):
    the largest of its terms.

    The terms are taken cheapest first (the last service so far, or the way home; the
    trucks' covering walks; the drones' sortie times; their shared work; each unserved
    customer's earliest service: the order in which they prune most per microsecond on one
    truck with two drones), and once their maximum reaches ``cutoff`` it is
    returned without the rest: still a valid bound (a maximum of valid terms), and at least
    ``cutoff``, so a caller that prunes at ``cutoff`` prunes the same labels."""
    S, M, svc, trucks = label
    n = tab.n
    tau = tab.tau
    full = tab.full
    lazy = tab.lazy
    unserved = full & ~S
    if lazy:
        # a stale drone launched with no customer yet takes one only after a predecessor
        # served since its launch (:func:`_appendable`); with none left it cannot be
        # completed
        waits = -1
        for _w, _A, _T, _ev, _fin, _F, drones in trucks:
            for dr in drones:
                if dr[0] == 1 and dr[2] == 0 and not dr[6]:
                    if waits < 0:  # the predecessors of the unserved drone-servable customers
                        waits = _watched(tab, S)[2]
                    if not waits & ~dr[7]:
                        return INF
    ret = tab.ret
    if not ret:
        b = M
    else:  # every truck home, an airborne drone recovered and driven home
        b = 0.0
        depot = tab.depot
        for w, _A, T, _ev, fin, F, drones in trucks:
            if fin:
                v = F
            else:
                v = T + tab.tt[w][depot]
                for dr in drones:
                    if dr[0] == 1 and dr[1] >= 0:
                        u = dr[3] + tab.home[dr[1]]
                        if u > v:
                            v = u
            if v > b:
                b = v
    if b >= cutoff or not unserved:
        return b
    # customers an airborne drone with room can take next (``relaxed``, left out of the walk
    # term; the sortie term keeps them, save at most ``room``) and its earliest such service
    relaxed = 0
    ext = 0  # customers a stale drone may take only after its next append ...
    more = 0  # ... at most this many of them in all
    air: list[float] | None = None
    room = 0  # how many customers the sorties in the air may still take, in all
    c = tab.c
    for k, (_w, _A, _T, _ev, fin, _F, drones) in enumerate(trucks):
        if fin:
            continue
        for dr in drones:
            if not (dr[0] == 1 and dr[5] and dr[2] < c):
                continue
            if air is None:
                air = [INF] * n
            room += c - dr[2]
            takes, later, extra, reach = _air_reach(tab, k, dr, S)
            relaxed |= takes
            ext |= later
            more += extra
            t = dr[3]
            for j, fly in reach:
                v = t + fly + tau
                if v < air[j]:
                    air[j] = v
    ext &= ~relaxed
    v = _walk_bound(tab, unserved & ~relaxed, trucks, ext, more)
    if v > b:
        b = v
        if b >= cutoff:
            return b
    est = None
    if any(dr[0] == 1 and dr[2] == 0 for tr in trucks if not tr[4] for dr in tr[6]):
        # a drone launched with no customer yet: its first customer's predecessors'
        # earliest services delay its recovery (:func:`_first_recoveries`), so those first
        est = _earliest_services(tab, S, svc, trucks, air)
        v = _service_term(tab, unserved, est)
        if v > b:
            b = v
            if b >= cutoff:
                return b
    # the drones' sortie times (the most expensive term, but on one truck with several
    # drones it prunes about 30 times as often as the earliest services): every customer a
    # sortie in the air may still take (``relaxed | ext``) is kept, save at most ``room`` of
    # them (those sorties take no more in all; a drone launched with no customer yet is
    # recovered only after its first, which :func:`_first_recoveries` charges)
    v = _sortie_time_bound(
        tab, tab.drone_only & ~S, trucks, S, svc, est, relaxed | ext, room, cutoff
    )
    if v > b:
        b = v
        if b >= cutoff:
            return b
    v = _water_fill(tab, S, trucks)
    if v > b:
        b = v
        if b >= cutoff:
            return b
    if est is None:
        est = _earliest_services(tab, S, svc, trucks, air)
        v = _service_term(tab, unserved, est)
        if v > b:
            b = v
    return b


def next_flight(tab: Any, dr: tuple, j: int) -> float | None:
    """The flight time of the airborne drone ``dr`` from its last customer (or its launch
    stop while it has served none) to customer j, or None when j is out of its range (the
    distance flown, the leg to j and j's nearest way back exceed the drone's range)."""
    o = dr[1]
    if o >= 0:
        dist, fly = tab.fcd[o][j], tab.fct[o][j]
    else:
        dist, fly = tab.fsd[j][-o - 1], tab.fst[j][-o - 1]
    return fly if dr[4] + dist + tab.near[j] <= tab.limit else None


def _air_reach(
    tab: _Tables, k: int, dr: tuple, S: int
) -> tuple[int, int, int, list[tuple[int, float]]]:
    """For an airborne drone ``dr`` of truck k with room (:func:`_bound`): the customers it
    may take next (``relaxed``), those it may take only after its next append and how many
    of them at most (``ext``, ``more``), and (j, its flight time to j) for each of either,
    whose service it bounds from below by ``t + ft + τ``. Memoised per (k, S, ℓ or launch
    stop, distance flown, m, the served set at its last event when it is stale).

    A stale drone takes next only a customer with a predecessor served since its last event
    (:func:`_appendable`); after that append it is fresh, so with room for two it may go on
    to any customer within range (d(ℓ, j) + d(j, k) >= d(ℓ, k)), at most c - m - 1 of them:
    those may stay out of the walk and sortie terms too."""
    stale = tab.lazy and not dr[6]
    key = (k, S, dr[1], dr[4], dr[2], dr[7] if stale else -1)
    got = tab._reach.get(key)
    if got is not None:
        return got
    n, c = tab.n, tab.c
    owner, drone_ok, pred_mask = tab.owner, tab.drone_ok, tab.pred_mask
    flights: dict[int, float] = {}
    found = []
    rule = stale
    for _ in range(2):
        takes = 0
        for j in range(n):
            if S >> j & 1 or not drone_ok[j] or (owner is not None and owner[j] != k):
                continue  # (truck_of: only j's own truck may serve it)
            if rule and not pred_mask[j] & ~dr[7]:
                continue
            fly = next_flight(tab, dr, j)
            if fly is not None:
                takes |= 1 << j
                flights[j] = fly
        found.append(takes)
        if not (rule and takes and c - dr[2] >= 2):
            break
        rule = False
    if len(found) == 2:
        got = (found[0], found[1], c - dr[2] - 1, list(flights.items()))
    else:
        got = (found[0], 0, 0, list(flights.items()))
    if len(tab._reach) > 1 << 16:
        tab._reach.clear()
    tab._reach[key] = got
    return got


def _service_term(tab: _Tables, unserved: int, est: list[float]) -> float:
    """The largest earliest service of an unserved customer (under ``"return"`` plus its
    least way home, ``back``)."""
    b = 0.0
    back = tab.back if tab.ret else None
    for j in range(tab.n):
        if unserved >> j & 1:
            e = est[j] if back is None else est[j] + back[j]
            if e > b:
                b = e
    return b


def _earliest_services(
    tab: _Tables, S: int, svc: Sequence[float], trucks: tuple, air: list[float] | None
) -> list[float]:
    """Per customer, its service time when served (in S), else the least time it can be
    served from the label over the fleet (by a truck at its stop, by a sortie not yet
    launched, :func:`_fresh_sorties`, or appended to an airborne sortie, ``air``), raised
    along the precedences and to its release."""
    n = tab.n
    owner = tab.owner
    fresh = _fresh_sorties(tab, trucks, S, svc)
    tt = tab.tt
    est = [0.0] * n
    for j in tab.topo:
        if S >> j & 1:
            est[j] = svc[j]
            continue
        e = INF if air is None else air[j]
        tok, dok = tab.truck_ok[j], tab.drone_ok[j]
        for k, (w, A, T, _ev, fin, _F, drones) in enumerate(trucks):
            if fin or (owner is not None and owner[j] != k):
                continue
            if tok:
                js = tab.cstop[j]
                v = A if js == w else T + tt[w][js]
                if v < e:
                    e = v
            if dok and drones:
                v = fresh[k][j]
                if v < e:
                    e = v
        for r in tab.preds[j]:
            if est[r] > e:
                e = est[r]
        if tab.release[j] > e:
            e = tab.release[j]
        est[j] = e
    return est


def _needed(tab: _Tables, S: int) -> int:
    """The customers some unserved customer of ``S``'s complement must wait for."""
    if not tab.lazy:
        return 0
    need = 0
    for j in range(tab.n):
        if not S >> j & 1:
            need |= tab.pred_mask[j]
    return need


def _appendable(tab: _Tables, dr: tuple, need: int) -> tuple[bool, int]:
    """The part of an airborne drone's state that says which customers it may still take
    (the key of :func:`_signature`): whether it is fresh and, under precedences, which of
    the customers in ``need`` had been served at its last event.

    *Canonical appends* (precedences only, :func:`_children`): customer j is appended to an
    airborne drone d only while d is *fresh* (no action other than an append since d's last
    launch or append) or when a predecessor of j was served after that event (not in the
    drone's ``seen`` set). This loses no plan's times: in any sequence of actions, move an
    append of j to d that breaks the rule to just before the first non-append action after
    d's last event. There d is fresh; j's time ``max(t + ft(ℓ, j) + τ, t_r)`` is unchanged
    (d's state and every predecessor's time were already final); the actions passed over
    do not involve d or j's successors, so theirs are unchanged too. Each such move puts an
    append where a non-append action was, so the sequence of action kinds decreases
    lexicographically and the moves end, in a sequence that keeps the rule and every time.
    Two labels compare (dominance) only when these parts are equal, so the one kept may
    take every append the other may."""
    if not tab.lazy or not dr[5] or dr[2] >= tab.c:
        return (False, 0)
    return (dr[6], dr[7] & need)


def _watched(tab: _Tables, S: int) -> tuple[int, tuple[int, ...], int]:
    """(:func:`_needed` of S, the served customers of S with an unserved successor, whose
    service times the dominance compares, the predecessors of the unserved drone-servable
    customers); cached per S."""
    got = tab._watch.get(S)
    if got is None:
        if len(tab._watch) > 1 << 16:
            tab._watch.clear()
        succ = tab.succ_mask
        watch = tuple(r for r in range(tab.n) if S >> r & 1 and succ[r] & ~S)
        waits = 0
        for j in range(tab.n):
            if not S >> j & 1 and tab.drone_ok[j]:
                waits |= tab.pred_mask[j]
        got = tab._watch[S] = (_needed(tab, S), watch, waits)
    return got


def _signature(tab: _Tables, label: tuple) -> tuple[tuple, tuple]:
    """(key, vector): labels with equal keys compare by their vectors (all smaller = better)."""
    S, M, svc, trucks = label
    need, watch, _ = _watched(tab, S)
    vec: list[float] = [M] if not tab.ret else []
    for r in watch:
        vec.append(svc[r])
    lazy, c = tab.lazy, tab.c
    if len(trucks) == 1:
        w, A, T, ev, fin, F, drones = trucks[0]
        parts: list[tuple[tuple[Any, ...], tuple[float, ...]]] = []
        for dr in drones:
            if dr[0] == 0:
                parts.append(((0,), (dr[1] if dr[1] > A else A,)))
            elif not lazy or not dr[5] or dr[2] >= c:
                parts.append(((1, dr[1], dr[2], dr[5], False, 0), (dr[3], dr[4])))
            else:
                parts.append(((1, dr[1], dr[2], dr[5], dr[6], dr[7] & need), (dr[3], dr[4])))
        parts.sort()
        vec += (A, T, F)
        for p in parts:
            vec += p[1]
        return (S, ((w, ev, fin, tuple(p[0] for p in parts)),)), tuple(vec)
    per_truck = []
    for w, A, T, ev, fin, F, drones in trucks:
        parts = []
        for dr in drones:
            if dr[0] == 0:
                parts.append(((0,), (dr[1] if dr[1] > A else A,)))
            else:
                parts.append(
                    ((1, dr[1], dr[2], dr[5], *_appendable(tab, dr, need)), (dr[3], dr[4]))
                )
        parts.sort()
        disc = (w, ev, fin, tuple(p[0] for p in parts))
        cont = (A, T, F, *itertools.chain.from_iterable(p[1] for p in parts))
        per_truck.append((disc, cont))
    ordered = []
    for group in tab.groups:
        ordered += sorted(per_truck[k] for k in group)
    key = (S, tuple(d for d, _ in ordered))
    for _, cont in ordered:
        vec.extend(cont)
    return key, tuple(vec)


def _metric_entries(tab: _Tables, label: tuple) -> list[tuple[tuple, int, float, float, tuple]]:
    """Per unfinished truck k: (key without truck k's stop, its stop, A, T, vector).

    Label X dominates label Y of the same such key when X's truck k, driving from its stop to
    Y's, arrives no later than Y's did (``T_X + tt[w_X, w_Y] <= A_Y``) and X's other times
    are all <= Y's: X can drive there and do all Y can, no later (tt is a metric), and its
    aboard drones are ready on arrival."""
    S, M, svc, trucks = label
    need, watch, _ = _watched(tab, S)
    head: list[float] = [M] if not tab.ret else []
    for r in watch:
        head.append(svc[r])
    if len(trucks) == 1:
        w, A, T, _ev, fin, F, drones = trucks[0]
        if fin:
            return []
        lazy, c = tab.lazy, tab.c
        air: list[tuple[tuple[Any, ...], tuple[float, ...]]] = []
        aboard = 0
        for dr in drones:
            if dr[0] == 0:
                aboard += 1
            elif not lazy or not dr[5] or dr[2] >= c:
                air.append(((1, dr[1], dr[2], dr[5], False, 0), (dr[3], dr[4])))
            else:
                air.append(((1, dr[1], dr[2], dr[5], dr[6], dr[7] & need), (dr[3], dr[4])))
        air.sort()
        for p in air:
            head += p[1]
        disc = ((0,),) * aboard + tuple(p[0] for p in air)  # (0,) sorts before (1, ...)
        return [((S, 0, (fin, disc), ()), w, A, T, tuple(head))]
    discs: list[tuple[Any, ...]] = []
    conts: list[tuple[tuple[float, ...], tuple[float, ...]]] = []
    for w, A, T, _ev, fin, F, drones in trucks:
        parts: list[tuple[tuple[Any, ...], tuple[float, ...], tuple[float, ...]]] = []
        for dr in drones:
            if dr[0] == 0:
                parts.append(((0,), (dr[1] if dr[1] > A else A,), ()))
            else:
                parts.append(
                    (
                        (1, dr[1], dr[2], dr[5], *_appendable(tab, dr, need)),
                        (dr[3], dr[4]),
                        (dr[3], dr[4]),
                    )
                )
        parts.sort()
        discs.append((w, fin, tuple(p[0] for p in parts)))
        conts.append(
            (
                (A, T, F, *itertools.chain.from_iterable(p[1] for p in parts)),
                tuple(itertools.chain.from_iterable(p[2] for p in parts)),
            )
        )
    out = []
    for k, (w, A, T, _ev, fin, _F, _drones) in enumerate(trucks):
        if fin:
            continue
        key = (S, k, discs[k][1:], tuple(discs[i] for i in range(len(trucks)) if i != k))
        vec = list(head)
        for i in range(len(trucks)):
            if i != k:
                vec.extend(conts[i][0])
        vec.extend(conts[k][1])
        out.append((key, w, A, T, tuple(vec)))
    return out


def _children(tab: _Tables, label: tuple) -> list[tuple[tuple, Any]]:
    """Every (child label, action) of ``label``."""
    S, M, svc, trucks = label
    n, c, tau = tab.n, tab.c, tab.tau
    out: list[tuple[tuple, Any]] = []
    lazy = tab.lazy
    owner = tab.owner
    # without precedences, a drone being filled (open) takes appends or is closed by any
    # other action; one with no customer yet must be filled first
    filling = None
    if not lazy:
        for k, tr in enumerate(trucks):
            for d, dr in enumerate(tr[6]):
                if dr[0] == 1 and dr[5]:
                    filling = (k, d)

    # with precedences, an airborne drone is *fresh* until an action other than an append
    # is taken (:func:`_appendable`)
    stale = lazy and any(dr[0] == 1 and dr[6] for tr in trucks for dr in tr[6])

    def closed(trs: list, keep: tuple[int, int] | None = None) -> tuple:
        if stale:
            for k2, tr in enumerate(trs):
                if any(dr[0] == 1 and dr[6] for dr in tr[6]):
                    staled = tuple(
                        dr[:6] + (False, dr[7]) if dr[0] == 1 and dr[6] and (k2, d2) != keep else dr
                        for d2, dr in enumerate(tr[6])
                    )
                    trs[k2] = tr[:6] + (staled,)
        if filling is None:
            return tuple(trs)
        k, d = filling
        tr = trs[k]
        dr = tr[6][d]
        if dr[0] == 1 and dr[5]:
            drones = list(tr[6])
            drones[d] = dr[:5] + (False,) + dr[6:]
            trs[k] = tr[:6] + (tuple(drones),)
        return tuple(trs)

    def ready(j: int) -> float | None:
        """max t_r over j's predecessors, or None when one is unserved."""
        if tab.pred_mask[j] & ~S:
            return None
        t = tab.release[j]
        for r in tab.preds[j]:
            if svc[r] > t:
                t = svc[r]
        return t

    # appends
    for k, tr in enumerate(trucks):
        w, A, T, ev, fin, F, drones = tr
        for d, dr in enumerate(drones):
            if dr[0] != 1 or not dr[5] or dr[2] >= c:
                continue
            o = dr[1]
            for j in range(n):
                if S >> j & 1 or not tab.drone_ok[j] or (owner is not None and owner[j] != k):
                    continue
                wait = ready(j)
                if wait is None:
                    continue
                if lazy and not dr[6] and not tab.pred_mask[j] & ~dr[7]:
                    continue  # j could have been appended at the drone's last event
                if o >= 0:
                    dist, fly = tab.fcd[o][j], tab.fct[o][j]
                else:
                    dist, fly = tab.fsd[j][-o - 1], tab.fst[j][-o - 1]
                delta = dr[4] + dist
                if delta + tab.near[j] > tab.limit:
                    continue
                t = dr[3] + fly + tau
                if wait > t:
                    t = wait
                nd = list(drones)
                nd[d] = (1, j, dr[2] + 1, t, delta, True, True, S | 1 << j)
                trs = list(trucks)
                trs[k] = (w, A, T, ev, fin, F, tuple(nd))
                nsvc = svc[:j] + (t,) + svc[j + 1 :]
                out.append(((S | 1 << j, max(M, t), nsvc, tuple(trs)), ("append", k, d, j)))
    if filling is not None:
        k, d = filling
        if trucks[k][6][d][2] == 0:
            return out  # an empty sortie must be filled first
    tt = tab.tt
    for k, tr in enumerate(trucks):
        w, A, T, ev, fin, F, drones = tr
        if fin:
            continue
        tt_w = tt[w]
        # the truck's state at stop w2: here (same position) or after driving there
        moved = tuple((0, 0.0) if dr[0] == 0 else dr for dr in drones)

        def at(
            w2: int,
            w: int = w,
            A: float = A,
            T: float = T,
            drones: tuple = drones,
            tt_w: list = tt_w,
            moved: tuple = moved,
        ) -> tuple[float, float, tuple]:
            if w2 == w:
                return A, T, drones
            a2 = T + tt_w[w2]
            return a2, a2, moved

        # serve j at its stop
        for j in range(n):
            if S >> j & 1 or not tab.truck_ok[j] or (owner is not None and owner[j] != k):
                continue
            wait = ready(j)
            if wait is None:
                continue
            w2 = tab.cstop[j]
            assert w2 is not None  # truck_ok[j]: the constructor required its stop
            A2, T2, dr2 = at(w2)
            t = A2 if A2 > wait else wait
            trs = list(trucks)
            trs[k] = (w2, A2, T2 if T2 > t else t, True, fin, F, dr2)
            nsvc = svc[:j] + (t,) + svc[j + 1 :]
            out.append(((S | 1 << j, max(M, t), nsvc, closed(trs)), ("serve", k, j, w2)))
        # recover an airborne drone at a stop within its range
        airborne = False
        for d, dr in enumerate(drones):
            if dr[0] != 1:
                continue
            airborne = True
            if dr[2] < 1:
                continue
            o = dr[1]
            fsd_o, fst_o = tab.fsd[o], tab.fst[o]
            for w2 in range(tab.s):
                if dr[4] + fsd_o[w2] > tab.limit:
                    continue
                A2, T2, dr2 = at(w2)
                back = dr[3] + fst_o[w2]
                R = (back if back > A2 else A2) + tau
                nd = list(dr2)
                nd[d] = (0, R)
                trs = list(trucks)
                trs[k] = (w2, A2, T2 if T2 > R else R, True, fin, F, tuple(nd))
                out.append(((S, M, svc, closed(trs)), ("recover", k, d, w2)))
        # launch an aboard drone at a stop some unserved customer can be reached from
        classes: dict[float, int] = {}
        for d, dr in enumerate(drones):
            if dr[0] == 0:
                rho = dr[1] if dr[1] > A else A
                classes.setdefault(rho, d)
        if classes:
            useful = tab.launch_ok
            unserved = ~S & tab.full
            for w2 in range(tab.s):
                if not useful[w2] & unserved:
                    continue
                A2, T2, dr2 = at(w2)
                seen_here: set[float] = set()
                for rho0, d in classes.items():
                    rho = A2 if w2 != w else rho0
                    if rho in seen_here:
                        continue
                    seen_here.add(rho)
                    nd = list(dr2)
                    nd[d] = (1, -(w2 + 1), 0, rho, 0.0, True, True, S)
                    trs = list(trucks)
                    trs[k] = (w2, A2, T2 if T2 > rho else rho, True, fin, F, tuple(nd))
                    out.append(((S, M, svc, closed(trs, (k, d))), ("launch", k, d, w2)))
        # finish (only "return" needs it: under last_service a truck may just stop)
        if tab.ret and not airborne:
            trs = list(trucks)
            trs[k] = (w, A, T, ev, True, T + tt_w[tab.depot], drones)
            out.append(((S, M, svc, closed(trs)), ("finish", k)))
    return out


def _complete(tab: _Tables, label: tuple) -> bool:
    S, M, svc, trucks = label
    if S != (1 << tab.n) - 1:
        return False
    for tr in trucks:
        for dr in tr[6]:
            if dr[0] == 1 and dr[2] == 0:
                return False  # a launched drone with no customer
    if tab.ret:
        return all(tr[4] for tr in trucks)
    return True  # under last_service the recoveries left cost nothing (added on rebuild)


def _rebuild(problem: FleetProblem, tab: _Tables, actions: list[Any], final: tuple) -> FleetPlan:
    """Replay the actions from the root into a plan (adding free recoveries at the end)."""
    K = problem.K
    routes = [[problem.depot] for _ in range(K)]
    served: list[list[tuple[int, int]]] = [[] for _ in range(K)]
    flights: list[list[list[Sortie]]] = [[[] for _ in range(problem.drones[k])] for k in range(K)]
    open_: dict[tuple[int, int], tuple[int, list[int]]] = {}
    for act in actions:
        kind, k = act[0], act[1]
        if kind in ("serve", "launch", "recover") and routes[k][-1] != act[3]:
            routes[k].append(act[3])
        here = len(routes[k]) - 1
        if kind == "serve":
            served[k].append((here, act[2]))
        elif kind == "launch":
            open_[(k, act[2])] = (here, [])
        elif kind == "append":
            open_[(k, act[2])][1].append(act[3])
        elif kind == "recover":
            launch, cs = open_.pop((k, act[2]))
            flights[k][act[2]].append(Sortie(launch, tuple(cs), here))
    for (k, d), (launch, cs) in sorted(open_.items()):
        # last_service only: recover at the stop nearest the last customer (no later service)
        stop = int(np.argmin(problem.flight_stop[cs[-1]]))
        if routes[k][-1] != stop:
            routes[k].append(stop)
        flights[k][d].append(Sortie(launch, tuple(cs), len(routes[k]) - 1))
    return FleetPlan(routes, served, flights)


def _simple_plan(problem: FleetProblem, truck_of: Sequence[int] | None = None) -> FleetPlan | None:
    """A feasible plan when one exists: the customers, in a topological order, dealt to the
    trucks in turn (a drone-only one to a truck carrying a drone; with ``truck_of``, customer
    j to truck ``truck_of[j]``, None when that truck cannot serve it); each truck serves its own
    one by one, by itself at the customer's stop when it may, else by a single-customer sortie
    of its first drone launched and recovered at the customer's nearest stop. Every wait
    points to a customer earlier in the order, so no deadlock."""
    if problem.unservable():
        return None
    if truck_of is not None and any(
        not problem.truck_servable(j) and problem.drones[truck_of[j]] == 0 for j in range(problem.n)
    ):
        return None
    import networkx as nx

    K = problem.K
    carriers = [k for k in range(K) if problem.drones[k] > 0]
    routes = [[problem.depot] for _ in range(K)]
    served: list[list[tuple[int, int]]] = [[] for _ in range(K)]
    flights: list[list[Sortie]] = [[] for _ in range(K)]
    for i, j in enumerate(nx.topological_sort(problem.precedence_graph)):
        by_truck = problem.truck_servable(j)
        k = i % K if by_truck or problem.drones[i % K] > 0 else carriers[i % len(carriers)]
        if truck_of is not None:
            k = truck_of[j]
        stop = problem.customer_stop[j] if by_truck else int(np.argmin(problem.flight_stop[j]))
        if routes[k][-1] != stop:
            routes[k].append(stop)
        p = len(routes[k]) - 1
        if by_truck:
            served[k].append((p, j))
        else:
            flights[k].append(Sortie(p, (j,), p))
    sorties = [[flights[k] if d == 0 else [] for d in range(problem.drones[k])] for k in range(K)]
    return FleetPlan(routes, served, sorties)


def _beam(
    problem: FleetProblem, tab: _Tables, width: int, deadline: Deadline, best: float
) -> tuple[float, FleetPlan | None]:
    """A restricted pass of the same search for an incumbent: per number of actions keep the
    ``width`` labels of least bound (no dominance), until complete labels appear."""
    n = problem.n
    root_trucks = tuple(
        (problem.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d)))
        for d in problem.drones
    )
    layer: list[tuple[float, tuple, tuple]] = [(0.0, (0, 0.0, (-1.0,) * n, root_trucks), ())]
    found: tuple[float, tuple, tuple] | None = None
    for _ in range(8 * n + 8 * problem.K + 8):
        if deadline.expired() or not layer:
            break
        nxt: list[tuple[float, tuple, tuple]] = []
        seen: set[tuple] = set()
        for _lb, label, acts in layer:
            if deadline.expired():
                break
            for child, act in _children(tab, label):
                b = _bound(tab, child, best)
                if b >= best or b == INF:
                    continue
                key, vec = _signature(tab, child)
                if (key, vec) in seen:
                    continue
                seen.add((key, vec))
                item = (b, child, acts + (act,))
                if _complete(tab, child):
                    if found is None or b < found[0]:
                        found = item
                    continue
                nxt.append(item)
        if found is not None and (not nxt or min(x[0] for x in nxt) >= found[0]):
            break
        nxt.sort(key=lambda x: (x[0], -bin(x[1][0]).count("1")))
        layer = nxt[:width]
    if found is None:
        return INF, None
    plan = _rebuild(problem, tab, list(found[2]), found[1])
    try:
        return evaluate_fleet(problem, plan), plan
    except FeasibilityError:
        return INF, None


def _memo_key(
    problem: FleetProblem,
    truck_of: Sequence[int] | None,
    release: Sequence[float] | None,
    metric: bool,
    walk: bool,
) -> tuple[Any, ...]:
    """What a :func:`label_search` memo is valid for: the problem's data (its arrays' bytes),
    ``truck_of``, ``release``, ``metric`` and ``walk``."""
    p = problem
    return (
        p.n,
        p.s,
        p.depot,
        tuple(p.drones),
        p.capacity,
        p.flight_limit,
        p.v_drone,
        p.service_time,
        p.objective,
        tuple(p.service),
        tuple(p.customer_stop),
        tuple(sorted(p.precedences)),
        p.truck_time.tobytes(),
        p.flight_stop.tobytes(),
        p.flight_customer.tobytes(),
        None if truck_of is None else tuple(int(k) for k in truck_of),
        None if release is None else tuple(float(r) for r in release),
        bool(metric),
        bool(walk),
    )


def _remember(gone: list[tuple], vec: tuple, count: int) -> None:
    """Add the vector ``vec`` of a label pruned by the bound to its key's pruned memo
    ``gone`` (no vector of which is <= ``vec``: the caller looked), in place.

    The vectors ``vec`` is <= are dropped first: a label one of them dominates is dominated
    by ``vec`` too (<= is transitive), so the memo drops the same labels with fewer vectors
    to scan (measured: a quarter of the vectors kept at K1D2c1 were such). Then, when
    :data:`PRUNED_PER_KEY` vectors remain, ``vec`` replaces the one at ``count`` modulo that
    size (any choice keeps the memo sound: it only forgets)."""
    gone[:] = [other for other in gone if not all(map(le, vec, other))]
    if len(gone) < PRUNED_PER_KEY:
        gone.append(vec)
    else:
        gone[count % PRUNED_PER_KEY] = vec


def trace(parent: Sequence[int], action: Sequence[Any], found: int) -> list[Any]:
    """The actions from the root label (index 0) to label ``found``, in order, read back along
    the ``parent`` indices (the label searches' plan reconstruction)."""
    acts = []
    j = found
    while j > 0:
        acts.append(action[j])
        j = parent[j]
    acts.reverse()
    return acts


def paused_gc(function: _F) -> _F:
    """``function`` with the cyclic garbage collector paused while it runs: the label
    search's millions of acyclic tuples would make each full collection a pause of seconds
    under load, taken past the wall-clock limit (measured: 9 % of a run at n = 8; the search
    checks its clock between labels)."""

    @functools.wraps(function)
    def run(*args: Any, **kwargs: Any) -> Any:
        enabled = gc.isenabled()
        gc.disable()
        try:
            return function(*args, **kwargs)
        finally:
            if enabled:
                gc.enable()

    return cast(_F, run)


@paused_gc
def label_search(
    problem: FleetProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    max_labels: int | None = None,
    metric: bool = True,
    beam: int = 64,
    walk: bool = True,
    truck_of: Sequence[int] | None = None,
    floor: float = 0.0,
    cutoff: float = INF,
    release: Sequence[float] | None = None,
    memo: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Run the search; a dict with ``plan`` (best found or None), ``value``, ``bound``,
    ``stopped_by`` ("optimal", "infeasible", "time_limit" or "size") and counters.

    ``beam``: the width of the beam pass (:func:`_beam`) run for an incumbent, with a fifth of
    the limit, when no ``incumbent`` is given (0: none).

    ``truck_of`` restricts the plans: customer j is served by truck ``truck_of[j]`` or one of
    its drones (the trucks are then not interchangeable); the search then proves the optimum
    over those plans (an ``incumbent`` outside the restriction may still be returned when it
    is better). ``floor``: a known lower bound on that optimum (every label is priced at least
    that, so a plan reaching it stops the search). ``cutoff``: only plans below it are
    sought; when none exists the run ends "optimal" with ``bound`` = min(cutoff, the best
    plan's value) and ``plan`` the best plan given (or None).

    ``release``: per customer j a time before which it may not be served (0 by default; the
    split search's cross-truck predecessors, :func:`taopt.fleet.split.split_search`). The plans
    are then those of ``problem`` with t_j >= release[j] added, and ``value`` is the objective
    of the plan under those releases; incumbents and beam plans are priced by
    :func:`~taopt.fleet.evaluate.evaluate_fleet`, without them, which is no more: a run that
    ends on such a plan returns its release-free value, still a lower bound on the optimum
    with releases (no plan below it was found).

    ``memo``: a dict kept by the caller between runs on the same sub-problem (the split
    search's time slices, :func:`taopt.fleet.split.split_search`). A run stopped by the clock
    or the label cap leaves in it its open search (tables, heap, label store, pruned store,
    counters, best plan); a later run with the same memo continues it instead of starting
    over, and a finished one (optimal, infeasible) empties it. It is valid only for the same
    problem, ``truck_of``, ``release``, ``metric`` and ``walk`` (a key of those is kept: a run
    with another starts fresh). A later run may differ in

    * a lower ``cutoff`` or a better ``incumbent``: the cut only falls, so every label pruned
      or dropped before had no completion below the new cut either, and every label kept
      whose key reaches the new cut is dropped when popped (its key is a lower bound on its
      completions); a *higher* cut than the one the memo was searched under starts fresh;
    * a higher ``floor``: the heap keys are lower bounds on the labels' completions and so is
      the floor (on the optimum), so their maximum is, taken when a label is popped;
    * ``time_limit``, ``max_labels`` (the cap counts every label kept, the resumed ones too).

    So the first complete label popped is still optimal, and the bound of a stopped run is
    still the least open key (raised to the floor), proven.
    """
    deadline = Deadline(time_limit)
    clock = [time.perf_counter()]  # phase ends: start, tables, beam, search
    cap = DEFAULT_MAX_LABELS if max_labels is None else int(max_labels)
    if problem.unservable():
        return {
            "plan": None,
            "value": INF,
            "bound": INF,
            "stopped_by": "infeasible",
            "labels": 0,
            "expanded": 0,
        }
    ident = _memo_key(problem, truck_of, release, metric, walk)
    labels: list[tuple]
    parent: list[int]
    action: list[Any]
    dead: bytearray
    store: dict[tuple, list[tuple[tuple, int]]]
    mindex: dict[tuple, list[tuple[int, float, float, tuple, int]]]
    heap: list[tuple[float, int, int]]
    cutoffs: dict[tuple, list[tuple]]
    tab: _Tables
    best_plan: FleetPlan | None
    state = None if memo is None else memo.pop("state", None)
    if state is not None and state["key"] == ident:
        # resume: the memo's best plan and the caller's incumbent; the beam and the simple
        # plans were tried by the run that opened it
        best, best_plan = best_of(problem, [incumbent, state["plan"]])
        if min(best, cutoff) > state["best"]:
            state = None  # a higher cut than the memo's: its pruned labels may matter now
    else:
        state = None
    resumed = state is not None
    if state is not None:
        tab = state["tab"]
        clock.append(time.perf_counter())
        clock.append(time.perf_counter())
        planned = best
        best = min(best, cutoff)
        labels, parent, action, dead = (
            state["labels"],
            state["parent"],
            state["action"],
            state["dead"],
        )
        store, mindex, cutoffs, heap = (
            state["store"],
            state["mindex"],
            state["cutoffs"],
            state["heap"],
        )
        expanded, dominated, pruned, dominated_cut = state["counters"]
        tt = tab.tt
    else:
        tab = _Tables(
            problem, walk=walk, deadline=Deadline(None if time_limit is None else 0.25 * time_limit)
        )
        if truck_of is not None:
            tab.owner = [int(k) for k in truck_of]
            tab.groups = [[k] for k in range(problem.K)]
        if release is not None:
            tab.release = [float(r) for r in release]
        clock.append(time.perf_counter())
        candidates = [incumbent, _simple_plan(problem, truck_of)]
        if truck_of is None and synced_applies(problem):
            # one truck, several drones: the best synchronised plan (milliseconds at n = 8)
            share = None if time_limit is None else SYNCED_SHARE * time_limit
            candidates.append(synced_plan(problem, share)[1])
        best, best_plan = best_of(problem, candidates)
        if beam and time_limit is not None:
            sub = Deadline(0.2 * time_limit)
        else:
            sub = deadline
        if beam and best > floor and incumbent is None:
            # only without the caller's incumbent: at n = 6-8 with one truck and two or three
            # drones the beam found no plan better than the ILS's in 2 s on any of 18 instances
            # (most found none), while taking a fifth of the limit
            value, beamed = _beam(problem, tab, beam, sub, best)
            if beamed is not None and value < best:
                best, best_plan = value, beamed
        clock.append(time.perf_counter())
        planned = best  # the best plan's value; best may drop to the cutoff (no plan there)
        best = min(best, cutoff)
        n = problem.n
        root_trucks = tuple(
            (problem.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d)))
            for d in problem.drones
        )
        root = (0, 0.0, (-1.0,) * n, root_trucks)
        labels = [root]
        parent = [-1]
        action = [None]
        dead = bytearray(1)
        store = {}
        mindex = {}
        tt = tab.tt
        key, vec = _signature(tab, root)
        store[key] = [(vec, 0)]
        heap = [(max(_bound(tab, root), floor), 0, 0)]
        expanded = dominated = pruned = dominated_cut = 0
        cutoffs = {}  # per key, vectors of labels pruned by the bound
    stopped_by = "optimal"
    found = -1
    slack = 1e-12
    cut = best * (1 - slack)  # a label whose bound reaches it is pruned
    while heap:
        lb, _, i = heapq.heappop(heap)
        if dead[i]:
            continue
        if lb < floor:
            lb = floor  # a resumed search's floor may have risen (docstring: ``memo``)
        if lb >= best * (1 - slack):
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
            # the same discrete state first (a dominated child needs no bound), then the bound
            # (cheapest terms first: most children are pruned by one), then metric dominance
            key, vec = _signature(tab, child)
            bucket = store.get(key)
            if bucket is not None:
                skip = False
                for other, _ in bucket:
                    if all(map(le, other, vec)):
                        skip = True
                        break
                if skip:
                    dominated += 1
                    continue
            gone = cutoffs.get(key)
            if gone is not None:
                skip = False
                for other in gone:
                    if all(map(le, other, vec)):
                        skip = True
                        break
                if skip:
                    dominated_cut += 1
                    continue
            b = _bound(tab, child, cut)
            if b < lb:
                b = lb  # the parent's bound holds for the child's completions too
            if b < floor:
                b = floor
            if b >= cut:
                pruned += 1
                # remembered: a later label it dominates has no completion below the cut
                # either (its completions are matched by this one's, no better), so it is
                # dropped without its bound (the cut only falls)
                if gone is None:
                    cutoffs[key] = [vec]
                else:
                    _remember(gone, vec, pruned)
                continue
            entries = _metric_entries(tab, child) if metric else []
            hit = False
            for mkey, w, A, _T, mvec in entries:
                for ow, _oA, oT, ovec, oid in mindex.get(mkey, ()):
                    if dead[oid] or ow == w:
                        continue
                    if oT + tt[ow][w] <= A and all(map(le, ovec, mvec)):
                        hit = True
                        break
                if hit:
                    break
            if hit:
                dominated += 1
                continue
            if bucket is not None:
                keep = []
                for other, oid in bucket:
                    if all(map(le, vec, other)):
                        dead[oid] = 1
                    else:
                        keep.append((other, oid))
                bucket[:] = keep
            else:
                bucket = store[key] = []
            cid = len(labels)
            for mkey, w, A, T, mvec in entries:
                bucket2 = mindex.setdefault(mkey, [])
                for ow, oA, _oT, ovec, oid in bucket2:
                    if (
                        not dead[oid]
                        and ow != w
                        and T + tt[w][ow] <= oA
                        and all(map(le, mvec, ovec))
                    ):
                        dead[oid] = 1
                bucket2.append((w, A, T, mvec, cid))
            labels.append(child)
            parent.append(i)
            action.append(act)
            dead.append(0)
            bucket.append((vec, cid))
            heapq.heappush(heap, (b, -bin(child[0]).count("1"), cid))
        if len(labels) > cap:
            stopped_by = "size"
            break
    clock.append(time.perf_counter())
    bound = best
    if stopped_by != "optimal":
        live = [b for b, _, j in heap if not dead[j]]
        bound = min(max(min(live, default=best), floor), best)
        if memo is not None:  # left to be continued (docstring: ``memo``)
            memo["state"] = {
                "key": ident,
                "tab": tab,
                "best": best,
                "plan": best_plan,
                "labels": labels,
                "parent": parent,
                "action": action,
                "dead": dead,
                "store": store,
                "mindex": mindex,
                "cutoffs": cutoffs,
                "heap": heap,
                "counters": (expanded, dominated, pruned, dominated_cut),
            }
    result = {
        "labels": len(labels),
        "expanded": expanded,
        "dominated": dominated,
        "pruned": pruned,
        "dominated_by_pruned": dominated_cut,
        "stopped_by": stopped_by,
        "resumed": resumed,
        "seconds": {
            name: round(b - a, 4)
            for name, a, b in zip(("tables", "beam", "search"), clock, clock[1:], strict=False)
        },
    }
    if found >= 0:
        acts = trace(parent, action, found)
        plan = _rebuild(problem, tab, acts, labels[found])
        value = evaluate_fleet(problem, plan)
        # with releases the scorer (which has none) may only say less
        released = release is not None and value <= best * (1 + MATCH_TOLERANCE)
        if not released and abs(value - best) > MATCH_TOLERANCE * max(1.0, abs(value)):
            raise SolverError(
                f"fleet label search: the plan found scores {value!r} but the search says {best!r}"
            )
        best_plan, best = plan, best if released else value
        bound = min(bound, value)
    else:
        best = planned
    result.update(plan=best_plan, value=best, bound=bound)
    return result


__all__ = ["label_search", "DEFAULT_MAX_LABELS"]
