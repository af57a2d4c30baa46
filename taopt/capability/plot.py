"""Chapter 3 plots: the field with obstacles, grid paths, routes by capability, the study.

Every function takes an optional ``ax``, returns the Axes, and can save a PNG (``path``).
They build bare matplotlib Figures (no pyplot state), so they work on any backend.

* :func:`plot_scene` — quiver of the drift, obstacles (green, as Fig. 3.2), targets and
  vehicle starts coloured by capability.
* :func:`plot_grid_paths` — shortest grid paths (§3.3) between pairs of points.
* :func:`figure_3_2` — Fig. 3.2's setting: a path both ways round an obstacle in the
  ``1e-2`` field.
* :func:`plot_routes` — a solution's routes coloured by capability (Fig. 3.2 style: each leg
  drawn along its grid path when there are obstacles).
* :func:`plot_printed_arcs` — the arcs the printed model (3.1)–(3.3) picks, its subtours and
  foreign tails marked.
* :func:`plot_quality` — Figs. 3.4–3.6: mean q against |A| per method.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.plot import (
    LINESTYLES,
    _axes,
    dodge,
    label_points,
    legend_outside,
    method_style,
    plot_field,
)

__all__ = [
    "capability_colours",
    "plot_obstacles",
    "plot_scene",
    "plot_grid_paths",
    "figure_3_2",
    "plot_routes",
    "plot_printed_arcs",
    "figure_printed_vs_corrected",
    "plot_quality",
]


def capability_colours(capabilities: Sequence[Any]) -> dict[Any, Any]:
    """One tab10/tab20 colour per capability, in order of first appearance."""
    from matplotlib import colormaps

    labels = list(dict.fromkeys(capabilities))
    cmap = colormaps["tab10" if len(labels) <= 10 else "tab20"]
    return {label: cmap(k % cmap.N) for k, label in enumerate(labels)}


def _save(ax: Any, path: str | None) -> None:
    if path:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")  # keeps the outside legend


def plot_obstacles(obstacles: Sequence[Any], ax: Any) -> Any:
    """Fill each obstacle polygon in green (as Fig. 3.2)."""
    from matplotlib.patches import Polygon

    for k, obstacle in enumerate(obstacles):
        vertices = np.asarray(getattr(obstacle, "vertices", obstacle), dtype=float)
        ax.add_patch(
            Polygon(
                vertices,
                closed=True,
                facecolor="tab:green",
                edgecolor="darkgreen",
                alpha=0.8,
                zorder=2,
                label="obstacles" if k == 0 else None,
            )
        )
    return ax


def plot_scene(
    instance: Any, ax: Any = None, density: int = 15, path: str | None = None, ids: bool = True
) -> Any:
    """The instance: drift quiver, obstacles, targets (by demand count), vehicles by capability.

    Parameters
    ----------
    instance : taopt.Instance
    ax : matplotlib Axes, optional
    density : int
        Quiver arrows per side.
    path : str, optional
        Save as PNG.
    ids : bool
        Write the instance's target and vehicle ids next to their points.
    """
    ax = _axes(ax, (7.0, 7.0))
    if instance.field is not None:
        plot_field(instance.field, instance.region, ax=ax, density=density, color="0.75")
    else:  # still water: no arrows to draw
        xmin, xmax, ymin, ymax = instance.region
        ax.set_xlim(xmin, xmax)
        ax.set_ylim(ymin, ymax)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    xmin, xmax, ymin, ymax = instance.region
    pad = 0.03 * max(xmax - xmin, ymax - ymin)  # points on the border stay visible
    ax.set_xlim(xmin - pad, xmax + pad)
    ax.set_ylim(ymin - pad, ymax + pad)
    plot_obstacles(instance.obstacles, ax)
    colours = capability_colours([v.capability for v in instance.vehicles])
    targets = np.array([t.position for t in instance.targets])
    sizes = np.array([len(t.demands) for t in instance.targets])
    ax.scatter(
        targets[:, 0], targets[:, 1], s=12 + 10 * sizes, c="black", zorder=3, label="targets"
    )
    for capability, colour in colours.items():
        starts = np.array([v.start for v in instance.vehicles if v.capability == capability])
        ax.scatter(
            starts[:, 0],
            starts[:, 1],
            s=80,
            marker="^",
            color=colour,
            edgecolor="black",
            zorder=4,
            label=f"vehicles {capability}",
        )
    if ids:
        label_points(targets, [t.id for t in instance.targets], ax)
        starts = np.array([v.start for v in instance.vehicles])
        label_points(starts, [v.id for v in instance.vehicles], ax, fontweight="bold")
    if not ax.get_title():
        ax.set_title(
            f"{getattr(instance, 'name', '') or 'instance'}: "
            + ", ".join(
                f"{len(items)} {word}{'' if len(items) == 1 else 's'}"
                for items, word in (
                    (instance.targets, "target"),
                    (instance.vehicles, "vehicle"),
                    (instance.obstacles, "obstacle"),
                )
            ),
            fontsize=10,
        )
    legend_outside(ax)
    _save(ax, path)
    return ax


def plot_grid_paths(
    graph: Any,
    pairs: Sequence[tuple[Any, Any]],
    ax: Any = None,
    labels: Sequence[str] | None = None,
    show_blocked: bool = True,
    path: str | None = None,
) -> Any:
    """Shortest grid paths (:meth:`taopt.navigation.grid.GridGraph.path`) between point pairs.

    Parameters
    ----------
    graph : taopt.navigation.grid.GridGraph
    pairs : sequence of (start, goal)
    labels : sequence of str, optional
        Legend entries (default: the grid time of each path).
    show_blocked : bool
        Shade the blocked cells.
    """
    ax = _axes(ax, (7.0, 7.0))
    plot_field(graph.field, graph.region, ax=ax, color="0.75")
    if show_blocked and graph.blocked.any():
        half = graph.cell / 2
        for x, y in graph.centres[graph.blocked]:
            ax.add_patch(_square(x - half, y - half, graph.cell, facecolor="tab:green", alpha=0.8))
    colours = ["tab:blue", "tab:red", "tab:purple", "tab:orange", "tab:brown"]
    for k, (start, goal) in enumerate(pairs):
        line = graph.path(start, goal)
        time = graph.path_time(line)
        colour = colours[k % len(colours)]
        label = labels[k] if labels is not None else f"t = {time:.2f} s"
        ax.plot(line[:, 0], line[:, 1], "-", color=colour, lw=2, label=label)
        # as taopt.plot.plot_paths: the goal an open square under, the start a dot over it
        ax.plot(*line[-1], "s", color=colour, ms=12, mfc="none", mew=1.8, zorder=4, gid="goal")
        ax.plot(*line[0], "o", color=colour, ms=6, mec="white", zorder=5, gid="start")
    ax.plot([], [], "o", color="0.3", ms=6, mec="white", label="start")
    ax.plot([], [], "s", color="0.3", ms=12, mfc="none", mew=1.8, label="goal")
    if not ax.get_title():
        ax.set_title(
            f"shortest grid paths round the obstacles (cell {graph.cell:g} m)", fontsize=10
        )
    legend_outside(ax)
    _save(ax, path)
    return ax


def _square(x: float, y: float, side: float, **style: Any) -> Any:
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), side, side, linewidth=0, zorder=2, **style)


def figure_3_2(
    path: str | None = None,
    point_1: Sequence[float] = (15.0, 20.0),
    point_2: Sequence[float] = (85.0, 80.0),
    obstacle: Sequence[Sequence[float]] = ((35.0, 30.0), (65.0, 30.0), (65.0, 70.0), (35.0, 70.0)),
    cell: float = 1.0,
    neighbours: int = 16,
) -> Any:
    """Fig. 3.2's setting: paths 1 -> 2 and 2 -> 1 round an obstacle in the 1e-2 field.

    The thesis gives the field ``1e-2 [0.3x + 0.2y, -0.2x + 0.3y]``, ``v = 1`` and
    ``t(1, 2) = 66.5618 s`` but neither the points nor the obstacle; the defaults here are a
    100 m square with a rectangle between the two points, so the times are not the thesis's.
    """
    from taopt.fields import thesis_field
    from taopt.navigation.grid import GridGraph

    graph = GridGraph(thesis_field(1e-2), (0, 100, 0, 100), cell, [obstacle], 1.0, neighbours)
    times = graph.travel_time_matrix(np.array([point_1, point_2]))
    ax = plot_grid_paths(
        graph,
        [(point_1, point_2), (point_2, point_1)],
        labels=[f"1 -> 2: {times[0, 1]:.2f} s", f"2 -> 1: {times[1, 0]:.2f} s"],
        show_blocked=True,
    )
    label_points([point_1, point_2], ["1", "2"], ax, offset=(6, 6), fontsize=12)
    ax.set_title(
        f"grid ({neighbours} moves, {cell:g} m): t(1,2) = {times[0, 1]:.2f} s, "
        f"t(2,1) = {times[1, 0]:.2f} s",
        fontsize=9,
    )
    _save(ax, path)
    return ax


def plot_routes(
    instance: Any,
    problem: Any,
    routes: Sequence[Sequence[int]],
    graph: Any = None,
    ax: Any = None,
    title: str = "",
    path: str | None = None,
) -> Any:
    """A solution's routes coloured by capability, over the field and the obstacles.

    Parameters
    ----------
    instance : taopt.Instance
        Positions, field and obstacles (targets first, then vehicle starts).
    problem : CapabilityProblem
        The problem the routes solve (its vehicles' capabilities).
    routes : list of list of int
        One route per vehicle (``Solution.routes``).
    graph : taopt.navigation.grid.GridGraph, optional
        Draw every leg along its grid path (default: a 10 m, 16-move grid when the instance
        has obstacles, as :func:`~taopt.capability.instances.capability_problem_from_instance`
        plans them). Without obstacles each leg is its minimum-time path in the field (the
        curve its travel time was computed along), or a straight arrow in still water.

    Each vehicle has its capability's colour and its own line style; the legend (outside
    the axes) spells every route with the instance's ids.
    """
    from taopt.routing.plot import route_text

    ax = plot_scene(instance, ax=ax)
    points = instance.points
    n = problem.n
    if graph is None and instance.obstacles:
        from taopt.capability.instances import STUDY_CELL, STUDY_NEIGHBOURS
        from taopt.navigation.grid import GridGraph

        graph = GridGraph(
            instance.field,
            instance.region,
            STUDY_CELL,
            instance.obstacles,
            instance.vehicles[0].speed,
            STUDY_NEIGHBOURS,
        )
    target_ids = [t.id for t in instance.targets]
    colours = capability_colours(problem.vehicle_capability)
    for k, route in enumerate(routes):
        colour = colours[problem.vehicle_capability[k]]
        style = LINESTYLES[k % len(LINESTYLES)]
        nodes = [n + k, *route]
        for a, b in zip(nodes[:-1], nodes[1:], strict=True):
            if graph is not None:
                line = graph.path(points[a], points[b])
            elif instance.field is not None:
                from taopt.navigation import min_time_path

                speed = instance.vehicles[k].speed
                line = min_time_path(instance.field, points[a], points[b], speed=speed).xy
            else:
                line = np.array([points[a], points[b]])
            ax.plot(line[:, 0], line[:, 1], color=colour, ls=style, lw=1.5, zorder=3)
            mid = max(len(line) // 2, 1)
            ax.annotate(
                "",
                xy=line[mid],
                xytext=line[mid - 1],
                arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.2},
                zorder=3,
            )
        vehicle = instance.vehicles[k].id
        label = f"{route_text(vehicle, route, target_ids)} ({problem.vehicle_capability[k]})"
        ax.plot([], [], color=colour, ls=style, lw=1.5, label=label)
    legend_outside(ax)
    if title:
        ax.set_title(title, fontsize=9)
    _save(ax, path)
    return ax


def plot_printed_arcs(
    instance: Any, problem: Any, arcs: Any, ax: Any = None, title: str = "", path: str | None = None
) -> Any:
    """The printed model's arcs (``σ_ijk = 1``) by capability; subtours dashed, foreign
    tails (an arc leaving a point its class never visits) in red.

    Parameters
    ----------
    instance : taopt.Instance
    problem : CapabilityProblem
    arcs : taopt.models.capability.PrintedArcs or dict
        :func:`taopt.models.capability.decode_printed`'s result, or a Solution's ``info``.
    """
    ax = plot_scene(instance, ax=ax, density=8)
    data = arcs if isinstance(arcs, dict) else arcs.to_dict()
    points = instance.points
    colours = capability_colours(problem.vehicle_capability)
    cycles = {tuple(sorted(c)) for _, c in data.get("subtours", [])}
    on_cycle = {t for c in cycles for t in c}
    foreign = {tuple(a) for a in data.get("foreign_tails", [])}
    for i, j, k in data["arcs"]:
        colour = colours[problem.vehicle_capability[k]]
        style, bend = "-", 0.0
        if (i, j, k) in foreign:
            colour, bend = "red", 0.35  # bent, so it shows beside an arc of the other class
        elif i in on_cycle and j in on_cycle:
            style, bend = "--", 0.25  # both arcs of a 2-cycle stay visible
        ax.annotate(
            "",
            xy=points[j],
            xytext=points[i],
            arrowprops={
                "arrowstyle": "->",
                "color": colour,
                "lw": 1.8,
                "linestyle": style,
                "connectionstyle": f"arc3,rad={bend}",
                "shrinkA": 4,
                "shrinkB": 4,
            },
            zorder=5,
        )
    ax.plot([], [], color="0.3", ls="--", label="arc on a subtour")
    ax.plot([], [], color="red", label="arc from another class's start")
    legend_outside(ax)
    if title:
        ax.set_title(title, fontsize=9)
    _save(ax, path)
    return ax


def figure_printed_vs_corrected(
    instance: Any, printed: Any, corrected: Any, path: str | None = None
) -> Any:
    """Two panels: the printed model's arcs (left) and the corrected optimum (right).

    Parameters
    ----------
    instance : Instance
        Positions and field of the problem.
    printed, corrected : Solution
        ``taopt.models.solve_capability(problem, "printed")`` and ``(..., "corrected")`` on
        ``capability_problem_from_instance(instance)`` (the caller solves; plots never do).

    Returns
    -------
    matplotlib Figure
    """
    from matplotlib.figure import Figure

    from taopt.capability.instances import capability_problem_from_instance

    problem = capability_problem_from_instance(instance)
    figure = Figure(figsize=(12.0, 5.0))
    left, right = figure.subplots(1, 2)
    plot_printed_arcs(
        instance,
        problem,
        printed.info,
        ax=left,
        title=f"printed (3.1)-(3.3): {printed.objective:.2f} s (dashed: subtour, red: an arc "
        "from another vehicle's start)",
    )
    plot_routes(
        instance,
        problem,
        corrected.routes,
        ax=right,
        title=f"corrected (per class (2.2)-(2.5)): optimum {corrected.objective:.2f} s",
    )
    if path:
        figure.tight_layout()
        figure.savefig(path, dpi=120, bbox_inches="tight")
    return figure


def plot_quality(
    table: Any,
    column: str = "q_thesis",
    instance: str | None = None,
    ax: Any = None,
    path: str | None = None,
) -> Any:
    """Figs. 3.4–3.6: mean quality ratio against |A|, one line per method.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`taopt.orchestration.studies.capability.summarize`'s output (columns ``instance``, ``A``,
        ``method`` and the mean of ``column``).
    column : str
        "q_thesis" (f / f^a, the thesis's (3.15)), "q_valid" (f / arborescence) or
        "q_exact" (f / optimum).
    instance : str, optional
        One of the table's instances ("n50m10", ...); default all, one panel each.
    """
    data = table if instance is None else table[table["instance"] == instance]
    ax = _axes(ax, (5.0, 4.0))
    methods = sorted(set(data["method"]))
    counts = data["A"].astype(float) if len(data) else np.zeros(1)
    span = float(counts.max() - counts.min()) or 1.0
    for (name, method), rows in data.groupby(["instance", "method"], sort=True):
        rows = rows.sort_values("A")
        label = method if instance is not None else f"{name} {method}"
        k = methods.index(method)
        style = method_style(method, k)
        colour = "black" if method == "exact" else None
        # a heuristic at the optimum would hide the exact line's markers: shift sideways
        shift = dodge(k, len(methods), span, share=0.015)
        ax.plot(rows["A"] + shift, rows[column], color=colour, label=label, **style)
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # |A| is a count
    ax.set_xlabel("|A|, capabilities (count); methods shifted a little")
    ax.set_ylabel(
        {
            "q_thesis": "mean q = f / f^a (3.15), ratio (1)",
            "q_valid": "mean f / arborescence bound, ratio (1)",
        }.get(column, "mean f / optimum, ratio (1)")
    )
    ax.set_title(f"{instance or 'all instances'}: mean {column} per method", fontsize=9)
    ax.grid(alpha=0.3)
    legend_outside(ax, fontsize=7)
    _save(ax, path)
    return ax
