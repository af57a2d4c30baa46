"""Thesis §5.4's insertion heuristics carried to the fleet (§6.2): NIA, MMA and SMMA.

Chapter 5 inserts customers one at a time, in an order that respects the precedence DAG (the
topological-sorting technique of §5.4.1: a customer is *viable* once all its predecessors are
placed), choosing the customer and its place by the drone's travel time (NIA, (5.12)), by the
marginal cost (MMA, (5.14)–(5.16)) or by a one-step look-ahead on the marginal cost (SMMA,
(5.17)–(5.18)). For the fleet, "its place" is a *service option* of one vehicle, appended to
that vehicle's plan so far (:class:`FleetBuilder`):

* ``truck``: truck k drives to the customer's stop (or is there) and serves it;
* ``drone``: drone (k, d) is launched from one of the last positions of truck k where it is
  aboard (or from a new stop near the customer the truck drives to first), serves the customer
  and is recovered either where the truck is, the truck waiting, or at a new stop near the
  customer (or, under ``"return"`` for a truck's last customer in :func:`decode`, at the
  depot) the truck drives to meanwhile (TSP-D's
  truck-and-drone-in-parallel leg), also after driving to a new launch stop;
* ``merge`` (c > 1, the thesis's "sortie merging"): the customer is added to the end of the
  drone's last sortie, when that sortie is recovered at the truck's current position and has
  fewer than c customers and the longer flight stays within the range;
* ``open`` and ``join`` (only when the builder is made with ``open_sorties``, as the ILS's
  decoder under ``"last_service"``): drone (k, d) is launched as for ``drone`` but its
  recovery is left *open*, the truck driving on at once; later customers may ``join`` the
  open sortie (up to c, the flight able to reach a stop near the new last customer within the
  range) while the truck serves elsewhere, and the recovery is placed when the drone is needed
  for a new sortie or at the end (:meth:`~taopt.heuristics.fleet.FleetBuilder.close`): at
  the truck's position then (the truck waiting) or, out of range, at the stop nearest the
  sortie's last customer. Without
  it, a sortie's recovery is fixed when its first customer is placed (where the truck is, or
  one new stop near that customer), so a drone cannot serve two customers while its truck
  drives through several stops (the shipped example's better plans need that).

Every option is checked against the range and the capacity when it is generated, so every plan
built is feasible, and the times the builder keeps are exactly the earliest schedule of
:func:`taopt.fleet.evaluate.schedule` (an option only adds events after the ones already
placed, so no earlier time moves: see :class:`FleetBuilder`). Every method re-scores its plan
with :func:`taopt.evaluate` (:func:`taopt.result.make_solution`).

The rules
---------
* **NIA** (5.12): the viable customer and option with the shortest *leg*: the vehicle's travel
  time to the customer (the drone's flight from its launch stop or previous customer, or the
  truck's drive), ignoring waits; ties by the service time.
* **MMA** (5.14)–(5.16): the least *marginal makespan*: the objective of the partial plan after
  the option minus before it; ties (the usual case while a later customer already fixes the
  makespan) by the service time plus the delay the option adds to the truck.
* **SMMA** (5.17)–(5.18): for each of the ``width`` best (customer, option) pairs by MMA's key,
  the best MMA key of a second viable customer after it; the first whose pair is best is placed.

References
----------
Thesis §5.4 (NIA, MMA, SMMA; §5.4.1 the topological sorting), §6.2 (recommendations 2 and 3).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from taopt.errors import InstanceError
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.registry import register_method
from taopt.result import FEASIBLE, INFEASIBLE, Solution, make_solution

#: Positions of a truck's sequence a drone may be launched from (the last ones where it is
#: aboard): wider finds a little more and costs linearly.
WINDOW = 3

#: Candidate stops per customer for a new launch or recovery stop (the nearest ones in range).
NEAR_STOPS = 3

# Service modes of a customer in an encoding (:func:`decode`). 3P and ILS search over the
# mode of a customer that both a truck and a drone may serve (TSP-D's "truck node" / "drone
# node").

#: The free service mode, the option of least marginal makespan of any kind (the thesis's rule).
FREE = -1
#: The truck service mode, the truck serves the customer at its stop.
TRUCK = 0
#: The drone service mode, a drone serves the customer (a new sortie or a merge into the last).
DRONE = 1
#: ``PINNED + d``: drone d of the customer's truck serves it (the searches' "re-pair" moves
#: choose which drone, and so which customers share a sortie; :data:`DRONE` lets the key choose).
PINNED = 2


def pinned(mode: int) -> int:
    """The drone a service mode pins (-1 when it pins none)."""
    return mode - PINNED if mode >= PINNED else -1


@dataclass
class _Drone:
    """A drone's state while a plan is built: where and when it is next aboard, its sorties."""

    aboard_pos: int = 0
    aboard_time: float = 0.0
    sorties: list[list[Any]] = field(default_factory=list)  # [launch, [customers], recovery]
    # the last sortie, for merging: its flight so far (launch -> last customer) and that
    # customer's service time
    flown: float = 0.0
    last_time: float = 0.0
    # the last sortie's recovery is not placed yet (an *open* sortie, see FleetBuilder)
    open: bool = False


