"""Chapter 4: task assignment under a limited communication range.

Registers the family :class:`CommProblem` (payload :class:`Trajectories`, scorer
:func:`evaluate_trajectories`, bound ``mst`` (Lemma 4.8)). The simulation engine is
:mod:`taopt.comm.engine`; the algorithms CAA, DAA and HDA are its policies in
:mod:`taopt.heuristics.comm` (``taopt.solve(problem, "DAA", seed=0)``), the certified
optimum f_o is ``taopt.solve(problem, "exact")`` (:mod:`taopt.models.comm`).
"""

from taopt.bounds import comm_lower
from taopt.comm.bounds import mst_bound
from taopt.comm.problem import CommProblem, random_problem
from taopt.comm.trajectories import Trajectories, evaluate_trajectories
from taopt.registry import register_family


def _plot_run(
    problem: CommProblem, trajectories: Trajectories, path: str, method: str = "", **_: object
) -> None:
    """The driven trajectories, targets and start points (as ``taopt simulate --plot``)."""
    from taopt.comm.plot import plot_run

    plot_run(problem, trajectories, path=path, method=method)


register_family(
    CommProblem,
    kind="comm_problem",
    payload=Trajectories,
    title="task assignment under a limited communication range (chapter 4)",
    evaluate=evaluate_trajectories,
    bounds={"mst": mst_bound, "lower": comm_lower},
    plots={"run": _plot_run},
)

__all__ = ["CommProblem", "Trajectories", "evaluate_trajectories", "mst_bound", "random_problem"]
