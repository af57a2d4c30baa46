"""Chapter 4's algorithms CAA, DAA and HDA, as policies of the event-driven engine.

Each algorithm is a :class:`~taopt.comm.engine.Policy`: it plans a vehicle's initial route
alone, and reacts when a group of vehicles becomes newly connected by exchanging messages
through the :class:`~taopt.comm.engine.Group` (which counts every message with the one byte
model of :mod:`taopt.comm.bytes`) and setting routes. None of them advances time.

* **CAA** (Algorithm 3, §4.3.1): every member floods its information tuple for n rounds
  (the leader — most one-hop neighbours, ties drawn with the run's seed — thus holds all of
  them), the leader merges what is known to be visited (4.5)–(4.6), decides with line 15
  whether to reassign, builds the cooperative targets (4.7)–(4.8) and assigns them by the
  smallest marginal cost (4.9)–(4.13) from empty routes; per ability class the new routes
  are kept only if they do not lengthen the class's projected total (4.14); the result is
  flooded back (|R_i| rounds).
* **DAA** (Algorithms 4–6, §4.3.2): Phase 1 floods ``X_j(:, 1:n+2)``, ``R^c_j`` and ``s_j``
  for n rounds, then (line 15) positions and projected distances, then the β of the
  vehicles named by (4.7) to agree on T_i; Phase 2 assigns the cooperative targets one at a
  time — every member bids its cheapest insertion (4.9) on every target, the bids are
  flooded for |R_i| rounds keeping the smallest (c, β), and each member reads the winner
  from its own copy; Phase 3 floods the new projected distances (|R_i| rounds) and each
  class keeps its new routes only if (4.14) does not grow.
* **HDA** (Zhao, Meng & Chung 2016, as the thesis describes it in §4.1 and §4.4.2): the
  same Phase 1; then, starting from the members' current routes restricted to T_i, every
  member computes the *significance* of each target on its route (distance saved by
  removing it) and the *marginal significance* of each other target of its ability (its
  cheapest insertion); the smallest of each per target (with the vehicle naming it) is
  flooded. A target on several routes (fresh vehicles all hold every target of their
  ability) stays with the holder of the smallest significance, the others drop it; a
  member releases a target when another member's marginal significance is smaller than its
  significance, and that member takes it over. Releases are agreed by a second flood and
  made largest saving first, each member in at most one per iteration; repeat until no
  release saves distance. Every iteration lowers the projected total, so HDA needs no
  Phase 3 (see :meth:`HDA.release_loop`).

Decisions where the thesis is ambiguous (kept in this one place)
----------------------------------------------------------------
* **u_jk and line 15.** ``u_jk`` is the time of the last *adopted* reassignment that j and
  k took part in together (NaN if never; the printed ``u_j(0) = 0`` would make two fresh
  vehicles look up to date), and ``max u_k`` the time of k's last adopted joint
  reassignment. Line 15 fires when two members of one ability have ``u_jk`` differing from
  ``max u_k`` or ``max u_j`` — they have never reassigned together, or one has reassigned
  with someone else since. (4.15) sets ``u_jk = t`` for the members of each ability class
  whose new routes were adopted (a class of one vehicle records nothing).
* **(4.7).** ``R^1_ij`` are the members of ability a that have never adopted a joint
  reassignment (so their route still holds every target of ability a they do not know to be
  visited), ``R^2_ij`` the others; ``p`` the member of ``R^1`` with the shortest projected
  route (lowest id on ties). ``T_ij = o_p`` when ``R^2`` is empty or
  ``Σ_{R^2} d(o_k) >= d(o_p)``, else the union of the ``R^2`` routes — the first case of the
  printed equation, whose two conditions are split across its lines. The members of class a
  whose targets are not in ``T_ij`` drop them (they are on other vehicles' routes, Lemma
  4.3's argument).
* **Reassignment scope.** When line 15 fires the whole group reassigns (T_i of every class,
  (4.8)); the keep-or-adopt test (4.14) / Alg. 6 l. 20 is made per ability class, adopting
  when ``f'_ij <= f_ij``.
* **Ties.** The smallest marginal cost wins; among equal costs the lowest target index,
  then the lowest vehicle index (CAA and DAA alike, so they agree to the bit); insertion at
  the earliest position.
* **Phase 1 length.** n rounds as printed, or m when there are fewer targets than vehicles
  (the thesis assumes n > m; n rounds could then leave a long group without consensus).
* **Messages** and their sizes: :mod:`taopt.comm.bytes`.
"""

