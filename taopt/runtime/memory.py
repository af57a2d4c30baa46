"""Size guards: the memory a run would need, checked before it spends it.

(The time a run may spend is :mod:`taopt.runtime.deadline`.)

**A size guard refuses what cannot fit.** Before anything is built, the memory a method would
need is estimated from the problem's size (:func:`footprint`, one estimator registered per
family and method with :func:`register_footprint`) and compared with a limit: by default
:data:`DEFAULT_MAX_MEMORY_GB` GB, or the environment variable ``TAOPT_MAX_MEMORY_GB``, or the
``max_memory_gb`` option of :func:`taopt.solve` (``math.inf`` switches the guard off). Above
it, :class:`~taopt.errors.InstanceError` names the size, the estimate and the limit, in
milliseconds instead of a ``MemoryError`` after minutes.

The estimates are rough on purpose (a factor of two either way): they were measured on the
models as built (``benchmarks/bench_time_limits.py`` prints them next to the measured peaks)
and only need to tell 200 MB from 20 GB.

**A method that degrades is never refused.** A method that takes ``max_memory_gb`` is handed
the limit and fits itself to it; its registered estimate is then the footprint of the stage it
will run, at most the limit. The SOP portfolio is one (:mod:`taopt.models.sop_stages`): its
estimate per stage is a model fitted on peak resident memory measured per stage in fresh
processes (``benchmarks/bench_sop_memory.py``), each stage checks its own estimate before it
starts, and above the limit it runs a weaker stage that fits (the DP with fewer states, a beam
search, the cheap bounds alone) and answers ``time_limit`` with a proven bound.

Example
-------
>>> check_memory(2e9, "a model", max_memory_gb=4)
>>> check_memory(8e9, "a model of 10,000 targets", max_memory_gb=4)
Traceback (most recent call last):
...
taopt.errors.InstanceError: a model of 10,000 targets needs about 8.0 GB, above the limit of 4 GB (raise it with TAOPT_MAX_MEMORY_GB=... or max_memory_gb=...)
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from taopt.errors import InstanceError

#: Memory limit in GB when neither ``max_memory_gb`` nor ``TAOPT_MAX_MEMORY_GB`` is given.
DEFAULT_MAX_MEMORY_GB = 4.0

#: Environment variable that sets the memory limit (GB; "inf" switches the guard off).
MEMORY_ENV = "TAOPT_MAX_MEMORY_GB"

#: Bytes per ordered pair of points when a travel-time matrix is built by navigation: the
#: float64 matrix and the vectorised solvers' work arrays (an instance of 10,000 targets
#: failed at 7.6 GB, about 76 bytes per pair).
NAVIGATION_BYTES_PER_PAIR = 80.0

#: Bytes per column of a MILP built with cvxpy and handed to HiGHS (cvxpy's canonical
#: form, the sparse matrices and HiGHS's copy): about 1 KB per column on the SOP flow
#: model of ESC47 (100,611 columns, 93 MB) and 2 KB per arc on the routing model.
MILP_BYTES_PER_COLUMN = 2048.0


def max_memory_gb(value: float | None = None) -> float:
    """The memory limit in GB: ``value`` if given, else ``TAOPT_MAX_MEMORY_GB``, else the
    default :data:`DEFAULT_MAX_MEMORY_GB`.

    Raises
    ------
    InstanceError
        The value (or the environment variable) is not a positive number.
    """
    source = "max_memory_gb"
    if value is None:
        raw = os.environ.get(MEMORY_ENV)
        if raw is None or not raw.strip():
            return DEFAULT_MAX_MEMORY_GB
        source = MEMORY_ENV
        try:
            value = float(raw)
        except ValueError:
            raise InstanceError(f"{MEMORY_ENV}={raw!r} is not a number of GB") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise InstanceError(f"{source} must be a positive number of GB, got {value!r}")
    return float(value)


def check_memory(needed_bytes: float, what: str, max_memory_gb: float | None = None) -> None:
    """Refuse ``what`` if it needs more than the memory limit.

    Parameters
    ----------
    needed_bytes : float
        The estimate.
    what : str
        Names the item and its size ("the exact model of 3,000 targets (9.0e6 arcs)").
    max_memory_gb : float, optional
        The limit (see :func:`max_memory_gb`).

    Raises
    ------
    InstanceError
        The estimate is above the limit; the message gives both and how to raise the limit.
    """
    limit = globals()["max_memory_gb"](max_memory_gb)
    if needed_bytes > limit * 1e9:
        raise InstanceError(
            f"{what} needs about {needed_bytes / 1e9:.1f} GB, above the limit of {limit:g} GB "
            f"(raise it with {MEMORY_ENV}=... or max_memory_gb=...)"
        )


def navigation_bytes(n_points: int) -> float:
    """Estimated peak bytes of a travel-time matrix of ``n_points`` points by navigation."""
    return NAVIGATION_BYTES_PER_PAIR * float(n_points) ** 2


def milp_bytes(columns: float) -> float:
    """Estimated peak bytes of a cvxpy + HiGHS MILP with ``columns`` variables."""
    return MILP_BYTES_PER_COLUMN * float(columns)


# -- estimators per (family, method) ----------------------------------------------------------
#: (problem type, method name) -> estimator(problem, options) -> (bytes, description).
_FOOTPRINTS: dict[tuple[type, str], Callable[[Any, dict[str, Any]], tuple[float, str]]] = {}


def register_footprint(
    problem_type: type, method: str
) -> Callable[[Callable[[Any, dict[str, Any]], tuple[float, str]]], Any]:
    """Decorator: register ``estimate(problem, options) -> (bytes, what)`` for a method.

    ``what`` names the item and its size for the message ("the SOP flow model of ESC47:
    100,611 columns").
    """

    def wrap(func: Callable[[Any, dict[str, Any]], tuple[float, str]]) -> Any:
        _FOOTPRINTS[(problem_type, method)] = func
        return func

    return wrap


def footprint(
    problem: Any, method: str, options: dict[str, Any] | None = None
) -> tuple[float, str]:
    """Estimated peak bytes of ``method`` on ``problem`` and a description; (0, "") when no
    estimator is registered (a heuristic works on the problem's own matrices)."""
    for cls in type(problem).__mro__:
        estimate = _FOOTPRINTS.get((cls, method))
        if estimate is not None:
            return estimate(problem, dict(options or {}))
    return 0.0, ""


def check_footprint(
    problem: Any,
    method: str,
    options: dict[str, Any] | None = None,
    max_memory_gb: float | None = None,
) -> None:
    """:func:`check_memory` on the :func:`footprint` of ``method`` on ``problem``."""
    needed, what = footprint(problem, method, options)
    if needed:
        check_memory(needed, what, max_memory_gb)


__all__ = [
    "DEFAULT_MAX_MEMORY_GB",
    "MEMORY_ENV",
    "max_memory_gb",
    "check_memory",
    "navigation_bytes",
    "milp_bytes",
    "register_footprint",
    "footprint",
    "check_footprint",
]
