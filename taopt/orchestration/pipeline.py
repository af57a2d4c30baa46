"""``taopt.solve``: the one entry point for every problem family and method.

It only wires (as PyVRP's ``solve.py``): it looks the method up in :mod:`taopt.registry`,
passes the options the method takes, gives an exact model its incumbent from the
registered warm-start heuristics (the models never run heuristics themselves), and
checks the payload with the family's one scorer :func:`taopt.evaluate` before returning:
a Solution built by :func:`taopt.result.make_solution` for this problem was scored there,
once; any other (hand-built) one is re-scored here.

This module is the orchestration layer: it imports the method packages (which register
their methods on import) when one of its functions is first called
(:func:`register_methods`), so a first :func:`solve`'s imports run on its own clock.

Example
-------
>>> import numpy as np, taopt
>>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), n_targets=2)
>>> taopt.solve(p, "exact").routes, taopt.solve(p, "MC").objective
([[1, 0]], 4.0)
"""

from __future__ import annotations

import logging
import math
from typing import Any

from taopt.defaults import SEED, TIME_LIMIT
from taopt.errors import InstanceError, SolverError, TaoptError
from taopt.registry import (
    CATEGORIES,
    ensure_families,
    family_of,
    get_method,
    improver,
    methods,
)
from taopt.registry import certifying_method as _certifying_method
from taopt.result import ERROR, INFEASIBLE, NO_SOLUTION, RELAXATION, Solution
from taopt.runtime import (
    MARGIN,
    WARM_START_SHARE,
    CancelToken,
    Deadline,
    cancel_scope,
    check_footprint,
)
from taopt.scoring import evaluate

#: Relative tolerance between a method's reported objective and the scorer's value.
SCORE_TOLERANCE = 1e-6

#: Smallest time limit passed on to a method (a budget already spent still gets this).
MIN_SECONDS = 1e-3

logger = logging.getLogger("taopt")


def register_methods() -> None:
    """Import :mod:`taopt.models` and :mod:`taopt.heuristics`, which register every method.

    Called first by each function here, not when this module is imported: a first
    :func:`solve` in a fresh process spends 1-2 s importing them (cvxpy, OR-Tools' bindings,
    ...), and that is inside its ``time_limit`` (the deadline starts before). Later calls
    find them in ``sys.modules``.
    """
    import taopt.heuristics  # noqa: F401  (registers the heuristics)
    import taopt.models  # noqa: F401  (registers the exact models)


def _warm_start(
    problem: Any,
    names: tuple[str, ...],
    seed: int | None,
    deadline: Deadline,
    kwargs: dict[str, Any],
) -> dict[str, Any] | None:
    """Run the warm-start heuristics ``names``; put the best payload in ``kwargs``.

    Under a limit they share :data:`WARM_START_SHARE` of it (each one that takes a
    ``time_limit`` gets its part and stops on it; once the share is spent the remaining
    ones are skipped). A heuristic that fails (a :class:`TaoptError`) is skipped and
    logged: the exact method still runs, without that incumbent.
    """
    budget = deadline.share(WARM_START_SHARE)
    end = None if budget is None else deadline.elapsed() + budget
    warm: list[Solution] = []
    for k, name in enumerate(names):
        limit = None
        if end is not None:
            left = end - deadline.elapsed()
            if left <= 0 and warm:
                logger.info("warm start %s skipped: its share of the time limit is spent", name)
                continue
            limit = max(left / (len(names) - k), MIN_SECONDS)
        try:
            warm.append(solve(problem, name, seed=seed, time_limit=limit))
        except TaoptError as exc:
            logger.warning("warm start %s failed and is skipped: %s", name, exc)
    warm = [s for s in warm if s.solution is not None and math.isfinite(s.objective)]
    if not warm:
        return None
    best = min(warm, key=lambda s: s.objective)
    kwargs["incumbent"] = best.solution
    return {"method": best.method, "objective": best.objective, "runtime": deadline.elapsed()}


