"""Plots of chapter 5: a plan's map (thesis Figs. 5.6–5.7), its Gantt chart, an SOP order.

Each takes an optional matplotlib ``ax``, returns it, and works with the Agg backend
(``ax.figure.savefig("plan.png", bbox_inches="tight")``: the legends sit outside the axes).
"""

from __future__ import annotations

from typing import Any

import networkx as nx
import numpy as np

from taopt.delivery.evaluate import timeline
from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.plot import _axes, label_points, legend_outside, place_labels


def _plan_of(plan: Any) -> Plan:
    return plan.plan if hasattr(plan, "plan") and hasattr(plan, "objective") else plan


def _new_ax(ax: Any, figsize: tuple[float, float]) -> Any:
    return _axes(ax, figsize)


def plot_plan(
    instance: DeliveryInstance,
    plan: Any,
    ax: Any = None,
    label_customers: bool = True,
    method: str = "",
) -> Any:
    """Street network, truck path and drone sorties of a plan (Fig. 5.6 style).

    Streets are grey, stops small dots, the depot a black square. The truck path
    (street shortest paths between consecutive launch/landing stops) is a thick blue
    line; each sortie is a dashed orange launch -> customer -> landing polyline.
    Customers are red dots labelled ``j (#p)``: their index j in the file and the plan
    (``Plan.order``) and their sortie number p (1 = first served). The launch and landing
    stops the plan uses are labelled ``s<i>`` (``Plan.launch``, ``Plan.landing``).

    Parameters
    ----------
    instance : DeliveryInstance
        Positions in metres.
    plan : Plan or Solution
    ax : matplotlib Axes, optional
    method : str
        Named in the title.

    Returns
    -------
    matplotlib Axes
    """
    plan = _plan_of(plan)
    line = timeline(instance, plan)
    ax = _new_ax(ax, (7, 7))
    stops, customers = instance.stops, instance.customers
    for u, v in instance.graph.edges:
        ax.plot(*stops[[u, v]].T, color="0.8", lw=1.0, zorder=1)
    ax.scatter(*stops.T, s=8, color="0.55", zorder=2)
    # truck path on the streets
    route: list[int] = [instance.depot]
    for a, b, *_ in line.truck_legs:
        if a != b:
            route += nx.shortest_path(instance.graph, a, b, weight="length")[1:]
    if len(route) > 1:
        ax.plot(*stops[route].T, color="tab:blue", lw=2.5, alpha=0.8, zorder=3, label="truck")
    # drone sorties
    for p, (j, i, k) in enumerate(zip(plan.order, plan.launch, plan.landing, strict=True)):
        pts = np.array([stops[i], customers[j], stops[k]])
        ax.plot(
            *pts.T, ls="--", color="tab:orange", lw=1.2, zorder=4, label="drone" if p == 0 else None
        )
    ax.scatter(*customers.T, s=30, color="tab:red", zorder=5, label="customer")
    ax.scatter(*stops[instance.depot], marker="s", s=80, color="black", zorder=6, label="depot")
    ax.plot([], [], " ", label="labels: customer j (#sortie),\nstop s<i>")
    ax.set_aspect("equal")
    if label_customers:
        position = {j: p for p, j in enumerate(plan.order)}
        tags = [
            f"{j}" if j not in position else f"{j} (#{position[j] + 1})"
            for j in range(len(customers))
        ]
        used = sorted(set(plan.launch) | set(plan.landing) | {instance.depot})
        crowded = len(customers) > 12  # smaller type on a crowded map
        # labels over the lines, on a light patch that keeps them legible
        patch = {"boxstyle": "square,pad=0.05", "facecolor": "white", "alpha": 0.6, "lw": 0}
        place_labels(
            ax,
            [
                (
                    customers,
                    tags,
                    {"fontsize": 6.5 if crowded else 7, "color": "darkred", "bbox": patch},
                ),
                (
                    stops[used],
                    [f"s{i}" for i in used],
                    {"fontsize": 5.5 if crowded else 6, "color": "navy", "bbox": patch},
                ),
            ],
            avoid=stops,
            distance=4.5,
        )
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    who = f"{method} plan" if method else "plan"
    ax.set_title(
        f"{instance.name or 'delivery'}: {who}, makespan (5.1) {line.makespan:.1f} s, "
        f"L = {instance.flight_range:g} m",
        fontsize=10,
    )
    legend_outside(ax)
    return ax


