"""The embedded demo: the default instance solved exactly and by every chapter 2 heuristic.

``taopt demo`` calls :func:`run_demo`: the embedded instance (10 targets, 3 vehicles in the
thesis's drift field), its travel-time matrix by CasADi collocation with Lemma 2.3's checks, the
certified optimum of (2.2)-(2.5), and the gap table of VN, VM, EVN, EVM, MC and the GA against it.
"""

from __future__ import annotations

import sys
import time
from importlib import resources
from typing import IO, Any

import numpy as np

from taopt.instance import Instance
from taopt.orchestration.solving import method_table, wrap_notes
from taopt.routing.problem import AssignmentProblem


def load_demo_instance() -> Instance:
    """The embedded default: 10 targets, 3 vehicles, the thesis's 1e-3 field, 1000 m square.

    Generated once by ``Instance.random(10, 3, side=1000.0, field=thesis_field(1e-3), seed=2021)``
    and shipped as ``taopt/data/demo.json``.
    """
    text = resources.files("taopt").joinpath("data/demo.json").read_text()
    import json

    return Instance.from_dict(json.loads(text))


def format_matrix(
    matrix: np.ndarray, names: list[str], digits: int = 1, line_width: int | None = None
) -> str:
    """A plain-text table of ``matrix`` with row/column names; with ``line_width``, its
    columns are split into blocks (separated by a blank line) so no line is wider."""
    width = max(max(len(n) for n in names), len(f"{matrix.max():.{digits}f}")) + 1
    per_block = len(names)
    if line_width is not None:
        per_block = max(1, (line_width - width) // width)
    blocks = []
    for start in range(0, len(names), per_block):
        columns = range(start, min(start + per_block, len(names)))
        head = " " * width + "".join(f"{names[j]:>{width}}" for j in columns)
        rows = [
            f"{names[i]:>{width}}" + "".join(f"{matrix[i, j]:>{width}.{digits}f}" for j in columns)
            for i in range(len(names))
        ]
        blocks.append("\n".join([head, *rows]))
    return "\n\n".join(blocks)


def run_demo(
    plot: str | None = None,
    out: IO[str] | None = None,
    progress: bool = True,
    methods: tuple[str, ...] | None = None,
    seed: int = 0,
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
        ``instance``, ``matrix`` (N, N), ``report`` (MatrixReport), ``seconds`` (matrix time),
        ``problem`` (AssignmentProblem), ``table`` (gap table, DataFrame), ``solutions``.
    """
    from taopt.navigation import travel_time_matrix
    from taopt.navigation.checks import matrix_report

    out = out or sys.stdout
    methods = DEMO_METHODS if methods is None else tuple(methods)
    instance = load_demo_instance()
    speed = float(instance.speeds.min())
    print(
        f"instance {instance.name!r}: {instance.n_targets} targets, "
        f"{instance.n_vehicles} vehicles, region {instance.region},\n"
        f"field {instance.field!r}, speed {speed:g}",
        file=out,
    )
    tic = time.perf_counter()
    matrix = travel_time_matrix(instance.field, instance.points, speed, progress=progress)
    seconds = time.perf_counter() - tic
    names = [t.id for t in instance.targets] + [v.id for v in instance.vehicles]
    print(
        f"\ntravel-time matrix t(i, j) in seconds (row i -> column j), {seconds:.2f} s:", file=out
    )
    from taopt.orchestration.cli import terminal_width

    print(format_matrix(matrix, names, line_width=terminal_width()), file=out)
    report = matrix_report(matrix)
    print("\n" + "\n".join(wrap_notes([report.summary()])), file=out)
    print(f"Lemma 2.3 triangle inequality within 1e-6: {report.triangle_holds(1e-6)}", file=out)

    problem = AssignmentProblem(matrix, n_targets=instance.n_targets, name=instance.name)
    table, solutions = method_table(problem, methods=methods, seed=seed)
    print(
        "\nexact optimum against the thesis's heuristics (objective: total travel time, s):",
        file=out,
    )
    text = table.to_string(
        index=False, float_format=lambda v: f"{v:.4g}", line_width=terminal_width()
    )
    print(text, file=out)
    exact = solutions.get("exact")
    if exact is not None:
        print(f"\n{exact.summary()}", file=out)
        for vehicle, route in enumerate(exact.routes or []):
            names_route = " -> ".join(
                [instance.vehicles[vehicle].id] + [instance.targets[t].id for t in route]
            )
            print(f"  vehicle {instance.vehicles[vehicle].id}: {names_route}", file=out)
    if plot is not None:
        from taopt.routing.plot import plot_instance_routes

        best = exact if exact is not None else min(solutions.values(), key=lambda s: s.objective)
        plot_instance_routes(
            instance,
            best.routes or [],
            title=f"{instance.name}: {best.method} routes, total travel time {best.objective:.1f} s",
            path=plot,
        )
        print(f"plot written to {plot}", file=out)
    return {
        "instance": instance,
        "matrix": matrix,
        "report": report,
        "seconds": seconds,
        "problem": problem,
        "table": table,
        "solutions": solutions,
    }


DEMO_METHODS = ("exact", "VN", "VM", "EVN", "EVM", "MC", "GA")
