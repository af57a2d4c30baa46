"""Chapter 4: task assignment under a limited communication range.

The family's spec is :mod:`taopt.comm.family`: :class:`CommProblem` (payload :class:`Trajectories`, scorer
:func:`evaluate_trajectories`, bound ``mst`` (Lemma 4.8)). The simulation engine is
:mod:`taopt.comm.engine`; the algorithms CAA, DAA and HDA are its policies in
:mod:`taopt.heuristics.comm` (``taopt.solve(problem, "DAA", seed=0)``), the certified
optimum f_o is ``taopt.solve(problem, "exact")`` (:mod:`taopt.models.comm`).
"""

from taopt.comm import family as _family  # noqa: F401  (registers the family)
from taopt.comm.bounds import mst_bound
from taopt.comm.problem import CommProblem, random_problem
from taopt.comm.trajectories import Trajectories, evaluate_trajectories

__all__ = ["CommProblem", "Trajectories", "evaluate_trajectories", "mst_bound", "random_problem"]
