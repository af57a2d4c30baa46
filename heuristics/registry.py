"""``taopt.heuristics.run``: run a registered heuristic by name (a thin look-up).

Heuristics register themselves with :func:`taopt.registry.register_method` where they are
defined; :func:`taopt.solve` is the one entry point for every method. :func:`run` is kept
for scripts written before it: it looks the heuristic up in the same registry.
"""

from __future__ import annotations

from typing import Any

from taopt.registry import get_method
from taopt.result import Solution


def run(name: str, problem: Any, seed: int = 0, **options: Any) -> Solution:
    """Run heuristic ``name`` on ``problem``; the result is scored by ``taopt.evaluate``.

    Raises
    ------
    InstanceError
        No method ``name`` is registered for this problem's type (the message lists them),
        or an option it does not take.
    """
    method = get_method(problem, name)
    method.check_options({"seed": seed, **options})
    return method.func(problem, seed=seed, **options)


__all__ = ["run"]
