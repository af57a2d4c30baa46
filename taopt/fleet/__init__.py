"""Thesis §6.2's recommendations 2 and 3: trucks carrying multi-parcel drones, precedence across
the fleet.

Registers the family :class:`FleetProblem` (payload :class:`FleetPlan`, scorer
:func:`evaluate_fleet`) through :mod:`taopt.fleet.family`. See ``docs/families/fleet.md``.
"""

from taopt.fleet import family as _family  # noqa: F401  (registers the family)
from taopt.fleet.evaluate import FleetSchedule, evaluate_fleet, schedule
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie

__all__ = ["FleetPlan", "FleetProblem", "FleetSchedule", "Sortie", "evaluate_fleet", "schedule"]
