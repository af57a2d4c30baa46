"""Name -> method registry for :func:`taopt.heuristics.run`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from taopt.errors import InstanceError
from taopt.result import Solution

# METHODS[kind][name] = callable(problem, seed=..., **options) -> Solution
METHODS: dict[str, dict[str, Callable[..., Solution]]] = {"routing": {}, "delivery": {}}


def register(name: str, kind: str) -> Callable[[Callable[..., Solution]], Callable[..., Solution]]:
    """Decorator: register ``func`` as heuristic ``name`` for problems of ``kind``."""

    def wrap(func: Callable[..., Solution]) -> Callable[..., Solution]:
        METHODS.setdefault(kind, {})[name] = func
        return func

    return wrap


def problem_kind(problem: Any) -> str:
    from taopt.routing.problem import AssignmentProblem

    if isinstance(problem, AssignmentProblem):
        return "routing"
    from taopt.delivery.instance import DeliveryInstance

    if isinstance(problem, DeliveryInstance):
        return "delivery"
    raise InstanceError(f"no heuristics for problems of type {type(problem).__name__}")


def run(name: str, problem: Any, seed: int = 0, **options: Any) -> Solution:
    """Run heuristic ``name`` on ``problem``; the result is scored by ``taopt.evaluate``."""
    kind = problem_kind(problem)
    methods = METHODS.get(kind, {})
    if name not in methods:
        raise InstanceError(f"unknown {kind} heuristic {name!r}; choose from {sorted(methods)}")
    return methods[name](problem, seed=seed, **options)
