"""Exact truck–drone model of chapter 5: a linear equivalent of (5.1)–(5.7), cvxpy + HiGHS.

The printed formulation (§5.2.2) is not a MILP and is not complete:

* (5.5) ``P(t_j − d(i, j)/v_d) σ_ijk = σ_ijk i`` uses the truck position P(t) as
  a function of continuous time: not linear, and the truck's motion is not
  modelled by any other constraint.
* (5.3) ``σ_ijk = y_ik`` for all j (and k ≠ i) ties every customer to the same
  truck move: if the truck drives i -> k (y_ik = 1) then σ_ijk = 1 for EVERY
  customer j, so with (5.2) at most one truck move exists, and either all
  customers are served i -> k, or every sortie lands where it was launched
  (k = i, which (5.3) does not cover) and the truck never moves. The intent
  ("the drone is recovered by the truck after each customer") is kept below
  as the sortie chain with truck continuity.
* There is no truck routing (continuity of the truck between sorties) and no
  timing constraint linking t_j to the truck and drone motions; (5.5) only
  says the truck is at i when the drone leaves, nothing about k.
* (5.4) ``y_ii = 0`` says the truck never "drives" from a stop to itself. Here a
  zero-length leg ``w[p, k, k]`` means the truck stays where the drone landed,
  and a sortie may land where it was launched (k = i, as (5.3) excluding k = i
  and the thesis's pattern t_α (5.8) allow); so (5.4) has no counterpart.

This module implements the problem under the project's timing semantics
(:mod:`taopt.delivery.evaluate`): sortie p launches at stop i at ``S_p``, serves
customer j at ``t_p = S_p + flight_time[j, i] + τ`` and is recovered at stop k
at ``R_p = max(t_p + flight_time[j, k], S_p + truck_time[i, k]) + τ``; the truck
then drives to the next launch stop, ``S_{p+1} = R_p + truck_time[k, i']``.

Sets: positions ``p = 0..n-1`` (the p-th sortie), stops W, customers C, and the
FEASIBLE triples ``(i, j, k)`` with ``d(i, j) + d(j, k) ≤ L`` (5.6), reduced by
dominance (see :func:`feasible_triples`).

Variables

* ``y[p, (i, j, k)]`` binary: sortie p launches at i, serves j, lands at k
  (the thesis's σ_ijk, with the position p added). At the last position the
  landing stop does not affect (5.1), so one landing per (i, j) is kept.
* ``w[p, k, i] ≥ 0`` (p ≥ 1): truck leg from the landing stop k of sortie p−1
  to the launch stop i of sortie p (the thesis's y_ik, as a transport plan).
* ``S_p, t_p, R_p`` continuous: launch, service and recovery times.

Constraints (name used as the cvxpy label → printed equation it implements)

* (5.2) ``Σ_{p,i,k} y[p,i,j,k] = 1`` for every customer j.
* one sortie per position ``Σ_{i,j,k} y[p,i,j,k] = 1``: the drone carries one
  package at a time, so sorties are sequential (thesis: "the drone can carry
  only one package each time").
* (5.6) by construction: y exists only for triples within range L.
* (5.3)/(5.5) truck continuity: ``Σ_i w[p,k,i] = Σ_{i',j} y[p−1,i',j,k]``
  (landing indicator of p−1 at k) and ``Σ_k w[p,k,i] = Σ_{j,k'} y[p,i,j,k']``
  (launch indicator of p at i). Both marginals are one-hot in an integer
  solution; a nonnegative matrix whose row sums are e_k and column sums are
  e_i has all its mass in row k and column i, so ``w[p] = e_k e_iᵀ`` exactly:
  the product "landed at k and launches at i" is forced without binaries or
  big-M. This replaces the non-linear P(t) of (5.5): the truck is at the
  launch stop at S_p because it drove there, and at the landing stop by R_p.
* timing (5.5), launch: ``S_0 ≥ Σ_i truck_time[w0, i]·(launch indicator)``,
  ``S_p ≥ R_{p−1} + Σ_{k,i} truck_time[k, i] w[p,k,i]``.
* timing (5.1), service: ``t_p = S_p + Σ y·(flight_time[j, i] + τ)``.
* timing (5.3), recovery: ``R_p ≥ S_p + Σ y·(max(flight_time[j,i] + τ +
  flight_time[j,k], truck_time[i,k]) + τ)``. The max is a constant per
  triple, so the recovery rule is exact and linear (no big-M).
* (5.7) precedence r before j, cumulative form: for every position q,
  ``Σ_{p≤q} z[p,j] ≤ Σ_{p<q} z[p,r]`` with ``z[p,j] = Σ_{i,k} y[p,i,j,k]``
  ("j is served by sortie q only if r was served earlier"). It implies the
  aggregated ``pos_r + 1 ≤ pos_j`` and has a stronger LP relaxation.
* objective (5.1): ``min t_{n−1}``; times increase along the sorties
  (``t_p ≤ R_p ≤ S_{p+1} ≤ t_{p+1}``), so ``t_{n−1} = max_j t_j``.

No big-M appears: the products are linearised by the transport plans and the
max by per-triple constants. Model reduction: y exists only for (5.6)-feasible
triples, only at positions inside the customer's precedence window
(#ancestors ≤ p ≤ n−1−#descendants), minus dominated triples (on the test
instances the dominance removes about 2/3 of the position-0 triples, few
others); at the last position one landing per (i, j) is kept. Solving, a
heuristic plan's makespan is passed to HiGHS as an objective cut-off
(``incumbent`` of :func:`solve_delivery`). The time variables use ``≥`` (waiting allowed);
waiting never helps, so at the optimum the model's times equal the scorer's,
and the decoded plan's :func:`taopt.evaluate` equals the objective.

Example
-------
>>> from taopt.delivery.instance import DeliveryInstance
>>> inst = DeliveryInstance.grid([[100, 300], [700, 900]], k=3, side=1000, v_drone=1.0,
...                              v_truck=1.0, flight_range=900)
>>> sol = solve_delivery(inst)
>>> sol.status, round(sol.objective, 6) == round(__import__("taopt").evaluate(inst, sol.plan), 6)
('optimal', True)
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import networkx as nx
import numpy as np
import scipy.sparse as sp

from taopt.delivery.bounds import arborescence_bound
from taopt.delivery.evaluate import evaluate_plan
from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.errors import InstanceError, SolverError
from taopt.models.highs import HighsModel, solve_highs
from taopt.result import FEASIBLE, INFEASIBLE, OPTIMAL, TIME_LIMIT, Solution, finish
from taopt.runtime import MARGIN, Deadline, milp_bytes, register_footprint

logger = logging.getLogger(__name__)  # a child of the "taopt" logger

__all__ = [
    "DeliveryModel",
    "Triples",
    "build",
    "decode",
    "describe",
    "feasible_triples",
    "solve_delivery",
]

_REL_EPS = 1e-9  # strictness margin of the dominance test, relative to the time scale


# ----------------------------------------------------------------------------- triples
@dataclass
class Triples:
    """The sortie triples (i, j, k) the model may use, per kind of position.

    Attributes
    ----------
    first, middle, last : (m, 3) int arrays
        Rows (launch i, customer j, landing k) usable at position 0, at positions
        1..n−2, and at position n−1 (for n = 1 the single position uses ``last``
        with the depot as previous stop).
    feasible : int
        Number of triples satisfying (5.6) before any reduction.
    """

    first: np.ndarray
    middle: np.ndarray
    last: np.ndarray
    feasible: int


def _recovery_duration(
    instance: DeliveryInstance, i: np.ndarray, j: np.ndarray | int, k: np.ndarray
) -> np.ndarray:
    """``R_p − S_p`` of triple (i, j, k): ``max(ft[j,i] + τ + ft[j,k], tt[i,k]) + τ``."""
    ft, tt, tau = instance.flight_time, instance.truck_time, instance.service_time
    return np.maximum(ft[j, i] + tau + ft[j, k], tt[i, k]) + tau


def _undominated(
    score: np.ndarray, d_launch: np.ndarray, d_land: np.ndarray, eps: float
) -> np.ndarray:
    """Mask of candidates no other candidate strictly dominates.

    Candidate b dominates a when ``d_launch[b, a] + score[b] − score[a] + d_land[b, a] < −eps``:
    for every previous stop x and next launch stop y, b's contribution
    ``tt[x, i_b] + score_b + tt[k_b, y]`` is below a's. The relation is a strict
    partial order, so every dominated candidate has an undominated dominator.
    """
    worse = d_launch + d_land + score[:, None] - score[None, :] < -eps
    return ~worse.any(axis=0)


def feasible_triples(instance: DeliveryInstance, reduce: bool = True) -> Triples:
    """Triples satisfying (5.6), reduced by a proven-safe dominance rule.

    A triple a = (i, j, k) contributes ``truck_time[x, i] + c_a + truck_time[k, y]``
    to the time between the previous landing stop x and the next launch at y,
    with ``c_a`` = :func:`_recovery_duration`; every later time is non-decreasing
    in it. So a is dominated by b = (i', j, k') (same customer, within range) when
    ``max_x (tt[x,i'] − tt[x,i]) + c_b − c_a + max_y (tt[k',y] − tt[k,y]) < 0``:
    replacing a by b in any plan delays nothing. x ranges over every stop (the
    depot only at position 0), y over every stop. At the last position only
    ``t = S + ft[j,i] + τ`` matters, so the rule compares
    ``max_x(tt[x,i'] − tt[x,i]) + ft[j,i'] − ft[j,i]`` and keeps one landing
    (the earliest-recovery one) per launch.

    Parameters
    ----------
    reduce : bool
        False keeps every feasible triple (for checking that the reduction is safe).
    """
    n = instance.n
    tt, ft = instance.truck_time, instance.flight_time
    fd, limit = instance.flight_distance, instance.flight_limit
    scale = max(float(tt.max()), float(ft.max()), 1.0)
    eps = _REL_EPS * scale
    # max_x (tt[x, a] - tt[x, b]) for all stops x: launch_gap[a, b]; landing_gap[a, b]
    launch_gap_all = (tt[:, :, None] - tt[:, None, :]).max(axis=0)
    launch_gap_depot = tt[instance.depot][:, None] - tt[instance.depot][None, :]
    landing_gap = (tt[:, None, :] - tt[None, :, :]).max(axis=2)
    first, middle, last = [], [], []
    total = 0
    for j in range(n):
        ok = fd[j][:, None] + fd[j][None, :] <= limit
        i_idx, k_idx = np.nonzero(ok)
        total += len(i_idx)
        if len(i_idx) == 0:
            raise InstanceError(f"customer {j} has no launch/landing pair within L")
        c = _recovery_duration(instance, i_idx, j, k_idx)
        jj = np.full(len(i_idx), j)
        # last position: one landing per launch (the earliest recovery), then launch dominance
        launches = np.unique(i_idx)
        best_k = np.array([k_idx[i_idx == i][c[i_idx == i].argmin()] for i in launches])
        serve = ft[j, launches]
        rows_mid = np.column_stack([i_idx, jj, k_idx])
        rows_last = np.column_stack([launches, np.full(len(launches), j), best_k])
        if not reduce:
            first.append(rows_mid)
            middle.append(rows_mid)
            last.append(rows_last)
            continue
        land = landing_gap[np.ix_(k_idx, k_idx)]
        keep_mid = _undominated(c, launch_gap_all[np.ix_(i_idx, i_idx)], land, eps)
        keep_first = _undominated(c, launch_gap_depot[np.ix_(i_idx, i_idx)], land, eps)
        zero = np.zeros((len(launches), len(launches)))
        x_gap = launch_gap_depot if n == 1 else launch_gap_all
        keep_last = _undominated(serve, x_gap[np.ix_(launches, launches)], zero, eps)
        first.append(rows_mid[keep_first])
        middle.append(rows_mid[keep_mid])
        last.append(rows_last[keep_last])
    return Triples(np.vstack(first), np.vstack(middle), np.vstack(last), total)


# ----------------------------------------------------------------------------- model
@dataclass
class DeliveryModel:
    """A built model: the cvxpy problem, its variables and the index arrays.

    Attributes
    ----------
    problem : cvxpy.Problem
    sortie : cvxpy.Variable
        y over the rows ``(position[a], launch[a], customer[a], landing[a])``.
    position, launch, customer, landing : int arrays
        The index of each y entry.
    truck_leg : cvxpy.Variable or None
        w over ``(leg_position, leg_from, leg_to)``.
    launch_time, service_time, recovery_time : cvxpy.Variable
        S, t, R per position.
    families : list of dict
        Constraint family, row count and the printed equation it implements.
    """

    problem: cp.Problem
    sortie: cp.Variable
    position: np.ndarray
    launch: np.ndarray
    customer: np.ndarray
    landing: np.ndarray
    truck_leg: cp.Variable | None
    leg_position: np.ndarray
    leg_from: np.ndarray
    leg_to: np.ndarray
    launch_time: cp.Variable
    service_time: cp.Variable
    recovery_time: cp.Variable
    families: list[dict[str, Any]]


def _position_ranges(instance: DeliveryInstance) -> tuple[np.ndarray, np.ndarray, nx.DiGraph]:
    """Earliest/latest sortie of each customer: #ancestors .. n−1−#descendants (5.7)."""
    closure = nx.transitive_closure_dag(instance.precedence_graph)
    n = instance.n
    lo = np.array([closure.in_degree(j) for j in range(n)])
    hi = np.array([n - 1 - closure.out_degree(j) for j in range(n)])
    return lo, hi, closure


def _indicator(rows: np.ndarray, size: int, n_cols: int) -> sp.csr_matrix:
    """Sparse 0/1 matrix with a 1 at (rows[a], a)."""
    return sp.csr_matrix((np.ones(len(rows)), (rows, np.arange(len(rows)))), shape=(size, n_cols))


def customer_gaps(instance: DeliveryInstance) -> np.ndarray:
    """Lower bound ``g[j, j']`` on ``t_p − t_{p−1}`` when j' directly follows j.

    ``t_p − t_{p−1} = ft[j,k] + τ + (wait) + tt[k,i'] + ft[j',i'] + τ`` with k the
    landing stop of j and i' the launch stop of j', both in the viable sets V_j,
    V_j' (stops within ``L − min_h d(w_h, c)``); so ``g[j, j'] = min_{k ∈ V_j,
    i' ∈ V_j'} (ft[j,k] + tt[k,i'] + ft[j',i']) + 2τ``. (A variant of t* (5.11).)
    """
    n = instance.n
    ft, tt, fd = instance.flight_time, instance.truck_time, instance.flight_distance
    viable = [np.flatnonzero(fd[j] + fd[j].min() <= instance.flight_limit) for j in range(n)]
    gaps = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            leg = tt[np.ix_(viable[a], viable[b])]
            gaps[a, b] = (ft[a, viable[a]][:, None] + leg + ft[b, viable[b]][None, :]).min()
    return gaps + 2 * instance.service_time


def _add_customer_legs(
    instance: DeliveryInstance,
    position: np.ndarray,
    customer: np.ndarray,
    sortie: cp.Variable,
    service_time: cp.Variable,
    add: Callable[[Any, str, str], None],
) -> None:
    """Valid inequalities ``t_p ≥ t_{p−1} + Σ g[j,j'] x[p,j,j']`` (see :func:`build`)."""
    n, n_y = instance.n, len(position)
    gaps = customer_gaps(instance)
    p_idx, a_idx, b_idx = np.meshgrid(np.arange(1, n), np.arange(n), np.arange(n), indexing="ij")
    keep = a_idx != b_idx
    p_idx, a_idx, b_idx = p_idx[keep], a_idx[keep], b_idx[keep]
    pair = cp.Variable(len(p_idx), nonneg=True, name="x")
    served = _indicator(customer * n + position, n * n, n_y)  # z[j, p] as row j*n + p
    out_rows = a_idx * n + (p_idx - 1)
    in_rows = b_idx * n + p_idx
    used_out, used_in = np.unique(out_rows), np.unique(in_rows)
    add(
        _indicator(out_rows, n * n, len(p_idx))[used_out] @ pair == served[used_out] @ sortie,
        "valid: sum_j' x[p,j,j'] = z[p-1,j] (customer pair transport plan)",
        "(strengthening; implied by (5.2)-(5.5))",
    )
    add(
        _indicator(in_rows, n * n, len(p_idx))[used_in] @ pair == served[used_in] @ sortie,
        "valid: sum_j x[p,j,j'] = z[p,j'] (customer pair transport plan)",
        "(strengthening; implied by (5.2)-(5.5))",
    )
    step = sp.csr_matrix(
        (gaps[a_idx, b_idx], (p_idx - 1, np.arange(len(p_idx)))), shape=(n - 1, len(p_idx))
    )
    add(
        service_time[1:] >= service_time[:-1] + step @ pair,
        "valid: t_p >= t_{p-1} + sum g[j,j'] x[p,j,j']",
        "(strengthening; g a lower bound like t* (5.11))",
    )


def build(
    instance: DeliveryInstance,
    relax: bool = False,
    reduce: bool = True,
    customer_legs: bool = False,
) -> DeliveryModel:
    """Build the linear model of (5.1)–(5.7) (see the module docstring).

    Parameters
    ----------
    instance : DeliveryInstance
    relax : bool
        Continuous ``0 ≤ y ≤ 1``: the LP relaxation.
    reduce : bool
        Apply the dominance reduction of :func:`feasible_triples`.
    customer_legs : bool
        Add the valid inequalities ``t_p ≥ t_{p−1} + Σ g[j,j'] x[p,j,j']`` with a
        customer-pair transport plan x (marginals z[p−1,·] and z[p,·], forced to
        the product as for w) and ``g`` from :func:`customer_gaps`. They raise the
        LP bound a lot (e.g. 2838 -> 3623 on an 8-customer instance with optimum
        4108) but did not make HiGHS faster on the 8-customer benchmark, so they
        are off by default (``benchmarks/bench_delivery_exact.py`` compares).

    Returns
    -------
    DeliveryModel
    """
    if not isinstance(instance, DeliveryInstance):
        raise InstanceError(
            f"solve_delivery needs a DeliveryInstance, got {type(instance).__name__}"
        )
    n = instance.n
    if n == 0:
        raise InstanceError("the instance has no customers")
    triples = feasible_triples(instance, reduce=reduce)
    lo, hi, closure = _position_ranges(instance)
    position, launch, customer, landing = _sortie_index(triples, lo, hi, n).T
    sortie = cp.Variable(len(position), boolean=not relax, name="y")
    leg_position, leg_from, leg_to = _truck_legs(position, launch, landing, n).T
    n_w = len(leg_position)
    truck_leg = cp.Variable(n_w, nonneg=True, name="w") if n_w else None
    launch_time = cp.Variable(n, nonneg=True, name="S")
    service_time = cp.Variable(n, nonneg=True, name="t")
    recovery_time = cp.Variable(n, nonneg=True, name="R")
    model = DeliveryModel(
        cp.Problem(cp.Minimize(0)),  # replaced below, once every row is in
        sortie,
        position,
        launch,
        customer,
        landing,
        truck_leg,
        leg_position,
        leg_from,
        leg_to,
        launch_time,
        service_time,
        recovery_time,
        [],
    )
    rows = _Rows(model.families)
    rows.note_implicit(triples.feasible, n * instance.s * instance.s)
    _assignment_rows(model, rows, n, relax)
    _continuity_rows(model, rows, instance.s, n)
    _timing_rows(instance, model, rows)
    _precedence_rows(model, rows, closure, n)
    if customer_legs and n > 1:
        _add_customer_legs(instance, position, customer, sortie, service_time, rows.add)
    model.problem = cp.Problem(cp.Minimize(service_time[n - 1]), rows.constraints)
    return model


def _sortie_index(triples: Any, lo: np.ndarray, hi: np.ndarray, n: int) -> np.ndarray:
    """The sortie variables y[p, (i, j, k)]: one row (p, i, j, k) per usable (position,
    triple), the triples of the first, middle or last position within customer j's
    (5.7) position window ``lo[j] <= p <= hi[j]``."""
    blocks = []
    for p in range(n):
        rows = triples.last if p == n - 1 else (triples.first if p == 0 else triples.middle)
        allowed = (lo[rows[:, 1]] <= p) & (p <= hi[rows[:, 1]])  # (5.7) position window
        rows = rows[allowed]
        blocks.append(np.column_stack([np.full(len(rows), p), rows]))
    return np.vstack(blocks)


def _truck_legs(
    position: np.ndarray, launch: np.ndarray, landing: np.ndarray, n: int
) -> np.ndarray:
    """The truck legs w[p, k, i]: rows (p, k, i), k a possible landing of sortie p − 1 and i
    a possible launch of sortie p."""
    leg_rows = []
    for p in range(1, n):
        lands = np.unique(landing[position == p - 1])
        launches = np.unique(launch[position == p])
        kk, ii = np.meshgrid(lands, launches, indexing="ij")
        leg_rows.append(np.column_stack([np.full(kk.size, p), kk.ravel(), ii.ravel()]))
    return np.vstack(leg_rows) if leg_rows else np.zeros((0, 3), dtype=np.int64)


class _Rows:
    """The model's constraints and, for :func:`describe`, one family entry per row block."""

    def __init__(self, families: list[dict[str, Any]]) -> None:
        self.constraints: list = []
        self.families = families

    def add(self, constraint: Any, label: str, printed: str) -> None:
        """Add a labelled row block implementing the printed equation ``printed``."""
        constraint.set_label(label)
        self.constraints.append(constraint)
        self.families.append({"label": label, "rows": int(constraint.size), "implements": printed})

    def note_implicit(self, feasible: int, triples: int) -> None:
        """The printed rows that hold by construction: (5.6) and (5.4)."""
        self.families.append(
            {
                "label": "(5.6) flight range: only triples with d(i,j) + d(j,k) <= L get a y "
                f"({feasible} feasible of {triples}; by construction, no rows)",
                "rows": 0,
                "implements": "(5.6) (d(i,j) + d(j,k)) sigma_ijk <= L",
            }
        )
        self.families.append(
            {
                "label": "(5.4) y_ii = 0: no counterpart (a zero-length leg w[p,k,k] = the truck "
                "stays; landing where launched is allowed)",
                "rows": 0,
                "implements": "(5.4) y_ii = 0",
            }
        )


def _assignment_rows(model: DeliveryModel, rows: _Rows, n: int, relax: bool) -> None:
    """(5.2) every customer served once, one sortie per position (and 0 <= y <= 1)."""
    sortie, n_y = model.sortie, len(model.position)
    # (5.2) each customer served by exactly one sortie
    rows.add(
        _indicator(model.customer, n, n_y) @ sortie == 1,
        "(5.2) every customer served once: sum_{p,i,k} y[p,i,j,k] = 1",
        "(5.2) sum_{i,k} sigma_ijk = 1",
    )
    rows.add(
        _indicator(model.position, n, n_y) @ sortie == 1,
        "one sortie per position: sum_{i,j,k} y[p,i,j,k] = 1",
        "(one package per flight, §5.2.1; implicit in the thesis)",
    )
    if relax:
        rows.add(sortie <= 1, "0 <= y <= 1 (LP relaxation)", "(relaxation of binary sigma)")
        rows.add(sortie >= 0, "0 <= y <= 1 (LP relaxation)", "(relaxation of binary sigma)")


def _continuity_rows(model: DeliveryModel, rows: _Rows, s: int, n: int) -> None:
    """(5.3), (5.5) truck continuity: the legs into launch stops and out of landing stops."""
    n_w = len(model.leg_position)
    if not n_w:
        return
    sortie, truck_leg, n_y = model.sortie, model.truck_leg, len(model.position)
    assert truck_leg is not None  # n_w > 0
    # launch indicator a[p, i] and landing indicator b[p, k] as sparse rows of y
    launch_ind = _indicator(model.position * s + model.launch, n * s, n_y)
    landing_ind = _indicator(model.position * s + model.landing, n * s, n_y)
    # Σ_i w[p,k,i] = b[p−1,k] ; Σ_k w[p,k,i] = a[p,i]
    out_rows = (model.leg_position - 1) * s + model.leg_from
    in_rows = model.leg_position * s + model.leg_to
    used_out = np.unique(out_rows)
    used_in = np.unique(in_rows)
    leg_out = _indicator(out_rows, n * s, n_w)[used_out]
    leg_in = _indicator(in_rows, n * s, n_w)[used_in]
    rows.add(
        leg_out @ truck_leg == landing_ind[used_out] @ sortie,
        "(5.3) truck continuity: sum_i w[p,k,i] = landing of sortie p-1 at k",
        "(5.3) sigma_ijk = y_ik (drone recovered by the truck at k)",
    )
    rows.add(
        leg_in @ truck_leg == launch_ind[used_in] @ sortie,
        "(5.5) truck continuity: sum_k w[p,k,i] = launch of sortie p at i",
        "(5.5) P(t_j - d(i,j)/v_d) = i (truck at the launch stop)",
    )


def _timing_rows(instance: DeliveryInstance, model: DeliveryModel, rows: _Rows) -> None:
    """(5.5) launch times after the truck's drive, (5.1) service times, (5.3) recoveries."""
    n = instance.n
    tt, ft, tau = instance.truck_time, instance.flight_time, instance.service_time
    position, launch, customer, landing = (
        model.position, model.launch, model.customer, model.landing,
    )  # fmt: skip
    sortie, n_y, n_w = model.sortie, len(position), len(model.leg_position)
    launch_time, service_time = model.launch_time, model.service_time
    recovery_time = model.recovery_time
    first = position == 0
    depot_drive = sp.csr_matrix(
        (
            tt[instance.depot, launch[first]],
            (np.zeros(first.sum(), dtype=int), np.flatnonzero(first)),
        ),
        shape=(1, n_y),
    )
    rows.add(
        launch_time[0] >= depot_drive @ sortie,
        "(5.5) timing: S_0 >= truck_time[w0, launch of sortie 0]",
        "(5.5) truck position P(t) at the launch (linear via the leg times)",
    )
    if n_w:
        assert model.truck_leg is not None  # n_w > 0
        drive = sp.csr_matrix(
            (tt[model.leg_from, model.leg_to], (model.leg_position - 1, np.arange(n_w))),
            shape=(n - 1, n_w),
        )
        rows.add(
            launch_time[1:] >= recovery_time[:-1] + drive @ model.truck_leg,
            "(5.5) timing: S_p >= R_{p-1} + sum_{k,i} truck_time[k,i] w[p,k,i]",
            "(5.5) truck position P(t) at the launch (linear via the leg times)",
        )
    outbound = sp.csr_matrix(
        (ft[customer, launch] + tau, (position, np.arange(n_y))), shape=(n, n_y)
    )
    rows.add(
        service_time == launch_time + outbound @ sortie,
        "(5.1) service time: t_p = S_p + sum y (flight_time[j,i] + tau)",
        "(5.1) t_j, the time customer j is served",
    )
    if n > 1:
        mid = position < n - 1
        duration = _recovery_duration(instance, launch[mid], customer[mid], landing[mid])
        cycle = sp.csr_matrix((duration, (position[mid], np.flatnonzero(mid))), shape=(n - 1, n_y))
        rows.add(
            recovery_time[:-1] >= launch_time[:-1] + cycle @ sortie,
            "(5.3) recovery: R_p >= S_p + sum y (max(ft[j,i]+tau+ft[j,k], tt[i,k]) + tau)",
            "(5.3) drone recovered by the truck at k (both there, then tau)",
        )


def _precedence_rows(model: DeliveryModel, rows: _Rows, closure: nx.DiGraph, n: int) -> None:
    """(5.7) cumulative precedence: by any position, r is served no later than j."""
    edges = [(r, j) for r, j in closure.edges()]
    if not edges:
        return
    n_y = len(model.position)
    served_by = _indicator(model.customer * n + model.position, n * n, n_y)  # z[j, p]: j*n+p
    cum = sp.csr_matrix(np.tril(np.ones((n, n))))  # cum[q, p] = [p <= q]
    blocks = []
    for r, j in edges:
        z_j = served_by[j * n : (j + 1) * n]
        z_r = served_by[r * n : (r + 1) * n]
        shifted = sp.csr_matrix(np.tril(np.ones((n, n)), k=-1))  # [p < q]
        blocks.append(cum @ z_j - shifted @ z_r)
    prec = sp.vstack(blocks).tocsr()
    nonempty = np.flatnonzero(np.diff(prec.indptr) > 0)
    rows.add(
        prec[nonempty] @ model.sortie <= 0,
        "(5.7) precedence r before j: sum_{p<=q} z[p,j] <= sum_{p<q} z[p,r]",
        "(5.7) (t_r - t_j) p_j^r <= 0",
    )


def describe(instance: DeliveryInstance, show: bool = True) -> list[dict[str, Any]]:
    """Constraint families of the model for ``instance``: label, row count, printed equation.

    Returns a list of ``{"label", "rows", "implements"}`` (one per family; the
    LP-relaxation bounds are not listed). Logs a table at INFO on the ``taopt`` logger when
    ``show``.
    """
    model = build(instance)
    merged: dict[str, dict[str, Any]] = {}
    for fam in model.families:
        entry = merged.setdefault(fam["label"], dict(fam, rows=0))
        entry["rows"] += fam["rows"]
    table = list(merged.values())
    if show:
        n_w = 0 if model.truck_leg is None else model.truck_leg.size
        lines = [
            f"truck-drone MILP: {model.sortie.size} binary y, {n_w} continuous w, "
            f"{3 * instance.n} times"
        ]
        lines += [
            f"  {row['rows']:>6}  {row['label']}\n          implements {row['implements']}"
            for row in table
        ]
        logger.info("\n".join(lines))
    return table


def decode(model: DeliveryModel, instance: DeliveryInstance, values: Any = None) -> Plan:
    """The :class:`Plan` chosen by y (the largest entry per position).

    Raises
    ------
    SolverError
        A position has no chosen sortie.
    """
    values = model.sortie.value if values is None else values
    if values is None:
        raise SolverError("the model has no solution to decode")
    values = np.asarray(values)
    order, launch, landing = [], [], []
    for p in range(instance.n):
        rows = np.flatnonzero(model.position == p)
        best = rows[values[rows].argmax()]
        if values[best] < 0.5:
            raise SolverError(f"no sortie chosen at position {p}")
        order.append(int(model.customer[best]))
        launch.append(int(model.launch[best]))
        landing.append(int(model.landing[best]))
    return Plan(tuple(order), tuple(launch), tuple(landing))


# ----------------------------------------------------------------------------- solve
def _cutoff(instance: DeliveryInstance, incumbent: Any) -> tuple[float, Plan] | None:
    """Makespan and plan of the incumbent (see :func:`solve_delivery`), or None."""
    if incumbent is None:
        return None
    plan = incumbent.plan if hasattr(incumbent, "plan") else incumbent
    return evaluate_plan(instance, plan), plan


#: Seconds per column for cvxpy to compile the model for HiGHS (outside HiGHS's own clock);
#: measured about 2e-5 on the SOP flow model, taken with a margin.
COMPILE_SECONDS_PER_COLUMN = 3e-5
#: Compile time per second of building, per customer: cvxpy's compile took 1.0-1.3x the
#: build at n = 8, 1.1-1.2x at 12, 2.2-2.7x at 20 and 4.3-5.4x at 30 (residential generator).
#: Measured on the build of the same call, the estimate follows the machine's load.
COMPILE_PER_BUILD_PER_CUSTOMER = 0.2
#: HiGHS's MIP presolve and setup do not look at the clock: without probing (see
#: :data:`LIMITED_RUN_OPTIONS`) 0.05-0.08 n times the build (n = 12, 20, 30). A run is only
#: started when what is left covers this estimate (then HiGHS stops on time).
PRESOLVE_PER_BUILD_PER_CUSTOMER = 0.1
#: HiGHS options of a time-limited run: its probing (presolve rule 2^15) and its restarts
#: (a second presolve after the root) overran the limit by 30-110 % on the 20-customer
#: example (HiGHS 1.16: 3 s took 4.1 s, 6 s took 7.8-13 s; without them 3.2 s and 6.2 s).
LIMITED_RUN_OPTIONS = {"presolve_rule_off": 2**15, "mip_allow_restart": False}


def _stopped(
    instance: DeliveryInstance, known: Any, bound: float | None, began: float, info: dict
) -> Solution:
    """Status "time_limit" before HiGHS found a plan: the incumbent (or no plan, objective
    inf) and the larger of HiGHS's bound and Proposition 5.3's arborescence bound."""
    tree = arborescence_bound(instance)
    return finish(
        instance,
        None if known is None else known[1],
        method="exact-milp",
        stop="time_limit",
        bound=tree if bound is None else max(bound, tree),
        runtime=time.perf_counter() - began,
        info=info,
    )


@register_footprint(DeliveryInstance, "exact")
def _footprint(instance: DeliveryInstance, options: dict) -> tuple[float, str]:
    """Columns grow about as n^3 after :func:`feasible_triples`'s reduction (measured 1,268
    at n = 8, 21,478 at n = 20, 33,756 at n = 30 on the residential generator): 3 n^3 is
    taken, an over-estimate."""
    n = instance.n
    columns = 3.0 * float(n) ** 3
    return milp_bytes(columns), (
        f"the delivery MILP of {instance.name or 'this instance'} ({n} customers, about "
        f"{columns:,.0f} columns)"
    )


def solve_delivery(
    instance: DeliveryInstance,
    time_limit: float | None = None,
    mip_gap: float | None = None,
    verbose: bool = False,
    customer_legs: bool = False,
    incumbent: Any = None,
) -> Solution:
    """Exact optimum of (5.1)–(5.7) by the linear model of this module (HiGHS).

    Parameters
    ----------
    instance : DeliveryInstance
    time_limit : float, optional
        Wall-clock seconds for everything (building, compiling, HiGHS, decoding). On the
        limit the incumbent is returned with status "time_limit" and the proven bound;
        with no plan found, objective inf and no plan (never an exception). Compiling and
        HiGHS's presolve do not look at the clock, so their time is estimated from the
        build's measured time (which follows the machine's load) and a stage that cannot
        fit is not started (``info["model"]`` says where it stopped); HiGHS then gets
        exactly what is left (a persistent :class:`~taopt.models.highs.HighsModel`).
    mip_gap : float, optional
        HiGHS relative gap tolerance; default 1e-9. The status is "optimal"
        only when the final gap is at most 1e-6
        (:data:`taopt.models.highs.OPTIMALITY_TOLERANCE`); a run stopped by a
        looser ``mip_gap`` is "feasible" with its proven bound
        (``info["stopped_by"] == "mip_gap"``).
    verbose : bool
        Print HiGHS's log.
    customer_legs : bool
        Add the customer-pair valid inequalities (see :func:`build`).
    incumbent : Plan, Solution or None
        A known feasible plan whose makespan f (scored by :func:`taopt.evaluate`)
        is given to HiGHS as an objective cut-off (``objective_bound`` =
        f·(1 + 1e-6)): nodes whose bound exceeds it are pruned. It only prunes, so
        the result is still proven by HiGHS's own bound, and the returned plan is
        HiGHS's. The model never runs a heuristic itself: the caller passes one
        (``taopt.solve(instance, "exact")`` passes the best of NIA, MMA and SMMA,
        which cuts the 8-customer benchmark times by about a third); None (default)
        uses no cut-off.

    Returns
    -------
    Solution
        ``.plan`` the decoded :class:`Plan`, ``.objective`` = ``taopt.evaluate`` of
        it (the model's own value is in ``info["model_objective"]``), ``.status``
        "optimal", "feasible" (loose ``mip_gap``) or "time_limit", ``.bound`` the
        proven lower bound, ``.runtime``.
        On a time limit the bound is the larger of HiGHS's and the arborescence
        bound of Proposition 5.3 (:func:`taopt.delivery.bounds.arborescence_bound`).
        If the time limit stops HiGHS before it finds a plan below the incumbent's
        cut-off, the incumbent is returned (status "time_limit", HiGHS's bound,
        ``info["model_objective"]`` NaN); a run stopped by a limit or a loose
        ``mip_gap`` never returns a plan worse than the incumbent.

    Raises
    ------
    InstanceError
        Not a DeliveryInstance, or bad options.
    SolverError
        HiGHS failed, or stopped without a feasible plan and without a time limit.

    References
    ----------
    Thesis §5.2.2, (5.1)–(5.7); timing semantics of :mod:`taopt.delivery.evaluate`.
    """
    began = time.perf_counter()
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    if mip_gap is not None and not (0 <= mip_gap < 1):
        raise InstanceError(f"mip_gap must be in [0, 1), got {mip_gap}")
    deadline = Deadline(time_limit)
    known = _cutoff(instance, incumbent)
    cutoff = None if known is None else known[0]
    if deadline.expired(MARGIN):  # the warm start or the incumbent's scoring took it all
        return _stopped(instance, known, None, began, {"model": "not built"})
    building = time.perf_counter()
    model = build(instance, customer_legs=customer_legs)
    built_in = time.perf_counter() - building
    gap = 1e-9 if mip_gap is None else float(mip_gap)
    bound_at = None if cutoff is None else cutoff * (1 + 1e-6) + 1e-9
    values = None
    if deadline.limited:

        def left() -> float:
            return deadline.remaining() or 0.0  # limited: never None

        # compile apart from solving (HighsModel), so HiGHS gets exactly what is left; a
        # compile that cannot fit is not started (its estimate follows the machine's load)
        columns = sum(v.size for v in model.problem.variables())
        presolve = PRESOLVE_PER_BUILD_PER_CUSTOMER * instance.n * built_in
        estimate = presolve + max(
            COMPILE_SECONDS_PER_COLUMN * columns,
            COMPILE_PER_BUILD_PER_CUSTOMER * instance.n * built_in,
        )
        if left() - estimate - MARGIN <= 0:
            info = {"model": "built, not compiled", "columns": columns, "estimate": estimate}
            return _stopped(instance, known, None, began, info)
        compiled = HighsModel(model.problem, verbose=verbose)
        if left() - presolve - MARGIN <= 0:
            info = {"model": "compiled, not solved", "columns": columns, "estimate": presolve}
            return _stopped(instance, known, None, began, info)
        extra = {
            **LIMITED_RUN_OPTIONS,
            "objective_bound": math.inf if bound_at is None else bound_at,
        }
        run = compiled.solve(left() - MARGIN, gap, options=extra)
        if run.status == INFEASIBLE and cutoff is not None and not deadline.expired(MARGIN):
            # the cut-off pruned everything (see below): re-solve without it
            run = compiled.solve(left() - MARGIN, gap, options={"objective_bound": math.inf})
        if run.has_point:
            values = compiled.values(model.sortie)
    else:
        options: dict[str, Any] = {
            "mip_rel_gap": gap,
            "objective_bound": bound_at,
            "verbose": verbose,
        }
        run = solve_highs(model.problem, **options)
        if run.status == INFEASIBLE and cutoff is not None:
            # the cut-off pruned everything (cannot happen for a valid incumbent, since a
            # plan at least as good is always in the reduced model): re-solve without it
            options["objective_bound"] = None
            run = solve_highs(model.problem, **options)
    if run.solver_status == "solver_error":
        raise SolverError(f"HiGHS failed on the delivery model: {run.message}")
    stopped_by = run.stopped_by
    if run.status == TIME_LIMIT and not run.has_point and known is not None:
        # the limit came before HiGHS found a plan below the cut-off: the incumbent
        # is the best known plan, HiGHS's bound is still proven
        plan, objective, model_objective = known[1], known[0], float("nan")
    elif run.status == TIME_LIMIT and not run.has_point:
        return _stopped(instance, None, run.bound, began, {"solver_status": run.solver_status})
    elif run.status == INFEASIBLE and cutoff is not None and known is not None:
        # the re-solve without the cut-off was skipped for lack of time
        return _stopped(instance, known, None, began, {"solver_status": run.solver_status})
    elif run.status not in (OPTIMAL, FEASIBLE, TIME_LIMIT) or not run.has_point:
        raise SolverError(
            f"HiGHS returned status {run.solver_status!r} without a feasible plan "
            f"(time_limit={time_limit})"
        )
    else:
        plan = decode(model, instance, values)
        objective = evaluate_plan(instance, plan)
        assert run.objective is not None  # has_point
        model_objective = float(run.objective)
        if abs(objective - model_objective) > 1e-6 * max(1.0, abs(objective)):
            # the model's times equal the scorer's at every integral point HiGHS
            # returns at an optimum; at a limit the model may wait, so only >= holds
            if run.status == OPTIMAL or objective > model_objective + 1e-6 * abs(objective):
                raise SolverError(
                    f"decoded plan scores {objective!r} but the model says {model_objective!r}"
                )
        if run.status != OPTIMAL and known is not None and known[0] < objective:
            # stopped by a limit or a loose mip_gap with a plan worse than the incumbent:
            # return the best known plan (HiGHS's bound stays proven for the instance)
            plan, objective = known[1], known[0]
    bound = run.bound
    if run.status != OPTIMAL:  # also Proposition 5.3's valid bound, so a limit keeps a gap
        arborescence = arborescence_bound(instance)
        bound = arborescence if bound is None else max(bound, arborescence)
    return finish(  # the one status rule: optimal only when proven within 1e-6
        instance,
        plan,
        method="exact-milp",
        stop=stopped_by,
        bound=bound,
        runtime=time.perf_counter() - began,
        info={
            "model_objective": model_objective,
            "binaries": int(model.sortie.size),
            "legs": 0 if model.truck_leg is None else int(model.truck_leg.size),
            "nodes": run.nodes,
            "mip_gap": run.mip_gap,
            "cutoff": cutoff,
            "solver_status": run.solver_status,
        },
    )
