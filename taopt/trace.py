"""A method's trace drawn: the DFJ cut loop round by round, the ideal DP layer by layer.

``taopt.solve(problem, "exact", trace=True)`` keeps, in ``solution.info["trace"]``, what the
exact method did (plain JSON data, saved with the solution):

* chapter 2's DFJ loop (:func:`taopt.models.routing.solve_routing`, ``"kind": "dfj"``): one
  round per LP of the root and per MIP round, each with its point (the arcs with σ > 0),
  the target sets S whose subtour row (2.5) it violates and the rows added;
* chapter 5's DP over order ideals (:func:`taopt.delivery.ideal_dp.ideal_dp`,
  ``"kind": "ideal_dp"``): one entry per layer (customers served) with the states reached,
  dominated, pruned and kept and the proven bound.

:func:`plot_trace` (also :func:`taopt.plot.trace`) draws it in one figure, one panel per
round (or the DP's two charts); :func:`animate_trace` writes a GIF with one frame per round
(``taopt solve FILE --trace trace.gif``).

Example
-------
>>> import numpy as np, taopt
>>> cost = np.array([[0, 1, 9, 9], [1, 0, 9, 9], [9, 9, 0, 9], [5, 6, 4, 0.0]])
>>> solution = taopt.solve(taopt.AssignmentProblem(cost, 3), "exact", trace=True)
>>> [r["stage"] for r in rounds(solution)][:2], rounds(solution)[0]["subtours"]
(['root', 'root'], [[0, 1]])

References
----------
Thesis §2.2.1 ((2.2)–(2.5)), §5.3 (the ideal DP).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from taopt.errors import InstanceError

#: What the marks of a round's map mean (the caption of an animation's frames).
MAP_KEY = (
    "solid arrow: arc with σ = 1;  dashed red arrow: 0 < σ < 1 (its value written);  "
    "shaded discs: a target set S whose subtour row (2.5) the point violates"
)

#: Stage names of a DFJ round, as panel titles say them.
STAGE_NAMES = {"root": "root LP", "mip": "MIP round", "fallback": "compact model"}


def trace_of(solution: Any) -> dict[str, Any]:
    """The trace of ``solution`` (a :class:`~taopt.Solution` or the trace mapping itself).

    Raises
    ------
    InstanceError
        The solution holds no trace (solved without ``trace=True``, or by a method that
        keeps none), or the trace is of an unknown kind.
    """
    if isinstance(solution, Mapping) and "kind" in solution:
        found: Any = solution
    else:
        found = getattr(solution, "info", {}).get("trace")
        if found is None:
            method = getattr(solution, "method", "") or "?"
            raise InstanceError(
                f"the solution of method {method!r} holds no trace: solve with "
                "taopt.solve(problem, 'exact', trace=True) (the DFJ loop of chapter 2 or the "
                "ideal DP of chapter 5)"
            )
    if found.get("kind") not in ("dfj", "ideal_dp"):
        raise InstanceError(
            f"unknown trace kind {found.get('kind')!r} (expected 'dfj' or 'ideal_dp')"
        )
    return dict(found)


def rounds(solution: Any) -> list[dict[str, Any]]:
    """The frames of a trace: the DFJ rounds, or the ideal DP's layers."""
    found = trace_of(solution)
    return list(found["rounds"] if found["kind"] == "dfj" else found["layers"])


def _points(problem: Any, instance: Any = None) -> tuple[np.ndarray, str, list[str], list[str]]:
    """(points, unit, target ids, vehicle ids): the instance's map, or a schematic layout."""
    n, m = int(problem.n), int(problem.m)
    if instance is not None and getattr(instance, "points", None) is not None:
        points = np.asarray(instance.points, dtype=float)
        if points.shape == (n + m, 2):
            return (
                points,
                "m",
                [t.id for t in instance.targets],
                [v.id for v in instance.vehicles],
            )
    from taopt.plot import schematic_layout

    return (
        schematic_layout(problem.cost),
        "s, schematic",
        [f"t{k}" for k in range(n)],
        [f"v{k}" for k in range(m)],
    )


