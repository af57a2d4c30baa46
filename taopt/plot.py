"""Navigation plots: drift fields, minimum-time paths, Fig. 2.1 (matplotlib, Agg-safe).

Every function takes an optional ``ax``, returns the Axes (or Figure), and can
save a PNG. Other areas keep their plots in their own subpackages; the helpers shared by
every plot of taopt live here:

* :func:`check_output` — refuse an output file of the wrong kind before any work;
* :func:`legend_outside` — the legend right of (or below) the axes, never over the data;
* :func:`label_points` — ids (``t0``, ``v0``, ...) written next to points;
* :func:`place_labels` — the same, each label on the side where it covers the fewest others;
* :func:`dodge` — a small sideways shift per series, so equal values do not hide markers;
* :func:`schematic_layout` — 2-D positions for a problem given only by a cost matrix;
* :func:`save` — PNG with the outside legend kept in the picture;
* :func:`trace` — the rounds of a traced exact run (:mod:`taopt.trace`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.errors import OutputError
from taopt.fields import Field
from taopt.navigation.path import Path, as_field

Region = tuple[float, float, float, float]

#: Line styles and markers that tell methods apart without colour (a comparison plot gives
#: each method its own pair; ``method_style(name)`` picks it).
LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)))
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "h", "<", ">")
#: Looks of study labels that are not a registered method (a variant of one).
_VARIANT_STYLES = {"GA-memetic": (":", "p")}


def method_style(method: str, k: int = 0) -> dict[str, Any]:
    """Matplotlib keywords (``linestyle``, ``marker``) that identify ``method`` in black and white.

    A method keeps the style its registration declares (``register_method(..., style=)``),
    in every figure of taopt; any other gets the ``k``-th pair of ``LINESTYLES`` x
    ``MARKERS``.
    """
    from taopt.registry import method_style as registered_style

    fixed = registered_style(str(method)) or _VARIANT_STYLES.get(str(method))
    linestyle, marker = fixed or (LINESTYLES[k % len(LINESTYLES)], MARKERS[k % len(MARKERS)])
    return {"linestyle": linestyle, "marker": marker}


def dodge(k: int, count: int, span: float, share: float = 0.02) -> float:
    """Sideways shift of the ``k``-th of ``count`` overlaid series: ``share`` of ``span`` apart.

    Series that take equal values (two heuristics both at the optimum) would hide one
    another's markers; shifted by a few per cent of the axis (``span``, in data units),
    centred on the true x, each stays visible. Say so in the axis label or caption.
    """
    if count <= 1:
        return 0.0
    return (k - (count - 1) / 2.0) * share * span


def check_output(path: str | os.PathLike[str] | None, suffix: str, option: str) -> None:
    """Raise :class:`~taopt.errors.OutputError` unless ``path`` ends in ``suffix``.

    Called before any work starts, so a misspelt output file never wastes a solve.

    Parameters
    ----------
    path : path or None
        The output file (None: nothing asked, nothing checked).
    suffix : str
        ".png" or ".gif".
    option : str
        The option that named the file ("--plot"), for the message.

    Example
    -------
    >>> check_output("routes.png", ".png", "--plot")
    >>> check_output("routes.jpg", ".png", "--plot")
    Traceback (most recent call last):
    ...
    taopt.errors.OutputError: --plot routes.jpg: the file must end in .png (taopt writes PNG images here)
    """
    if path is None:
        return
    if not os.fspath(path).lower().endswith(suffix):
        kind = {".png": "PNG images", ".gif": "GIF animations"}.get(suffix, suffix)
        raise OutputError(
            f"{option} {os.fspath(path)}: the file must end in {suffix} (taopt writes {kind} here)"
        )
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    if not os.path.isdir(folder):
        raise OutputError(f"{option} {os.fspath(path)}: the folder {folder} does not exist")


def legend_outside(ax: Any, where: str = "right", **options: Any) -> Any:
    """A legend outside the axes, right of them (``where="right"``) or below (``"below"``).

    Keyword ``options`` go to ``Axes.legend`` (``handles``, ``ncol``, ...). Returns the
    Legend, or None when nothing has a label.
    """
    handles, labels = ax.get_legend_handles_labels()
    if not handles and "handles" not in options:
        return None
    options.setdefault("fontsize", 8)
    if where == "below":
        options.setdefault("ncol", 3)
        from matplotlib.transforms import offset_copy

        # 40 points under the axes: below the tick labels and the x label, whatever the size
        under = offset_copy(ax.transAxes, fig=ax.figure, y=-40, units="points")
        return ax.legend(
            loc="upper center",
            bbox_to_anchor=(0.5, 0.0),
            bbox_transform=under,
            borderaxespad=0.0,
            **options,
        )
    return ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **options)


def label_points(
    points: Any, names: Sequence[str], ax: Any, offset: tuple[float, float] = (4, 4), **style: Any
) -> list[Any]:
    """Write ``names[k]`` next to ``points[k]`` (offset in points); returns the Text artists."""
    style.setdefault("fontsize", 8)
    return [
        ax.annotate(
            str(name), (float(x), float(y)), textcoords="offset points", xytext=offset, **style
        )
        for name, (x, y) in zip(names, np.asarray(points, dtype=float), strict=True)
    ]


def place_labels(
    ax: Any,
    groups: Sequence[tuple[Any, Sequence[str], dict[str, Any]]],
    avoid: Any = None,
    distance: float = 5.0,
) -> list[Any]:
    """Write ids next to points, each on the side where it covers the fewest others.

    Greedy placement in display space: for each point in turn, eight candidate spots
    around it (``distance`` points away: upper right, lower right, ...) and eight three
    times as far (joined to the point by a thin leader line) are scored by the area the
    label's box would share with the boxes already placed plus a penalty for every marker
    (of ``groups`` and of ``avoid``) under it and a small one for the far ring; the least
    covered spot wins (ties: the first, upper right). Call it after everything is drawn and
    the limits are set; the axes' aspect is applied first. Cost: O(labels² x 16), numpy.

    Parameters
    ----------
    ax : matplotlib Axes
    groups : sequence of (points, names, style)
        ``(N, 2)`` positions in data units, their N labels and the ``annotate`` keywords
        (``fontsize``, ``color``, ...) for that group.
    avoid : (K, 2) array, optional
        Further markers that labels should not cover (e.g. unlabelled stops).
    distance : float
        Gap between a point and its label, in points.

    Returns
    -------
    list of matplotlib Text
        One per name, in the order given.
    """
    ax.apply_aspect()
    to_display = ax.transData.transform
    scale = ax.figure.dpi / 72.0  # display pixels per point
    anchors = [np.asarray(points, dtype=float).reshape(-1, 2) for points, _, _ in groups]
    markers = [to_display(a) for a in anchors if len(a)]
    if avoid is not None and len(avoid):
        markers.append(to_display(np.asarray(avoid, dtype=float).reshape(-1, 2)))
    marker_xy = np.vstack(markers) if markers else np.zeros((0, 2))
    # (dx, dy) unit directions and the matching text alignment, upper right first
    sides = [
        (1, 1, "left", "bottom"),
        (1, -1, "left", "top"),
        (-1, 1, "right", "bottom"),
        (-1, -1, "right", "top"),
        (1, 0, "left", "center"),
        (-1, 0, "right", "center"),
        (0, 1, "center", "bottom"),
        (0, -1, "center", "top"),
    ]
    placed: list[tuple[float, float, float, float]] = []
    texts = []
    for points, (_, names, style) in zip(anchors, groups, strict=True):
        style = {"fontsize": 8, "zorder": 7, **style}
        size = float(style["fontsize"]) * scale
        for (x, y), name in zip(points, names, strict=True):
            px, py = to_display([[x, y]])[0]
            width, height = 0.6 * size * len(str(name)), 1.0 * size
            best, best_score, best_box = (1, 1, "left", "bottom", 1.0), np.inf, None
            # the near ring first; a ring three times as far (with a leader line) costs a
            # little more, so a label leaves its point only to get out of a cluster
            for ring, cost in ((1.0, 0.0), (3.0, 0.15 * width * height)):
                for dx, dy, ha, va in sides:
                    gap = ring * distance * scale / (np.sqrt(2.0) if dx and dy else 1.0)
                    left = px + dx * gap - {"left": 0.0, "right": width, "center": width / 2}[ha]
                    bottom = (
                        py + dy * gap - {"bottom": 0.0, "top": height, "center": height / 2}[va]
                    )
                    box = (left, bottom, left + width, bottom + height)
                    score = cost
                    if placed:
                        boxes = np.asarray(placed)
                        wide = np.minimum(box[2], boxes[:, 2]) - np.maximum(box[0], boxes[:, 0])
                        high = np.minimum(box[3], boxes[:, 3]) - np.maximum(box[1], boxes[:, 1])
                        score += float(np.sum(np.clip(wide, 0, None) * np.clip(high, 0, None)))
                    inside = (
                        (marker_xy[:, 0] > box[0] - 2 * scale)
                        & (marker_xy[:, 0] < box[2] + 2 * scale)
                        & (marker_xy[:, 1] > box[1] - 2 * scale)
                        & (marker_xy[:, 1] < box[3] + 2 * scale)
                    )
                    score += float(inside.sum()) * width * height / 4
                    if score < best_score - 1e-9:
                        best, best_score, best_box = (dx, dy, ha, va, ring), score, box
            dx, dy, ha, va, ring = best
            gap = ring * distance / (np.sqrt(2.0) if dx and dy else 1.0)
            if best_box is not None:  # every candidate scores below inf: always set
                placed.append(best_box)
            leader = {"arrowstyle": "-", "lw": 0.5, "color": style.get("color", "0.3")}
            texts.append(
                ax.annotate(
                    str(name),
                    (float(x), float(y)),
                    textcoords="offset points",
                    xytext=(dx * gap, dy * gap),
                    ha=ha,
                    va=va,
                    arrowprops=leader if ring > 1 else None,
                    **style,
                )
            )
    return texts


def schematic_layout(cost: Any, seed: int = 0) -> np.ndarray:
    """2-D positions whose distances approximate a cost matrix (classical MDS).

    For problems given only by a matrix: the symmetric part ``(C + C^T) / 2`` (infinite
    entries replaced by the largest finite one) is embedded by Torgerson's classical
    multidimensional scaling (the two leading eigenvectors of the double-centred squared
    distances). The picture is a schematic: asymmetry and triangle-inequality violations
    are lost, and its axes are in the matrix's units, not positions.

    Returns
    -------
    (N, 2) ndarray
    """
    c = np.array(cost, dtype=float)
    finite = np.isfinite(c) & (c >= 0)
    fill = float(c[finite].max()) if finite.any() else 1.0
    c = np.where(finite, c, fill)
    d = (c + c.T) / 2.0
    np.fill_diagonal(d, 0.0)
    n = len(d)
    centring = np.eye(n) - np.ones((n, n)) / n
    gram = -0.5 * centring @ (d**2) @ centring
    values, vectors = np.linalg.eigh(gram)
    top = np.argsort(values)[::-1][:2]
    xy = vectors[:, top] * np.sqrt(np.clip(values[top], 0.0, None))
    if xy.shape[1] < 2:
        xy = np.column_stack([xy, np.zeros(n)])
    if not np.any(np.abs(xy) > 1e-12):  # all points equal: spread them on a circle
        angle = 2 * np.pi * np.arange(n) / max(n, 1)
        xy = np.column_stack([np.cos(angle), np.sin(angle)]) * fill
    return xy


def _axes(ax: Any = None, figsize: tuple[float, float] = (6.0, 6.0)) -> Any:
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    # a bare Figure (no pyplot state): safe on any backend and in worker threads
    fig = Figure(figsize=figsize)
    return fig.add_subplot()


def plot_field(
    field: Field | None, region: Region, ax: Any = None, density: int = 15, color: str = "0.6"
) -> Any:
    """Quiver plot of the drift ``v_c`` on a ``density`` x ``density`` grid of ``region``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    field = as_field(field)
    ax = _axes(ax)
    xmin, xmax, ymin, ymax = region
    gx, gy = np.meshgrid(np.linspace(xmin, xmax, density), np.linspace(ymin, ymax, density))
    vel = field.velocity(np.column_stack([gx.ravel(), gy.ravel()]))
    ax.quiver(
        gx, gy, vel[:, 0].reshape(gx.shape), vel[:, 1].reshape(gx.shape), color=color, alpha=0.8
    )
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return ax


