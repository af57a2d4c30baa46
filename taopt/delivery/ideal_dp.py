"""Exact truck–drone delivery by dynamic programming over the order ideals of G^p.

A served set of customers is always an *order ideal* of the precedence DAG G^p (a set
closed under predecessors, (5.7)), so the states (served set, landing stop) of
:func:`taopt.delivery.schedule.optimal_plan` need only range over ideals: on the dag40
instances of Tables 5.1–5.2 that is 10^4–10^6 sets instead of 2^40. This module expands
them ideal by ideal in order of size (one layer per number of served customers), keeping
the current and the next layer's values and compact back-pointers, with

* the transitions of :func:`taopt.delivery.schedule._sortie_step` folded into one min-plus
  matrix per customer (below),
* dominance among the landing stops of one ideal (the truck times are a shortest-path
  metric),
* pruning by a valid completion bound (:func:`completion_bound`) against an incumbent,
* a wall-clock time limit and a size guard that return the best plan with a proven bound.

The optimal order found is scheduled again by :func:`taopt.delivery.schedule.schedule`
(the fixed-order DP, made of :func:`_sortie_step`) and the plan is scored by
:func:`taopt.delivery.evaluate.evaluate_plan`; the DP's own value must agree
(:func:`taopt.delivery.schedule._matches`).
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt import ideals
from taopt.delivery.evaluate import evaluate_plan
from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.delivery.schedule import _matches, _sortie_data, schedule
from taopt.errors import InstanceError
from taopt.ideals import distinct, ideal_layers, predecessor_masks
from taopt.result import FEASIBLE, Solution, finish, make_solution
from taopt.runtime import Deadline, max_memory_gb

#: Largest number of customers (ideals are bit masks in an unsigned 64-bit integer).
MAX_CUSTOMERS = 63

#: Default cap on the states kept over the whole run (back-pointers, about 10 bytes each)
#: and on the cells of one layer's dense table (ideals x stops, about 21 bytes each with
#: the dominance rounds' copies), for the default memory limit of 4 GB.
DEFAULT_MAX_STATES = 100_000_000

#: Bytes of memory limit per state allowed when ``max_states`` follows the limit: a full
#: layer table, the back-pointers and the relaxation (8 (n + 1) bytes per ideal, at most
#: ``max_states / (n + 1)`` ideals) together stay under 40 bytes per state.
BYTES_PER_STATE = 40.0

#: Transition values computed at once (bounds the transient memory: 8 bytes each, times 3).
CHUNK_CELLS = 4_000_000

#: Relative safety margin taken off a completion bound before it prunes (floating point).
BOUND_SLACK = 1e-10


@dataclass
class _Tables:
    """Per-instance arrays of the DP (built once per call).

    ``move[j]`` (s, |V_j|): the min-plus matrix of one sortie to customer j, from the
    previous landing stop k' to the landing stop k ∈ V_j; ``finish[j, k']`` the earliest
    service time of j after recovering at k' (last sortie); ``incoming[j]`` the cheapest
    t*-style edge into j; ``need[j]`` the bit mask of j's direct predecessors.
    """

    viable: list[np.ndarray]
    move: list[np.ndarray]
    finish: np.ndarray
    incoming: np.ndarray
    need: np.ndarray
    slack: float
    edge: np.ndarray


def _tables(instance: DeliveryInstance) -> _Tables:
    n, s = instance.n, instance.s
    tt = instance.truck_time
    ft = instance.flight_time
    tau = instance.service_time
    data = _sortie_data(instance)
    viable, move = [], []
    finish = np.empty((n, s))
    for j in range(n):
        v, flight, penalty, carry = data.get(j)
        # R = max(S + ft_i + τ + ft_k, S + tt_ik) + τ  =  S + cost[i, k]
        cost = np.maximum(flight[:, None] + tau + flight[None, :], carry) + penalty
        to_launch = tt[:, v]  # (s, |V_j|)
        best = np.full((s, v.size), np.inf)
        step = max(1, CHUNK_CELLS // max(1, s * v.size))  # launch stops per slice
        for lo in range(0, v.size, step):
            part = to_launch[:, lo : lo + step, None] + cost[None, lo : lo + step, :]
            np.minimum(best, part.min(axis=1), out=best)
        move.append(best)
        finish[j] = (to_launch + (flight + tau)[None, :]).min(axis=1)
        viable.append(v)
    # t*-style edge j -> j': served j, fly back to any stop k, truck k -> i', fly to j';
    # back_then_launch[j, i] = min_k flight_time[j, k] + truck_time[k, i]
    back_then_launch = np.stack([(ft[j][:, None] + tt).min(axis=0) for j in range(n)])
    edge = (back_then_launch[:, None, :] + ft[None, :, :]).min(axis=2) + 2.0 * tau  # (n, n)
    need = predecessor_masks(n, instance.precedences)
    after = np.zeros((n, n), dtype=bool)  # after[r, j]: r must precede j (transitive)
    for r, j in instance.precedences:
        after[r, j] = True
    for k in range(n):  # transitive closure (Warshall)
        after |= after[:, [k]] & after[[k], :]
    # j may be served right before j' unless j' must precede j: after[j', j]
    allowed = ~after.T
    np.fill_diagonal(allowed, False)
    incoming = np.where(allowed, edge, np.inf).min(axis=0)
    incoming[~np.isfinite(incoming)] = 0.0  # n = 1
    # largest violation of the triangle inequality of truck_time (rounding only)
    viol = 0.0
    for b in range(s):
        viol = max(viol, float((tt - (tt[:, [b]] + tt[[b], :])).max()))
    return _Tables(viable, move, finish, incoming, need, max(viol, 0.0), edge)


_IDEAL_COUNTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def count_ideals(instance: DeliveryInstance, cap: int = 10_000_000) -> int | None:
    """The number of order ideals of G^p (the empty and the full set included), or None
    when it exceeds ``cap`` or n > :data:`MAX_CUSTOMERS` (:func:`taopt.ideals.count_ideals`;
    cached per instance and cap).

    Example
    -------
    >>> from taopt.delivery import example_instance
    >>> count_ideals(example_instance(250.0))
    3384
    """
    key = int(cap)
    cached = _IDEAL_COUNTS.setdefault(instance, {})
    if key not in cached and instance.n > MAX_CUSTOMERS:
        cached[key] = None  # beyond 64-bit masks: the DP refuses it anyway
    if key not in cached:
        need = predecessor_masks(instance.n, instance.precedences)
        count, capped = ideals.count_ideals(need, instance.n, key)
        cached[key] = None if capped else count
    return cached[key]


def _byte_tables(values: np.ndarray) -> np.ndarray:
    """(8, 256) table: the sum of ``values[j]`` over the bits j set in each byte."""
    table = np.zeros((8, 256))
    bits = (np.arange(256)[:, None] >> np.arange(8)[None, :]) & 1
    for b in range(8):
        chunk = np.zeros(8)
        part = values[8 * b : 8 * b + 8]
        chunk[: part.size] = part
        table[b] = bits @ chunk
    return table


def _mask_sum(table: np.ndarray, ideals: np.ndarray) -> np.ndarray:
    out = np.zeros(ideals.size)
    for b in range(8):
        out += table[b][((ideals >> np.uint64(8 * b)) & np.uint64(255)).astype(np.intp)]
    return out


def _bounds(tab: _Tables, ideals: np.ndarray, stops: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two terms of :func:`completion_bound` per state: max_U F_j(k), and
    min over addable j1 of F_j1(k) − in(j1)."""
    n = tab.finish.shape[0]
    one_sortie = np.zeros(ideals.size)
    first = np.full(ideals.size, np.inf)
    for j in range(n):
        bit = np.uint64(1) << np.uint64(j)
        open_ = (ideals & bit) == 0
        if not open_.any():
            continue
        f = tab.finish[j, stops]
        one_sortie = np.where(open_, np.maximum(one_sortie, f), one_sortie)
        addable = open_ & ((ideals & tab.need[j]) == tab.need[j])
        first = np.where(addable, np.minimum(first, f - tab.incoming[j]), first)
    return one_sortie, first