@dataclass
class _Truck:
    """A truck's state: its stop sequence, arrival times, and the earliest departure from its
    last position (every event there included)."""

    route: list[int]
    arrival: list[float]
    ready: float = 0.0
    served: list[tuple[int, int]] = field(default_factory=list)
    drones: list[_Drone] = field(default_factory=list)

    def for_closing(self, d: int) -> _Truck:
        """A view for :meth:`FleetBuilder.close` of drone d: the route, arrivals, services
        and other drones shared (``close`` rebinds, never mutates, the route and arrivals),
        drone d and its last sortie copied. O(drone d's sorties), not O(route)."""
        x = self.drones[d]
        drones = list(self.drones)
        last = x.sorties[-1]
        drones[d] = _Drone(
            x.aboard_pos,
            x.aboard_time,
            [*x.sorties[:-1], [last[0], last[1], last[2]]],
            x.flown,
            x.last_time,
            x.open,
        )
        return _Truck(self.route, self.arrival, self.ready, self.served, drones)

    def copy(self) -> _Truck:
        return _Truck(
            list(self.route),
            list(self.arrival),
            self.ready,
            list(self.served),
            [
                _Drone(
                    d.aboard_pos,
                    d.aboard_time,
                    [[s[0], list(s[1]), s[2]] for s in d.sorties],
                    d.flown,
                    d.last_time,
                    d.open,
                )
                for d in self.drones
            ],
        )


#: An option: (kind, truck, drone, launch position or -1, new stop a or -1, new stop b or -1,
#: service time t_j, the truck's new ready time, the truck's new last stop, leg time).
Option = tuple[str, int, int, int, int, int, float, float, int, float]


