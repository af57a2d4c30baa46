"""Plots for chapter 2: routes drawn in the drift field (or on a schematic layout).

Example
-------
>>> import numpy as np
>>> ax = plot_routes(np.array([[0, 0], [1, 1], [2, 0.0]]), [[0, 1]])  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.plot import LINESTYLES, _axes, label_points, legend_outside, plot_field

__all__ = ["plot_routes", "plot_instance_routes", "route_text", "routes_lines"]


def route_text(vehicle: str, route: Sequence[int], target_ids: Sequence[str]) -> str:
    """``"v0: v0 -> t3 -> t1"``: a route as ``taopt demo`` prints it (``"v0: v0 (no target)"``)."""
    text = f"{vehicle}: " + " -> ".join([vehicle, *(target_ids[t] for t in route)])
    return text if len(route) else f"{text} (no target)"


def routes_lines(problem: Any, routes: Any, instance: Any = None) -> list[str]:
    """One ``"  v0: v0 -> t2 -> t1"`` line per route, with the instance's ids (else ``t<k>``
    and ``v<j>``): the ``describe`` hook of every family whose payload is Routes."""
    routes = [list(r) for r in routes]
    if instance is not None:
        targets = [t.id for t in instance.targets]
        vehicles = [v.id for v in instance.vehicles]
    else:
        targets = [f"t{k}" for k in range(problem.n_targets)]
        vehicles = [f"v{k}" for k in range(len(routes))]
    return [f"  {route_text(vehicles[k], r, targets)}" for k, r in enumerate(routes)]


def plot_routes(
    points: Any,
    routes: Sequence[Sequence[int]],
    field: Any = None,
    ax: Any = None,
    title: str = "",
    curved: bool = False,
    speed: float | Sequence[float] = 1.0,
    path: str | None = None,
    target_ids: Sequence[str] | None = None,
    vehicle_ids: Sequence[str] | None = None,
    unit: str = "m",
    caption: str = "",
) -> Any:
    """Draw one open route per vehicle over the drift field, with target and vehicle ids.

    Each vehicle has its own colour and line style; the legend (outside the axes, on the
    right) spells every route with the ids ``taopt demo`` and ``taopt solve`` print.

    Parameters
    ----------
    points : (n + m, 2) array_like
        Targets first, then the m vehicle starts (thesis order), in metres.
    routes : list of list of int
        One list of target indices per vehicle (``Solution.routes``).
    field : Field, optional
        Drawn as a quiver plot underneath.
    ax : matplotlib Axes, optional
    title : str
        What is drawn (method, objective).
    curved : bool
        Draw each leg as its minimum-time path (``taopt.navigation.min_time_path``,
        one small solve per leg) instead of a straight arrow: the path the travel time
        t(i, j) of (2.1) was computed along.
    speed : float or sequence of float
        Vehicle speed (one per vehicle, or one for all), for ``curved``.
    path : str, optional
        Save the figure as PNG there.
    target_ids, vehicle_ids : sequence of str, optional
        Default ``t0, t1, ...`` and ``v0, v1, ...``.
    unit : str
        Unit of the coordinates, for the axis labels ("m"; the caller of a schematic
        layout passes e.g. "s, schematic").
    caption : str
        A note printed under the axes (e.g. how a schematic layout was made).

    Returns
    -------
    matplotlib Axes
    """
    points = np.asarray(points, dtype=float)
    m = len(routes)
    n = len(points) - m
    if n < 0:
        raise ValueError(f"{len(points)} points cannot hold {m} vehicle starts")
    target_ids = list(target_ids) if target_ids is not None else [f"t{k}" for k in range(n)]
    vehicle_ids = list(vehicle_ids) if vehicle_ids is not None else [f"v{k}" for k in range(m)]
    speeds = np.broadcast_to(np.asarray(speed, dtype=float), (m,))
    ax = _axes(ax, (8.0, 6.0))
    from matplotlib import colormaps

    low, high = points.min(axis=0), points.max(axis=0)
    pad = 0.08 * max(float((high - low).max()), 1e-9)
    region = (low[0] - pad, high[0] + pad, low[1] - pad, high[1] + pad)
    if field is not None:
        plot_field(field, region, ax=ax, color="0.78")
    colours = colormaps["tab10"](np.arange(max(m, 1)) % 10)
    for k, route in enumerate(routes):
        style = LINESTYLES[k % len(LINESTYLES)]
        nodes = [n + k, *route]
        for a, b in zip(nodes[:-1], nodes[1:], strict=False):
            if curved and field is not None:
                from taopt.navigation import min_time_path

                leg = min_time_path(field, points[a], points[b], speed=float(speeds[k]))
                ax.plot(leg.xy[:, 0], leg.xy[:, 1], color=colours[k], lw=1.6, ls=style)
                mid = len(leg.xy) // 2
                ax.annotate(
                    "",
                    xy=leg.xy[min(mid + 1, len(leg.xy) - 1)],
                    xytext=leg.xy[mid],
                    arrowprops={"arrowstyle": "-|>", "color": colours[k], "lw": 1.2},
                )
            else:
                ax.annotate(
                    "",
                    xy=points[b],
                    xytext=points[a],
                    arrowprops={
                        "arrowstyle": "-|>",
                        "color": colours[k],
                        "lw": 1.6,
                        "linestyle": style,
                        "shrinkA": 5,
                        "shrinkB": 5,
                    },
                )
        # the legend entry of this vehicle: its colour, style and route in ids
        ax.plot(
            [],
            [],
            color=colours[k],
            ls=style,
            lw=1.6,
            label=route_text(vehicle_ids[k], route, target_ids),
        )
    ax.scatter(points[:n, 0], points[:n, 1], s=22, color="black", zorder=3, label="targets")
    ax.scatter(
        points[n:, 0],
        points[n:, 1],
        s=70,
        marker="^",
        color=colours[:m],
        zorder=4,
        edgecolor="black",
        label="vehicle starts",
    )
    label_points(points[:n], target_ids, ax, fontsize=9)
    label_points(points[n:], vehicle_ids, ax, fontsize=9, fontweight="bold")
    ax.set_aspect("equal")
    ax.set_xlim(region[0], region[1])
    ax.set_ylim(region[2], region[3])
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    legend_outside(ax)
    if title:
        ax.set_title(title, fontsize=10)
    if caption:
        ax.annotate(
            caption,
            (0.0, 0.0),
            xycoords="axes fraction",
            xytext=(0, -36),
            textcoords="offset points",
            ha="left",
            va="top",
            fontsize=8,
            color="0.25",
        )
    if path:
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    return ax


def plot_instance_routes(
    instance: Any,
    routes: Sequence[Sequence[int]],
    title: str = "",
    ax: Any = None,
    path: str | None = None,
) -> Any:
    """Routes of an :class:`~taopt.Instance`'s chapter 2 problem, as ``demo`` and ``solve`` draw them.

    The instance's ids label the points; with a drift field every leg is its
    minimum-time path (the curve its travel time was computed along), otherwise a
    straight arrow. One speed (the instance's slowest, as its travel-time matrix uses).
    """
    return plot_routes(
        instance.points,
        routes,
        field=instance.field,
        ax=ax,
        title=title,
        curved=instance.field is not None,
        speed=float(instance.speeds.min()),
        target_ids=[t.id for t in instance.targets],
        vehicle_ids=[v.id for v in instance.vehicles],
        path=path,
    )