def solve(
    problem: Any,
    method: str = "exact",
    *,
    seed: int | None = SEED,
    time_limit: float | None = TIME_LIMIT,
    max_memory_gb: float | None = None,
    cancel: CancelToken | None = None,
    **options: Any,
) -> Solution:
    """Solve ``problem`` with the registered ``method``.

    Parameters
    ----------
    problem : a registered problem (AssignmentProblem, DeliveryInstance, SopProblem, ...)
    method : str
        A registered name: "exact", "MC", "GA", "SMMA", "pyvrp", ... (see
        :func:`available_methods`).
    seed : int, optional
        Passed to methods that take one (randomised ones); ignored by the others. Default
        :data:`taopt.defaults.SEED` (0), as ``taopt solve --seed``.
    time_limit : float, optional
        Default :data:`taopt.defaults.TIME_LIMIT` (60 s), as ``taopt solve --time-limit``;
        None for no limit.
        Wall-clock seconds for the whole call (docs/architecture.md, invariant 4): the clock
        starts on entry; the warm-start heuristics of an exact method get a share of it
        (:data:`taopt.runtime.WARM_START_SHARE`), the method the remaining seconds. Methods
        that take no limit (fast heuristics) ignore it. An exact model stopped by it returns
        its best plan with status "time_limit" and a proven bound; with no plan found in
        time, status "time_limit", objective ``inf``, no payload, and the bound.
    max_memory_gb : float, optional
        The size guard's limit (default ``TAOPT_MAX_MEMORY_GB`` or
        :data:`taopt.runtime.DEFAULT_MAX_MEMORY_GB`; ``math.inf`` switches it off): a method
        whose estimated memory (:func:`taopt.runtime.footprint`) is above it is refused
        before anything is built.
    cancel : taopt.runtime.CancelToken, optional
        Stops the run early once another thread cancels it: the method stops at its next
        check of its deadline (and a HiGHS run at its next interrupt callback) and returns
        its best answer as at a time limit (docs/architecture.md, "the runtime contract").
    **options
        Method-specific keyword options (an unknown one is an error naming it).
        ``incumbent=None`` switches off the warm start of an exact model.
        ``trace=True`` keeps a method's rounds in ``info["trace"]`` (the DFJ loop,
        :func:`taopt.models.routing.solve_routing`; the ideal DP,
        :func:`taopt.delivery.ideal_dp.ideal_dp`), drawn by :func:`taopt.plot.trace`; a
        method that keeps none refuses ``trace=True`` (InstanceError naming it) and
        ignores ``trace=False``.

    Returns
    -------
    Solution
        ``method`` is the registered name; ``runtime`` includes a warm start, which is
        recorded in ``info["warm_start"]``.

    Raises
    ------
    InstanceError
        Unknown method or option, a bad ``time_limit``, or a problem too large for the
        memory limit (the message names the size, the estimate and the limit).
    SolverError
        The method's objective differs from the scorer's value of its payload.
    """
    if cancel is not None:  # every deadline made during the call carries the token
        with cancel_scope(cancel):
            return solve(
                problem, method, seed=seed, time_limit=time_limit, max_memory_gb=max_memory_gb,
                **options,
            )  # fmt: skip
    deadline = Deadline(None)  # replaced below once time_limit is checked
    if time_limit is not None:
        if isinstance(time_limit, bool) or not (
            isinstance(time_limit, (int, float)) and math.isfinite(time_limit)
        ):
            raise InstanceError(f"time_limit must be a number of seconds, got {time_limit!r}")
        if time_limit <= 0:
            raise InstanceError(f"time_limit must be positive, got {time_limit}")
        deadline = Deadline(time_limit)  # the clock starts now: everything below counts
    register_methods()  # (a first call's imports: on the clock)
    spec = get_method(problem, method)
    method = spec.name  # the registered spelling ("mc" -> "MC")
    kwargs = dict(options)
    if "trace" in kwargs and not spec.accepts("trace"):
        if kwargs["trace"]:
            raise InstanceError(
                f"method {method!r} keeps no trace (trace=True); the exact DFJ loop of "
                "chapter 2 (AssignmentProblem, 'exact') and the exact ideal DP of chapter 5 "
                "(DeliveryInstance, 'exact') do"
            )
        del kwargs["trace"]  # trace=False: nothing to keep, whatever the method
    if seed is not None and spec.accepts("seed"):
        kwargs["seed"] = seed
    if time_limit is not None and spec.accepts("time_limit"):
        kwargs["time_limit"] = time_limit
    spec.check_options(kwargs)
    # the size guard: refuse before anything is built (milliseconds, not a MemoryError)
    if max_memory_gb is not None and spec.accepts("max_memory_gb"):
        kwargs.setdefault("max_memory_gb", max_memory_gb)  # a method that degrades to fit
    check_footprint(problem, method, kwargs, max_memory_gb)
    warm_info = None
    if spec.warm_start and spec.accepts("incumbent") and "incumbent" not in kwargs:
        warm_info = _warm_start(problem, spec.warm_start, seed, deadline, kwargs)
    if spec.category == "exact" and spec.accepts("improve") and "improve" not in kwargs:
        kwargs["improve"] = improver(problem)  # the family's, registered by a heuristic
    left = deadline.remaining()  # None only without a time_limit
    if "time_limit" in kwargs and left is not None:
        # the method gets what is left: warm start and checks above were on the clock
        kwargs["time_limit"] = max(left - MARGIN, MIN_SECONDS)
    result = spec.func(problem, **kwargs)
    if not isinstance(result, Solution):
        raise SolverError(f"method {method!r} returned {type(result).__name__}, not a Solution")
    runtime = deadline.elapsed()
    scored = result.is_scored_for(problem)  # built by make_solution: scored once already
    if (
        result.solution is not None
        and result.status not in (RELAXATION, ERROR, INFEASIBLE, NO_SOLUTION)
        and not scored
    ):
        value = evaluate(problem, result.solution)  # the one scorer, never the method's word
        if abs(value - result.objective) > SCORE_TOLERANCE * max(1.0, abs(value)):
            raise SolverError(
                f"method {method!r} reported objective {result.objective!r} but evaluate gives "
                f"{value!r}"
            )
    info = dict(result.info)
    if result.method and result.method != method:
        info.setdefault("variant", result.method)
    if warm_info is not None:
        info["warm_start"] = warm_info
    return result.replace(method=method, runtime=runtime, info=info)


