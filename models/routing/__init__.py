"""Exact model of chapter 2: open multi-depot routing (2.2)–(2.5) in cvxpy + HiGHS.

Sets and data (thesis §2.2.1): targets ``T = {0..n-1}``, vehicle start points
``R = {n..n+m-1}``, travel times ``t(i, j)`` = ``problem.cost[i, j]``.

Variables: one binary ``σ_ij`` per arc ``i -> j`` with ``i ∈ T ∪ R``,
``j ∈ T``, ``i ≠ j`` (no self loops, no arcs into a start point). They are held
in ONE cvxpy vector over the arc list (a masked matrix flattened), so every
constraint family is a single sparse matrix expression, never a Python loop
per arc.

* (2.2) objective ``min Σ t(i, j) σ_ij``
* (2.3) in-degree one on every target
* (2.4) out-degree at most one on every point
* (2.5) no subtour among targets, in one of three ways (``sec``):

  - ``"dfj"`` — the thesis's own (2.5), Dantzig–Fulkerson–Johnson. It has one
    constraint per subset, so it is added lazily: solve, find every cycle
    among targets in the incumbent, add ``Σ_{i,j∈S} σ_ij ≤ |S| − 1`` for each,
    re-solve, until no cycle is left. The loop runs on ONE live HiGHS model
    (:class:`DfjModel`): the cvxpy model is compiled once, rows are added in
    place, rows violated by the root LP are separated exactly first, arcs that
    cannot improve on the incumbent (by LP reduced cost) are switched off, and
    every round starts from the best solution known (see :func:`solve_routing`).
  - ``"mtz"`` — Miller–Tucker–Zemlin order variables (compact).
  - ``"flow"`` — single-commodity flow from the vehicles (compact).

The three give the same optimum; their LP relaxations differ
(``solve_routing(..., relax=True)``): DFJ's is the strongest.

The package holds the four jobs in four modules: :mod:`~taopt.models.routing.formulation`
(the cvxpy model, decoding, repair, the first bounds and incumbent),
:mod:`~taopt.models.routing.separation` (exact separation of (2.5)),
:mod:`~taopt.models.routing.dfj` (the DFJ loop on one live HiGHS model) and
:mod:`~taopt.models.routing.solve` (the driver :func:`solve_routing`), with the compact MTZ /
flow solve the DFJ loop falls back on in :mod:`~taopt.models.routing.compact`. Every public
name is importable from this package, as before the split.

Example
-------
>>> import numpy as np
>>> from taopt import AssignmentProblem
>>> cost = np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]])
>>> solve_routing(AssignmentProblem(cost, 2)).routes
[[1, 0]]
"""

from __future__ import annotations

from taopt.models.highs import OPTIMALITY_TOLERANCE
from taopt.models.routing.compact import (
    ASSIGNMENT_SECONDS_PER_CUBE,
    COMPACT_SECONDS_PER_ARC,
    HIGHS_OVERRUN,
)
from taopt.models.routing.dfj import (
    BUILD_SECONDS_PER_ARC,
    CORE_SIZE,
    FALLBACK_SEC,
    LIFTED_FAMILIES,
    LIFTED_MIN_GAIN,
    LIFTED_ROUNDS,
    LP_SECONDS_PER_ARC,
    MIP_OPTIONS,
    DfjModel,
    RootRelaxation,
    dfj_root,
)
from taopt.models.routing.formulation import (
    SUBTOUR_ELIMINATIONS,
    RoutingModel,
    arc_list,
    assignment_bound,
    build,
    decode,
    describe,
    entry_bound,
    find_subtours,
    greedy_routes,
    repair,
)
from taopt.models.routing.separation import (
    CUT_TOLERANCE,
    blossom_arcs,
    cut_rows,
    lifted_cycle_arcs,
    separate_blossoms,
    separate_lifted_cycles,
    separate_subtours,
)
from taopt.models.routing.solve import solve_routing

__all__ = [
    # the time estimates and tuning constants, read (and patched by tests) from here before
    # the split; patch them in the module that defines them
    "ASSIGNMENT_SECONDS_PER_CUBE",
    "BUILD_SECONDS_PER_ARC",
    "COMPACT_SECONDS_PER_ARC",
    "CORE_SIZE",
    "FALLBACK_SEC",
    "HIGHS_OVERRUN",
    "LIFTED_FAMILIES",
    "LIFTED_MIN_GAIN",
    "LIFTED_ROUNDS",
    "LP_SECONDS_PER_ARC",
    "MIP_OPTIONS",
    "arc_list",
    "CUT_TOLERANCE",
    "OPTIMALITY_TOLERANCE",
    "SUBTOUR_ELIMINATIONS",
    "DfjModel",
    "RootRelaxation",
    "assignment_bound",
    "RoutingModel",
    "blossom_arcs",
    "build",
    "cut_rows",
    "decode",
    "describe",
    "dfj_root",
    "entry_bound",
    "find_subtours",
    "greedy_routes",
    "lifted_cycle_arcs",
    "repair",
    "separate_blossoms",
    "separate_lifted_cycles",
    "separate_subtours",
    "solve_routing",
]