def plot_gantt(instance: DeliveryInstance, plan: Any, ax: Any = None, method: str = "") -> Any:
    """Truck and drone timelines of a plan.

    Truck row: repositioning with the drone aboard (blue), carrying legs while the
    drone is out (light blue), waiting for the drone (grey). Drone row: one bar per
    sortie p, from its launch S_p to its recovery R_p (the drone back aboard), with two
    ticks: the landing at the customer, ending at its service time t_j (red), and the
    landing on the truck, ending at R_p (black); each landing takes τ. Customer indices
    are written above their ticks t_j.

    The dotted line is the makespan (5.1), ``f = max_j t_j``: the time the last customer
    is served (chapter 5 minimises "the time when the last customer is served"). The
    last sortie's flight back to the truck and its landing τ come after it and are not
    part of f; they are drawn on a hatched background labelled so.

    Returns
    -------
    matplotlib Axes
        The drone row's bars are one collection with
        ``gid="drone sorties"`` (one rectangle per sortie); the landing ticks are the
        collections with ``gid="customer landings"`` and ``gid="truck landings"``.
    """
    plan = _plan_of(plan)
    line = timeline(instance, plan)
    ax = _new_ax(ax, (10, 2.8))
    truck_y, drone_y, h = 1.0, 0.0, 0.6

    def bar(y: float, start: float, end: float, color: str) -> None:
        if end > start:
            ax.broken_barh([(start, end - start)], (y - h / 2, h), facecolors=color)

    for _from, _to, depart, arrive, kind in line.truck_legs:
        bar(truck_y, depart, arrive, "tab:blue" if kind == "reposition" else "lightsteelblue")
    for p in range(len(plan.order)):
        # the truck waits at the landing stop for the drone, then while it lands (τ)
        bar(truck_y, line.truck_arrival[p], line.recovery_time[p], "0.75")
    sorties = [
        (float(S), float(R - S)) for S, R in zip(line.launch_time, line.recovery_time, strict=True)
    ]
    if sorties:
        # one rectangle per sortie, white edges so back-to-back sorties stay apart
        ax.broken_barh(
            sorties,
            (drone_y - h / 2, h),
            facecolors="tab:orange",
            edgecolors="white",
            linewidth=1.5,
            gid="drone sorties",
        )
        ticks = (drone_y - h / 2, drone_y + h / 2)
        ax.vlines(
            line.service_time, *ticks, colors="tab:red", linewidth=2.0, gid="customer landings"
        )
        ax.vlines(line.recovery_time, *ticks, colors="black", linewidth=1.2, gid="truck landings")
    for p, j in enumerate(plan.order):
        ax.annotate(
            str(j),
            (line.service_time[p], drone_y + h / 2),
            ha="center",
            va="bottom",
            fontsize=7,
            zorder=5,  # over the makespan line, on a white patch: a "1" is no dotted line
            bbox={"boxstyle": "square,pad=0.1", "facecolor": "white", "edgecolor": "none"},
        )
    end = max([line.makespan, *line.recovery_time]) if len(plan.order) else line.makespan
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    legend = [
        Patch(color="tab:blue", label="truck drives, drone aboard"),
        Patch(color="lightsteelblue", label="truck drives, drone out"),
        Patch(color="0.75", label="truck waits for the drone"),
        Patch(color="tab:orange", label="drone sortie: launch S_p to recovery R_p"),
        Line2D([], [], color="tab:red", lw=2.0, label="landing at customer j ends: t_j"),
        Line2D([], [], color="black", lw=1.2, label="landing on the truck ends: R_p"),
        Line2D([], [], color="k", ls=":", label="makespan (5.1): last customer served"),
    ]
    ax.axvline(line.makespan, color="k", ls=":", lw=1.2)
    ax.annotate(
        f"f = {line.makespan:.1f} s: last customer served",
        (line.makespan, 1.62),
        xytext=(-4, 0),
        textcoords="offset points",
        fontsize=7,
        ha="right",
        va="center",
    )
    if end > line.makespan:
        ax.axvspan(
            line.makespan, end, facecolor="none", edgecolor="0.6", hatch="//", lw=0, zorder=0
        )
        if end - line.makespan > 0.3 * end:  # room for the words inside the hatched part
            ax.annotate(
                "drone returns and lands:\nnot counted in f",
                (line.makespan, 1.62),
                xytext=(4, 0),
                textcoords="offset points",
                fontsize=7,
                va="center",
            )
        legend.append(
            Patch(
                facecolor="none",
                edgecolor="0.6",
                hatch="//",
                label="after the makespan: the drone flies back\nand lands, not part of (5.1)",
            )
        )
    ax.set_yticks([drone_y, truck_y], ["drone", "truck"])
    ax.set_ylim(-0.6, 1.9)
    ax.set_xlim(0.0, end * 1.02 if end > 0 else 1.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("vehicle")
    who = f"{method} plan" if method else "plan"
    ax.set_title(
        f"{instance.name or 'delivery'}: {who}, makespan (5.1) = {line.makespan:.1f} s "
        "(numbers: customer j at its service time t_j)",
        fontsize=9,
    )
    legend_outside(ax, handles=legend)
    return ax


def plot_order(
    problem: Any,
    order: Any,
    ax: Any = None,
    method: str = "",
    path: str | None = None,
) -> Any:
    """An SOP order as a position/cost chart with the precedence arcs.

    The k-th node of the order is drawn at (k, cumulative arc cost to reach it); the
    order's arcs join consecutive points (each labelled with its cost) and every
    precedence (r, j) of the problem is a dashed red arc from r to j above them. In a
    feasible order every precedence arc points right (r is visited first).

    Parameters
    ----------
    problem : SopProblem
    order : Order, Solution or sequence of int
    ax : matplotlib Axes, optional
    method : str
        Named in the title.
    path : str, optional
        Save as PNG.

    Returns
    -------
    matplotlib Axes
    """
    sequence = list(getattr(getattr(order, "solution", order), "sequence", order))
    cost = np.asarray(problem.cost, dtype=float)
    legs = cost[sequence[:-1], sequence[1:]] if len(sequence) > 1 else np.zeros(0)
    reach = np.concatenate([[0.0], np.cumsum(legs)])
    xy = np.column_stack([np.arange(len(sequence)), reach])
    where = {node: k for k, node in enumerate(sequence)}
    ax = _new_ax(ax, (max(6.0, 0.45 * len(sequence) + 3.0), 4.5))
    ax.plot(
        xy[:, 0],
        xy[:, 1],
        "-",
        color="tab:blue",
        lw=1.8,
        marker="o",
        ms=6,
        zorder=3,
        label="visiting order (arc cost on each step)",
    )
    if len(sequence) <= 40:
        for k, c in enumerate(legs):
            ax.annotate(
                f"{c:g}",
                (xy[k] + xy[k + 1]) / 2,
                xytext=(4, -8),
                textcoords="offset points",
                fontsize=7,
                color="tab:blue",
            )
    for r, j in problem.precedences:
        if r in where and j in where:
            ax.annotate(
                "",
                xy=xy[where[j]],
                xytext=xy[where[r]],
                arrowprops={
                    "arrowstyle": "-|>",
                    "color": "tab:red",
                    "lw": 1.0,
                    "linestyle": "--",
                    "connectionstyle": "arc3,rad=-0.35",
                    "shrinkA": 5,
                    "shrinkB": 5,
                    "alpha": 0.7,
                },
                zorder=2,
            )
    ax.plot([], [], "--", color="tab:red", label="precedence r -> j (r first)")
    label_points(
        xy,
        [str(node) for node in sequence],
        ax,
        offset=(-4, 6),
        fontsize=8,
        fontweight="bold",
        ha="right",
    )
    ax.set_xlabel("position in the order (visit number, 0 = start)")
    ax.set_ylabel("cumulative cost (cost units of the file)")
    ax.set_xlim(-0.6, len(sequence) - 0.4)
    ax.margins(y=0.12)
    ax.grid(alpha=0.3)
    who = f"{method} order" if method else "order"
    ax.set_title(
        f"{problem.name or 'SOP'}: {who}, path cost {reach[-1]:g} (labels: node ids)",
        fontsize=10,
    )
    legend_outside(ax, "below", ncol=2)
    if path:
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    return ax


__all__ = ["plot_plan", "plot_gantt", "plot_order"]
