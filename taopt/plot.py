"""Navigation plots: drift fields, minimum-time paths, Fig. 2.1 (matplotlib, Agg-safe).

Every function takes an optional ``ax``, returns the Axes (or Figure), and can
save a PNG. Other areas keep their plots in their own subpackages.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.fields import Field
from taopt.navigation.path import Path, as_field

Region = tuple[float, float, float, float]


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
        ax.plot(*path.start, "o", color=color)
        ax.plot(*path.goal, "s", color=color)
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
    ax.legend(loc="best", fontsize=8)
    return ax


def plot_points(points: np.ndarray, n_targets: int, ax: Any, labels: bool = True) -> Any:
    """Targets (squares, 0..n-1) and vehicle starts (triangles, n..), thesis order."""
    points = np.asarray(points, dtype=float)
    ax.plot(points[:n_targets, 0], points[:n_targets, 1], "s", color="tab:red", label="targets")
    ax.plot(
        points[n_targets:, 0], points[n_targets:, 1], "^", color="tab:blue", ms=9, label="vehicles"
    )
    if labels:
        for k, (x, y) in enumerate(points):
            ax.annotate(str(k), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.legend(loc="best", fontsize=8)
    return ax


def save(ax_or_fig: Any, path_out: str | os.PathLike[str], dpi: int = 120) -> None:
    """Save the figure of an Axes (or a Figure) as PNG."""
    fig = getattr(ax_or_fig, "figure", ax_or_fig)
    fig.tight_layout()
    fig.savefig(os.fspath(path_out), dpi=dpi)


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