class FleetBuilder:
    """A fleet plan built by appending customers; its times are the earliest schedule.

    Parameters
    ----------
    problem : FleetProblem
    window, near : int
        :data:`WINDOW` and :data:`NEAR_STOPS`.
    open_sorties : bool
        Also offer *open* sorties: a drone launched without fixing its recovery, so that
        later customers may join the sortie (up to c) while its truck drives on and serves;
        the recovery is placed only when the drone is needed again or at the end
        (:meth:`~taopt.heuristics.fleet.FleetBuilder.close_all`), at the truck's position
        then (the truck waiting) or, out of range, at the stop nearest the sortie's last
        customer.

    Notes
    -----
    Why the kept times equal :func:`taopt.fleet.evaluate.schedule`'s. Every option adds nodes
    of the schedule's constraint graph whose in-edges come from nodes already placed, and
    raises at most the departure from the truck's *last* position (a recovery there, a served
    customer there, a launch there) — no earlier node has an edge from it. A launch from an
    earlier position p where the drone is aboard does not raise ``Dep[k, p]``: its time
    ``max(A[k, p], R_prev)`` is already at most ``Dep[k, p]`` (the previous recovery at p is
    part of ``Dep[k, p]``; one before p is before ``A[k, p]``). A merge replaces a sortie's
    recovery at the last position by a later one (the triangle inequality: going on to j
    before returning never returns sooner). An open sortie's recovery is placed at the truck's
    *last* position when it is closed, so it too only raises that position's departure.
    Precedences point from customers placed before
    (the customers are placed in a topological order), so no cycle can form either.
    """

    def __init__(
        self,
        problem: FleetProblem,
        window: int = WINDOW,
        near: int = NEAR_STOPS,
        open_sorties: bool = False,
    ):
        self.problem = problem
        self.window = int(window)
        self.open_sorties = bool(open_sorties)
        self.tt = problem.truck_time
        self.fs = problem.flight_stop  # (n, s) distances
        self.fc = problem.flight_customer
        self.vd = float(problem.v_drone)
        self.tau = float(problem.service_time)
        self.limit = float(problem.flight_limit)
        self.c = int(problem.capacity)
        self.depot = int(problem.depot)
        self.return_objective = problem.objective == "return"
        self.trucks = [
            _Truck([self.depot], [0.0], 0.0, [], [_Drone() for _ in range(problem.drones[k])])
            for k in range(problem.K)
        ]
        self.service = np.full(problem.n, np.nan)
        self.last_service = 0.0
        self.order: list[int] = []
        self.truck_of = np.full(problem.n, -1, dtype=np.int64)
        self.mode_of = np.full(problem.n, FREE, dtype=np.int64)
        self.drone_of = np.full(problem.n, -1, dtype=np.int64)  # -1: the truck serves it
        self.preds: list[list[int]] = [[] for _ in range(problem.n)]
        for r, j in problem.precedences:
            self.preds[j].append(int(r))
        # candidate stops of each customer: the nearest ones a drone can reach out and back
        self.near: list[list[int]] = []
        for j in range(problem.n):
            order = np.argsort(self.fs[j], kind="stable")
            ok = [int(w) for w in order if 2.0 * self.fs[j, w] <= self.limit]
            self.near.append(ok[: int(near)])
        # the same distances as Python floats (indexing lists is the options' inner loop) and
        # each customer's shortest flight back to a near stop (an open sortie stays closable)
        self.fs_rows: list[list[float]] = self.fs.tolist()
        self.tt_rows: list[list[float]] = np.asarray(self.tt, dtype=float).tolist()
        self.home = [
            min((self.fs_rows[j][w] for w in self.near[j]), default=math.inf)
            for j in range(problem.n)
        ]
        # candidate recovery stops of a truck's last customer (``final``, set by the
        # decoder): the near ones and, under "return" (every truck ends at the depot), the
        # depot: TSP-D's last operation often recovers the drone there. Not offered earlier:
        # the marginal key does not see that a truck back at the depot must drive out again.
        self.final = np.zeros(problem.n, dtype=bool)
        self.recover: list[list[int]] = [
            w + [self.depot] if self.return_objective and self.depot not in w else w
            for w in self.near
        ]

    # -- reading -------------------------------------------------------------------------------
    def ready_time(self, j: int) -> float:
        """max_r t_r over j's predecessors (all placed: customers go in topological order)."""
        return max((float(self.service[r]) for r in self.preds[j]), default=0.0)

    def truck_return(self, truck: _Truck) -> float:
        return truck.ready + float(self.tt[truck.route[-1], self.depot])

    def objective(self) -> float:
        """The partial plan's objective (the full plan's once every customer is placed)."""
        if self.return_objective:
            return max(self.truck_return(t) for t in self.trucks)
        return self.last_service

    # -- options -----------------------------------------------------------------------------
    def options(
        self,
        j: int,
        k: int,
        truck: _Truck | None = None,
        mode: int = FREE,
        distinct: bool = False,
    ) -> list[Option]:
        """Every option of truck k (itself or one of its drones) for customer j (only those of
        service ``mode`` unless :data:`FREE`). With ``distinct``, a drone's sorties from a new
        stop are left out when an earlier drone of the truck, also aboard, offers the same
        ones (they depend on the truck only; the earlier drone's come first and win a tie)."""
        problem = self.problem
        t = self.trucks[k] if truck is None else truck
        rj = self.ready_time(j)
        out: list[Option] = []
        last = len(t.route) - 1
        here = t.route[last]
        tt = self.tt
        if mode < DRONE and problem.truck_servable(j):
            w = problem.truck_stop(j)
            if w == here:
                tj = max(t.arrival[last], rj)
                out.append(("truck", k, -1, last, -1, -1, tj, max(t.ready, tj), here, 0.0))
            else:
                drive = float(tt[here, w])
                tj = max(t.ready + drive, rj)
                out.append(("truck", k, -1, -1, w, -1, tj, tj, w, drive))
        if mode == TRUCK or not problem.drone_servable(j) or not t.drones:
            return out
        aboard_before = False
        only = pinned(mode)
        for d, drone in enumerate(t.drones):
            if only >= 0 and d != only:
                continue
            if drone.open:
                self._open_options(j, k, d, t, rj, out)
                closed = t.for_closing(d)
                self.close(closed, d)
                self._drone_options(j, k, d, closed, rj, out)
            else:
                self._drone_options(j, k, d, t, rj, out, not (distinct and aboard_before))
                aboard_before = True
        return out

    def _drone_options(
        self,
        j: int,
        k: int,
        d: int,
        t: _Truck,
        rj: float,
        out: list[Option],
        new_stops: bool = True,
    ) -> None:
        """The options of drone d of truck k (its state ``t``) for customer j: new sorties
        (open ones too with ``open_sorties``; from a new stop only with ``new_stops``) and
        merging into its last closed one."""
        vd, tau, limit = self.vd, self.tau, self.limit
        last = len(t.route) - 1
        here = t.route[last]
        fsj = self.fs_rows[j]
        tt_here = self.tt_rows[here]
        near = self.near[j]
        recover = self.recover[j] if self.final[j] else near
        # the shortest way back from j to a stop (an open sortie must stay closable)
        home = self.home[j]
        tt_rows = self.tt_rows
        drone = t.drones[d]
        # launch from an existing position p where the drone is aboard
        for p in range(max(drone.aboard_pos, last - self.window + 1), last + 1):
            a = t.route[p]
            out_leg = fsj[a]
            if 2.0 * out_leg > limit and out_leg + fsj[here] > limit:
                continue
            launch = max(t.arrival[p], drone.aboard_time)
            leg = out_leg / vd + tau
            tj = max(launch + leg, rj)
            back = fsj[here]
            if out_leg + back <= limit:  # recovered where the truck is (it waits)
                rec = max(tj + back / vd, t.arrival[last]) + tau
                out.append(("drone", k, d, p, -1, -1, tj, max(t.ready, rec), here, leg))
            if self.open_sorties and out_leg + home <= limit:  # flies on, open
                out.append(("open", k, d, p, -1, -1, tj, t.ready, here, leg))
            for b in recover:  # recovered at a new stop the truck drives to
                if b == here or out_leg + fsj[b] > limit:
                    continue
                arrive = t.ready + tt_here[b]
                rec = max(tj + fsj[b] / vd, arrive) + tau
                out.append(("drone", k, d, p, -1, b, tj, rec, b, leg))
        # the truck drives to a new stop near j, launches and waits
        for a in near if new_stops else ():
            if a == here:
                continue
            arrive = t.ready + tt_here[a]
            flight = fsj[a] / vd
            leg = flight + tau
            tj = max(arrive + leg, rj)
            leg += arrive - t.ready  # NIA's leg includes the drive (t* of (5.11) does)
            rec = tj + flight + tau
            out.append(("drone", k, d, -1, a, -1, tj, rec, a, leg))
            if self.open_sorties and fsj[a] + home <= limit:  # launch, drive on
                out.append(("open", k, d, -1, a, -1, tj, arrive, a, leg))
            for b in recover:  # ... and drives on to another stop near j to recover it
                if b == a or fsj[a] + fsj[b] > limit:
                    continue
                rec = max(tj + fsj[b] / vd, arrive + tt_rows[a][b]) + tau
                out.append(("drone", k, d, -1, a, b, tj, rec, b, leg))
        # sortie merging (c > 1): j appended to the drone's last sortie
        if drone.sorties and self.c > 1:
            sortie = drone.sorties[-1]
            if sortie[2] == last and len(sortie[1]) < self.c:
                u = sortie[1][-1]
                hop = float(self.fc[u, j])
                if drone.flown + hop + fsj[here] <= limit:
                    leg = hop / vd + tau
                    tj = max(drone.last_time + leg, rj)
                    rec = max(tj + fsj[here] / vd, t.arrival[last]) + tau
                    out.append(("merge", k, d, last, -1, -1, tj, max(t.ready, rec), here, leg))

    def _open_options(
        self, j: int, k: int, d: int, t: _Truck, rj: float, out: list[Option]
    ) -> None:
        """Customer j joins drone d's open sortie (fewer than c customers, and the longer
        flight can still reach a stop near j within the range); the truck is not delayed."""
        drone = t.drones[d]
        sortie = drone.sorties[-1]
        if len(sortie[1]) >= self.c:
            return
        hop = float(self.fc[sortie[1][-1], j])
        if drone.flown + hop + self.home[j] > self.limit:
            return
        leg = hop / self.vd + self.tau
        tj = max(drone.last_time + leg, rj)
        out.append(("join", k, d, -1, -1, -1, tj, t.ready, t.route[-1], leg))

    def close(self, t: _Truck, d: int) -> None:
        """Place the recovery of drone d's open sortie: at truck ``t``'s last position when
        the rest of the flight is within range (the truck waits), else at the stop nearest the
        sortie's last customer that is (the truck drives there)."""
        drone = t.drones[d]
        if not drone.open:
            return
        sortie = drone.sorties[-1]
        u = sortie[1][-1]
        here = t.route[-1]
        spare = self.limit - drone.flown
        if float(self.fs[u, here]) > spare:
            reach = [w for w in self.near[u] if float(self.fs[u, w]) <= spare]
            if not reach:  # cannot happen: every open sortie is checked to stay closable
                raise InstanceError(f"drone {d} cannot be recovered after customer {u}")
            b = min(reach, key=lambda w: (t.ready + float(self.tt[here, w]), w))
            # rebound, not appended: a truck from _Truck.for_closing shares these lists
            t.route = [*t.route, b]
            t.arrival = [*t.arrival, t.ready + float(self.tt[here, b])]
            t.ready = t.arrival[-1]
            here = b
        last = len(t.route) - 1
        rec = max(drone.last_time + float(self.fs[u, here]) / self.vd, t.arrival[last]) + self.tau
        sortie[2] = last
        drone.aboard_pos = last
        drone.aboard_time = rec
        drone.open = False
        t.ready = max(t.ready, rec)

    def close_all(self) -> None:
        """Close every open sortie (:meth:`close`): the plan is then complete."""
        for t in self.trucks:
            for d in range(len(t.drones)):
                self.close(t, d)

    # -- applying ----------------------------------------------------------------------------
    def apply(self, j: int, option: Option, truck: _Truck | None = None) -> None:
        """Place customer j by ``option`` (on ``truck``, a copy, when given: then only the truck
        changes, for a look-ahead; the builder's own state is untouched)."""
        kind, k, d, p, a, b, tj, ready, _, _ = option
        t = self.trucks[k] if truck is None else truck
        if kind not in ("truck", "join") and d >= 0 and t.drones[d].open:
            self.close(t, d)  # the options of an open drone were built after this closure
        if kind == "truck":
            if a >= 0:
                t.route.append(a)
                t.arrival.append(t.ready + float(self.tt[t.route[-2], a]))
            t.served.append((len(t.route) - 1, j))
        elif kind == "join":
            drone = t.drones[d]
            sortie = drone.sorties[-1]
            drone.flown += float(self.fc[sortie[1][-1], j])
            sortie[1].append(j)
            drone.last_time = tj
        elif kind == "merge":
            drone = t.drones[d]
            sortie = drone.sorties[-1]
            u = sortie[1][-1]
            drone.flown += float(self.fc[u, j])
            sortie[1].append(j)
            drone.last_time = tj
            drone.aboard_time = self._recovery(t, j, tj)
        else:
            drone = t.drones[d]
            if a >= 0:  # drive to a new stop, launch there
                t.route.append(a)
                t.arrival.append(t.ready + float(self.tt[t.route[-2], a]))
                p = len(t.route) - 1
            launch_stop = t.route[p]
            if kind == "open":
                drone.sorties.append([p, [j], -1])
                drone.flown = float(self.fs[j, launch_stop])
                drone.last_time = tj
                drone.open = True
                t.ready = ready
                if truck is None:
                    self._record(j, tj, k, DRONE, d)
                return
            if b >= 0:  # the truck leaves its last stop (the new launch stop: at once)
                depart = t.arrival[-1] if a >= 0 else t.ready
                t.route.append(b)
                t.arrival.append(depart + float(self.tt[t.route[-2], b]))
            last = len(t.route) - 1
            drone.sorties.append([p, [j], last])
            drone.flown = float(self.fs[j, launch_stop])
            drone.last_time = tj
            drone.aboard_pos = last
            drone.aboard_time = self._recovery(t, j, tj)
        t.ready = ready
        if truck is None:
            self._record(j, tj, k, TRUCK if kind == "truck" else DRONE, d)

    def _record(self, j: int, tj: float, k: int, mode: int, d: int) -> None:
        self.service[j] = tj
        self.last_service = max(self.last_service, tj)
        self.order.append(j)
        self.truck_of[j] = k
        self.mode_of[j] = mode
        self.drone_of[j] = d if mode == DRONE else -1

    def _recovery(self, t: _Truck, j: int, tj: float) -> float:
        here = t.route[-1]
        return max(tj + float(self.fs[j, here]) / self.vd, t.arrival[-1]) + self.tau

    # -- snapshots (the searches re-decode from a prefix) -------------------------------------
    def snapshot(self) -> tuple[Any, ...]:
        """A deep copy of the state after the customers placed so far."""
        return (
            [t.copy() for t in self.trucks],
            self.service.copy(),
            self.last_service,
            list(self.order),
            self.truck_of.copy(),
            self.mode_of.copy(),
            self.drone_of.copy(),
        )

    def restore(self, state: tuple[Any, ...]) -> None:
        """Back to a :meth:`snapshot` (copied again: the snapshot stays reusable)."""
        trucks, service, last_service, order, truck_of, mode_of, drone_of = state
        self.trucks = [t.copy() for t in trucks]
        self.service = service.copy()
        self.last_service = last_service
        self.order = list(order)
        self.truck_of = truck_of.copy()
        self.mode_of = mode_of.copy()
        self.drone_of = drone_of.copy()

    def place(self, j: int, k_fixed: int = -1, mode: int = FREE) -> None:
        """Place customer j by its least-marginal option among truck ``k_fixed``'s (-1: any
        truck able to serve it) of service mode ``mode`` (:data:`FREE`: any; :data:`TRUCK`:
        the truck serves j; :data:`DRONE`: a drone does; ``PINNED + d``: drone d does).

        Raises
        ------
        InstanceError
            No option (truck ``k_fixed`` cannot serve j in that mode).
        """
        ks = servers(self.problem, j) if k_fixed < 0 else [k_fixed]
        best: Option | None = None
        best_key: tuple[float, float] | None = None
        # MMA's key (:meth:`marginal`), inlined: this loop is the searches' inner loop
        before = self.objective()
        returning = self.return_objective
        tt, depot = self.tt, self.depot
        for k in ks:
            t_ready = self.trucks[k].ready
            for o in self.options(j, k, mode=mode, distinct=mode < PINNED):
                tj, ready = o[6], o[7]
                if returning:
                    after = max(before, ready + float(tt[o[8], depot]))
                else:
                    after = max(before, tj)
                key = (after - before, tj + (ready - t_ready))
                if best_key is None or key < best_key:
                    best, best_key = o, key
        if best is None:
            how = "" if mode == FREE else (" by truck" if mode == TRUCK else " by drone")
            if mode >= PINNED:
                how = f" by drone {pinned(mode)}"
            raise InstanceError(f"truck {k_fixed} cannot serve customer {j}{how}")
        self.apply(j, best)

    # -- keys --------------------------------------------------------------------------------
    def marginal(self, option: Option, truck: _Truck | None = None) -> tuple[float, float]:
        """MMA's key: (the objective after the option minus before, service time plus the
        delay the option adds to its truck)."""
        _, k, _, _, _, _, tj, ready, stop, _ = option
        t = self.trucks[k] if truck is None else truck
        before = self.objective()
        if self.return_objective:
            after = max(before, ready + float(self.tt[stop, self.depot]))
        else:
            after = max(before, tj)
        return (after - before, tj + (ready - t.ready))

    # -- the plan ----------------------------------------------------------------------------
    def plan(self) -> FleetPlan:
        """The payload (every customer must be placed)."""
        return FleetPlan(
            [list(t.route) for t in self.trucks],
            [[list(pair) for pair in t.served] for t in self.trucks],
            [
                [[Sortie(s[0], tuple(s[1]), s[2]) for s in drone.sorties] for drone in t.drones]
                for t in self.trucks
            ],
        )