from __future__ import annotations

import contextvars
import math
import time
from collections.abc import Sequence

import numpy as np

from taopt.comm.engine import Group, Policy, Simulation, SimulationStopped
from taopt.comm.problem import CommProblem
from taopt.comm.routes import InsertionTable, insert, insertion_costs, removal_savings
from taopt.errors import ConvergenceError
from taopt.heuristics.ga_routing import improve_routes
from taopt.registry import register_improver, register_method
from taopt.result import FEASIBLE, TIME_LIMIT, Solution, make_solution
from taopt.runtime import Deadline

#: Savings below this (metres) do not count as an improvement (HDA's stopping rule).
SAVING_TOLERANCE = 1e-9


# -- the marginal-cost auction, centrally (CAA) --------------------------------------------


#: The deadline of the simulation running in this context (set by a run with a time limit):
#: the auctions check it between insertions, so a run stops inside a long auction too.
_DEADLINE: contextvars.ContextVar[Deadline | None] = contextvars.ContextVar(
    "taopt_comm_deadline", default=None
)


def _check_deadline() -> None:
    """Raise SimulationStopped if the running simulation's deadline has passed."""
    deadline = _DEADLINE.get()
    if deadline is not None and deadline.expired():
        raise SimulationStopped("time limit reached during an auction")


def central_auction(
    problem: CommProblem,
    starts: np.ndarray,
    abilities: np.ndarray,
    targets: Sequence[int] | np.ndarray,
) -> list[list[int]]:
    """CAA's assignment (4.9)–(4.13) of ``targets`` to vehicles at ``starts``, from empty routes.

    Repeatedly the pair (vehicle j*, target q*) with the smallest marginal cost ``c_jq``
    (4.9) over the vehicles able to visit q is chosen (4.11) and q* inserted at its cheapest
    position in o'_j* (4.12); ties go to the lowest target, then the lowest vehicle.

    Parameters
    ----------
    problem : CommProblem
    starts : (k, n) array
        Distances from the vehicles' current positions p_j(t) to every target.
    abilities : (k,) int array
        Their ability codes.
    targets : sequence of int
        The targets to assign (each must have a vehicle of its attribute among the k).

    Returns
    -------
    list of k routes
    """
    targets = np.array(sorted(int(q) for q in targets), dtype=np.int64)
    k = len(starts)
    routes: list[list[int]] = [[] for _ in range(k)]
    if targets.size == 0:
        return routes
    dist = problem.distances[: problem.n, : problem.n]
    own = np.asarray(abilities)[:, None] == problem.target_code[targets][None, :]
    tables = [InsertionTable(starts[i], targets[own[i]], dist) for i in range(k)]
    costs = np.full((k, targets.size), np.inf)  # (4.9) for every vehicle and target
    where = np.zeros((k, targets.size), dtype=np.int64)
    for i in range(k):
        costs[i, own[i]], where[i, own[i]] = tables[i].cost, tables[i].position
    active = np.ones(targets.size, dtype=bool)
    for _ in range(targets.size):
        _check_deadline()
        columns = np.flatnonzero(active)
        block = costs[:, columns]
        best_vehicle = np.argmin(block, axis=0)  # lowest vehicle on ties
        best_cost = block[best_vehicle, np.arange(columns.size)]
        pick = int(np.argmin(best_cost))  # lowest target on ties
        if not math.isfinite(best_cost[pick]):
            raise ConvergenceError(
                f"no vehicle of the group can visit target {targets[columns[pick]]}"
            )
        q, j = int(columns[pick]), int(best_vehicle[pick])
        tables[j].insert(int(targets[q]), int(where[j, q]))  # (4.12)
        active[q] = False  # (4.13)
        costs[j, own[j]], where[j, own[j]] = tables[j].cost, tables[j].position
    return [table.route for table in tables]


