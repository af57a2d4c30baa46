"""Chapter 4 plots: a run, its animation (GIF), Remark 4.6's pair, q and bytes against r.

Every function takes an optional ``ax`` (or builds a bare matplotlib ``Figure``, safe on any
backend), returns the Axes or Figure, and saves to ``path`` when given.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.comm.problem import CommProblem
from taopt.comm.trajectories import Trajectories
from taopt.errors import InstanceError
from taopt.plot import LINESTYLES, dodge, legend_outside, method_style

_MARKERS = "so^DvP*Xhp<>"


def _axes(ax: Any = None, figsize: tuple[float, float] = (6.5, 6.0)) -> Any:
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    return Figure(figsize=figsize).add_subplot()


def _colour(j: int) -> Any:
    from matplotlib import colormaps

    return colormaps["tab10"](j % 10)


def _payload(solution: Any) -> Trajectories:
    payload = getattr(solution, "solution", solution)
    if not isinstance(payload, Trajectories):
        raise TypeError(f"expected trajectories, got {type(payload).__name__}")
    return payload


def _save(ax_or_fig: Any, path: str | os.PathLike[str] | None, dpi: int = 120) -> None:
    if path is None:
        return
    fig = getattr(ax_or_fig, "figure", ax_or_fig)
    fig.tight_layout()
    fig.savefig(os.fspath(path), dpi=dpi, bbox_inches="tight")  # keeps the outside legend


def plot_points(problem: CommProblem, ax: Any, labels: bool = True) -> Any:
    """Targets (one marker per attribute) and the vehicles' start points (triangles).

    With ``labels`` the targets carry their index q (as ``taopt simulate`` lists the visits)
    and the vehicles ``v0, v1, ...`` (vehicle j of the printed table).
    """
    for code, label in enumerate(problem.attributes):
        where = problem.target_code == code
        if where.any():
            ax.plot(
                problem.targets[where, 0],
                problem.targets[where, 1],
                _MARKERS[code % len(_MARKERS)],
                color="0.25",
                mfc="white",
                ms=7,
                label=f"targets, attribute {label}",
            )
    for j, (x, y) in enumerate(problem.vehicles):
        ax.plot(
            x, y, "^", color=_colour(j), ms=10, mec="k", label="vehicle starts" if j == 0 else None
        )
        if labels:
            ax.annotate(f"v{j}", (x, y), textcoords="offset points", xytext=(5, 5), fontsize=8)
    if labels:
        for q, (x, y) in enumerate(problem.targets):
            ax.annotate(str(q), (x, y), textcoords="offset points", xytext=(4, -10), fontsize=7)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return ax


def draw_range(problem: CommProblem, ax: Any, centres: Any = None) -> list[Any]:
    """Circles of radius r (the communication range of (4.3)) around each vehicle's start.

    Two vehicles can talk while each is inside the other's circle. The circles are dashed,
    in the vehicle's colour, with ``gid="communication range"``; one is labelled
    ``r = ... m`` and the legend says what they are. The axes keep the limits of the data
    (a range wider than the field is clipped, not zoomed out to).

    Returns
    -------
    list of matplotlib.patches.Circle
    """
    from matplotlib.patches import Circle

    r = float(problem.comm_range)
    centres = problem.vehicles if centres is None else centres
    ax.autoscale_view()
    xlim, ylim = ax.get_xlim(), ax.get_ylim()
    circles = []
    for j, (x, y) in enumerate(np.asarray(centres, dtype=float)):
        circle = Circle(
            (x, y),
            r,
            fill=False,
            ls="--",
            lw=0.9,
            edgecolor=_colour(j),
            alpha=0.7,
            gid="communication range",
            label=f"communication range r = {r:g} m\n(around the starts)" if j == 0 else None,
        )
        ax.add_patch(circle)
        circles.append(circle)
    if circles:
        x, y = np.asarray(centres, dtype=float)[0]
        ax.annotate(
            f"r = {r:g} m",
            (x + r * np.cos(np.pi / 4), y + r * np.sin(np.pi / 4)),
            fontsize=7,
            color=_colour(0),
            xytext=(2, 2),
            textcoords="offset points",
            annotation_clip=True,
        )
    ax.set_xlim(xlim)
    ax.set_ylim(ylim)
    return circles


def plot_run(
    problem: CommProblem,
    solution: Any,
    ax: Any = None,
    links: bool = True,
    labels: bool = True,
    title: str | None = None,
    path: str | os.PathLike[str] | None = None,
    method: str = "",
) -> Any:
    """A run: targets, start points, the driven paths by vehicle, the links and the range r.

    Each vehicle has its own colour and line style; the legend (outside the axes) gives
    each vehicle's ability and driven length, positions are in metres. A dashed circle of
    radius r around each start shows the communication range (:func:`draw_range`).

    Parameters
    ----------
    problem : CommProblem
    solution : Solution or Trajectories
        From ``taopt.solve(problem, "DAA")`` (its ``info["groups"]`` gives the links drawn
        at each re-planning event, dotted, between the members' positions then).
    links : bool
        Draw the communication links of each newly connected group.

    Returns
    -------
    matplotlib.axes.Axes
    """
    tr = _payload(solution)
    ax = _axes(ax, (8.0, 6.0))
    lengths = tr.lengths()
    for j, path_j in enumerate(tr.paths):
        ax.plot(
            path_j[:, 1],
            path_j[:, 2],
            color=_colour(j),
            ls=LINESTYLES[j % len(LINESTYLES)],
            lw=1.6,
            alpha=0.9,
            label=f"v{j} ({problem.vehicle_ability[j]}): {lengths[j]:.1f} m",
        )
        if len(path_j) > 1:
            end = path_j[-1, 1:]
            ax.plot(*end, "o", color=_colour(j), ms=5)
            mid = len(path_j) // 2
            a, b = path_j[mid - 1, 1:], path_j[mid, 1:]
            if np.hypot(*(b - a)) > 0:
                ax.annotate(
                    "",
                    xy=(a + b) / 2 + (b - a) * 0.01,
                    xytext=(a + b) / 2,
                    arrowprops={"arrowstyle": "->", "color": _colour(j)},
                )
    groups = getattr(solution, "info", {}).get("groups", []) if links else []
    for g in groups:
        where = {j: p for j, p in zip(g["members"], g["positions"], strict=True)}
        for a, b in g["links"]:
            pa, pb = where[a], where[b]
            ax.plot([pa[0], pb[0]], [pa[1], pb[1]], ":", color="0.4", lw=1.0)
    if groups:
        ax.plot([], [], ":", color="0.4", label="links when a group connects")
    plot_points(problem, ax, labels=labels)
    draw_range(problem, ax)
    if title is None:
        name = method or getattr(solution, "method", "") or "run"
        total = float(tr.lengths().sum())
        title = f"{name}: f = {total:.1f} m, r = {problem.comm_range:g} m"
        info = getattr(solution, "info", {})
        if "bytes" in info:
            title += f", {info['bytes']:,.0f} bytes relayed"
    ax.set_title(title, fontsize=10)
    legend_outside(ax, fontsize=7)
    _save(ax, path)
    return ax


def plot_pair(
    short: CommProblem,
    short_solution: Any,
    long: CommProblem,
    long_solution: Any,
    path: str | os.PathLike[str] | None = None,
) -> Any:
    """Remark 4.6 as Figs. 4.3–4.4: one instance run at two ranges, side by side.

    ``short_solution`` / ``long_solution`` are the runs (``taopt.solve(short, "DAA")``, ...).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 5.8))
    for k, (problem, result) in enumerate(((short, short_solution), (long, long_solution))):
        ax = fig.add_subplot(1, 2, k + 1)
        tr = _payload(result)
        lengths = ", ".join(f"{d:.1f}" for d in tr.lengths())
        name = getattr(result, "method", "") or "run"
        plot_run(
            problem,
            result,
            ax=ax,
            title=(
                f"{name}, r = {problem.comm_range:g} m: f = {tr.lengths().sum():.1f} m\n"
                f"(vehicles: {lengths} m)"
            ),
        )
    _save(fig, path)
    return fig


