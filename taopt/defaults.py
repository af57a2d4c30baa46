"""The defaults shared by the Python API and the command line (one place for each).

``taopt.solve``, :func:`taopt.orchestration.solving.solve_file`, every study function and
every ``taopt`` command take their default seed and time limit from here, so a call from
Python and the same command give the same rows.

This module imports nothing (``import taopt`` and ``taopt --help`` stay light).
"""

from __future__ import annotations

#: Seed of randomised methods (``--seed``; ``taopt.solve(seed=...)``; every study's seed).
SEED = 0

#: Wall-clock seconds of one method run (``--time-limit``; ``taopt.solve(time_limit=...)``):
#: a ceiling, which exact models and peers may reach and fast heuristics never do.
TIME_LIMIT = 60.0

__all__ = ["SEED", "TIME_LIMIT"]