def _own_targets(problem: CommProblem, vehicle: int) -> np.ndarray:
    return np.flatnonzero(problem.target_code == problem.vehicle_code[vehicle])


# -- Phase 1, shared by the three algorithms -------------------------------------------------


def merge_knowledge(group: Group, kind: str) -> np.ndarray:
    """(4.5)–(4.6): flood s_j and R^c_j; every member drops the targets known to be visited.

    The printed loops (Alg. 3 l. 2, Alg. 4 l. 2) run n rounds, enough because the thesis
    assumes n > m (§4.2); with fewer targets than vehicles n rounds may not cross the
    group, so ``max(n, m)`` rounds are run (m, the fleet size, bounds every group).

    Returns the members' projected distances d(o_j) after the deletion.

    Raises
    ------
    ConvergenceError
        A member did not learn every other member (cannot happen: max(n, m) >= |R_i|).
    """
    n, k = group.problem.n, group.size
    rows = np.hstack([group.knowledge, np.eye(k, dtype=bool)])
    merged = group.flood_or(rows, max(n, group.problem.m), kind)
    if not merged[:, n:].all():
        raise ConvergenceError(
            f"group {group.members.tolist()}: membership did not reach consensus"
        )
    known = merged[:, :n]
    group.set_knowledge(known)
    for i, route in enumerate(group.routes):
        group.set_route(i, [q for q in route if not known[i, q]])
    return np.array([group.route_length(i) for i in range(k)])


def needs_reassignment(group: Group) -> bool:
    """Alg. 3 l. 15 / Alg. 4 l. 15: two members of one ability not up to date with each other."""
    abilities, joint, last = group.abilities, group.joint, group.last
    for a in range(group.size):
        for b in range(a + 1, group.size):
            if abilities[a] != abilities[b]:
                continue
            u = joint[a, b]
            if math.isnan(u) or u != last[a] or u != last[b]:
                return True
    return False


def cooperative_targets(group: Group, lengths: np.ndarray) -> tuple[list[int], list[int]]:
    """(4.7)–(4.8): the cooperative targets T_i and the members whose routes form them (IDs).

    Parameters
    ----------
    group : Group
    lengths : (k,) float
        The members' projected distances d(o_j) after (4.6).
    """
    routes, last, abilities = group.routes, group.last, group.abilities
    chosen: list[int] = []
    for code in np.unique(abilities):
        members = [i for i in range(group.size) if abilities[i] == code]
        fresh = [i for i in members if math.isnan(last[i])]
        veteran = [i for i in members if not math.isnan(last[i])]
        if fresh:
            p = min(fresh, key=lambda i: (lengths[i], i))
            if not veteran or sum(lengths[i] for i in veteran) >= lengths[p]:
                chosen.append(p)
                continue
        chosen.extend(veteran)
    targets = sorted({q for i in chosen for q in routes[i]})
    return targets, sorted(chosen)


def agree_on_targets(group: Group, chosen: Sequence[int]) -> list[int]:
    """Alg. 4 l. 28–43: flood the β of the chosen members; return the agreed T_i."""
    n, k = group.problem.n, group.size
    beta = np.zeros((k, n), dtype=bool)
    for i in chosen:
        beta[i, group.routes[i]] = True
    agreed = group.flood_or(beta, k, "cooperative")
    if not (agreed == agreed[0]).all():
        raise ConvergenceError(f"group {group.members.tolist()}: T_i did not reach consensus")
    return [int(q) for q in np.flatnonzero(agreed[0])]


