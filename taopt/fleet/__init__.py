"""Thesis §6.2's recommendations 2 and 3: trucks carrying multi-parcel drones, precedence across
the fleet.

Registers the family :class:`FleetProblem` (payload :class:`FleetPlan`, scorer
:func:`evaluate_fleet`) through :mod:`taopt.fleet.family`. See ``docs/families/fleet.md``.
"""

from taopt.fleet import family as _family  # noqa: F401  (registers the family)
from taopt.fleet.evaluate import FleetSchedule, evaluate_fleet, schedule
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie


def tspd_path(name: str) -> str:
    """The shipped TSP-D instance ``name`` (e.g. ``"uniform-1-n11"``: Agatz, Bouman & Schmidt's
    uniform set with its published optima, ``taopt/data/tspd/``), as a file path usable from
    any folder.

    Example
    -------
    >>> FleetProblem.from_tspd(tspd_path("uniform-1-n5")).n
    4
    """
    from importlib.resources import files

    from taopt.errors import InstanceError

    path = files("taopt.data") / "tspd" / f"{name}.txt"
    if not path.is_file():
        raise InstanceError(f"no shipped TSP-D instance {name!r} (taopt/data/tspd/)")
    return str(path)


__all__ = [
    "FleetPlan",
    "FleetProblem",
    "FleetSchedule",
    "Sortie",
    "evaluate_fleet",
    "schedule",
    "tspd_path",
]