def certifying_method(problem: Any) -> str | None:
    """The exact method that certifies ``problem`` fastest, among every registered one
    (:func:`taopt.registry.certifying_method` after this module has imported
    ``taopt.models``): what ``taopt verify --exact`` re-solves with."""
    register_methods()
    return _certifying_method(problem)


def available_methods(problem: Any, category: str | None = None) -> list[str]:
    """Names of the methods usable on ``problem`` here: exact methods first.

    Then heuristics, peers, simulations and relaxations (registration order within each
    category). Every registered method of ``problem``'s family (optionally of one ``category``: "exact",
    "heuristic", "peer", "simulation", "relaxation") whose packages are installed: a peer
    such as "pyvrp" or "ortools" is listed only when its package is (found with
    ``importlib.util.find_spec``, never imported here).

    Parameters
    ----------
    problem : a registered problem, or its class
    category : str, optional

    Returns
    -------
    list of str

    Example
    -------
    >>> import numpy as np, taopt
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), n_targets=2)
    >>> taopt.available_methods(p, "exact")
    ['exact']
    """
    register_methods()
    found = [spec for spec in methods(problem, category).values() if spec.available]
    found.sort(key=lambda spec: CATEGORIES.index(spec.category))  # stable: exact first
    return [spec.name for spec in found]


def default_methods(problem: Any) -> list[str]:
    """The methods ``taopt solve`` runs when none are named: exact first, then heuristics.

    Peers (optional extras) and relaxations are left out; a method registered with a
    ``default`` predicate (e.g. a DP only for small instances) is included when it holds.
    """
    register_methods()
    found = methods(problem)
    order = ("exact", "heuristic", "simulation")
    return [
        name
        for category in order
        for name, spec in found.items()
        if spec.category == category and spec.is_default_for(problem) and spec.available
    ]


def no_optimum_note(problem: Any) -> str:
    """Why the default methods compute no certified optimum of ``problem`` ("" when they do).

    One line naming the exact method left out and why (e.g. the delivery DP beyond 12
    customers); ``taopt solve`` prints it under its table.
    """
    register_methods()
    exact = methods(problem, "exact")
    if not exact or any(spec.is_default_for(problem) for spec in exact.values()):
        return ""
    first = next(iter(exact.values()))
    return f"no certified optimum: {first.why_not_default(problem)}"


def lower(problem: Any, strength: str = "auto") -> float:
    """:func:`taopt.bounds.lower` (the strongest valid lower bound of the problem's family).

    Example
    -------
    >>> import numpy as np, taopt
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), n_targets=2)
    >>> taopt.lower(p, "strong") <= taopt.solve(p, "exact").objective
    True
    """
    register_methods()
    from taopt.bounds import lower as core_lower

    return core_lower(problem, strength)


def load_problem(data: Any) -> Any:
    """Build the problem of a JSON document by its ``kind`` (the registry's loaders)."""
    register_methods()
    ensure_families()
    if not isinstance(data, dict):
        raise InstanceError("a problem file must hold a JSON object")
    from taopt.registry import family_for_kind

    return family_for_kind(data.get("kind")).load(data)


__all__ = [
    "solve",
    "register_methods",
    "certifying_method",
    "available_methods",
    "default_methods",
    "no_optimum_note",
    "load_problem",
    "lower",
    "family_of",
]
