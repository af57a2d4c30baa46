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
