"""The runtime: deadlines, cancellation, size guards, Ctrl-C, worker processes, HiGHS hooks.

One home for everything about *how* a run is run rather than *what* it computes
(docs/architecture.md, "the runtime contract"):

* :mod:`taopt.runtime.deadline` — :class:`Deadline` (a wall-clock budget), :class:`CancelToken`
  and :func:`cancel_scope`, :func:`overrun_allowance`;
* :mod:`taopt.runtime.memory` — the size guard (:func:`check_memory`, :func:`register_footprint`);
* :mod:`taopt.runtime.interrupt` — SIGINT and other signals: install and restore handlers,
  the "a solver was interrupted / a run was abandoned" state and the ``os._exit(130)`` path;
* :mod:`taopt.runtime.workers` — worker processes: :class:`~taopt.runtime.workers.WorkerPool`
  (spawned, Ctrl-C ignored, dying with their parent, terminated at once on request) and the
  set-up every worker runs (:func:`~taopt.runtime.workers.become_worker`);
* :mod:`taopt.runtime.highs` — HiGHS's interrupt callbacks (Ctrl-C and deadlines), its quiet
  start (standard output discarded, C buffers flushed).

This package is core: it imports no ``taopt.models`` or ``taopt.heuristics`` module. The
names of the first two modules are re-exported here (standard library only); the others are
imported as submodules (``highs`` imports highspy).
"""

from __future__ import annotations

from taopt.runtime.deadline import (
    MARGIN,
    MIN_SHARE,
    WARM_START_SHARE,
    CancelToken,
    Deadline,
    cancel_scope,
    current_token,
    overrun_allowance,
)
from taopt.runtime.memory import (
    DEFAULT_MAX_MEMORY_GB,
    MEMORY_ENV,
    check_footprint,
    check_memory,
    footprint,
    max_memory_gb,
    milp_bytes,
    navigation_bytes,
    register_footprint,
)

__all__ = [
    "MARGIN",
    "MIN_SHARE",
    "WARM_START_SHARE",
    "CancelToken",
    "Deadline",
    "cancel_scope",
    "current_token",
    "overrun_allowance",
    "DEFAULT_MAX_MEMORY_GB",
    "MEMORY_ENV",
    "check_footprint",
    "check_memory",
    "footprint",
    "max_memory_gb",
    "milp_bytes",
    "navigation_bytes",
    "register_footprint",
]