def adopt_per_class(
    group: Group, new_routes: Sequence[Sequence[int]], old_lengths: np.ndarray
) -> list[int]:
    """(4.14) / Alg. 6 l. 19–23 and (4.15), per ability class; returns the adopting members."""
    new_lengths = np.array([group.route_length(i, r) for i, r in enumerate(new_routes)])
    abilities = group.abilities
    adopted: list[int] = []
    for code in np.unique(abilities):
        members = np.flatnonzero(abilities == code)
        if new_lengths[members].sum() > old_lengths[members].sum():
            continue  # keep the previous routes
        for i in members:
            group.set_route(int(i), new_routes[int(i)])
        group.record_joint(members.tolist())
        adopted.extend(int(i) for i in members)
    group.notes["reassigned"] = bool(adopted)
    group.notes["adopted"] = [int(group.members[i]) for i in adopted]
    return adopted


# -- the policies ------------------------------------------------------------------------------


class _Auction:
    """Shared by the three: the initial route of a vehicle alone (CAA with R_i = {j})."""

    name = ""

    def initial_route(self, problem: CommProblem, vehicle: int) -> list[int]:
        """§4.3.2: vehicle j inserts every target it can visit, by CAA with ``R_i = {j}``."""
        start = problem.distances[problem.n + vehicle : problem.n + vehicle + 1, : problem.n]
        code = problem.vehicle_code[vehicle : vehicle + 1]
        return central_auction(problem, start, code, _own_targets(problem, vehicle))[0]


class CAA(_Auction):
    """Algorithm 3: the centralized auction run by a local leader."""

    name = "CAA"

    def on_connect(self, group: Group) -> None:
        degree = group.adjacency.sum(axis=1)
        candidates = np.flatnonzero(degree == degree.max())
        leader = int(candidates[group.rng.integers(candidates.size)])
        group.notes["leader"] = int(group.members[leader])
        lengths = merge_knowledge(group, "collect")
        if not needs_reassignment(group):
            group.notes["reassigned"] = False
            return
        targets, _ = cooperative_targets(group, lengths)
        new_routes = central_auction(group.problem, group.start_distances, group.abilities, targets)
        adopted = adopt_per_class(group, new_routes, lengths)
        group.send("distribute" if adopted else "keep", group.size)


class DAA(_Auction):
    """Algorithms 4–6: information consensus, marginal-cost auction by flooding, check."""

    name = "DAA"

    def on_connect(self, group: Group) -> None:
        lengths = merge_knowledge(group, "consensus")
        if not needs_reassignment(group):
            group.notes["reassigned"] = False
            return
        k = group.size
        group.send("positions", k)
        _, chosen = cooperative_targets(group, lengths)
        targets = agree_on_targets(group, chosen)
        new_routes = self.distributed_auction(group, targets)
        group.send("check", k)
        adopt_per_class(group, new_routes, lengths)

    @staticmethod
    def distributed_auction(group: Group, targets: Sequence[int] | np.ndarray) -> list[list[int]]:
        """Algorithm 5: each member keeps its own bids c_j, β_j and builds its own o'_j.

        Raises
        ------
        ConvergenceError
            Members disagree on the winner after |R_i| rounds (cannot happen on a connected
            group: |R_i| rounds exceed its diameter).
        """
        problem = group.problem
        k = group.size
        targets = np.array(sorted(targets), dtype=np.int64)
        routes: list[list[int]] = [[] for _ in range(k)]
        if targets.size == 0:
            return routes
        dist = group.target_distances
        starts = group.start_distances
        own = group.abilities[:, None] == problem.target_code[targets][None, :]
        tables = [InsertionTable(starts[i], targets[own[i]], dist) for i in range(k)]
        costs = np.full((k, targets.size), np.inf)  # member i's own bids c_j (4.9)
        where = np.zeros((k, targets.size), dtype=np.int64)
        for i in range(k):
            costs[i, own[i]], where[i, own[i]] = tables[i].cost, tables[i].position
        me = np.arange(k)[:, None]
        active = np.ones(targets.size, dtype=bool)
        for _ in range(targets.size):
            _check_deadline()
            columns = np.flatnonzero(active)
            bids = costs[:, columns]
            seen_cost, seen_bidder = group.flood_min(bids, me, k, "bid")  # l. 15-25
            picks = np.argmin(seen_cost, axis=1)  # each member's own q* (l. 26), lowest on ties
            winners = seen_bidder[np.arange(k), picks]
            if not ((picks == picks[0]).all() and (winners == winners[0]).all()):
                raise ConvergenceError(
                    f"group {group.members.tolist()}: members disagree on the next target"
                )
            q, j = int(columns[picks[0]]), int(winners[0])
            tables[j].insert(int(targets[q]), int(where[j, q]))  # only j builds o'_j (l. 27-33)
            active[q] = False
            costs[j, own[j]], where[j, own[j]] = tables[j].cost, tables[j].position
        routes = [table.route for table in tables]
        return routes