def completion_bound(
    instance: DeliveryInstance, served: Any, stop: int, relaxation: bool = True
) -> float:
    """A lower bound on the time from recovering at ``stop`` to the end of the plan.

    Parameters
    ----------
    instance : DeliveryInstance
    served : int (bit mask) or iterable of int
        The customers served so far (an order ideal of G^p, not the full set).
    stop : int
        The landing stop of the last sortie (the depot before the first).
    relaxation : bool
        Include the sequencing relaxation (built over all ideals: the strong term, as
        :func:`ideal_dp` prunes with it); False gives the two O(n) terms only.

    Returns
    -------
    float
        ``B(I, k)`` with makespan ≥ R + B(I, k) for every completion of a partial plan
        that has served I and recovered at k at time R.

    Notes
    -----
    Let U be the unserved customers. With ``F_j(k) = min_{i ∈ V_j} truck_time[k, i] +
    flight_time[j, i] + τ`` every j ∈ U is served at t_j ≥ R + F_j(k) (the truck must
    reach a launch stop, the drone fly out and land). Between two consecutive services
    j then j' the drone flies back to some stop k'', lands (τ), the truck drives to the
    next launch stop i', the drone flies out and lands at j' (τ)::

        t_j' − t_j ≥ e(j, j') = 2τ + min_{k'', i'} flight_time[j, k''] + truck_time[k'', i']
                                       + flight_time[j', i']

    (a t*-style edge of (5.11), ignoring (5.6) and the truck's own carry). Every j' ∈ U
    but the first served has a predecessor in the order that may precede it
    (not forced after it by G^p), so with ``in(j') = min_{j may precede j'} e(j, j')``::

        B(I, k) = max( max_{j ∈ U} F_j(k),
                       min_{j1 ∈ U addable} (F_{j1}(k) − in(j1)) + Σ_{j' ∈ U} in(j') )

    Both terms are valid, so is their maximum. O(n) per state.

    *Sequencing relaxation* (the strong term). The same gaps, with the precedences kept
    exactly: H(I', j) = the least Σ e over the orders of the customers outside I' that
    respect G^p, after j was served last (a DP over all ideals, :class:`_Relaxation`), and::

        B(I, k) ≥ min_{j' ∈ U addable} F_{j'}(k) + H(I ∪ {j'}, j')

    since the first customer served after (I, k) is addable, is served at R + F_{j'}(k) at
    the earliest, and every later gap is at least its e. On the dag40 instances this term
    is within a few per cent of the true completion near the root, where the two O(n) terms
    give about 40 %.

    References
    ----------
    Thesis §5.2 (timing of (5.1)–(5.7)), §5.3 (the t* edges of (5.11)).
    """
    tab = _tables(instance)
    ideal = _as_mask(served)
    full = (1 << instance.n) - 1
    if ideal == full:
        return 0.0
    ideals = np.array([ideal], dtype=np.uint64)
    stops = np.array([int(stop)])
    relax = None
    if relaxation:
        relax = _Relaxation.build(tab, tab.edge, instance.n, DEFAULT_MAX_STATES, Deadline(None))
    value = _completion(tab, np.uint64(full), ideals, stops, _byte_tables(tab.incoming), relax)
    return float(value[0])