def check_frames(frames: Any, fps: Any = 12) -> None:
    """InstanceError unless ``frames`` is an integer >= 2 and ``fps`` one >= 1 (a GIF of
    one frame is no animation, and matplotlib fails on none)."""
    for label, value, least in (("frames", frames, 2), ("fps", fps, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise InstanceError(
                f"an animation needs {label} >= {least} (an integer), got {value!r}"
            )


def animate_run(
    problem: CommProblem,
    solution: Any,
    path: str | os.PathLike[str],
    frames: int = 120,
    fps: int = 12,
    dpi: int = 80,
) -> Any:
    """Write a GIF of a run (matplotlib animation, pillow writer).

    Each frame shows the vehicles at that time with their trails, the targets (filled once
    visited), and the links of the communication graph then (4.3).

    Returns
    -------
    matplotlib.animation.FuncAnimation

    Raises
    ------
    InstanceError
        ``frames`` below 2 or ``fps`` below 1 (checked before anything is drawn or written).
    """
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.figure import Figure

    check_frames(frames, fps)
    tr = _payload(solution)
    name = getattr(solution, "method", "") or "run"
    end = max(tr.end_time, 1e-9)
    times = np.linspace(0.0, end, int(frames))
    fig = Figure(figsize=(6, 6))
    ax = fig.add_subplot()
    plot_points(problem, ax, labels=True)
    side = problem.side()
    ax.set_xlim(-0.02 * side, 1.02 * side)
    ax.set_ylim(-0.02 * side, 1.02 * side)
    visit_time = np.full(problem.n, np.inf)
    for j, seq in enumerate(tr.visits):
        for q, index in seq:
            visit_time[q] = min(visit_time[q], tr.paths[j][index, 0])
    (done,) = ax.plot([], [], "s", color="0.3", ms=7, label="visited")
    trails = [ax.plot([], [], "-", color=_colour(j), lw=1.4)[0] for j in range(problem.m)]
    dots = [ax.plot([], [], "o", color=_colour(j), ms=8, mec="k")[0] for j in range(problem.m)]
    link_lines = [ax.plot([], [], "-", color="0.5", lw=0.8)[0] for _ in range(problem.m**2)]
    clock = ax.set_title("")

    def draw(frame: int) -> list[Any]:
        t = times[frame]
        where = np.array([tr.position(j, t) for j in range(problem.m)])
        for j in range(problem.m):
            p = tr.paths[j]
            past = p[p[:, 0] <= t]
            xs = np.append(past[:, 1], where[j, 0])
            ys = np.append(past[:, 2], where[j, 1])
            trails[j].set_data(xs, ys)
            dots[j].set_data([where[j, 0]], [where[j, 1]])
        seen = visit_time <= t
        done.set_data(problem.targets[seen, 0], problem.targets[seen, 1])
        k = 0
        for a in range(problem.m):
            for b in range(a + 1, problem.m):
                if np.hypot(*(where[a] - where[b])) <= problem.comm_range:
                    link_lines[k].set_data([where[a, 0], where[b, 0]], [where[a, 1], where[b, 1]])
                    k += 1
        for line in link_lines[k:]:
            line.set_data([], [])
        clock.set_text(f"{name}: t = {t:.0f} s, r = {problem.comm_range:g} m (grey: links)")
        return [*trails, *dots, done, *link_lines, clock]

    animation = FuncAnimation(fig, draw, frames=len(times), blit=False)
    animation.save(os.fspath(path), writer=PillowWriter(fps=fps), dpi=dpi)
    return animation


def plot_range_curves(
    summary: Any,
    value: str = "q",
    algorithms: Sequence[str] = ("DAA", "HDA"),
    ax: Any = None,
    path: str | os.PathLike[str] | None = None,
    ylabel: str | None = None,
) -> Any:
    """``value`` (a column of a study summary: mean q, bytes, ...) against r, one line per |A|.

    ``summary`` has columns ``A``, ``r``, ``method`` and ``value`` (e.g.
    :func:`taopt.orchestration.studies.comm.summary`).
    """
    ax = _axes(ax, (7.0, 4.5))
    ranges = summary["r"].astype(float) if len(summary) else np.zeros(1)
    span = float(ranges.max() - ranges.min()) or 1.0
    for a_index, (attributes, part) in enumerate(summary.groupby("A")):
        for k, method in enumerate(algorithms):
            rows = part[part["method"] == method].sort_values("r")
            if rows.empty:
                continue
            # DAA and HDA often agree: shift each algorithm sideways so neither hides
            ax.plot(
                rows["r"] + dodge(k, len(algorithms), span, share=0.01),
                rows[value],
                ms=5,
                mfc="white" if method == "HDA" else None,
                color=_colour(a_index),
                label=f"{method}, |A| = {attributes}",
                **method_style(method, k),
            )
    ax.set_xlabel("communication range r (m); algorithms shifted sideways a little")
    ax.set_ylabel(ylabel or value)
    if not ax.get_title():
        ax.set_title(f"mean {value} against the communication range r", fontsize=10)
    ax.grid(alpha=0.3)
    legend_outside(ax, "below", fontsize=7, ncol=len(algorithms))
    _save(ax, path)
    return ax


__all__ = [
    "plot_points",
    "plot_run",
    "draw_range",
    "plot_pair",
    "animate_run",
    "check_frames",
    "plot_range_curves",
]