class HDA(_Auction):
    """HDA (Zhao, Meng & Chung 2016) as §4.1 describes it: release by significance."""

    name = "HDA"

    def on_connect(self, group: Group) -> None:
        lengths = merge_knowledge(group, "consensus")
        if not needs_reassignment(group):
            group.notes["reassigned"] = False
            return
        k = group.size
        group.send("positions", k)
        _, chosen = cooperative_targets(group, lengths)
        targets = agree_on_targets(group, chosen)
        new_routes, iterations = self.release_loop(group, targets)
        group.notes["iterations"] = iterations
        adopt_per_class(group, new_routes, lengths)

    @staticmethod
    def release_loop(
        group: Group, targets: Sequence[int] | np.ndarray
    ) -> tuple[list[list[int]], int]:
        """Release targets by significance until no release saves distance.

        Each iteration every member computes, for each cooperative target of its ability,
        its significance (if on its route) and its marginal significance (if not), and the
        smallest of each with the vehicle naming it are flooded (|R_i| rounds). Then

        * a target on several routes stays with the holder of the smallest significance and
          every other holder drops it (all at once: dropping targets never lengthens a route);
        * otherwise each member proposes its best release — the target whose significance
          exceeds the smallest marginal significance of another member by the most — the
          proposals are flooded (|R_i| rounds), and the releases are carried out greedily,
          largest saving first, each member in at most one release (as releaser or taker) so
          that every saving is exactly the one bid.

        Returns the new routes and the number of iterations.
        """
        problem = group.problem
        k = group.size
        keep = {int(q) for q in targets}
        routes = [[q for q in r if q in keep] for r in group.routes]
        targets = np.array(sorted(keep), dtype=np.int64)
        if targets.size == 0:
            return routes, 0
        size = targets.size
        column = {int(q): c for c, q in enumerate(targets)}
        dist = group.target_distances
        starts = group.start_distances
        own = group.abilities[:, None] == problem.target_code[targets][None, :]
        me = np.arange(k)[:, None]
        limit = 10 * (size + 1) * k + 100
        for iteration in range(1, limit + 1):
            bids = np.full((k, 2 * size), np.inf)  # [significance | marginal significance]
            savings: list[np.ndarray] = []
            holders = np.zeros(size, dtype=np.int64)
            for i in range(k):
                held = np.array([column[q] for q in routes[i]], dtype=np.int64)
                saving = removal_savings(starts[i], routes[i], dist)
                savings.append(saving)
                bids[i, held] = saving
                holders[held] += 1
                others = own[i].copy()
                others[held] = False
                others = np.flatnonzero(others)
                if others.size:
                    bids[i, size + others] = insertion_costs(
                        starts[i], routes[i], targets[others], dist
                    )[0]
            best, who = group.flood_min(bids, me, k, "significance")
            if not ((best == best[0]).all() and (who == who[0]).all()):
                raise ConvergenceError(
                    f"group {group.members.tolist()}: significances did not reach consensus"
                )
            keeper, taker = who[0, :size], who[0, size:]
            marginal = best[0, size:]
            drops = [
                (i, q)
                for i in range(k)
                for q in routes[i]
                if holders[column[q]] > 1 and keeper[column[q]] != i
            ]
            proposals = []
            for i in range(k):
                best_gain, best_target = SAVING_TOLERANCE, -1
                for position, q in enumerate(routes[i]):
                    c = column[q]
                    if holders[c] > 1:
                        continue
                    gain = savings[i][position] - marginal[c]
                    if gain > best_gain or (gain == best_gain and 0 <= c < best_target):
                        best_gain, best_target = gain, c
                if best_target >= 0:
                    proposals.append((-best_gain, best_target, i))
            group.send("release", k)
            if drops:
                for i, q in drops:
                    routes[i].remove(q)
                continue
            if not proposals:
                return routes, iteration
            busy: set[int] = set()
            for _, c, i in sorted(proposals):
                j = int(taker[c])
                if i in busy or j in busy:
                    continue
                q = int(targets[c])
                routes[i].remove(q)
                _, where = insertion_costs(starts[j], routes[j], targets[c : c + 1], dist)
                routes[j] = insert(routes[j], q, int(where[0]))
                busy.update((i, j))
        raise ConvergenceError(f"HDA did not settle within {limit} iterations")


