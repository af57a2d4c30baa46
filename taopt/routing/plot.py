"""Plots for chapter 2: routes drawn in the drift field, and the gap study's boxplot.

Example
-------
>>> import numpy as np
>>> ax = plot_routes(np.array([[0, 0], [1, 1], [2, 0.0]]), [[0, 1]])  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["plot_routes"]


def plot_routes(
    points: Any,
    routes: Sequence[Sequence[int]],
    field: Any = None,
    ax: Any = None,
    title: str = "",
    curved: bool = False,
    speed: float = 1.0,
    path: str | None = None,
) -> Any:
    """Draw one open route per vehicle over the drift field.

    Parameters
    ----------
    points : (n + m, 2) array_like
        Targets first, then the m vehicle starts (thesis order).
    routes : list of list of int
        One list of target indices per vehicle (``Solution.routes``).
    field : Field, optional
        Drawn as a quiver plot underneath.
    ax : matplotlib Axes, optional
    title : str
    curved : bool
        Draw each leg as its minimum-time path (``taopt.navigation.min_time_path``,
        one small solve per leg) instead of a straight arrow.
    speed : float
        Vehicle speed, for ``curved``.
    path : str, optional
        Save the figure as PNG there.

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt

    points = np.asarray(points, dtype=float)
    m = len(routes)
    n = len(points) - m
    if n < 0:
        raise ValueError(f"{len(points)} points cannot hold {m} vehicle starts")
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    low, high = points.min(axis=0), points.max(axis=0)
    pad = 0.05 * max(float((high - low).max()), 1e-9)
    if field is not None:
        gx, gy = np.meshgrid(
            np.linspace(low[0] - pad, high[0] + pad, 15),
            np.linspace(low[1] - pad, high[1] + pad, 15),
        )
        velocity = field.velocity(np.column_stack([gx.ravel(), gy.ravel()]))
        ax.quiver(
            gx,
            gy,
            velocity[:, 0].reshape(gx.shape),
            velocity[:, 1].reshape(gx.shape),
            color="0.75",
            width=0.003,
        )
    colours = plt.cm.tab10(np.arange(max(m, 1)) % 10)
    for k, route in enumerate(routes):
        nodes = [n + k, *route]
        for a, b in zip(nodes[:-1], nodes[1:], strict=False):
            if curved and field is not None:
                from taopt.navigation import min_time_path

                leg = min_time_path(field, points[a], points[b], speed=speed)
                ax.plot(leg.xy[:, 0], leg.xy[:, 1], color=colours[k], lw=1.5)
            else:
                ax.annotate(
                    "",
                    xy=points[b],
                    xytext=points[a],
                    arrowprops={"arrowstyle": "->", "color": colours[k], "lw": 1.5},
                )
    ax.scatter(points[:n, 0], points[:n, 1], s=18, color="black", zorder=3, label="targets")
    ax.scatter(
        points[n:, 0],
        points[n:, 1],
        s=70,
        marker="s",
        color=colours[:m],
        zorder=4,
        edgecolor="black",
        label="vehicle starts",
    )
    ax.set_aspect("equal")
    ax.set_xlim(low[0] - pad, high[0] + pad)
    ax.set_ylim(low[1] - pad, high[1] + pad)
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title)
    if path:
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    return ax
