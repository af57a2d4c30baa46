"""Command line: ``taopt navigate``, ``taopt demo`` (more subcommands are added by other areas).

Each subcommand is registered in :func:`build_parser` with its own handler
``handler(args) -> int``; :func:`main` turns any :class:`~taopt.errors.TaoptError`
or bad value into a one-line error on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path as FilePath

import numpy as np

from taopt.errors import InstanceError, TaoptError
from taopt.fields import Field, LinearField, UniformField, field_from_dict, thesis_field

FIELD_HELP = (
    "drift field: 'thesis' (1e-3 [0.3x+0.2y, -0.2x+0.3y]), 'fig21' (the same at 1e-2), "
    "'still', 'uniform:VX,VY', 'linear:A11,A12,A21,A22', or a JSON file holding a field "
    "or an instance (its field is used)"
)


def parse_numbers(text: str, count: int, what: str) -> list[float]:
    """``"1,2"`` -> ``[1.0, 2.0]``; :class:`InstanceError` naming ``what`` otherwise."""
    parts = [p for p in text.replace(" ", "").split(",") if p != ""]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise InstanceError(
            f"{what}: expected {count} comma-separated numbers, got {text!r}"
        ) from None
    if len(values) != count or not all(np.isfinite(values)):
        raise InstanceError(
            f"{what}: expected {count} comma-separated finite numbers, got {text!r}"
        )
    return values


def parse_field(spec: str) -> Field | None:
    """Field from a command-line SPEC (see ``FIELD_HELP``)."""
    key = spec.strip()
    lower = key.lower()
    if lower == "thesis":
        return thesis_field(1e-3)
    if lower == "fig21":
        return thesis_field(1e-2)
    if lower in ("still", "none"):
        return None
    if lower.startswith("uniform:"):
        vx, vy = parse_numbers(key.split(":", 1)[1], 2, "uniform field")
        return UniformField(vx, vy)
    if lower.startswith("linear:"):
        a = parse_numbers(key.split(":", 1)[1], 4, "linear field")
        return LinearField(np.reshape(a, (2, 2)))
    path = FilePath(key)
    if path.suffix.lower() == ".json" or path.exists():
        if not path.exists():
            raise InstanceError(f"field file {key!r} does not exist")
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise InstanceError(f"{key}: not valid JSON ({exc})") from None
        if isinstance(data, dict) and data.get("kind") == "instance":
            from taopt.instance import Instance

            return Instance.from_dict(data).field
        if isinstance(data, dict) and "field" in data and "kind" not in data:
            return None if data["field"] is None else field_from_dict(data["field"])
        return field_from_dict(data)
    raise InstanceError(f"unknown field {spec!r}; {FIELD_HELP}")


# -- subcommands -------------------------------------------------------------------------------


def cmd_navigate(args: argparse.Namespace) -> int:
    """Minimum travel times both ways between two points, t(i, j) and t(j, i)."""
    from taopt.navigation import min_time_path

    field = parse_field(args.field)
    start = parse_numbers(args.start, 2, "--from")
    goal = parse_numbers(args.goal, 2, "--to")
    # a finer grid when drawing, so the plotted path is smooth (times agree to ~1e-9)
    grid = {"intervals": 16} if args.plot and args.method == "collocation" else {}
    forward = min_time_path(field, start, goal, args.speed, args.method, **grid)
    backward = min_time_path(field, goal, start, args.speed, args.method, **grid)
    print(f"field: {field!r}  speed: {args.speed:g}  method: {args.method}")
    print(
        f"t(i, j) = {forward.time:.6f} s   from {tuple(start)} to {tuple(goal)}  [{forward.status}]"
    )
    print(
        f"t(j, i) = {backward.time:.6f} s   from {tuple(goal)} to {tuple(start)}  "
        f"[{backward.status}]"
    )
    if forward.time > 0:
        ratio = backward.time / forward.time
        print(f"asymmetry t(j, i) / t(i, j) = {ratio:.6f}")
    if args.plot:
        from taopt.plot import plot_paths, save

        ax = plot_paths(
            field,
            [forward, backward],
            labels=[f"i -> j: {forward.time:.3f} s", f"j -> i: {backward.time:.3f} s"],
        )
        save(ax, args.plot)
        print(f"plot written to {args.plot}")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """Travel-time matrix of the embedded default instance and its Lemma 2.3 report."""
    from taopt.demo import run_demo

    run_demo(plot=args.plot, progress=not args.quiet)
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``taopt`` parser; add subcommands with ``parser._subcommands.add_parser`` or
    :func:`add_subcommand`."""
    parser = argparse.ArgumentParser(
        prog="taopt",
        description="Cooperative multi-vehicle task assignment in drift fields (thesis toolkit).",
    )
    from taopt import __version__

    parser.add_argument("--version", action="version", version=f"taopt {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    parser._subcommands = sub  # type: ignore[attr-defined]

    nav = add_subcommand(
        parser, "navigate", cmd_navigate, "minimum travel times t(i, j) and t(j, i)"
    )
    nav.add_argument("--field", default="thesis", metavar="SPEC", help=FIELD_HELP)
    nav.add_argument("--from", dest="start", required=True, metavar="X,Y", help="point i")
    nav.add_argument("--to", dest="goal", required=True, metavar="X,Y", help="point j")
    nav.add_argument("--speed", type=float, default=1.0, help="vehicle speed v (default 1)")
    nav.add_argument(
        "--method",
        choices=["collocation", "shooting", "closed_form"],
        default="collocation",
        help="solver",
    )
    nav.add_argument("--plot", metavar="PNG", help="draw both paths to this PNG file")

    demo = add_subcommand(parser, "demo", cmd_demo, "run the embedded default instance")
    demo.add_argument("--plot", metavar="PNG", help="draw the instance to this PNG file")
    demo.add_argument("--quiet", action="store_true", help="no progress bar")

    add_study_subcommands(parser)

    solve = add_subcommand(
        parser, "solve", cmd_solve, "solve an instance file exactly and with every heuristic"
    )
    solve.add_argument(
        "file", help="JSON: an instance, an assignment_problem or a delivery_instance"
    )
    solve.add_argument("--methods", default=None, help="comma list (default: all that apply)")
    solve.add_argument("--seed", type=int, default=0)
    solve.add_argument("--time-limit", type=float, default=60.0, help="seconds for a MILP")
    solve.add_argument("--plot", metavar="PNG", help="draw the best solution")
    solve.add_argument("--gantt", metavar="PNG", help="chapter 5: truck and drone timelines")
    solve.add_argument("--quiet", action="store_true", help="no progress bar")

    claims = add_subcommand(
        parser, "claims", cmd_claims, "check chapter 2's lemmas and theorems on random instances"
    )
    claims.add_argument("--samples", type=int, default=200, help="instances per class")
    claims.add_argument("--seed", type=int, default=0)
    claims.add_argument(
        "--out", default=None, help="folder for the smallest counterexamples (JSON)"
    )
    claims.add_argument(
        "--classes",
        default="euclidean,uniform-drift,drift,metric",
        help="comma list of instance classes",
    )
    return parser


def cmd_solve(args: argparse.Namespace) -> int:
    """Solve an instance file (chapter 2 or chapter 5) and print the gap table."""
    from taopt.solve import solve_file

    methods = None
    if args.methods:
        methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    solve_file(
        args.file,
        methods=methods,
        seed=args.seed,
        time_limit=args.time_limit,
        plot=args.plot,
        gantt=args.gantt,
        progress=not args.quiet,
    )
    return 0


def cmd_claims(args: argparse.Namespace) -> int:
    """Run :func:`taopt.routing.claims.check_claims` and print how often each claim holds."""
    from taopt.routing.claims import check_claims

    table = check_claims(
        samples=args.samples,
        seed=args.seed,
        out_dir=args.out,
        classes=tuple(c.strip() for c in args.classes.split(",") if c.strip()),
    )
    shown = [c for c in table.columns if c not in ("instance",)]
    print(table[shown].to_string(index=False))
    return 0


def add_study_subcommands(parser: argparse.ArgumentParser) -> None:
    """``taopt study drift`` (chapter 2, §2.5) and ``taopt study delivery`` (chapter 5, §5.5)."""
    from taopt.delivery.study import register_cli as register_delivery
    from taopt.routing.study import register_cli as register_drift

    study = add_subcommand(parser, "study", None, "run a thesis study (chapter 2 or chapter 5)")
    group = study.add_subparsers(dest="study", metavar="STUDY")
    group.required = True
    drift = register_drift(group)
    drift.set_defaults(handler=lambda args: args.func(args))
    # The delivery study finds the "study" group created above and adds itself to it.
    register_delivery(parser._subcommands)  # type: ignore[attr-defined]


def add_subcommand(
    parser: argparse.ArgumentParser, name: str, handler, help_text: str
) -> argparse.ArgumentParser:
    """Register subcommand ``name`` handled by ``handler(args) -> int``; returns its parser."""
    sub = parser._subcommands  # type: ignore[attr-defined]
    child = sub.add_parser(name, help=help_text, description=help_text)
    child.set_defaults(handler=handler)
    return child


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``taopt`` script. Returns the exit code (2 on bad input)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse already printed usage and the error
        return int(exc.code or 0)
    try:
        return int(args.handler(args) or 0)
    except (TaoptError, ValueError, OSError) as exc:
        message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"taopt {args.command}: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
