"""The sequential ordering family's spec (TSPLIB SOP, used to certify chapter 5's exact core).

:class:`~taopt.SopProblem` (payload :class:`~taopt.result.Order`, scorer
:func:`~taopt.sop.problem.evaluate_order`), its bounds and the order plot.
"""

from __future__ import annotations

from typing import Any

from taopt.registry import Bound, Family, register_family
from taopt.result import Order
from taopt.sop.bounds import sop_lower
from taopt.sop.problem import SopProblem, evaluate_order, sop_arborescence_bound


def _plot_order(problem: SopProblem, order: Order, path: str, method: str = "", **_: Any) -> None:
    """The order as a position/cost chart with the precedence arcs."""
    from taopt.delivery.plot import plot_order

    plot_order(problem, order, method=method, path=path)


FAMILY = register_family(
    Family(
        problem_type=SopProblem,
        kind="sop_problem",
        payload=Order,
        title="sequential ordering, TSPLIB SOP (chapter 5 certification)",
        evaluate=evaluate_order,
        bounds={"arborescence": Bound(sop_arborescence_bound), "lower": Bound(sop_lower)},
        plots={"order": _plot_order},
        describe=lambda problem, order, instance=None: [
            "  order: " + " -> ".join(str(v) for v in order.sequence)
        ],
    )
)
