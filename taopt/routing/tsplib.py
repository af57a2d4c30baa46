"""TSPLIB asymmetric TSP files, and their reduction to the chapter 2 model.

The files in ``taopt/data/tsplib/`` are unmodified TSPLIB95 instances (see the
README there for the source and checksums). They certify the exact model:
a closed ATSP tour is an open route of ONE vehicle in (2.2)–(2.5) after the
reduction of :func:`atsp_to_assignment`.

Example
-------
>>> from taopt.routing.tsplib import load_atsp, atsp_to_assignment
>>> atsp = load_atsp("br17")
>>> atsp.dimension, atsp.optimum
(17, 39)
>>> atsp_to_assignment(atsp).n
17
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from taopt.errors import InstanceError
from taopt.routing.problem import AssignmentProblem
from taopt.tsplib import read_tsplib, shipped_tsplib, tsplib_file

#: Proven optima from TSPLIB95's documentation (DOC.PS, Table 2), also in its
#: ``atsp/bestSolutions.txt``; see ``taopt/data/tsplib/README.md``.
KNOWN_OPTIMA = {
    "br17": 39,
    "ftv33": 1286,
    "ftv35": 1473,
    "ftv38": 1530,
    "p43": 5620,
    "ftv44": 1613,
    "ry48p": 14422,
    "ft53": 6905,
}

__all__ = [
    "KNOWN_OPTIMA",
    "AtspInstance",
    "load_atsp",
    "atsp_to_assignment",
    "tour_length",
    "shipped",
]


@dataclass(frozen=True, eq=False)
class AtspInstance:
    """A TSPLIB ATSP instance: the header and the distance matrix.

    Attributes
    ----------
    name : str
    header : dict
        Every ``KEY: value`` line before ``EDGE_WEIGHT_SECTION`` (blanks stripped).
    distance : (N, N) ndarray
        ``distance[i, j]`` from city i to city j; the diagonal is kept as read
        but is meaningless (TSPLIB's big-M) and is never used.
    """

    name: str
    header: dict = field(repr=False)
    distance: np.ndarray = field(repr=False)

    @property
    def dimension(self) -> int:
        return self.distance.shape[0]

    @property
    def optimum(self) -> int | None:
        """TSPLIB's proven optimum, or None if not in :data:`KNOWN_OPTIMA`."""
        return KNOWN_OPTIMA.get(self.name)


def shipped() -> list[str]:
    """Names of the ATSP instances shipped in ``taopt/data/tsplib``."""
    return shipped_tsplib(".atsp")


def load_atsp(name_or_path: str | Path) -> AtspInstance:
    """Read a TSPLIB ``.atsp`` file (EXPLICIT, FULL_MATRIX).

    Parameters
    ----------
    name_or_path : str or Path
        A shipped instance name (``"br17"``) or a path to a ``.atsp`` file.

    Returns
    -------
    AtspInstance

    Raises
    ------
    InstanceError
        Unknown name, unsupported format, or a matrix of the wrong size.
    """
    path = Path(name_or_path)
    if path.suffix != ".atsp" and not path.exists():
        path = tsplib_file(f"{name_or_path}.atsp")
        if not path.is_file():
            raise InstanceError(f"no shipped TSPLIB instance {name_or_path!r}; have {shipped()}")
    elif not path.is_file():
        raise InstanceError(f"TSPLIB file {str(path)!r} does not exist")
    header, tokens = read_tsplib(path)
    if tokens is None:
        raise InstanceError(f"{name_or_path}: no EDGE_WEIGHT_SECTION")
    if header.get("TYPE") != "ATSP":
        raise InstanceError(f"{name_or_path}: TYPE is {header.get('TYPE')!r}, expected 'ATSP'")
    if (
        header.get("EDGE_WEIGHT_TYPE") != "EXPLICIT"
        or header.get("EDGE_WEIGHT_FORMAT") != "FULL_MATRIX"
    ):
        raise InstanceError(f"{name_or_path}: only EXPLICIT FULL_MATRIX is supported")
    try:
        dimension = int(header["DIMENSION"])
    except (KeyError, ValueError):
        raise InstanceError(f"{name_or_path}: bad or missing DIMENSION") from None
    if len(tokens) != dimension * dimension:
        raise InstanceError(
            f"{name_or_path}: {len(tokens)} weights for DIMENSION {dimension} "
            f"(expected {dimension * dimension})"
        )
    distance = np.array(tokens, dtype=float).reshape(dimension, dimension)
    distance.setflags(write=False)
    return AtspInstance(name=header.get("NAME", path.stem), header=header, distance=distance)


def atsp_to_assignment(atsp: AtspInstance) -> AssignmentProblem:
    """Reduce a closed ATSP tour to (2.2)–(2.5) with one vehicle.

    Points of the result (N = number of cities):

    * targets ``0..N-2`` are cities ``1..N-1``;
    * target ``N-1`` is a copy of city 0 that may only be *entered*: all its
      outgoing arcs cost ``P = 1 + Σ_i max_{j≠i} d(i, j)``;
    * point ``N`` (the only vehicle) starts at city 0.

    Every open route visits all N targets, so it is a path from city 0 through
    all cities. A route ending at the copy of city 0 is a closed tour of the
    same length. Any tour costs at most ``Σ_i max_j d(i, j) < P``, and a route
    that leaves the copy pays at least P, so the open-route optimum never
    leaves the copy: it equals the ATSP optimum. The vehicle-to-copy arc
    (TSPLIB's diagonal ``d(0, 0)``) is priced P as well.

    Returns
    -------
    AssignmentProblem
        ``n = N`` targets, ``m = 1``.
    """
    distance = np.array(atsp.distance, dtype=float)
    cities = distance.shape[0]
    if cities < 2:
        raise InstanceError(f"{atsp.name}: an ATSP needs at least 2 cities")
    off = distance.copy()
    np.fill_diagonal(off, -np.inf)
    prohibitive = 1.0 + float(off.max(axis=1).sum())
    # city of each point: targets 0..N-2 -> cities 1..N-1, target N-1 -> city 0, vehicle -> city 0
    city = np.concatenate([np.arange(1, cities), [0, 0]])
    cost = distance[np.ix_(city, city)]
    copy, vehicle = cities - 1, cities
    cost[copy, :] = prohibitive  # the copy of city 0 is a dead end
    cost[vehicle, copy] = prohibitive  # closing the tour at once is not a tour
    cost[:, vehicle] = 0.0  # nothing enters a start point; unused
    np.fill_diagonal(cost, 0.0)
    return AssignmentProblem(cost, n_targets=cities, name=atsp.name)


def tour_length(atsp: AtspInstance, route: list[int]) -> float:
    """Closed-tour length in the ATSP of a route of :func:`atsp_to_assignment`."""
    cities = atsp.dimension
    tour = [0] + [t + 1 if t < cities - 1 else 0 for t in route]
    if tour[-1] != 0:
        tour.append(0)
    if sorted(tour[:-1]) != list(range(cities)):
        raise InstanceError("route is not a tour of every city")
    return float(sum(atsp.distance[a, b] for a, b in zip(tour[:-1], tour[1:], strict=False)))
