"""The embedded demo: the default instance, its travel-time matrix and Lemma 2.3's checks.

``taopt demo`` calls :func:`run_demo`. The lead extends it to solve the instance.
"""

from __future__ import annotations

import sys
import time
from importlib import resources
from typing import IO, Any

import numpy as np

from taopt.instance import Instance


def load_demo_instance() -> Instance:
    """The embedded default: 10 targets, 3 vehicles, the thesis's 1e-3 field, 1000 m square.

    Generated once by ``Instance.random(10, 3, side=1000.0, field=thesis_field(1e-3), seed=2021)``
    and shipped as ``taopt/data/demo.json``.
    """
    text = resources.files("taopt").joinpath("data/demo.json").read_text()
    import json

    return Instance.from_dict(json.loads(text))


def format_matrix(matrix: np.ndarray, names: list[str], digits: int = 1) -> str:
    """A plain-text table of ``matrix`` with row/column names."""
    width = max(max(len(n) for n in names), len(f"{matrix.max():.{digits}f}")) + 1
    head = " " * width + "".join(f"{n:>{width}}" for n in names)
    rows = [
        f"{names[i]:>{width}}" + "".join(f"{v:>{width}.{digits}f}" for v in matrix[i])
        for i in range(len(names))
    ]
    return "\n".join([head, *rows])


def run_demo(
    plot: str | None = None, out: IO[str] = sys.stdout, progress: bool = True
) -> dict[str, Any]:
    """Travel-time matrix of the embedded instance, printed with its asymmetry/triangle report.

    Parameters
    ----------
    plot : str, optional
        PNG file for a picture of the instance and the field.
    out : text stream
        Where to print.
    progress : bool
        Show a progress bar (on stderr).

    Returns
    -------
    dict
        ``instance``, ``matrix`` (N, N), ``report`` (MatrixReport), ``seconds``.
    """
    from taopt.navigation import travel_time_matrix
    from taopt.navigation.checks import matrix_report

    instance = load_demo_instance()
    speed = float(instance.speeds.min())
    print(
        f"instance {instance.name!r}: {instance.n_targets} targets, "
        f"{instance.n_vehicles} vehicles, "
        f"region {instance.region}, field {instance.field!r}, speed {speed:g}",
        file=out,
    )
    tic = time.perf_counter()
    matrix = travel_time_matrix(instance.field, instance.points, speed, progress=progress)
    seconds = time.perf_counter() - tic
    names = [t.id for t in instance.targets] + [v.id for v in instance.vehicles]
    print(
        f"\ntravel-time matrix t(i, j) in seconds (row i -> column j), {seconds:.2f} s:", file=out
    )
    print(format_matrix(matrix, names), file=out)
    report = matrix_report(matrix)
    print("\n" + report.summary(), file=out)
    print(f"Lemma 2.3 triangle inequality within 1e-6: {report.triangle_holds(1e-6)}", file=out)
    if plot is not None:
        from taopt.plot import plot_field, plot_points, save

        ax = plot_field(instance.field, instance.region)
        plot_points(instance.points, instance.n_targets, ax)
        ax.set_title(
            f"{instance.name}: {instance.n_targets} targets, {instance.n_vehicles} vehicles"
        )
        save(ax, plot)
        print(f"plot written to {plot}", file=out)
    return {"instance": instance, "matrix": matrix, "report": report, "seconds": seconds}