# ---------------------------------------------------------------------------------------------
# Viable customers (§5.4.1) and the three rules
# ---------------------------------------------------------------------------------------------


class _Viable:
    """The topological-sorting technique: customers whose predecessors are all placed."""

    def __init__(self, problem: FleetProblem) -> None:
        self.waiting = np.zeros(problem.n, dtype=np.int64)
        self.successors: list[list[int]] = [[] for _ in range(problem.n)]
        for r, j in problem.precedences:
            self.waiting[j] += 1
            self.successors[r].append(int(j))
        self.open = [j for j in range(problem.n) if self.waiting[j] == 0]

    def place(self, j: int) -> list[int]:
        """Remove j; return the customers that became viable."""
        self.open.remove(j)
        new = []
        for v in self.successors[j]:
            self.waiting[v] -= 1
            if self.waiting[v] == 0:
                new.append(v)
        self.open.extend(new)
        return new


def servers(problem: FleetProblem, j: int) -> list[int]:
    """The trucks that can serve customer j (by truck or by one of their drones)."""
    out = []
    for k in range(problem.K):
        if problem.truck_servable(j) or (problem.drone_servable(j) and problem.drones[k] > 0):
            out.append(k)
    return out


def _check_servable(problem: FleetProblem) -> str:
    """ "" when every customer can be served, else why not (naming the first customer)."""
    missing = problem.unservable()
    if missing:
        j = missing[0]
        why = "no truck carries a drone" if problem.D == 0 else "out of every drone's range"
        return f"customer {j} may only be served by a drone and {why}"
    return ""


