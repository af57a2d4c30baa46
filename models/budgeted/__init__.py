"""Exact model of the budgeted family: (2.2)–(2.5) plus capacity and travel-time rows.

Thesis §2.2.1 (2.2)–(2.5) with §6.2's limits (:class:`~taopt.budgeted.BudgetedProblem`):
vehicle k serves at most ``Q_k`` targets and travels at most ``T_k``.

Form: a three-index (arc, vehicle) model
-----------------------------------------
One binary ``x[i, j, k]`` per arc ``i -> j`` (``j`` a target) and vehicle ``k``: arcs out
of a target for every vehicle, arcs out of a start point only for its own vehicle. With
``in_k(j) = Σ_i x[i, j, k]`` and ``out_k(j) = Σ_l x[j, l, k]``:

* (2.2) ``min Σ t(i, j) x[i, j, k]``
* (2.3) ``Σ_k in_k(j) = 1`` for every target j
* (2.4) ``out_k(j) <= in_k(j)`` for every target j and vehicle k (a vehicle leaves only a
  target it entered; summed over k this is (2.4), and it keeps a route on one vehicle),
  and ``Σ_j x[p_k, j, k] <= 1`` at every start point
* capacity ``Σ_{i,j} x[i, j, k] <= Q_k`` (each arc of k enters one target of k)
* travel time ``Σ_{i,j} t(i, j) x[i, j, k] <= T_k``
* (2.5) DFJ rows on the aggregated ``σ_ij = Σ_k x[i, j, k]``, added lazily: the root LP is
  separated exactly (:func:`taopt.models.routing.separate_subtours`, rows written by
  :func:`taopt.models.routing.cut_rows`), then MIP rounds add the cycles of every
  solution HiGHS reports until the round's optimum has none.

Why this form: both limits are plain rows of the LP (no big-M, no arrival-time variable),
so the LP bound sees them and the MIP rounds never return a limit-violating answer; only
(2.5) is lazy, as in chapter 2, and every row of the model is valid for every feasible
solution, so a MIP that HiGHS proves infeasible is a proof that no assignment meets the
limits. The alternatives considered: an assignment ``y[j, k]`` linked to chapter 2's
two-index σ (``σ_ij + y_ik - y_jk <= 1``: ``n^2 m`` rows, and the travel time still needs
arc–vehicle products); MTZ arrival times (big-M, a weak LP); infeasible-path cuts on the
two-index model (one cut removes one path: many rounds when a limit binds). Columns that
cannot be on a feasible route of vehicle k are never created
(:func:`taopt.budgeted.bounds.usable_arcs`): ``x[i, j, k]`` is dropped when
``d_k(i) + t(i, j) > T_k``, ``d_k`` the shortest travel time from ``p_k``, every
target-to-target arc of k when ``Q_k <= 1``, and all of k's columns when ``Q_k = 0``.
Measurements (n50m10 drift scenarios, ``benchmarks/bench_budgeted.py``) are in
``docs/families/budgeted.md``.

Reused from chapter 2 (:mod:`taopt.models.routing`): the arc list, exact separation and
row writing of (2.5), the Karp patching of a MIP answer's cycles, the first bounds; and
the live HiGHS model (:class:`taopt.models.highs.HighsModel`) with its status rule
:func:`taopt.status.decide` (through :func:`taopt.result.finish`). A problem without any finite limit is chapter 2's:
it is solved by :func:`~taopt.models.routing.solve_routing` on ``problem.routing``.

Modules (split by job): :mod:`~taopt.models.budgeted.arc_vehicle` (the three-index model),
:mod:`~taopt.models.budgeted.resource` (the two-index model with resources, the default),
:mod:`~taopt.models.budgeted.separation` (rounded route-count inequalities),
:mod:`~taopt.models.budgeted.starts` (starts and the ``Σ_k T_k`` cut-off) and
:mod:`~taopt.models.budgeted.solve` (:func:`solve_budgeted`, a driver over its stages). Every
public name is importable from this package.

References
----------
Thesis §2.2.1 (2.2)–(2.5), §6.2.
"""

from __future__ import annotations

from taopt.models.budgeted.arc_vehicle import BudgetedModel
from taopt.models.budgeted.resource import ResourceModel
from taopt.models.budgeted.separation import (
    capacity_rows,
    entry_times,
    route_counts,
    separate_capacity,
    time_counts,
)
from taopt.models.budgeted.solve import (
    FORMS,
    MIP_OPTIONS,
    SECONDS_PER_COLUMN,
    solve_budgeted,
)
from taopt.models.budgeted.starts import greedy_budgeted, repaired_routes, total_time_cap

__all__ = [
    "FORMS",
    "MIP_OPTIONS",
    "SECONDS_PER_COLUMN",
    "BudgetedModel",
    "ResourceModel",
    "capacity_rows",
    "entry_times",
    "greedy_budgeted",
    "repaired_routes",
    "route_counts",
    "separate_capacity",
    "solve_budgeted",
    "time_counts",
    "total_time_cap",
]
