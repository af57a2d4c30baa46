"""Stand-ins for a worker's task in the worker-process tests (tests/capability/test_capability_models.py):
module-level functions, so that a spawned worker (which inherits ``sys.path``) can import them.

They replace ``taopt.models.capability._solve_class`` to reach a state deterministically and at
once: a worker that dies mid-solve, or workers busy solving, without a hard instance and a timer.
"""

from __future__ import annotations

import os
import signal
import time
from typing import Any


def worker_state() -> tuple[int, object, str | None]:
    """In a worker: its pid, its SIGINT handler and its solver threads (``OMP_NUM_THREADS``)."""
    return os.getpid(), signal.getsignal(signal.SIGINT), os.environ.get("OMP_NUM_THREADS")


def die(*args: Any) -> None:
    """The worker is killed (SIGKILL) in the middle of its task."""
    os.kill(os.getpid(), signal.SIGKILL)


def busy(*args: Any) -> None:
    """The worker works on its task for ten minutes (until it is killed)."""
    time.sleep(600)