# -- registered methods ------------------------------------------------------------------------


def _run(
    problem: CommProblem,
    policy: Policy,
    seed: int,
    strict: bool,
    time_limit: float | None = None,
) -> Solution:
    """Simulate ``policy``; under ``time_limit`` a run that has not visited every target
    when it expires returns status "time_limit", objective inf and no trajectories (a
    partial simulation is no plan)."""
    began = time.perf_counter()
    deadline = Deadline(time_limit) if time_limit is not None else None
    token = _DEADLINE.set(deadline)
    try:
        simulation = Simulation(problem, policy, seed=seed, strict=strict)
        simulation.deadline = deadline
        run = simulation.run()
    except SimulationStopped as exc:
        return make_solution(
            problem,
            None,
            method=policy.name,
            status=TIME_LIMIT,
            runtime=time.perf_counter() - began,
            seed=seed,
            info={"stopped_by": "time_limit", "message": str(exc)},
        )
    finally:
        _DEADLINE.reset(token)
    return make_solution(
        problem,
        run.trajectories,
        method=policy.name,
        status=FEASIBLE,
        runtime=time.perf_counter() - began,
        seed=seed,
        info=run.info,
    )


# the exact f_o solves each attribute class as a chapter-2 problem: the same improver
register_improver(CommProblem)(improve_routes)


@register_method(CommProblem, "DAA", category="simulation", style=("-", "o"))
def daa(
    problem: CommProblem, *, seed: int = 0, strict: bool = False, time_limit: float | None = None
) -> Solution:
    """DAA (Algorithms 4–6): decentralized auction under limited range, simulated.

    ``time_limit`` (wall-clock seconds) stops the simulation: status "time_limit", no plan.
    """
    return _run(problem, DAA(), seed, strict, time_limit)


@register_method(CommProblem, "CAA", category="simulation", style=(":", "^"))
def caa(
    problem: CommProblem, *, seed: int = 0, strict: bool = False, time_limit: float | None = None
) -> Solution:
    """CAA (Algorithm 3): centralized auction by a local leader, simulated.

    ``time_limit`` (wall-clock seconds) stops the simulation: status "time_limit", no plan.
    """
    return _run(problem, CAA(), seed, strict, time_limit)


@register_method(CommProblem, "HDA", category="simulation", style=("--", "s"))
def hda(
    problem: CommProblem, *, seed: int = 0, strict: bool = False, time_limit: float | None = None
) -> Solution:
    """HDA (Zhao, Meng & Chung 2016, as read in §4.1): release by significance, simulated.

    ``time_limit`` (wall-clock seconds) stops the simulation: status "time_limit", no plan.
    """
    return _run(problem, HDA(), seed, strict, time_limit)


POLICIES = {"CAA": CAA, "DAA": DAA, "HDA": HDA}

__all__ = [
    "CAA",
    "DAA",
    "HDA",
    "POLICIES",
    "central_auction",
    "merge_knowledge",
    "needs_reassignment",
    "cooperative_targets",
    "agree_on_targets",
    "adopt_per_class",
]
