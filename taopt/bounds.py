"""Bounds, each saying whether it is valid (docs/architecture.md, invariant 3), from the specs.

Each family declares its bounds in its spec (:class:`taopt.registry.Family`, ``bounds``):
a name, the function, whether it is valid (proven) or kept "as printed" by the thesis, and
whether it is a lower or an upper bound. This module knows no bound name of its own:

* :func:`bound` — any declared bound by name: ``bound(problem, "arborescence")``;
* :func:`lower` — the family's strongest valid lower bound at a chosen cost (``strength``):
  the one to quote a gap against;
* :func:`valid_lower_bounds` — every valid lower bound the family declares, by name.

The names families declare are also attributes of this module
(``taopt.bounds.arborescence(problem)``, ``taopt.bounds.thesis_mcga(problem)``, ...).
Today's families declare, for example, ``arborescence`` (valid: Edmonds' min-cost
arborescence, per family), ``thesis_mcga`` (the thesis's Algorithm 1 as printed: NOT a valid
bound on asymmetric matrices), ``doubled_arborescence`` (Lemma 3.6's f^da, an upper bound)
and ``mst`` (Lemma 4.8, chapter 4); :func:`bound_names` lists what is registered.
"""

from __future__ import annotations

from typing import Any

from taopt.errors import InstanceError

#: Accepted values of ``strength`` in :func:`lower`.
STRENGTHS = ("fast", "auto", "strong")


def _declared(problem: Any) -> dict[str, Any]:
    from taopt.registry import family_of

    return dict(family_of(problem).bounds)


def bound(problem: Any, name: str) -> float:
    """The bound ``name`` the family of ``problem`` declares.

    Raises
    ------
    InstanceError
        The family declares no bound of that name (the message lists those it has).

    Example
    -------
    >>> import numpy as np, taopt
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]]), n_targets=2)
    >>> bound(p, "arborescence")
    4.0
    """
    declared = _declared(problem)
    if name not in declared:
        raise InstanceError(
            f"{type(problem).__name__} declares no bound {name!r}; it has {sorted(declared)}"
        )
    return float(declared[name].func(problem))


def valid_lower_bounds(problem: Any) -> dict[str, float]:
    """Every valid lower bound the family of ``problem`` declares, evaluated (``lower`` at
    its default strength included when declared)."""
    return {
        name: (float(b.func(problem, "auto")) if name == "lower" else float(b.func(problem)))
        for name, b in _declared(problem).items()
        if b.valid and b.side == "lower"
    }


def lower(problem: Any, strength: str = "auto") -> float:
    """The strongest valid lower bound on the optimum of ``problem`` at a given cost.

    Parameters
    ----------
    problem : a registered problem (AssignmentProblem, DeliveryInstance, ...)
    strength : {"fast", "auto", "strong"}
        "fast": the family's Edmonds/MST bound (milliseconds). "auto" (default): the
        strongest bound that takes seconds at the thesis's sizes. "strong": also the
        family's LP relaxations (e.g. chapter 2's DFJ LP,
        :func:`taopt.routing.bounds.lp_bound`) — may take minutes. Every value comes from
        the family's spec alone, so a call gives the same answer whatever was imported
        before it.

    Returns
    -------
    float
        A valid lower bound (never above the optimum), always >= the "fast" bound.

    Raises
    ------
    InstanceError
        Unknown problem type or strength.

    Notes
    -----
    The family's ``"lower"`` bound (its spec) is called as ``func(problem, strength)``; a
    family without one gets the largest of its valid lower bounds. Which bound each family
    gets is in its own bounds module (e.g. :func:`taopt.routing.bounds.routing_lower`).

    Example
    -------
    >>> import taopt
    >>> inst = taopt.DeliveryInstance.grid([[0, 100], [100, 100]], 2, 100, 10.0, 5.0, 150)
    >>> lower(inst) >= bound(inst, "arborescence")
    True

    References
    ----------
    Thesis Prop. 5.3 (§5.3.2), §2.4.3, Lemma 4.8; Held and Karp (1970).
    """
    if strength not in STRENGTHS:
        raise InstanceError(f"strength must be one of {STRENGTHS}, got {strength!r}")
    declared = _declared(problem)
    if "lower" in declared:
        value = float(declared["lower"].func(problem, strength))
    else:
        values = [
            float(b.func(problem)) for b in declared.values() if b.valid and b.side == "lower"
        ]
        if not values:
            raise InstanceError(f"{type(problem).__name__} declares no valid lower bound")
        value = max(values)
    return value


def bound_names() -> list[str]:
    """Every bound name some registered family declares."""
    from taopt.registry import families

    return sorted({name for family in families() for name in family.bounds})


def _by_name(name: str) -> Any:
    def named(problem: Any) -> float:
        return bound(problem, name)

    named.__name__ = named.__qualname__ = name
    named.__doc__ = f"The bound {name!r} of the problem's family (see :func:`bound`)."
    return named


def __getattr__(name: str) -> Any:
    """``taopt.bounds.<name>``: the bound ``name`` of any family that declares one."""
    if name.startswith("_") or name not in bound_names():
        raise AttributeError(f"module 'taopt.bounds' has no attribute {name!r}")
    return _by_name(name)


__all__ = ["bound", "lower", "valid_lower_bounds", "bound_names", "STRENGTHS"]