class _Relaxation:
    """The sequencing relaxation of the completion: an exact DP over all ideals with the
    gaps between services replaced by their lower bounds e(j, j').

    ``layers[m]`` the sorted ideals of size m; ``after[m][r, j']`` = H(I_r ∪ {j'}, j') for
    j' addable to I_r (+inf otherwise), where H(I, j) is the least Σ e over the orders of
    the customers outside I that respect G^p, starting after j::

        H(full, j) = 0,   H(I, j) = min_{j' addable to I} e(j, j') + H(I ∪ {j'}, j')

    Built backwards layer by layer; O(Σ_I addable(I) · n) time, O(#ideals · n) memory.
    ``None`` from :meth:`build` when the ideals exceed ``max_ideals``.
    """

    def __init__(self, layers: list[np.ndarray], after: list[np.ndarray]) -> None:
        self.layers = layers
        self.after = after

    @classmethod
    def build(
        cls, tab: _Tables, edge: np.ndarray, n: int, max_ideals: int, deadline: Deadline
    ) -> _Relaxation | None:
        layers = ideal_layers(tab.need, n, max_ideals, deadline)
        if layers is None:
            return None
        after: list[np.ndarray] = [np.empty((0, n))] * (n + 1)
        h_next = np.zeros((1, n))  # H(full, ·) = 0
        for m in range(n - 1, -1, -1):
            cur, nxt = layers[m], layers[m + 1]
            c = np.full((cur.size, n), np.inf)
            for j in range(n):
                bit = np.uint64(1) << np.uint64(j)
                can = np.flatnonzero(((cur & bit) == 0) & ((cur & tab.need[j]) == tab.need[j]))
                if can.size:
                    c[can, j] = h_next[np.searchsorted(nxt, cur[can] | bit), j]
            after[m] = c
            # H(I, j) = min_j' e(j, j') + C(I, j')
            h_next = np.full((cur.size, n), np.inf)
            for jp in range(n):
                col = c[:, jp]
                fin = np.isfinite(col)
                if fin.any():
                    h_next[fin] = np.minimum(h_next[fin], col[fin, None] + edge[None, :, jp])
            if deadline.limited and deadline.expired():
                return None
        return cls(layers, after)

    def bound(self, ideals: np.ndarray, stops: np.ndarray, finish: np.ndarray) -> np.ndarray:
        """min_{j'} F_{j'}(k) + H(I ∪ {j'}, j') per state (I, k) (all I of one size)."""
        if not ideals.size:
            return np.empty(0)
        m = int(ideals[0]).bit_count()
        rows = np.searchsorted(self.layers[m], ideals)
        c = self.after[m]
        out = np.full(ideals.size, np.inf)
        for jp in range(c.shape[1]):
            col = c[rows, jp]
            fin = np.isfinite(col)
            if fin.any():
                out[fin] = np.minimum(out[fin], finish[jp, stops[fin]] + col[fin])
        return out


