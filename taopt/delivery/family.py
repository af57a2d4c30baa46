"""The chapter-5 family's spec: precedence-constrained truck–drone delivery.

:class:`~taopt.DeliveryInstance` (payload :class:`~taopt.delivery.instance.Plan`, scorer
:func:`~taopt.delivery.evaluate.evaluate_plan`), Proposition 5.3's bound and the stronger
``lower``, the plan and Gantt plots, and the §5.5 study (``taopt study delivery``).
"""

from __future__ import annotations

from typing import Any

from taopt.delivery.bounds import arborescence_bound, delivery_lower
from taopt.delivery.evaluate import evaluate_plan
from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.registry import Bound, Family, Study, register_family


def _plot_plan(
    problem: DeliveryInstance, plan: Plan, path: str, method: str = "", **_: Any
) -> None:
    """The truck path and drone sorties on the street network."""
    from taopt.delivery.plot import plot_plan

    plot_plan(problem, plan, method=method).figure.savefig(path, dpi=120, bbox_inches="tight")


def _plot_gantt(
    problem: DeliveryInstance, plan: Plan, path: str, method: str = "", **_: Any
) -> None:
    """The truck's and the drone's timelines (Gantt chart)."""
    from taopt.delivery.plot import plot_gantt

    plot_gantt(problem, plan, method=method).figure.savefig(path, dpi=120, bbox_inches="tight")


def _plan_lines(instance: DeliveryInstance, plan: Plan, file: Any = None) -> list[str]:
    """One ``"  #p: customer j, launch s<i>, landing s<k>"`` line per sortie."""
    sorties = zip(plan.order, plan.launch, plan.landing, strict=True)
    return [
        f"  #{p + 1}: customer {j}, launch s{i}, landing s{k}"
        for p, (j, i, k) in enumerate(sorties)
    ]


FAMILY = register_family(
    Family(
        problem_type=DeliveryInstance,
        kind="delivery_instance",
        payload=Plan,
        title="precedence-constrained truck-drone delivery (chapter 5)",
        evaluate=evaluate_plan,
        bounds={"arborescence": Bound(arborescence_bound), "lower": Bound(delivery_lower)},
        plots={"plan": _plot_plan, "gantt": _plot_gantt},
        describe=_plan_lines,
        studies=(Study("delivery", "taopt.orchestration.studies.delivery"),),
        exports={"Plan": Plan},
    )
)

# the fixed-order schedule DP (the scorer of every ordering heuristic); imported with the family so
# it is known before any method look-up (taopt solve, taopt verify --exact)
from taopt.delivery import schedule as _schedule  # noqa: E402, F401
