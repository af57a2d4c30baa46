"""Moved to :mod:`taopt.sop.problem` (temporary re-export)."""

from taopt.sop.problem import *  # noqa: F401,F403
from taopt.sop.problem import KNOWN_OPTIMA, SopProblem, sop_arborescence_bound  # noqa: F401