def _completion(
    tab: _Tables,
    full: np.uint64,
    ideals: np.ndarray,
    stops: np.ndarray,
    in_table: np.ndarray,
    relax: _Relaxation | None = None,
) -> np.ndarray:
    one_sortie, first = _bounds(tab, ideals, stops)
    unserved = _mask_sum(in_table, full & ~ideals)
    out = np.maximum(one_sortie, first + unserved)
    if relax is not None:
        out = np.maximum(out, relax.bound(ideals, stops, tab.finish))
    return out


def _as_mask(served: Any) -> int:
    if isinstance(served, (int, np.integer)):
        return int(served)
    mask = 0
    for j in served:
        mask |= 1 << int(j)
    return mask


def _stopped(
    instance: DeliveryInstance,
    incumbent_plan: Plan | None,
    incumbent_value: float,
    proven: float,
    start: float,
    info: dict,
    why: str,
) -> Solution:
    """Status "time_limit": the incumbent (or no plan, objective inf) and the larger of
    the DP's proven bound and Proposition 5.3's arborescence bound."""
    from taopt.delivery.bounds import arborescence_bound

    return finish(
        instance,
        incumbent_plan,
        method="exact",
        stop=why,
        bound=min(max(proven, arborescence_bound(instance)), incumbent_value),
        runtime=time.perf_counter() - start,
        info=info,
    )


def _layer_record(
    served: int,
    n_ideals: int,
    states: int,
    dominated: int,
    pruned: int,
    bound: np.ndarray,
    incumbent: float,
) -> dict[str, Any]:
    """One layer of an :func:`ideal_dp` trace (plain JSON data; None for infinity)."""
    least = min(float(bound.min()), incumbent) if bound.size else incumbent
    return {
        "served": int(served),
        "ideals": int(n_ideals),
        "states": int(states),
        "dominated": int(dominated),
        "pruned": int(pruned),
        "kept": int(states - dominated - pruned),
        "bound": least if math.isfinite(least) else None,
        "incumbent": incumbent if math.isfinite(incumbent) else None,
    }