def draw_round(
    record: Mapping[str, Any],
    problem: Any,
    ax: Any,
    instance: Any = None,
    legend: bool = True,
) -> Any:
    """One DFJ round on the map of targets: its point's arcs and the sets it violates.

    Arcs with σ = 1 are solid arrows, fractional ones (0 < σ < 1, an LP point) dashed
    with their value written at the middle (each arrow slightly bent, so the two arcs of a
    2-cycle stay apart); every target set S whose subtour row (2.5)
    ``Σ_{i,j∈S} σ_ij ≤ |S| − 1`` the point violates is shaded in its own colour.

    Parameters
    ----------
    record : mapping
        One round of a ``"dfj"`` trace (:func:`rounds`).
    problem : AssignmentProblem
    ax : matplotlib Axes
    instance : Instance, optional
        Its positions make the map (metres); without one the points are placed by
        :func:`taopt.plot.schematic_layout` from the travel times (axes "s, schematic").
    legend : bool
        Draw the legend (outside the axes, right).

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib import colormaps

    from taopt.plot import label_points, legend_outside

    points, unit, target_ids, vehicle_ids = _points(problem, instance)
    n = int(problem.n)
    low, high = points.min(axis=0), points.max(axis=0)
    span = max(float((high - low).max()), 1e-9)
    pad = 0.08 * span
    colours = colormaps["tab10"](np.arange(10))
    for k, subset in enumerate(record.get("subtours", [])):
        members = points[np.asarray(subset, dtype=int)]
        ax.scatter(
            members[:, 0],
            members[:, 1],
            s=420,
            color=colours[(k + 1) % 10],
            alpha=0.3,
            linewidths=0,
            zorder=1,
            label="violated set S of (2.5)" if k == 0 else None,
        )
    whole = fractional = False
    for tail, head, value in record.get("arcs", []):
        a, b = points[int(tail)], points[int(head)]
        integral = value >= 1.0 - 1e-6
        ax.annotate(
            "",
            xy=b,
            xytext=a,
            arrowprops={
                "arrowstyle": "-|>",
                "color": "0.1" if integral else "tab:red",
                "lw": 1.5 if integral else 0.8 + 1.2 * float(value),
                "linestyle": "-" if integral else "--",
                "shrinkA": 5,
                "shrinkB": 5,
                # slightly bent: the two arcs of a 2-cycle i -> j -> i stay apart
                "connectionstyle": "arc3,rad=0.12",
            },
            zorder=2,
        )
        if not integral:
            middle = (a + b) / 2.0
            ax.text(middle[0], middle[1], f"{value:.2g}", fontsize=7, color="tab:red", zorder=5)
        whole, fractional = whole or integral, fractional or not integral
    if whole:
        ax.plot([], [], color="0.1", lw=1.5, label="arc with σ = 1")
    if fractional:
        ax.plot([], [], color="tab:red", lw=1.2, ls="--", label="arc with 0 < σ < 1")
    ax.scatter(points[:n, 0], points[:n, 1], s=22, color="black", zorder=3, label="targets")
    ax.scatter(
        points[n:, 0],
        points[n:, 1],
        s=70,
        marker="^",
        color="tab:blue",
        edgecolor="black",
        zorder=4,
        label="vehicle starts",
    )
    label_points(points[:n], target_ids, ax, fontsize=8)
    label_points(points[n:], vehicle_ids, ax, fontsize=8, fontweight="bold")
    ax.set_xlim(low[0] - pad, high[0] + pad)
    ax.set_ylim(low[1] - pad, high[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_title(round_title(record), fontsize=9)
    if legend:
        legend_outside(ax, fontsize=8)
    return ax


def round_title(record: Mapping[str, Any]) -> str:
    """``"round 3, root LP: value 2573.9, 2 violated sets, 2 rows (2.5) added"``."""
    stage = STAGE_NAMES.get(str(record.get("stage")), str(record.get("stage")))
    value = record.get("value")
    text = f"round {record.get('round')}, {stage}"
    if value is not None:
        text += f": value {value:.6g}"
    found, cuts = len(record.get("subtours", [])), len(record.get("cuts", []))
    text += f"\n{found} violated set{'s' if found != 1 else ''}, {cuts} row{'s' if cuts != 1 else ''} (2.5) added"
    if record.get("lifted"):
        text += f", {len(record['lifted'])} lifted"
    if record.get("discarded"):
        text += " (rolled back)"
    return text


def draw_progress(found: Mapping[str, Any], ax: Any, upto: int | None = None) -> Any:
    """Value and proven bound per round (DFJ), with the incumbent of the MIP rounds."""
    from matplotlib.ticker import MaxNLocator

    records = found["rounds"][:upto]
    index = [r["round"] for r in records]

    def series(key: str) -> list[float]:
        return [np.nan if r.get(key) is None else float(r[key]) for r in records]

    ax.plot(index, series("value"), marker="o", label="value of the round's point")
    ax.plot(index, series("bound"), marker="s", ls="--", label="proven lower bound")
    if any(r.get("incumbent") is not None for r in records):
        ax.plot(index, series("incumbent"), marker="^", ls=":", label="incumbent (best routes)")
    ax.set_xlabel("round")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("total travel time (s)")
    ax.set_title("value, bound and incumbent per round", fontsize=9)
    ax.legend(fontsize=7)
    return ax


def draw_layers(found: Mapping[str, Any], axes: Sequence[Any], upto: int | None = None) -> Any:
    """The ideal DP per layer: states reached, dominated, pruned and kept (left, log scale);
    the proven bound and the incumbent's makespan (right)."""
    from matplotlib.ticker import MaxNLocator

    layers = found["layers"][:upto]
    served = [layer["served"] for layer in layers]
    left, right = axes
    for key, marker, label in (
        ("states", "o", "states (I, k) reached"),
        ("dominated", "v", "dominated"),
        ("pruned", "x", "pruned by the completion bound"),
        ("kept", "s", "kept"),
    ):
        left.plot(served, [max(layer[key], 0.5) for layer in layers], marker=marker, label=label)
    left.set_yscale("log")
    for ax in axes:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    left.set_xlabel("layer: customers served |I|")
    left.set_ylabel("states (count, log scale; 0 drawn at 0.5)")
    left.set_title("states per layer", fontsize=9)
    left.legend(fontsize=7)

    def series(key: str) -> list[float]:
        return [np.nan if layer.get(key) is None else float(layer[key]) for layer in layers]

    right.plot(served, series("bound"), marker="s", label="proven lower bound (least R + B)")
    if any(layer.get("incumbent") is not None for layer in layers):
        right.plot(served, series("incumbent"), ls="--", label="incumbent's makespan")
    right.set_xlabel("layer: customers served |I|")
    right.set_ylabel("makespan (5.1) (time units of the instance)")
    right.set_title("bound vs layer", fontsize=9)
    right.legend(fontsize=7)
    full = found["layers"]
    if full:  # fixed axes, so an animation does not jump
        left.set_xlim(-0.5, full[-1]["served"] + 0.5)
        right.set_xlim(-0.5, full[-1]["served"] + 0.5)
    return axes


