"""Minimum-time navigation in a drift field (thesis §2.3, §3.3).

Public entry points
-------------------
``min_time_path(field, start, goal, speed=1.0, method="collocation") -> Path``
``travel_time_matrix(field, points, speed=1.0, ...) -> (N, N) ndarray``

Methods: direct collocation with IPOPT (the reference, and the default of
``min_time_path``), shooting on the navigation law (2.6)/(2.10) (the thesis's
route, an independent check), vectorised Pontryagin shooting of all pairs at
once (``"pmp"``, :mod:`taopt.navigation.pmp`; the default of
``travel_time_matrix`` for linear fields), and the closed form (3.4) for a
uniform drift.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from taopt.errors import InstanceError
from taopt.fields import Field
from taopt.navigation.collocation import DEFAULT_DEGREE, DEFAULT_INTERVALS, collocation_path
from taopt.navigation.matrix import travel_time_matrix
from taopt.navigation.path import Path, as_field, as_point, as_speed, check_drift
from taopt.navigation.pmp import PairTimes, is_analytic, is_smooth, pmp_path, pmp_travel_times
from taopt.navigation.shooting import navigation_law, shooting_path
from taopt.navigation.uniform import closed_form_path, uniform_travel_times

METHODS = ("collocation", "shooting", "pmp", "closed_form")


def min_time_path(
    field: Field | None,
    start: Any,
    goal: Any,
    speed: float = 1.0,
    method: str = "collocation",
    *,
    intervals: int = DEFAULT_INTERVALS,
    degree: int = DEFAULT_DEGREE,
) -> Path:
    """Minimum-time path from ``start`` to ``goal`` for a vehicle of speed ``speed`` (2.1).

    Parameters
    ----------
    field : Field or None
        Time-invariant drift ``v_c``; None is still water.
    start, goal : (2,) array_like
        End points.
    speed : float
        Speed ``v`` relative to the field; Assumption 2.1 needs ``v > |v_c|``.
    method : {"collocation", "shooting", "pmp", "closed_form"}
        "collocation" (default): CasADi direct collocation solved by IPOPT.
        "shooting": Newton on the two-point problem (2.10) with the law (2.6).
        "pmp": the vectorised shooting of :mod:`taopt.navigation.pmp` for one
        pair, with its accuracy and optimality checks (smooth fields only).
        "closed_form": the straight line of (3.4); only for uniform fields.
    intervals, degree : int
        Collocation grid (ignored by the other methods).

    Returns
    -------
    Path
        ``.time``, ``.xy`` (K, 2), ``.heading`` (K,), ``.status``, ``.iterations``, ``.method``.

    Raises
    ------
    InstanceError
        Bad points or speed, an unknown method, "closed_form" on a non-uniform
        field, "pmp" on a field that is not smooth, or Assumption 2.1 failing on
        the segment's bounding box.
    ConvergenceError
        The method (with its retry) did not converge.

    Example
    -------
    >>> from taopt.fields import UniformField
    >>> round(min_time_path(UniformField(0.5, 0.0), (0, 0), (3, 0)).time, 6)
    2.0

    References
    ----------
    Thesis §2.3, Lemma 2.2, (2.1), (2.6)-(2.10), (3.4).
    """
    field = as_field(field)
    start = as_point(start, "start")
    goal = as_point(goal, "goal")
    speed = as_speed(speed)
    if method not in METHODS:
        raise InstanceError(f"unknown method {method!r} (expected one of {', '.join(METHODS)})")
    check_drift(field, np.vstack([start, goal]), speed)
    if method == "closed_form":
        if not field.is_uniform:
            raise InstanceError(f"method 'closed_form' needs a uniform field, got {field!r}")
        return closed_form_path(field.velocity(start)[0], start, goal, speed)
    if method == "shooting":
        return shooting_path(field, start, goal, speed)
    if method == "pmp":
        return pmp_path(field, start, goal, speed)
    return collocation_path(field, start, goal, speed, intervals, degree)


__all__ = [
    "min_time_path",
    "travel_time_matrix",
    "Path",
    "uniform_travel_times",
    "navigation_law",
    "pmp_travel_times",
    "pmp_path",
    "PairTimes",
    "is_smooth",
    "is_analytic",
    "METHODS",
]