def construct(
    problem: FleetProblem, rule: str, width: int = 4, window: int = WINDOW, near: int = NEAR_STOPS
) -> FleetBuilder:
    """Build a plan with rule ``"NIA"``, ``"MMA"`` or ``"SMMA"`` (see the module docstring).

    The options of every viable customer are kept per truck and recomputed only for the truck
    that changed (and for customers that just became viable), so a step costs
    O(viable × options of one truck).

    Raises
    ------
    InstanceError
        Unknown rule, or ``width < 1``.
    """
    if rule not in ("NIA", "MMA", "SMMA"):
        raise InstanceError(f"rule must be NIA, MMA or SMMA, got {rule!r}")
    if width < 1:
        raise InstanceError(f"width must be >= 1, got {width}")
    builder = FleetBuilder(problem, window, near)
    viable = _Viable(problem)
    trucks_of = [servers(problem, j) for j in range(problem.n)]
    cache: dict[tuple[int, int], list[Option]] = {}

    def refresh(j: int, k: int) -> None:
        cache[(j, k)] = builder.options(j, k)

    for j in viable.open:
        for k in trucks_of[j]:
            refresh(j, k)
    while viable.open:
        candidates = [(j, o) for j in viable.open for k in trucks_of[j] for o in cache[(j, k)]]
        if rule == "NIA":
            j, best = min(candidates, key=lambda c: (c[1][9], c[1][6], c[0]))
        elif rule == "MMA" or len(viable.open) == 1:
            j, best = min(candidates, key=lambda c: (*builder.marginal(c[1]), c[0]))
        else:
            j, best = _smma_step(builder, viable.open, trucks_of, cache, candidates, width)
        builder.apply(j, best)
        k = best[1]
        for v in viable.place(j):
            for kk in trucks_of[v]:
                refresh(v, kk)
        del_keys = [key for key in cache if key[0] == j]
        for key in del_keys:
            del cache[key]
        for v in viable.open:
            if k in trucks_of[v]:
                refresh(v, k)
    return builder