def ideal_dp(
    instance: DeliveryInstance,
    time_limit: float | None = None,
    incumbent: Any = None,
    max_states: int | None = None,
    dominance: bool = True,
    prune: bool = True,
    relaxation: bool = True,
    beam: int = 2000,
    trace: bool = False,
    _beam: int | None = None,
    _shared: tuple | None = None,
    _start: tuple[int, int, float] | None = None,
) -> Solution:
    """Exact optimum of (5.1)–(5.7) by dynamic programming over the order ideals of G^p.

    Parameters
    ----------
    instance : DeliveryInstance
        At most :data:`MAX_CUSTOMERS` customers.
    time_limit : float, optional
        Wall-clock seconds (:class:`taopt.runtime.Deadline`). When the DP has not finished,
        the result has status "time_limit", the incumbent (or no plan, objective inf) and
        the bound ``max(min over open states of R + B, arborescence_bound)``.
    incumbent : Plan or Solution, optional
        A feasible plan; states whose value plus completion bound reaches its makespan are
        pruned (``taopt.solve`` passes the best of NIA, MMA and SMMA).
    max_states : int, optional
        Size guard: the run stops like a time limit (``info["stopped_by"] == "size"``) when
        the states kept, or the cells of one layer's table, would exceed it. Default: the
        memory limit of :func:`taopt.runtime.max_memory_gb` (``TAOPT_MAX_MEMORY_GB``, 4 GB)
        divided by :data:`BYTES_PER_STATE` (100,000,000 at 4 GB).
    dominance, prune, relaxation : bool
        Switch the dominance rule, the bound pruning or the sequencing relaxation of the
        bound off (for measurements).
    beam : int
        Width of the restricted pass that finds an incumbent (0: none).
    trace : bool
        Keep the exact pass layer by layer in ``info["trace"]`` (plain JSON data, saved
        with the solution): ``{"kind": "ideal_dp", "n", "layers"}``, one entry per layer
        (``"served"``: customers served by its ideals, 0 for the start) with
        ``"ideals"`` (the ideals of that size reached), ``"states"`` (states (I, k) reached
        with a finite recovery time), ``"dominated"``, ``"pruned"`` (by the completion
        bound against the incumbent), ``"kept"``, ``"bound"`` (the least R + B over the
        kept states, capped at the incumbent: a proven lower bound on the optimum once the
        layer is done) and ``"incumbent"`` (its makespan, None without one). Drawn by
        :func:`taopt.plot.trace`. False (the default) records nothing and changes nothing.

    Returns
    -------
    Solution
        ``.status`` "optimal", ``.objective == .bound`` the optimal makespan (5.1) as scored
        by :func:`taopt.delivery.evaluate.evaluate_plan` (checked against the DP's value
        within :data:`taopt.delivery.schedule.MATCH_TOLERANCE` relative), ``.plan`` an
        optimal plan, ``.info`` with ``ideals`` (expanded), ``states_kept``,
        ``states_pruned`` (by the bound), ``states_dominated``, ``peak_layer_states``,
        ``peak_layer_ideals``, ``dp_objective``.

    Raises
    ------
    InstanceError
        More than :data:`MAX_CUSTOMERS` customers.

    Notes
    -----
    States (I, k): I an ideal, k the landing stop of the last sortie; value R(I, k) the
    earliest recovery time. The sortie to j from recovery R at k' is, for launch i and
    landing k in V_j (as :func:`taopt.delivery.schedule._sortie_step`)::

        S = R + truck_time[k', i],   t_j = S + flight_time[j, i] + τ,
        R' = max(t_j + flight_time[j, k], S + truck_time[i, k]) + τ

    so R' = R + M_j[k', k] with the min-plus matrix
    ``M_j[k', k] = min_i truck_time[k', i] + max(flight_time[j, i] + τ + flight_time[j, k],
    truck_time[i, k]) + τ`` (+inf unless (5.6)), computed once per customer: a transition
    costs O(|V_j|) per state instead of O(|V_j|²). Later times are non-decreasing in R, so
    the earliest R per state is exact (the argument of :func:`schedule`).

    *Dominance.* ``truck_time`` is a shortest-path metric, so if R(I, k) ≥ R(I, k') +
    truck_time[k', k] every launch reachable from (I, k) is reached as early from (I, k'):
    (I, k) is dropped. The triangle inequality's largest floating-point violation on the
    instance is added to the test, so no state is dropped by rounding.

    *Pruning.* A state with R + B(I, k) ≥ the incumbent's makespan cannot lead to a better
    plan (:func:`completion_bound`, with its sequencing relaxation built once over all ideals
    while they number at most ``max_states / (n + 1)``). When every state is pruned the
    incumbent is optimal.

    *Incumbent.* Unless ``beam=0``, a restricted pass of the same DP first keeps only the
    ``beam`` states of least R + B per layer (at most half the time limit); its plan, or the
    caller's if better, prunes the exact pass. On dag40 the restricted pass finds the optimum
    itself and the exact pass only proves it.

    *Rebuild.* The back-pointers (customer added, previous landing stop) give the optimal
    order; :func:`taopt.delivery.schedule.schedule` schedules it (made of
    :func:`_sortie_step`, the scorer's floating-point operations) and the DP's value is
    checked against the scorer's.

    Time O(Σ_layers states · Σ_j |V_j|) after O(n s³) tables and O(#ideals · n²) for the
    relaxation; memory O(peak layer ideals · s) for one layer's table, about 10 bytes per
    state kept and 8n bytes per ideal for the relaxation. Measured (2 shared cores): the 60
    dag40 pairs of Tables 5.1–5.2 in 0.4–5.5 s each (median 1.5 s, SMMA's warm start
    included); the largest, 513,982 ideals at L/L0 = 0.9, in 2.8 s and 0.37 GB, against
    796 s and 9.2 GB without the relaxation, the beam and the incumbent.

    References
    ----------
    Thesis §5.2 ((5.1)–(5.7)), §5.3.2 (Proposition 5.3, the fallback bound).
    """
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    n, s = instance.n, instance.s
    if n > MAX_CUSTOMERS:
        raise InstanceError(
            f"ideal_dp: n = {n} customers > {MAX_CUSTOMERS} (ideals are 64-bit masks)"
        )
    if max_states is None:
        limit = max_memory_gb()  # inf: no guard
        max_states = int(limit * 1e9 / BYTES_PER_STATE) if math.isfinite(limit) else 1 << 62
    inc_plan = getattr(incumbent, "plan", incumbent) if incumbent is not None else None
    inc_value = math.inf if inc_plan is None else evaluate_plan(instance, inc_plan)
    tab = _tables(instance) if _shared is None else _shared[0]
    in_table = _byte_tables(tab.incoming)
    full = np.uint64((1 << n) - 1)
    tt = instance.truck_time
    margin = tab.slack
    if _start is None:
        ideals = np.array([0], dtype=np.uint64)
        st_idx = np.array([0], dtype=np.intp)
        st_stop = np.array([instance.depot], dtype=np.intp)
        st_val = np.array([0.0])
    else:
        ideals = np.array([_start[0]], dtype=np.uint64)
        st_idx = np.array([0], dtype=np.intp)
        st_stop = np.array([int(_start[1])], dtype=np.intp)
        st_val = np.array([float(_start[2])])
    size0 = int(ideals[0]).bit_count()
    # back-pointer layers: (ideals, state key idx*s+stop sorted, customer, previous stop)
    history: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = [
        (ideals, st_idx * s + st_stop, np.full(1, -1, np.int8), np.full(1, -1, np.int16))
    ]
    counts: dict[str, Any] = {
        "ideals_expanded": 1,
        "states_kept": 1,
        "states_pruned": 0,
        "states_dominated": 0,
        "peak_layer_states": 1,
        "peak_layer_ideals": 1,
    }
    relax = None
    if _shared is not None:
        relax = _shared[1]
    elif relaxation:
        relax = _Relaxation.build(tab, tab.edge, n, max_states // (n + 1), deadline)
        counts["relaxation"] = relax is not None
    if relax is not None:
        counts["ideals"] = sum(int(layer.size) for layer in relax.layers)
    if beam and _beam is None and _start is None:
        # a restricted pass (the ``beam`` states of least value + bound per layer) for
        # an incumbent: a plan of the same DP, often optimal, that prunes the exact pass
        quick = ideal_dp(
            instance,
            time_limit=deadline.share(0.5),  # the exact pass keeps at least half
            max_states=max_states,
            dominance=dominance,
            prune=prune,
            _beam=beam,
            _shared=(tab, relax),
        )
        counts["beam_objective"] = quick.objective
        if quick.plan is not None and quick.objective < inc_value:
            inc_plan, inc_value = quick.plan, quick.objective
    st_bound = st_val + _completion(tab, full, ideals[st_idx], st_stop, in_table, relax)
    layers: list[dict[str, Any]] | None = None
    if trace and _beam is None:
        layers = [_layer_record(size0, 1, 1, 0, 0, st_bound, inc_value)]
        counts["trace"] = {"kind": "ideal_dp", "n": n, "layers": layers}

    def halt(why: str) -> Solution:
        # every optimal completion passes through an open state of the current layer
        proven = float(st_bound.min()) if st_bound.size else inc_value
        return _stopped(instance, inc_plan, inc_value, min(proven, inc_value), start, counts, why)

    for _size in range(size0, n - 1):
        if deadline.limited and deadline.expired():
            return halt("time_limit")
        # -- next layer's ideals --------------------------------------------------------
        blocks = []
        for j in range(n):
            bit = np.uint64(1) << np.uint64(j)
            can = ((ideals & bit) == 0) & ((ideals & tab.need[j]) == tab.need[j])
            if can.any():
                blocks.append((j, np.flatnonzero(can)))
        new_ideals = distinct(
            np.concatenate([ideals[rows] | (np.uint64(1) << np.uint64(j)) for j, rows in blocks])
        )
        m = new_ideals.size
        if m * s > max_states or counts["states_kept"] > max_states:
            return halt("size")
        table = np.full((m, s), np.inf)
        back_j = np.full((m, s), -1, dtype=np.int8)
        back_k = np.full((m, s), -1, dtype=np.int16)
        # states grouped by ideal (st_idx sorted): group starts per source ideal
        group_start = np.searchsorted(st_idx, np.arange(ideals.size))
        group_len = np.diff(np.append(group_start, st_idx.size))
        for j, rows in blocks:
            if deadline.limited and deadline.expired():
                return halt("time_limit")
            v = tab.viable[j]
            lens_all = group_len[rows]
            # chunks of source ideals holding at most CHUNK_CELLS transition values
            cells = np.cumsum(lens_all) * v.size
            cuts = np.searchsorted(
                cells, np.arange(1, int(cells[-1] // CHUNK_CELLS) + 1) * CHUNK_CELLS
            )
            for part in np.split(np.arange(rows.size), np.unique(cuts[cuts < rows.size])):
                if part.size:
                    _transition(
                        tab,
                        j,
                        v,
                        rows[part],
                        group_start,
                        group_len,
                        st_stop,
                        st_val,
                        ideals,
                        new_ideals,
                        table,
                        back_j,
                        back_k,
                        s,
                    )
        # -- dominance among the landing stops of each ideal -------------------------------
        finite = np.isfinite(table)
        before = int(finite.sum())
        if dominance:
            keep = np.zeros((m, s), dtype=bool)
            work = table.copy()
            rows_left = np.arange(m)
            while rows_left.size:
                if deadline.limited and deadline.expired():
                    return halt("time_limit")
                sub = work[rows_left]
                kstar = sub.argmin(axis=1)
                vstar = sub[np.arange(rows_left.size), kstar]
                ok = np.isfinite(vstar)
                rows_left, kstar, vstar, sub = rows_left[ok], kstar[ok], vstar[ok], sub[ok]
                if not rows_left.size:
                    break
                keep[rows_left, kstar] = True
                sub[np.arange(rows_left.size), kstar] = np.inf
                sub[sub >= vstar[:, None] + tt[kstar] + margin] = np.inf
                work[rows_left] = sub
                alive_left = np.isfinite(sub).any(axis=1)
                rows_left = rows_left[alive_left]
            counts["states_dominated"] += before - int(keep.sum())
        else:
            keep = finite
        idx, stop = np.nonzero(keep)  # sorted by ideal, then stop
        val = table[idx, stop]
        # -- pruning by the completion bound ----------------------------------------------
        bound = val + _completion(tab, full, new_ideals[idx], stop, in_table, relax)
        pruned = 0
        if prune and math.isfinite(inc_value):
            ok = bound * (1.0 - BOUND_SLACK) < inc_value
            pruned = int((~ok).sum())
            counts["states_pruned"] += pruned
            idx, stop, val, bound = idx[ok], stop[ok], val[ok], bound[ok]
        if layers is not None:
            dominated = before - int(keep.sum()) if dominance else 0
            layers.append(_layer_record(_size + 1, m, before, dominated, pruned, bound, inc_value))
        if _beam is not None and idx.size > _beam:
            best = np.sort(np.argpartition(bound, _beam)[:_beam])
            idx, stop, val, bound = idx[best], stop[best], val[best], bound[best]
        # keep only ideals with a state, renumbered
        used, idx = np.unique(idx, return_inverse=True)
        ideals = new_ideals[used]
        bj, bk = back_j[used[idx], stop], back_k[used[idx], stop]
        st_idx, st_stop, st_val, st_bound = idx.astype(np.intp), stop.astype(np.intp), val, bound
        history.append((ideals, st_idx * s + st_stop, bj, bk))
        counts["ideals_expanded"] += int(ideals.size)
        counts["states_kept"] += int(st_idx.size)
        counts["peak_layer_states"] = max(counts["peak_layer_states"], int(st_idx.size))
        counts["peak_layer_ideals"] = max(counts["peak_layer_ideals"], int(ideals.size))
        del table, back_j, back_k
        if st_idx.size == 0:
            break
    # -- last sortie: the one missing customer of each ideal of size n - 1 ----------------
    best_value, best_state, best_j = math.inf, -1, -1
    if st_idx.size and int(ideals[0]).bit_count() == n - 1:
        missing = (full & ~ideals[st_idx]).astype(np.uint64)
        last = np.log2(missing.astype(np.float64)).round().astype(np.intp)
        ends = tab.finish[last, st_stop] + st_val
        p = int(ends.argmin())
        best_value, best_state, best_j = float(ends[p]), p, int(last[p])
    elif st_idx.size and int(ideals[0]).bit_count() == n:  # started from the full set
        best_value, best_state, best_j = float(st_val[0]), 0, -1
    info = dict(counts)
    if not best_value < inc_value:
        if inc_plan is None:
            raise InstanceError("ideal_dp: no complete plan exists (no customers?)")
        details = {**info, "dp_objective": inc_value, "incumbent_optimal": True}
        if _beam is not None:  # a restricted pass proves nothing
            return make_solution(
                instance,
                inc_plan,
                method="exact",
                status=FEASIBLE,
                runtime=time.perf_counter() - start,
                info=details,
            )
        return finish(  # every state expanded: the incumbent is proven optimal
            instance,
            inc_plan,
            method="exact",
            stop="optimal",
            bound=inc_value,
            runtime=time.perf_counter() - start,
            info=details,
        )
    order = _rebuild(history, s, best_state, best_j)
    if _start is not None:
        return finish(  # a partial start: the value only, no plan to score
            instance,
            None,
            method="exact",
            stop="optimal",
            objective=best_value,
            bound=best_value,
            runtime=time.perf_counter() - start,
            info={**info, "dp_objective": best_value, "order": order},
        )
    scheduled = schedule(instance, order)  # the plan, scored once (make_solution)
    _matches(scheduled.objective, best_value, "ideal_dp", scheduled.plan)
    if scheduled.objective >= inc_value:  # equal up to rounding: keep the incumbent
        scheduled = make_solution(instance, inc_plan, method="exact", status=FEASIBLE)
    if _beam is not None:  # a restricted pass proves nothing
        return scheduled.replace(
            method="exact-beam", status=FEASIBLE, runtime=time.perf_counter() - start, info=info
        )
    return finish(  # every ideal expanded: the DP's optimum, its own bound
        instance,
        scheduled.solution,
        method="exact",
        stop="optimal",
        bound=scheduled.objective,
        runtime=time.perf_counter() - start,
        info={**info, "dp_objective": best_value},
    )


def _transition(
    tab: _Tables,
    j: int,
    v: np.ndarray,
    rows: np.ndarray,
    group_start: np.ndarray,
    group_len: np.ndarray,
    st_stop: np.ndarray,
    st_val: np.ndarray,
    ideals: np.ndarray,
    new_ideals: np.ndarray,
    table: np.ndarray,
    back_j: np.ndarray,
    back_k: np.ndarray,
    s: int,
) -> None:
    """Sorties to customer j from every state of the source ideals ``rows``: the next
    layer's ``table`` (min) and back-pointers updated in place."""
    lens = group_len[rows]
    offsets = np.cumsum(lens) - lens
    sel = np.repeat(group_start[rows] - offsets, lens) + np.arange(int(lens.sum()))
    stops = st_stop[sel]
    vals = st_val[sel][:, None] + tab.move[j][stops]  # (states, |V_j|)
    best = np.minimum.reduceat(vals, offsets, axis=0)  # (ideals, |V_j|)
    hit = vals == np.repeat(best, lens, axis=0)
    prev = np.minimum.reduceat(np.where(hit, stops[:, None], s), offsets, axis=0)
    target = np.searchsorted(new_ideals, ideals[rows] | (np.uint64(1) << np.uint64(j)))
    where = (target[:, None], v[None, :])
    cur = table[where]
    better = best < cur
    if better.any():
        table[where] = np.where(better, best, cur)
        back_j[where] = np.where(better, j, back_j[where])
        back_k[where] = np.where(better, prev, back_k[where])


def _rebuild(history: list, s: int, state: int, last_j: int) -> list[int]:
    """The order of customers leading to ``state`` of the last layer (then ``last_j``)."""
    order = [] if last_j < 0 else [last_j]
    layer = len(history) - 1
    ideals, keys, bj, bk = history[layer]
    while layer > 0:
        j, k_prev = int(bj[state]), int(bk[state])
        ideal = ideals[keys[state] // s] & ~(np.uint64(1) << np.uint64(j))
        order.append(j)
        layer -= 1
        ideals, keys, bj, bk = history[layer]
        i = int(np.searchsorted(ideals, ideal))
        state = int(np.searchsorted(keys, i * s + k_prev))
    return order[::-1]


__all__ = ["ideal_dp", "completion_bound", "count_ideals", "MAX_CUSTOMERS"]
