"""Plots of the fleet family: the map of a plan and its Gantt chart (one row per vehicle).

:func:`plot_fleet_map` draws the street network, each truck's walk (street shortest paths
between consecutive stops of its sequence, one colour per truck) and each sortie (dashed, in
its drone's own shade of its truck's colour, :func:`drone_colour`, a marker per drone);
:func:`plot_fleet_gantt` draws one row per truck and per drone over time (truck: driving
bars; drone: one bar per sortie, from launch to recovery, with a tick at each customer
served); :func:`plot_fleet` puts both side by side (what
``taopt solve FILE --plot x.png`` writes). The times are the earliest schedule of
:func:`taopt.fleet.evaluate.schedule`. Each works with the Agg backend.
"""

from __future__ import annotations

from typing import Any

import networkx as nx
import numpy as np

from taopt.fleet.evaluate import as_plan, schedule
from taopt.fleet.problem import FleetProblem
from taopt.plot import legend_outside

#: One colour per truck (its drones get shades of it: :func:`drone_colour`).
COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")

#: One marker per drone of a truck.
MARKERS = ("^", "v", "<", ">", "P", "X")


def truck_colour(k: int) -> str:
    """Truck k's colour."""
    return COLOURS[k % len(COLOURS)]


def drone_colour(k: int, d: int, drones: int) -> tuple[float, float, float]:
    """Drone d of truck k (of ``drones`` on it): its own shade of truck k's colour, from
    darker (d = 0) to lighter, never the truck's own.

    Example
    -------
    >>> drone_colour(0, 0, 2) != drone_colour(0, 1, 2)
    True
    """
    from matplotlib.colors import to_rgb

    base = np.array(to_rgb(truck_colour(k)))
    # shades spread over [-0.45, +0.45]: < 0 mixes with black, > 0 with white; 0 is skipped
    # (the truck's colour), so one drone gets a darker shade
    t = -0.45 if drones <= 1 else -0.45 + 0.9 * d / (drones - 1)
    if abs(t) < 0.15:
        t = 0.15 if t >= 0 else -0.15
    mixed = base * (1 + t) if t < 0 else base + (1 - base) * t
    r, g, b = (float(x) for x in np.clip(mixed, 0.0, 1.0))
    return (r, g, b)


def _street_path(problem: FleetProblem, a: int, b: int) -> list[int]:
    if a == b:
        return [a]
    return list(nx.shortest_path(problem.graph, a, b, weight="length"))


def plot_fleet_map(problem: FleetProblem, plan: Any, ax: Any = None, method: str = "") -> Any:
    """Street network, truck walks and sorties of a fleet plan (positions in metres).

    Streets grey, stops small grey dots, the depot a black square, customers dots labelled
    with their index (red: served by a drone, black ring: by a truck). Truck k's walk is a
    thick line in colour k; each sortie of drone (k, d) is a dashed line in that drone's shade
    of colour k (:func:`drone_colour`; legend "truck k drone d") from its launch stop through
    its customers to its recovery stop, with drone marker d at the first customer.
    """
    import matplotlib.pyplot as plt

    plan = as_plan(plan)
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 7))
    stops, customers = problem.stops, problem.customers
    for u, v in problem.graph.edges:
        ax.plot(*stops[[u, v]].T, color="0.85", lw=1.0, zorder=1)
    ax.scatter(*stops.T, s=8, color="0.6", zorder=2)
    ax.scatter(*stops[problem.depot], s=90, marker="s", color="black", zorder=6, label="depot")
    by_truck = {j for items in plan.truck_service for _, j in items}
    for k, route in enumerate(plan.routes):
        colour = truck_colour(k)
        walk: list[int] = [route[0]]
        for a, b in zip(route[:-1], route[1:], strict=True):
            walk += _street_path(problem, a, b)[1:]
        if problem.objective == "return" and walk[-1] != problem.depot:
            walk += _street_path(problem, walk[-1], problem.depot)[1:]
        ax.plot(*stops[walk].T, color=colour, lw=3.0, alpha=0.7, zorder=3, label=f"truck {k}")
        for d, flights in enumerate(plan.sorties[k]):
            marker = MARKERS[d % len(MARKERS)]
            shade = drone_colour(k, d, problem.drones[k])
            for i, f in enumerate(flights):
                pts = np.vstack(
                    [stops[route[f.launch]], customers[list(f.customers)], stops[route[f.recovery]]]
                )
                ax.plot(
                    *pts.T,
                    color=shade,
                    ls="--",
                    lw=1.2,
                    zorder=4,
                    label=f"truck {k} drone {d}" if i == 0 else None,
                )
                ax.scatter(*customers[f.customers[0]], marker=marker, s=60, color=shade, zorder=5)
    drone_served = [j for j in range(problem.n) if j not in by_truck]
    ax.scatter(*customers[drone_served].T, s=22, color="red", zorder=6, label="customer (drone)")
    if by_truck:
        ax.scatter(
            *customers[sorted(by_truck)].T,
            s=50,
            facecolors="none",
            edgecolors="black",
            zorder=6,
            label="customer (truck)",
        )
    for j, (x, y) in enumerate(customers):
        ax.annotate(str(j), (x, y), textcoords="offset points", xytext=(3, 3), fontsize=7)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    value = schedule(problem, plan).objective
    title = f"{method}: " if method else ""
    ax.set_title(f"{title}{problem.objective} = {value:.1f} s")
    legend_outside(ax, "bottom")
    return ax


