"""Chapter 2's heuristics made limit-aware for :class:`~taopt.budgeted.BudgetedProblem` (§6.2).

The thesis's future work (§6.2) asks whether its task-assignment algorithms keep their
performance when "each vehicle can visit a maximum number of target locations" (capacity
``Q_k``) or "has a maximum travel time" (``T_k``). Three of chapter 2's methods are made
aware of the limits here, each the smallest change that keeps the printed algorithm:

* "MC" — marginal-cost clustering (2.15): the global cheapest insertion, where a vehicle
  whose route would exceed ``Q_k`` or ``T_k`` by taking a target is refused (its marginal
  cost is ``inf``). Without limits it is chapter 2's MC, step for step.
* "EVM" — extended Voronoi clustering (2.12)–(2.14) + smallest marginal cost sequencing
  (2.18)–(2.19): the Prim-like growth refuses a (vehicle, target) pair when the vehicle is
  full or when its cluster with the target, sequenced by (2.18), would take longer than
  ``T_k``. Without limits it is chapter 2's EVM.
* "GA" — the memetic GA of §2.5 (:mod:`taopt.heuristics.ga_routing`: its encoding,
  crossover, mutations and local search), with a *penalty* for violated limits and, in
  its memetic step, a repair and a limit-aware local search (:func:`genetic_algorithm`).

A heuristic cannot prove that no feasible answer exists. When MC or EVM is left with
targets no vehicle can take, or the GA never met a feasible chromosome, the answer is
status ``"no_solution"`` (``taopt.result.NO_SOLUTION``: the heuristic's outcome, not a
failure and not a proof) with ``solution=None``, ``objective=inf``, ``info["unassigned"]`` (how many targets were left,
for MC and EVM) and ``info["error"]`` saying that this is not a proof of infeasibility.
Never a fake feasible answer: every returned payload is scored by
:func:`~taopt.budgeted.evaluate_budgeted`, which re-checks the limits.

Limits are checked with ``time <= T_k (1 + 1e-9)``, stricter than the scorer's tolerance
(:data:`taopt.budgeted.problem.TIME_TOLERANCE`), so an accepted route always passes it.

Modules (split by job): :mod:`~taopt.heuristics.budgeted.clustering` (MC and EVM),
:mod:`~taopt.heuristics.budgeted.descent` (the repair, the limit-aware descent, the registered
improver), :mod:`~taopt.heuristics.budgeted.ga` (the GA) and
:mod:`~taopt.heuristics.budgeted.common` (the limit test, the answer). Every public name is
importable from this package.

References
----------
Thesis §2.4 (2.11)–(2.19), §2.5 (the GA), §6.2 (future work).
"""

from __future__ import annotations

from taopt.heuristics.budgeted.clustering import (
    evm,
    limited_extended_voronoi_routes,
    limited_marginal_cost_routes,
    mc,
)
from taopt.heuristics.budgeted.descent import (
    LimitedDescent,
    improve_budgeted,
    limited_local_search,
    repair,
)
from taopt.heuristics.budgeted.ga import (
    MEMETIC_STEPS,
    capacity_unit,
    genetic_algorithm,
    penalised_cost,
    route_times,
)

__all__ = [
    "MEMETIC_STEPS",
    "limited_marginal_cost_routes",
    "limited_extended_voronoi_routes",
    "repair",
    "limited_local_search",
    "LimitedDescent",
    "improve_budgeted",
    "route_times",
    "penalised_cost",
    "mc",
    "evm",
    "genetic_algorithm",
    "capacity_unit",
]
