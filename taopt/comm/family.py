"""The chapter-4 family's spec: task assignment under a limited communication range.

:class:`~taopt.CommProblem` (payload :class:`~taopt.comm.trajectories.Trajectories`, scorer
:func:`~taopt.comm.trajectories.evaluate_trajectories`), Lemma 4.8's MST bound, the plot of
the driven trajectories and the §4.4 study (``taopt study comm``).
"""

from __future__ import annotations

from taopt.comm.bounds import comm_lower, mst_bound
from taopt.comm.problem import CommProblem
from taopt.comm.trajectories import Trajectories, evaluate_trajectories
from taopt.registry import Bound, Family, Study, register_family


def _plot_run(
    problem: CommProblem, trajectories: Trajectories, path: str, method: str = "", **_: object
) -> None:
    """The driven trajectories, targets and start points (as ``taopt simulate --plot``)."""
    from taopt.comm.plot import plot_run

    plot_run(problem, trajectories, path=path, method=method)


FAMILY = register_family(
    Family(
        problem_type=CommProblem,
        kind="comm_problem",
        payload=Trajectories,
        title="task assignment under a limited communication range (chapter 4)",
        evaluate=evaluate_trajectories,
        bounds={"mst": Bound(mst_bound), "lower": Bound(comm_lower)},
        plots={"run": _plot_run},
        studies=(Study("comm", "taopt.orchestration.studies.comm"),),
        exports={"Trajectories": Trajectories},
    )
)