def plot_fleet_gantt(problem: FleetProblem, plan: Any, ax: Any = None, method: str = "") -> Any:
    """Gantt chart: one row per truck (driving bars, in the truck's colour) and per drone (one
    bar per sortie from launch to recovery in the drone's own shade, :func:`drone_colour`; a
    tick at each service); time in seconds."""
    import matplotlib.pyplot as plt

    plan = as_plan(plan)
    sched = schedule(problem, plan)
    rows = [f"truck {k}" for k in range(problem.K)] + [
        f"truck {k} drone {d}" for k, d in problem.drone_ids()
    ]
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 0.5 * len(rows) + 1.5))
    y_of = {name: len(rows) - 1 - i for i, name in enumerate(rows)}
    tt = problem.truck_time
    for k, route in enumerate(plan.routes):
        y = y_of[f"truck {k}"]
        colour = truck_colour(k)
        for p in range(len(route) - 1):
            start, end = sched.departure[k][p], sched.arrival[k][p + 1]
            if end > start:
                ax.barh(y, end - start, left=start, height=0.5, color=colour, alpha=0.8)
        if problem.objective == "return" and route[-1] != problem.depot:
            start = sched.departure[k][-1]
            ax.barh(
                y,
                float(tt[route[-1], problem.depot]),
                left=start,
                height=0.5,
                color=colour,
                alpha=0.4,
            )
        for _p, j in plan.truck_service[k]:
            ax.plot([sched.service[j]] * 2, [y - 0.3, y + 0.3], color="black", lw=1.5)
            ax.annotate(str(j), (sched.service[j], y + 0.3), fontsize=7, ha="center")
    for k, d, i, launch, _back, recovery in sched.sorties:
        y = y_of[f"truck {k} drone {d}"]
        ax.barh(
            y,
            recovery - launch,
            left=launch,
            height=0.5,
            color=drone_colour(k, d, problem.drones[k]),
            alpha=0.8,
            edgecolor="black",
            lw=0.5,
        )
        for j in plan.sorties[k][d][i].customers:
            ax.plot([sched.service[j]] * 2, [y - 0.3, y + 0.3], color="red", lw=1.5)
            ax.annotate(str(j), (sched.service[j], y + 0.3), fontsize=7, ha="center")
    ax.axvline(sched.objective, color="black", ls=":", lw=1)
    ax.set_yticks([y_of[r] for r in rows], rows)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("vehicle")
    title = f"{method}: " if method else ""
    ax.set_title(f"{title}bars: truck driving / drone sorties; ticks: services")
    return ax


def plot_fleet(problem: FleetProblem, plan: Any, method: str = "") -> Any:
    """The map and the Gantt chart side by side; returns the figure."""
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(
        1, 2, figsize=(15, 7.5), gridspec_kw={"width_ratios": [1.0, 1.2]}
    )
    plot_fleet_map(problem, plan, ax=left, method=method)
    plot_fleet_gantt(problem, plan, ax=right, method=method)
    fig.tight_layout()
    return fig


def save_fleet_plot(
    problem: FleetProblem, plan: Any, path: str, instance: Any = None, method: str = ""
) -> None:
    """``taopt solve --plot``: :func:`plot_fleet` written to ``path``."""
    import matplotlib.pyplot as plt

    fig = plot_fleet(problem, plan, method=method)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def save_fleet_gantt(
    problem: FleetProblem, plan: Any, path: str, instance: Any = None, method: str = ""
) -> None:
    """``taopt solve --gantt``: :func:`plot_fleet_gantt` written to ``path``."""
    import matplotlib.pyplot as plt

    ax = plot_fleet_gantt(problem, plan, method=method)
    ax.figure.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(ax.figure)


__all__ = [
    "drone_colour",
    "plot_fleet",
    "plot_fleet_gantt",
    "plot_fleet_map",
    "save_fleet_gantt",
    "save_fleet_plot",
    "truck_colour",
]
