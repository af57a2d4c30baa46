"""Wall-clock budgets and cancellation: what a run may spend, and how it is told to stop.

**A time limit is wall-clock** (docs/architecture.md, invariant 4 and "the runtime
contract"). A :class:`Deadline` is taken when the call starts; the warm-start heuristics get
a share of it (:data:`WARM_START_SHARE`) and the method the *remaining* seconds, so warm
start, model building, separation and decoding all count. A method that runs out returns its
best plan with a proven bound and status "time_limit" (objective ``inf`` and no payload when
it found no plan): never an exception. The promise holds on a loaded machine too: a call
with ``time_limit=T`` returns within ``T + overrun_allowance(T)`` = ``T + max(1 s, 5 % of
T)`` (:func:`overrun_allowance`), so every step that does not look at the clock itself is
either short or estimated from a measured step of the same call (the delivery MILP's compile
and presolve), heuristics look at their deadline inside their local searches, and a peer's
worker (its start-up and import included) is stopped at the deadline plus a grace with the
best solution it reported (``benchmarks/bench_time_limits.py`` measures every method under a
load it creates).

**Cancellation** is a :class:`CancelToken`: whoever owns the run (a study, a thread, a user's
callback) calls :meth:`CancelToken.cancel`; a :class:`Deadline` that carries the token then
reads as expired, so every loop that looks at its deadline (and a HiGHS run through
:func:`taopt.runtime.highs.interrupt_when`) stops at its next check and returns its best
answer, with :attr:`Deadline.reason` "interrupted" instead of "time_limit". A deadline made
without a token takes the one of the innermost :func:`cancel_scope` (if any), so a token set
around :func:`taopt.solve` reaches every method without a new keyword.

Example
-------
>>> d = Deadline(10.0)
>>> 9.0 < d.remaining() <= 10.0, Deadline(None).remaining() is None
(True, True)
>>> token = CancelToken()
>>> with cancel_scope(token):
...     d = Deadline(None)
>>> token.cancel()
>>> d.expired(), d.reason
(True, 'interrupted')
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import threading
import time
from collections.abc import Iterator

#: Share of a time limit the warm-start heuristics of an exact method may use.
WARM_START_SHARE = 0.25

#: Seconds a method keeps in hand for what follows its last check (decoding, scoring).
MARGIN = 0.05

#: The least budget :meth:`Deadline.share` hands out (seconds).
MIN_SHARE = 1e-3


def overrun_allowance(seconds: float) -> float:
    """The most a call with ``time_limit=seconds`` may run past it: max(1 s, 5 %).

    Example
    -------
    >>> overrun_allowance(0.5), overrun_allowance(60.0)
    (1.0, 3.0)
    """
    return max(1.0, 0.05 * float(seconds))


class CancelToken:
    """A flag one party sets and the running method reads at its loop heads (thread-safe).

    Parameters
    ----------
    parent : CancelToken, optional
        A token this one follows: cancelling the parent cancels this one, not the reverse.

    Example
    -------
    >>> token = CancelToken()
    >>> token.cancelled, token.cancel(), token.cancelled
    (False, None, True)
    >>> run = CancelToken()
    >>> part = CancelToken(parent=run)
    >>> run.cancel(); part.cancelled
    True
    """

    def __init__(self, parent: CancelToken | None = None) -> None:
        self._event = threading.Event()
        self.parent = parent

    def cancel(self) -> None:
        """Ask the run to stop (idempotent); the parent, if any, is not touched."""
        self._event.set()

    @property
    def cancelled(self) -> bool:
        """Whether :meth:`cancel` was called on this token or on its parent (a child token
        stops a part of a run, e.g. one side of a race, and also stops with the whole run)."""
        return self._event.is_set() or (self.parent is not None and self.parent.cancelled)

    def wait(self, timeout: float | None = None) -> bool:
        """Block until cancelled or ``timeout`` seconds passed; whether it was cancelled."""
        if self.parent is None:
            return self._event.wait(timeout)
        end = None if timeout is None else time.monotonic() + timeout
        while not self.cancelled:  # the parent's event is not ours: look at it now and then
            left = 0.05 if end is None else min(0.05, end - time.monotonic())
            if left <= 0:
                return False
            self._event.wait(left)
        return True

    def __repr__(self) -> str:
        return f"CancelToken(cancelled={self.cancelled})"


_SCOPE: contextvars.ContextVar[CancelToken | None] = contextvars.ContextVar(
    "taopt_cancel_token", default=None
)


@contextlib.contextmanager
def cancel_scope(token: CancelToken) -> Iterator[CancelToken]:
    """Within the block, a :class:`Deadline` made without a token carries ``token``."""
    reset = _SCOPE.set(token)
    try:
        yield token
    finally:
        _SCOPE.reset(reset)


def current_token() -> CancelToken | None:
    """The token of the innermost :func:`cancel_scope`, or None."""
    return _SCOPE.get()


class Deadline:
    """A wall-clock budget taken at construction, and the run's cancel token.

    Parameters
    ----------
    seconds : float or None
        The budget; None means no limit (``remaining()`` and ``share()`` answer None).
    cancel : CancelToken, optional
        Stops the run early: :meth:`expired` is true once it is cancelled. Default: the
        token of the innermost :func:`cancel_scope`, if any.
    """

    def __init__(self, seconds: float | None, cancel: CancelToken | None = None) -> None:
        self.began = time.perf_counter()
        self.seconds = None if seconds is None else float(seconds)
        self.end = math.inf if seconds is None else self.began + float(seconds)
        self.token = cancel if cancel is not None else current_token()

    @property
    def limited(self) -> bool:
        """Whether the run is limited: by a time limit, or by a cancellation already asked
        for (then :meth:`remaining` is 0 and :meth:`expired` true), so that a loop head's
        ``deadline.limited and deadline.expired()`` stops on either."""
        return self.seconds is not None or self.cancelled

    @property
    def cancelled(self) -> bool:
        """Whether the run's cancel token was set."""
        return self.token is not None and self.token.cancelled

    @property
    def reason(self) -> str:
        """The stop to report once :meth:`expired`: "interrupted" (cancelled) or
        "time_limit" (``taopt.status.decide``'s words)."""
        return "interrupted" if self.cancelled else "time_limit"

    def elapsed(self) -> float:
        """Seconds since the deadline was taken."""
        return time.perf_counter() - self.began

    def remaining(self) -> float | None:
        """Seconds left (never below 0; 0 once cancelled), or None without a limit."""
        if self.cancelled:
            return 0.0
        if self.seconds is None:
            return None
        return max(0.0, self.end - time.perf_counter())

    def expired(self, margin: float = 0.0) -> bool:
        """Whether fewer than ``margin`` seconds are left, or the run was cancelled."""
        return self.cancelled or time.perf_counter() + margin >= self.end

    def share(self, fraction: float) -> float | None:
        """``fraction`` of the remaining seconds, at least :data:`MIN_SHARE` (None without a
        limit): a stage started once the time is spent gets the least positive limit, which
        every solver here accepts and stops on at once (a limit of 0 is refused as bad
        input, and a time-limited run must end with a status, never an exception)."""
        left = self.remaining()
        return None if left is None else max(left * fraction, MIN_SHARE)

    def __repr__(self) -> str:
        return f"Deadline({self.seconds!r}, remaining={self.remaining()!r})"


__all__ = [
    "WARM_START_SHARE",
    "MARGIN",
    "MIN_SHARE",
    "overrun_allowance",
    "CancelToken",
    "cancel_scope",
    "current_token",
    "Deadline",
]