def plot_paths(
    field: Field | None,
    paths: Sequence[Path] | Path,
    region: Region | None = None,
    ax: Any = None,
    labels: Sequence[str] | None = None,
    headings: bool = True,
) -> Any:
    """Paths over the field's quiver; optional heading arrows (the thrust direction psi).

    Starts are small filled dots drawn over the goals, large open squares, so in a round
    trip (i -> j, j -> i: each start is the other path's goal) both show. Axes in metres.

    ``region`` defaults to the paths' bounding box grown by 10 %.
    """
    if isinstance(paths, Path):
        paths = [paths]
    ax = _axes(ax)
    if region is None:
        pts = np.vstack([p.xy for p in paths])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        pad = 0.1 * max(float(np.max(hi - lo)), 1.0)
        region = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    plot_field(field, region, ax=ax)
    colors = ["tab:blue", "tab:red", "tab:green", "tab:orange", "tab:purple", "tab:brown"]
    for k, path in enumerate(paths):
        color = colors[k % len(colors)]
        label = labels[k] if labels is not None else f"t = {path.time:.2f} s ({path.method})"
        ax.plot(path.xy[:, 0], path.xy[:, 1], "-", color=color, lw=2, label=label)
        # a round trip starts where the other path ends: the goal is a large open square
        # under, the start a small filled dot over it, so both stay visible
        ax.plot(*path.goal, "s", color=color, ms=12, mfc="none", mew=1.8, zorder=4, gid="goal")
        ax.plot(*path.start, "o", color=color, ms=6, mec="white", zorder=5, gid="start")
        if headings and len(path.xy) > 2:
            step = max(1, len(path.xy) // 8)
            sel = slice(0, None, step)
            ax.quiver(
                path.xy[sel, 0],
                path.xy[sel, 1],
                np.cos(path.heading[sel]),
                np.sin(path.heading[sel]),
                color=color,
                width=0.004,
                alpha=0.6,
            )
    ax.plot([], [], "o", color="0.3", ms=6, mec="white", label="start")
    ax.plot([], [], "s", color="0.3", ms=12, mfc="none", mew=1.8, label="goal")
    if not ax.get_title():
        speeds = ", ".join(sorted({f"{p.speed:g}" for p in paths}))
        ax.set_title(f"minimum-time paths in the drift field, speed {speeds} m/s", fontsize=10)
    legend_outside(ax, "below", ncol=2)
    return ax


def plot_points(
    points: np.ndarray,
    n_targets: int,
    ax: Any,
    labels: bool = True,
    names: Sequence[str] | None = None,
) -> Any:
    """Targets (squares) and vehicle starts (triangles), thesis order (targets first).

    ``names`` label the points (default ``t0, t1, ...`` for targets and ``v0, v1, ...`` for
    vehicles, as ``taopt demo`` and the route tables print them).
    """
    points = np.asarray(points, dtype=float)
    if names is None:
        names = [f"t{k}" for k in range(n_targets)]
        names += [f"v{k}" for k in range(len(points) - n_targets)]
    ax.plot(points[:n_targets, 0], points[:n_targets, 1], "s", color="tab:red", label="targets")
    ax.plot(
        points[n_targets:, 0], points[n_targets:, 1], "^", color="tab:blue", ms=9, label="vehicles"
    )
    if labels:
        label_points(points, names, ax)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    legend_outside(ax)
    return ax


def save(ax_or_fig: Any, path_out: str | os.PathLike[str], dpi: int = 120) -> None:
    """Save the figure of an Axes (or a Figure) as PNG, atomically (:func:`taopt.io.atomic_path`:
    a failed write leaves no partial file and raises an OutputError naming ``path_out``)."""
    from taopt.io import atomic_path

    fig = getattr(ax_or_fig, "figure", ax_or_fig)
    fig.tight_layout()
    # "tight" keeps a legend placed outside the axes inside the picture
    with atomic_path(path_out) as tmp:
        fig.savefig(os.fspath(tmp), dpi=dpi, bbox_inches="tight")


def figure_2_1(
    path_out: str | os.PathLike[str] | None = None,
    point_1: Sequence[float] = (10.0, 80.0),
    point_2: Sequence[float] = (90.0, 15.0),
    speed: float = 1.0,
    method: str = "collocation",
) -> Any:
    """Fig. 2.1 style: the optimal paths 1 -> 2 and 2 -> 1 in the 1e-2 field on a 100 m square.

    The thesis reports t(1, 2) = 73.0058 s and t(2, 1) = 103.3586 s but not its
    points; the default points here are our own, chosen to show the asymmetry.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from taopt.fields import thesis_field
    from taopt.navigation import min_time_path

    field = thesis_field(1e-2)
    grid = {"intervals": 16} if method == "collocation" else {}
    forward = min_time_path(field, point_1, point_2, speed, method, **grid)
    backward = min_time_path(field, point_2, point_1, speed, method, **grid)
    ax = _axes(None)
    plot_paths(
        field,
        [forward, backward],
        region=(0.0, 100.0, 0.0, 100.0),
        ax=ax,
        labels=[
            f"1 -> 2: t(1,2) = {forward.time:.4f} s",
            f"2 -> 1: t(2,1) = {backward.time:.4f} s",
        ],
    )
    for name, p in (("1", point_1), ("2", point_2)):
        ax.annotate(name, p, textcoords="offset points", xytext=(6, 6), fontsize=12)
    ax.set_title("Minimum-time paths in $v_c = 10^{-2}[0.3x+0.2y, -0.2x+0.3y]$, v = 1")
    if path_out is not None:
        save(ax, path_out)
    return ax.figure


def trace(
    solution: Any,
    problem: Any = None,
    path: str | os.PathLike[str] | None = None,
    instance: Any = None,
    which: Sequence[int] | None = None,
    columns: int = 3,
) -> Any:
    """Draw the trace of a run solved with ``trace=True``: :func:`taopt.trace.plot_trace`.

    The DFJ cut loop of chapter 2 one panel per round (each round's fractional arcs on the
    map of targets, the violated sets S of (2.5) shaded, then value and bound per round);
    the ideal DP of chapter 5 as states per layer and bound vs layer. The GIF, one frame
    per round, is :func:`taopt.trace.animate_trace` (``taopt solve FILE --trace X.gif``).
    """
    from taopt.trace import plot_trace

    return plot_trace(solution, problem, path, instance=instance, which=which, columns=columns)