def plot_trace(
    solution: Any,
    problem: Any = None,
    path: str | os.PathLike[str] | None = None,
    instance: Any = None,
    which: Sequence[int] | None = None,
    columns: int = 3,
) -> Any:
    """Draw a trace in one figure.

    A DFJ trace: one panel per round (:func:`draw_round`: the point's arcs, fractional
    ones dashed with their σ, the violated sets S of (2.5) shaded), then the value, bound
    and incumbent per round (:func:`draw_progress`). An ideal-DP trace: states per layer
    and bound vs layer (:func:`draw_layers`).

    Parameters
    ----------
    solution : Solution or mapping
        Solved with ``trace=True`` (or the trace itself).
    problem : AssignmentProblem, optional
        Needed for a DFJ trace (the points to draw).
    path : path, optional
        Save the figure as PNG there (:func:`taopt.plot.save`).
    instance : Instance, optional
        The map of a DFJ trace (positions in metres); without one a schematic layout.
    which : sequence of int, optional
        Round numbers (1-based) to draw; default all.
    columns : int
        Panels per row.

    Returns
    -------
    matplotlib Figure

    Raises
    ------
    InstanceError
        No trace, or a DFJ trace without its problem.
    """
    from matplotlib.figure import Figure

    from taopt.plot import save

    found = trace_of(solution)
    if found["kind"] == "ideal_dp":
        fig = Figure(figsize=(11.0, 4.2))
        draw_layers(found, fig.subplots(1, 2))
    else:
        if problem is None:
            raise InstanceError("a DFJ trace is drawn on its problem: pass problem=")
        records = found["rounds"]
        if which is not None:
            wanted = {int(k) for k in which}
            records = [r for r in records if r["round"] in wanted]
        panels = len(records) + 1
        cols = max(1, min(int(columns), panels))
        rows = -(-panels // cols)
        fig = Figure(figsize=(4.6 * cols, 4.4 * rows))
        axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
        for k, record in enumerate(records):
            draw_round(record, problem, axes[k], instance=instance, legend=k == 0)
        draw_progress(found, axes[len(records)])
        for ax in axes[panels:]:
            ax.set_visible(False)
    fig.tight_layout()
    if path is not None:
        save(fig, path)
    return fig


def animate_trace(
    solution: Any,
    problem: Any,
    path: str | os.PathLike[str],
    instance: Any = None,
    fps: int = 1,
    dpi: int = 80,
) -> Any:
    """Write a GIF with one frame per round of a trace (one per layer of an ideal DP).

    Each frame of a DFJ trace is the round's map (:func:`draw_round`) beside the value and
    bound so far (:func:`draw_progress`); each frame of an ideal-DP trace the charts of
    :func:`draw_layers` up to that layer. Matplotlib's ``FuncAnimation`` with its pillow
    writer.

    Parameters
    ----------
    solution : Solution or mapping
        Solved with ``trace=True``.
    problem : problem
        The problem solved.
    path : path
        The ``.gif`` written (atomically: no partial file on an error).
    instance : Instance, optional
        The map of a DFJ trace.
    fps : int
        Frames (rounds) per second.
    dpi : int

    Returns
    -------
    int
        The frames written (the rounds, or the layers).
    """
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.figure import Figure

    from taopt.io import atomic_path

    found = trace_of(solution)
    frames = rounds(found)
    if not frames:
        raise InstanceError("the trace holds no round to animate (the run stopped before one)")
    fig = Figure(figsize=(11.0, 5.0))
    left, right = fig.subplots(1, 2)
    caption = MAP_KEY if found["kind"] == "dfj" else ""

    def draw(k: int) -> list[Any]:
        left.clear()
        right.clear()
        if found["kind"] == "dfj":
            draw_round(frames[k], problem, left, instance=instance, legend=False)
            draw_progress(found, right, upto=k + 1)
            right.set_xlim(0.5, frames[-1]["round"] + 0.5)
        else:
            draw_layers(found, (left, right), upto=k + 1)
        return []

    # the layout once, from the first frame: the axes keep their places (a steady picture,
    # and tight_layout per frame cost more than the drawing)
    draw(0)
    fig.tight_layout(rect=(0.0, 0.05 if caption else 0.0, 1.0, 1.0))
    if caption:
        fig.text(0.5, 0.01, caption, ha="center", va="bottom", fontsize=8, color="0.25")
    animation = FuncAnimation(fig, draw, frames=len(frames), init_func=list, blit=False)
    with atomic_path(path) as tmp:
        animation.save(os.fspath(tmp), writer=PillowWriter(fps=fps), dpi=dpi)
    return len(frames)


__all__ = [
    "MAP_KEY",
    "STAGE_NAMES",
    "animate_trace",
    "draw_layers",
    "draw_progress",
    "draw_round",
    "plot_trace",
    "round_title",
    "rounds",
    "trace_of",
]