def _smma_step(
    builder: FleetBuilder,
    open_: list[int],
    trucks_of: list[list[int]],
    cache: dict[tuple[int, int], list[Option]],
    candidates: list[tuple[int, Option]],
    width: int,
) -> tuple[int, Option]:
    """(5.17): the first customer whose pair (itself, then the best second one) is best."""
    firsts: dict[int, tuple[tuple[float, float], Option]] = {}
    for j, o in candidates:  # each customer's best option (q1* of (5.17))
        key = builder.marginal(o)
        if j not in firsts or key < firsts[j][0]:
            firsts[j] = (key, o)
    ranked = sorted(firsts.items(), key=lambda item: (item[1][0], item[0]))[:width]
    before = builder.objective()
    best: tuple[Any, ...] | None = None
    for j1, (key1, o1) in ranked:
        k1 = o1[1]
        trial = builder.trucks[k1].copy()
        builder.apply(j1, o1, truck=trial)
        tj1 = o1[6]
        # the partial plan after j1: objective and last service as the builder would hold them
        saved = builder.service[j1], builder.last_service
        builder.service[j1] = tj1
        builder.last_service = max(builder.last_service, tj1)
        after1 = (
            max(before, o1[7] + float(builder.tt[o1[8], builder.depot]))
            if builder.return_objective
            else builder.last_service
        )
        second = math.inf, math.inf
        for j2 in open_:
            if j2 == j1:
                continue
            for k in trucks_of[j2]:
                options = builder.options(j2, k, trial) if k == k1 else cache[(j2, k)]
                for o2 in options:
                    tj2, ready2, stop2 = o2[6], o2[7], o2[8]
                    t = trial if k == k1 else builder.trucks[k]
                    if builder.return_objective:
                        after2 = max(after1, ready2 + float(builder.tt[stop2, builder.depot]))
                    else:
                        after2 = max(after1, tj2)
                    key2 = (after2 - before, tj2 + (ready2 - t.ready))
                    if key2 < second:
                        second = key2
        builder.service[j1], builder.last_service = saved
        total = (second[0] if math.isfinite(second[0]) else key1[0], key1[1] + second[1])
        if not math.isfinite(total[1]):
            total = key1
        if best is None or (total, j1) < best[0]:
            best = ((total, j1), j1, o1)
    assert best is not None
    return best[1], best[2]


