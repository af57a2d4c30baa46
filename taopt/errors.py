"""One exception hierarchy for taopt.

Every error names the offending item (which target, which constraint, which
value) in a short message.
"""

from __future__ import annotations


class TaoptError(Exception):
    """Base class of every error taopt raises on purpose."""


class InstanceError(TaoptError, ValueError):
    """Problem data is invalid (raised on construction, before any solving)."""


class FeasibilityError(TaoptError, ValueError):
    """A solution violates a constraint; the message names the constraint and the item."""


class SolverError(TaoptError, RuntimeError):
    """A solver failed, or returned something that cannot be trusted."""


class ConvergenceError(SolverError):
    """An iterative method (collocation, shooting) did not converge."""


class OutputError(TaoptError, ValueError):
    """An output file cannot be written as asked (e.g. ``--plot x.jpg`` where PNG is drawn)."""


def require(value: object, expected: type, who: str, hint: str = "") -> None:
    """Raise :class:`InstanceError` unless ``value`` is an ``expected``.

    The one guard of the entry points that take one family's problem (``taopt.solve``
    picks the right one by registration; a direct call can still be handed another
    family's problem or a bare matrix). The message names the caller, the type it
    takes and the type it got, e.g. ``solve_routing needs a taopt.AssignmentProblem,
    got ndarray``; ``hint`` (optional) follows after a semicolon.

    Example
    -------
    >>> require([[0.0]], dict, "f")
    Traceback (most recent call last):
    ...
    taopt.errors.InstanceError: f needs a taopt.dict, got list
    """
    if not isinstance(value, expected):
        message = f"{who} needs a taopt.{expected.__name__}, got {type(value).__name__}"
        raise InstanceError(f"{message}; {hint}" if hint else message)
