"""Plots of a chapter 5 plan: the map (thesis Figs. 5.6–5.7) and a Gantt chart.

Both take an optional matplotlib ``ax``, return it, and work with the Agg backend
(``ax.figure.savefig("plan.png")``).
"""

from __future__ import annotations

from typing import Any

import networkx as nx
import numpy as np

from taopt.delivery.evaluate import timeline
from taopt.delivery.instance import DeliveryInstance, Plan


def _plan_of(plan: Any) -> Plan:
    return plan.plan if hasattr(plan, "plan") and hasattr(plan, "objective") else plan


def _new_ax(ax: Any, figsize: tuple[float, float]) -> Any:
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=figsize)
    return ax


def plot_plan(
    instance: DeliveryInstance, plan: Any, ax: Any = None, label_customers: bool = True
) -> Any:
    """Street network, truck path and drone sorties of a plan (Fig. 5.6 style).

    Streets are grey, stops small dots, the depot a black square. The truck path
    (street shortest paths between consecutive launch/landing stops) is a thick blue
    line; each sortie is a dashed orange launch -> customer -> landing polyline.
    Customers are red dots labelled with their index and serving position.

    Parameters
    ----------
    instance : DeliveryInstance
    plan : Plan or Solution
    ax : matplotlib Axes, optional

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
    if label_customers:
        position = {j: p for p, j in enumerate(plan.order)}
        for j, (x, y) in enumerate(customers):
            tag = f"{j}" if j not in position else f"{j} ({position[j] + 1})"
            ax.annotate(tag, (x, y), xytext=(3, 3), textcoords="offset points", fontsize=7)
    ax.scatter(*stops[instance.depot], marker="s", s=80, color="black", zorder=6, label="depot")
    ax.set_aspect("equal")
    ax.set_title(
        f"{instance.name or 'plan'}: makespan {line.makespan:.1f} s, L = {instance.flight_range:g}"
    )
    ax.legend(loc="best", fontsize=8)
    return ax


def plot_gantt(instance: DeliveryInstance, plan: Any, ax: Any = None) -> Any:
    """Truck and drone timelines of a plan.

    Truck row: repositioning with the drone aboard (blue), carrying legs while the
    drone is out (light blue), waiting for the drone (grey). Drone row: flights (orange),
    landing time τ at the customer and on the truck (red), waiting at the landing stop
    (grey); customer indices are written at their service times t_j.

    Returns
    -------
    matplotlib Axes
    """
    plan = _plan_of(plan)
    line = timeline(instance, plan)
    tau = instance.service_time
    ax = _new_ax(ax, (10, 2.8))
    truck_y, drone_y, h = 1.0, 0.0, 0.6

    def bar(y: float, start: float, end: float, color: str) -> None:
        if end > start:
            ax.broken_barh([(start, end - start)], (y - h / 2, h), facecolors=color)

    for _from, _to, depart, arrive, kind in line.truck_legs:
        bar(truck_y, depart, arrive, "tab:blue" if kind == "reposition" else "lightsteelblue")
    for p, j in enumerate(plan.order):
        S, t, back = line.launch_time[p], line.service_time[p], line.drone_return[p]
        truck, R = line.truck_arrival[p], line.recovery_time[p]
        bar(truck_y, truck, R - tau, "0.75")
        bar(drone_y, S, t - tau, "tab:orange")
        bar(drone_y, t - tau, t, "tab:red")
        bar(drone_y, t, back, "tab:orange")
        bar(drone_y, back, R - tau, "0.75")
        bar(drone_y, R - tau, R, "tab:red")
        ax.annotate(str(j), (t, drone_y + h / 2), ha="center", va="bottom", fontsize=7)
    ax.axvline(line.makespan, color="k", ls=":", lw=1)
    ax.set_yticks([drone_y, truck_y], ["drone", "truck"])
    ax.set_ylim(-0.6, 1.9)
    ax.set_xlabel("time (s)")
    ax.set_title(f"makespan (5.1) = {line.makespan:.1f} s")
    from matplotlib.patches import Patch

    legend = [
        Patch(color="tab:blue", label="truck drives, drone aboard"),
        Patch(color="lightsteelblue", label="truck drives, drone out"),
        Patch(color="0.75", label="waiting"),
        Patch(color="tab:orange", label="drone flies"),
        Patch(color="tab:red", label="landing time τ"),
    ]
    ax.legend(handles=legend, loc="upper center", ncol=5, fontsize=7, frameon=False)
    ax.figure.tight_layout()
    return ax


__all__ = ["plot_plan", "plot_gantt"]