# ---------------------------------------------------------------------------------------------
# Registered methods
# ---------------------------------------------------------------------------------------------


def infeasible_solution(problem: FleetProblem, name: str, why: str, began: float) -> Solution:
    """No plan exists (a customer nobody can serve): status ``infeasible``, no payload."""
    return make_solution(
        problem,
        None,
        method=name,
        status=INFEASIBLE,
        runtime=time.perf_counter() - began,
        info={"reason": why},
    )


def _rule_method(name: str, problem: FleetProblem, seed: int, **options: Any) -> Solution:
    began = time.perf_counter()
    why = _check_servable(problem)
    if why:
        return infeasible_solution(problem, name, why, began)
    builder = construct(problem, name, **options)
    return make_solution(
        problem,
        builder.plan(),
        method=name,
        status=FEASIBLE,
        runtime=time.perf_counter() - began,
        seed=seed,
        info={"order": list(builder.order), "built_objective": builder.objective()},
    )


@register_method(FleetProblem, "NIA", style=("-", "o"))
def nia_fleet(
    problem: FleetProblem, seed: int = 0, window: int = WINDOW, near: int = NEAR_STOPS
) -> Solution:
    """NIA (5.12) for the fleet: the viable customer and vehicle with the shortest leg.

    Deterministic (``seed`` is only recorded). ``window``: launch positions tried per drone;
    ``near``: candidate new stops per customer. ``info["order"]``: the serving order built.
    """
    return _rule_method("NIA", problem, seed, window=window, near=near)


@register_method(FleetProblem, "MMA", style=("--", "s"))
def mma_fleet(
    problem: FleetProblem, seed: int = 0, window: int = WINDOW, near: int = NEAR_STOPS
) -> Solution:
    """MMA (5.14)–(5.16) for the fleet: each customer to the truck, drone and sortie of least
    marginal makespan (options as NIA)."""
    return _rule_method("MMA", problem, seed, window=window, near=near)


@register_method(FleetProblem, "SMMA", style=("-.", "D"))
def smma_fleet(
    problem: FleetProblem,
    seed: int = 0,
    width: int = 4,
    window: int = WINDOW,
    near: int = NEAR_STOPS,
) -> Solution:
    """SMMA (5.17)–(5.18) for the fleet: MMA with a one-customer look-ahead over the ``width``
    best first choices (options as NIA)."""
    return _rule_method("SMMA", problem, seed, width=width, window=window, near=near)


# ---------------------------------------------------------------------------------------------
# The decoder shared by 3P and ILS: a priority order and (optionally) fixed trucks
# ---------------------------------------------------------------------------------------------


def decode(
    problem: FleetProblem,
    order: Sequence[int],
    truck_of: Sequence[int] | np.ndarray | None = None,
    window: int = WINDOW,
    near: int = NEAR_STOPS,
    modes: Sequence[int] | np.ndarray | None = None,
    open_sorties: bool = False,
) -> FleetBuilder:
    """Place the customers in ``order`` (a topological order of G^p), each by its option of
    least marginal makespan (MMA's key) among the trucks ``truck_of[j]`` (-1 or None: any)
    and of service mode ``modes[j]`` (:data:`FREE` or None: any; :data:`TRUCK`;
    :data:`DRONE`; ``PINNED + d``: drone d of the truck).

    The last customer of each truck (:func:`final_customers`) may also have its sortie
    recovered at the depot under ``"return"``.

    A drone customer placed after the truck customers a truck serves while the drone flies is
    launched from the stop before them (one of the last :data:`WINDOW` positions) and
    recovered where the truck is: the order and the modes together express TSP-D's
    operations (launch, truck serves on, recovery), which the free rule alone never builds.

    With ``open_sorties`` the builder also offers open sorties (see the module docstring and
    :meth:`~taopt.heuristics.fleet.FleetBuilder.close`); every one still open at the end is
    closed before returning.

    Raises
    ------
    InstanceError
        ``order`` is not a permutation respecting the precedences, or ``truck_of[j]`` cannot
        serve j (in mode ``modes[j]``).
    """
    builder = FleetBuilder(problem, window, near, open_sorties)
    builder.final = final_customers(problem, order, truck_of)
    placed = np.zeros(problem.n, dtype=bool)
    for j in order:
        for r in builder.preds[j]:
            if not placed[r]:
                raise InstanceError(f"order places customer {j} before its predecessor {r}")
        builder.place(
            j,
            -1 if truck_of is None else int(truck_of[j]),
            FREE if modes is None else int(modes[j]),
        )
        placed[j] = True
    if not placed.all():
        raise InstanceError(f"order misses customer {int(np.flatnonzero(~placed)[0])}")
    builder.close_all()
    return builder


def final_customers(
    problem: FleetProblem,
    order: Sequence[int],
    truck_of: Sequence[int] | np.ndarray | None = None,
) -> np.ndarray:
    """Which customers are the last of their truck in ``order`` (the last of the order when
    ``truck_of`` is None or -1 for it)."""
    final = np.zeros(problem.n, dtype=bool)
    seen: set[int] = set()
    for j in reversed(list(order)):
        k = -1 if truck_of is None else int(truck_of[j])
        if k not in seen:
            final[j] = True
            seen.add(k)
    return final


__all__ = [
    "DRONE",
    "FREE",
    "PINNED",
    "TRUCK",
    "FleetBuilder",
    "construct",
    "decode",
    "final_customers",
    "pinned",
    "servers",
]
