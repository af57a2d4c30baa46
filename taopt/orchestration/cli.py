"""The ``taopt`` command line (the only module that uses argparse).

Subcommands: ``navigate``, ``demo``, ``solve``, ``verify``, ``claims``, ``simulate``, and
``study NAME`` (one per study a family declares). One grammar: the same flag means the same
thing, with the same default, in every command that has it:

``--seed`` (default 0), ``--methods`` (a comma list, case-insensitive, ``all`` for every
available method; ``exact`` is a method), ``--time-limit`` (seconds per exact or peer run,
default :data:`TIME_LIMIT`), ``--out`` (the output folder), ``--jobs`` and ``--dask``
(parallel work), ``--plot`` (a PNG), ``--quiet`` and ``-v`` (log level), ``--scenarios`` (a
count of scenarios in every study), ``--sizes`` (study sizes ``nNmM``). The defaults of
``--seed`` and ``--time-limit`` are the Python API's (:mod:`taopt.defaults`). Every option's
help shows its default. A file argument may be ``example:NAME`` (:mod:`taopt.examples`). Old
spellings (``solve --save``, ``study comm --exact``, ``study capability --instances SIZES``,
``study delivery --instances N``, ``study drift --n N --m M``, ``simulate --save``,
``simulate --algorithm``) still work for one release and print a deprecation line on stderr.

This module imports only the standard library and :mod:`taopt.errors` at the top, so
``taopt --version`` and ``taopt --help`` load no numpy, cvxpy or matplotlib; every handler
imports what it needs.

:func:`main` turns any :class:`~taopt.errors.TaoptError` or bad value into a one-line error
on stderr and exit code 2; Ctrl-C prints one line (``taopt solve: interrupted``; a study
says where its rows are) and exits with 130, no traceback: a HiGHS run stops through its
interrupt callbacks (:mod:`taopt.runtime.highs`), Python code between
bytecodes.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import logging

#: Seconds per exact model (or peer) run in ``solve``, ``verify`` and every study, and seed of
#: randomised methods in every command: :mod:`taopt.defaults`, shared with the Python API.
from taopt.defaults import SEED, TIME_LIMIT  # noqa: E402
from taopt.errors import InstanceError, TaoptError

#: The packaged examples (:mod:`taopt.examples`), named in the help texts.
EXAMPLES_TEXT = (
    "assignment_problem, budgeted_problem, capability_problem, comm_problem, "
    "delivery_instance, sop_problem, instance, field, solution, demo (an instance, 10 "
    "targets), delivery_example_20 (20 customers)"
)

FIELD_HELP = (
    "drift field: 'thesis' (1e-3 [0.3x+0.2y, -0.2x+0.3y]), 'fig21' (the same at 1e-2), "
    "'still', 'uniform:VX,VY', 'linear:A11,A12,A21,A22', or a JSON file holding a field "
    "or an instance (its field is used), e.g. example:field"
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
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InstanceError(
            f"{what}: expected {count} comma-separated finite numbers, got {text!r}"
        )
    return values


def parse_field(spec: str) -> Any:
    """Field from a command-line SPEC (see ``FIELD_HELP``); None for a still medium."""
    import numpy as np

    from taopt.fields import LinearField, UniformField, field_from_dict, thesis_field

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
    from pathlib import Path

    from taopt.examples import resolve

    path = Path(resolve(key))
    if path.suffix.lower() == ".json" or path.exists():
        if not path.exists():
            raise InstanceError(f"field file {key!r} does not exist")
        from taopt.io import load_json
        from taopt.schemas import naming

        data = load_json(path)  # the one reader: size and depth guards, errors name the file
        with naming(str(path)):
            if isinstance(data, dict) and data.get("kind") == "instance":
                from taopt.instance import Instance

                return Instance.from_dict(data, source=str(path)).field
            if isinstance(data, dict) and "field" in data and "kind" not in data:
                return None if data["field"] is None else field_from_dict(data["field"])
            return field_from_dict(data)
    raise InstanceError(f"unknown field {spec!r}; {FIELD_HELP}")


def terminal_width() -> int:
    """Columns of the terminal (``COLUMNS``, else 100 when not a terminal): printed tables are
    wrapped to it (pandas' ``line_width``)."""
    import shutil

    return shutil.get_terminal_size((100, 24)).columns


def folder(path: str) -> Any:
    """``pathlib.Path(path)``, imported when a command writes files (not for ``--version``)."""
    from pathlib import Path

    return Path(path)


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
        print(f"asymmetry t(j, i) / t(i, j) = {backward.time / forward.time:.6f}")
    if args.plot:
        from taopt.plot import plot_paths, save

        ax = plot_paths(
            field,
            [forward, backward],
            labels=[f"i -> j: {forward.time:.3f} s", f"j -> i: {backward.time:.3f} s"],
        )
        ax.set_title(f"minimum-time paths i <-> j, speed {args.speed:g} m/s ({args.method})")
        save(ax, args.plot)
        print(f"plot written to {args.plot}")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """The embedded instance: matrix, exact optimum and every chapter 2 heuristic."""
    from taopt.orchestration.demo import run_demo

    run_demo(plot=args.plot, progress=not args.quiet, seed=args.seed)
    return 0


def method_list(text: str | None) -> tuple[str, ...] | None:
    if not text:
        return None
    methods = tuple(dict.fromkeys(m.strip() for m in text.split(",") if m.strip()))
    if not methods:
        raise InstanceError(f"--methods: no method names in {text!r}")
    return methods


def cmd_solve(args: argparse.Namespace) -> int:
    """Solve a problem file with every (or the named) method and print the gap table.

    Exit code 1 when some method failed (its row says "error" and why), 0 otherwise.
    """
    from taopt.orchestration.solving import solve_file

    result = solve_file(
        args.file,
        methods=method_list(args.methods),
        seed=args.seed,
        time_limit=args.time_limit,
        plot=args.plot,
        gantt=args.gantt,
        save=args.out,
        progress=not args.quiet,
        trace=args.trace,
    )
    return 1 if result["failed"] else 0


def cmd_export(args: argparse.Namespace) -> int:
    """Write one of the toolkit's MILPs of a problem file as LP or MPS (thesis names)."""
    from taopt.orchestration.export import export
    from taopt.orchestration.solving import load_problem_file

    problem, _ = load_problem_file(args.file, progress=not args.quiet)
    path = export(problem, args.model, args.out, format=args.format)
    print(f"wrote {path} ({args.model}, {args.format or path.suffix.lstrip('.')})")
    return 0


def cmd_verify(args: argparse.Namespace) -> int:
    """Re-check a saved solution from the problem file alone (exit codes in the help)."""
    from taopt.orchestration.solving import verify_file

    verdict = verify_file(args.solution, args.problem, exact=args.exact, time_limit=args.time_limit)
    return verdict.exit_code


def cmd_kinds(args: argparse.Namespace) -> int:
    """Body of ``taopt kinds``: every problem family's file kind, from its spec."""
    from taopt.orchestration.pipeline import available_methods, register_methods
    from taopt.registry import families

    register_methods()

    for family in sorted(families(), key=lambda f: f.kind):
        bounds = ", ".join(
            f"{name} ({'valid' if b.valid else 'as printed'} {b.side})"
            for name, b in family.bounds.items()
        )
        print(f"{family.kind}: {family.title}")
        print(f"  problem {family.problem_type.__name__}, payload {family.payload.__name__}")
        print(
            f"  schema taopt/schemas/{family.kind}.schema.json, example example:{family.kind} "
            f"(taopt solve example:{family.kind})"
        )
        print(f"  bounds: {bounds or 'none'}")
        print(f"  methods: {', '.join(available_methods(family.problem_type))}")
        if family.studies:
            print(f"  studies: {', '.join('taopt study ' + s.name for s in family.studies)}")
    return 0


def cmd_claims(args: argparse.Namespace) -> int:
    """Check chapter 2's lemmas and theorems on random instances."""
    from taopt.orchestration.studies.routing_claims import check_claims

    if args.samples < 1:
        raise InstanceError(f"--samples must be >= 1, got {args.samples}")
    from tqdm.auto import tqdm

    classes = tuple(c.strip() for c in args.classes.split(",") if c.strip())
    with tqdm(
        total=args.samples * len(classes), unit="instance", disable=args.quiet, leave=False
    ) as bar:
        table = check_claims(
            samples=args.samples,
            seed=args.seed,
            out_dir=args.out,
            classes=classes,
            progress=lambda _: bar.update(),
        )
    shown = [c for c in table.columns if c not in ("instance",)]
    print(table[shown].to_string(index=False, line_width=terminal_width()))
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    """Body of ``taopt simulate FILE``: chapter 4 runs, their bytes, routes and pictures."""
    from taopt.comm import CommProblem
    from taopt.comm.plot import animate_run, check_frames, plot_run
    from taopt.examples import resolve
    from taopt.orchestration.pipeline import register_methods, solve
    from taopt.registry import get_method

    register_methods()

    if args.animate:
        check_frames(args.frames)  # before the run: nothing printed or written on bad input
    problem = CommProblem.load(resolve(args.file))
    if args.range is not None:
        problem = problem.replace(comm_range=args.range)
    names = list(
        dict.fromkeys(get_method(problem, m).name for m in method_list(args.methods) or ("DAA",))
    )
    bad = [m for m in names if get_method(problem, m).category != "simulation"]
    if bad:
        raise InstanceError(
            f"--methods: {', '.join(bad)} is not a simulation; simulate runs DAA, CAA or HDA "
            "(taopt solve runs the exact model)"
        )
    single = [o for o in ("plot", "animate", "save_file") if getattr(args, o, None)]
    if len(names) > 1 and single:
        raise InstanceError(
            f"--{single[0].replace('_file', '')} draws or saves one run: name one method"
        )
    where = None
    if args.out:
        from taopt.io import check_writable

        where = check_writable(args.out, "--out folder")
    for name in names:
        result = solve(problem, name, seed=args.seed)
        info = result.info
        print(result.summary())
        print(
            f"r = {problem.comm_range:g} m, bytes relayed {info['bytes']:.6g} "
            f"({info['numbers']} numbers, {info['messages']} messages, {info['rounds']} rounds), "
            f"{info['group_events']} newly connected groups, {info['replans']} reassignments"
        )
        for j, d in enumerate(result.solution.lengths()):
            print(f"  vehicle {j}: {d:.2f} m, visits {result.solution.visited_targets(j)}")
        if where is not None:
            result.save(where / f"{name}.json")
            print(f"solution written to {where / f'{name}.json'}")
        if args.save_file:
            result.save(args.save_file)
            print(f"solution written to {args.save_file}")
        if args.plot:
            plot_run(problem, result, path=args.plot)
            print(f"plot written to {args.plot}")
        if args.animate:
            animate_run(problem, result, args.animate, frames=args.frames)
            print(f"animation written to {args.animate}")
    return 0


# -- one grammar: shared flags, defaults in every help, deprecated spellings --------------------


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Keeps descriptions' line breaks and shows every option's default.

    A required option gets "(required: no default)". An option whose help already says
    "default" is left as written (that is how options whose default is None say what
    happens then: "default: none (...)"); any other option with a value gets
    "(default: VALUE)", an on/off flag "(default: off)".
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if not action.option_strings or action.default is argparse.SUPPRESS:
            return text
        if action.required:
            return f"{text} (required: no default)"
        if "default" in text or action.default is None:
            return text
        if action.nargs == 0 and action.default is False:
            return f"{text} (default: off)"
        return f"{text} (default: %(default)s)"


class _Deprecated(argparse.Action):
    """An old spelling kept for one release: warns on stderr, then acts as its replacement."""

    def __init__(self, option_strings: list[str], dest: str, replacement: str, **kwargs: Any):
        kwargs.setdefault("help", argparse.SUPPRESS)
        super().__init__(option_strings, dest, **kwargs)
        self.replacement = replacement

    def __call__(self, parser: Any, namespace: Any, values: Any, option_string: Any = None) -> None:
        print(
            f"taopt: DeprecationWarning: {option_string} is deprecated and will be removed in "
            f"the next release; use {self.replacement}",
            file=sys.stderr,
        )
        setattr(namespace, self.dest, True if self.nargs == 0 else values)


def deprecated(
    parser: argparse.ArgumentParser, old: str, dest: str, replacement: str, **kw: Any
) -> None:
    """Keep ``old`` working as ``replacement`` (stored in ``dest``) with a warning, hidden."""
    parser.add_argument(old, dest=dest, action=_Deprecated, replacement=replacement, **kw)


def _seconds(text: str) -> float | None:
    """``--time-limit`` value: positive seconds, or 'none' for no limit."""
    if text.strip().lower() in ("none", "inf", "unlimited"):
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds or 'none', got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected positive seconds or 'none', got {text!r}")
    return value


def _seed(text: str) -> int:
    """``--seed`` value: an integer in [0, 2**32) (numpy's and the peers' seed range)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"expected an integer in [0, 2**32), got {text!r}")
    return value


def add_subcommand(parent: Any, name: str, handler: Any, help_text: str) -> argparse.ArgumentParser:
    """A subcommand of ``parent`` (a subparsers group) handled by ``handler(args) -> int``.

    Every subcommand takes ``--quiet`` and ``-v`` (the log level of the ``taopt`` logger).
    """
    child = parent.add_parser(
        name, help=help_text, description=help_text, formatter_class=_Formatter
    )
    child.set_defaults(handler=handler)
    group = child.add_mutually_exclusive_group()
    group.add_argument(
        "--quiet", action="store_true", help="no progress bar; log warnings and errors only"
    )
    group.add_argument(
        "-v", "--verbose", action="store_true", help="log debug messages of the library too"
    )
    return child


def _common(parser: argparse.ArgumentParser, *names: str) -> None:
    """The shared flags, with the same names, meanings, defaults and help everywhere."""
    if "seed" in names:
        parser.add_argument("--seed", type=_seed, default=SEED, help="seed of randomised methods")
    if "methods" in names:
        parser.add_argument(
            "--methods",
            default=None,
            metavar="LIST",
            help="comma-separated method names, case-insensitive, 'exact' among them; 'all' "
            "for every method available here ('taopt kinds' lists them) (default: none named: "
            "the family's default set, printed under the table: the certified optimum where "
            "affordable, then the heuristics; other exact models, variants and peers only "
            "when named)",
        )
    if "time-limit" in names:
        parser.add_argument(
            "--time-limit",
            type=_seconds,
            default=TIME_LIMIT,
            metavar="SECONDS",
            help="per exact model (or peer) run, 'none' for no limit; a stopped model reports "
            f"its proven gap (default: {TIME_LIMIT:g} s)",
        )
    if "jobs" in names:
        parser.add_argument(
            "--jobs", type=int, default=1, help="worker processes (scenarios in parallel)"
        )
        parser.add_argument(
            "--dask",
            default=None,
            metavar="ADDRESS",
            help="run on a Dask cluster: 'local' (a LocalCluster of --jobs workers) or a "
            "scheduler address (needs taopt[dask]) (default: none: worker processes here)",
        )
    if "plot" in names:
        parser.add_argument(
            "--plot", default=None, metavar="PNG", help="write a plot to this PNG (default: none)"
        )


def setup_logging(quiet: bool = False, verbose: bool = False) -> logging.Logger:
    """Send the ``taopt`` logger to stderr: WARNING with ``--quiet``, DEBUG with ``-v``, else INFO.

    Calling it again (``main`` run twice in one process) replaces the handler it installed.
    """
    import logging

    logger = logging.getLogger("taopt")
    for handler in list(logger.handlers):
        if handler.get_name() == "taopt-cli":
            logger.removeHandler(handler)
    handler = logging.StreamHandler(sys.stderr)
    handler.set_name("taopt-cli")
    handler.setFormatter(logging.Formatter("%(name)s: %(levelname)s: %(message)s"))
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO)
    return logger


# -- the parser ---------------------------------------------------------------------------------

SOLVE_DESCRIPTION = (
    "Solve a JSON problem file with the default methods of its family (or --methods) and\n"
    "print one table: status, objective, proven bound and gap, true gap to a certified\n"
    "optimum, ratios to bounds. The certified optimum is computed by default where it is\n"
    "affordable; one line says why when it is not. Under the table: the messages of failed\n"
    "methods (numbered), what each ratio column divides by, and the default method set.\n\n"
    "Columns: gap = what the method proves (objective / its bound - 1); gap_to_optimum =\n"
    "objective / the certified optimum of this run - 1; q_valid = objective / the family's\n"
    "fast valid lower bound (>= 1; 1 proves optimality); q_thesis = objective / the thesis's\n"
    "Algorithm 1 value as printed (not a valid bound on asymmetric costs: it may be < 1).\n\n"
    "Default methods: the family's exact method (where affordable) and its heuristics; other\n"
    "exact models (the same optimum, slower), variants, budgeted searches (ILS) and peers\n"
    "(pyvrp, ortools, cpsat) run only when named; '--methods all' runs every one.\n\n"
    "File kinds (docs/file-formats.md; schemas in taopt/schemas/): 'instance' (positions,\n"
    "field, obstacles: travel times by navigation) and the kind of every problem family\n"
    "('taopt kinds' lists them). Examples ship with the package, from any folder:\n"
    "example:NAME (taopt.examples.path(NAME)), NAME one of " + EXAMPLES_TEXT + "."
)


def build_parser(with_studies: bool = True) -> argparse.ArgumentParser:
    """The ``taopt`` parser with every subcommand.

    The study commands come from the family specs (:func:`add_studies`), which imports the
    families; ``with_studies=False`` leaves them out so that ``taopt --version``, ``--help``
    and every other command parse without importing numpy.
    """
    from taopt import __version__

    parser = argparse.ArgumentParser(
        prog="taopt",
        description="Cooperative multi-vehicle task assignment (thesis toolkit): navigation,\n"
        "exact models, heuristics and distributed algorithms, side by side.",
        epilog="'taopt COMMAND --help' shows a command's options, each with its default.\n"
        "'python -m taopt' is the same command.",
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=f"taopt {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    nav = add_subcommand(sub, "navigate", cmd_navigate, "minimum travel times t(i, j) and t(j, i)")
    nav.add_argument("--field", default="thesis", metavar="SPEC", help=FIELD_HELP)
    nav.add_argument("--from", dest="start", required=True, metavar="X,Y", help="point i")
    nav.add_argument("--to", dest="goal", required=True, metavar="X,Y", help="point j")
    nav.add_argument("--speed", type=float, default=1.0, help="vehicle speed v (m/s)")
    nav.add_argument(
        "--method",
        choices=["collocation", "pmp", "shooting", "closed_form"],
        default="collocation",
        help="navigation solver",
    )
    _common(nav, "plot")

    demo = add_subcommand(
        sub, "demo", cmd_demo, "the embedded instance solved exactly and by every heuristic"
    )
    _common(demo, "seed", "plot")

    solve = add_subcommand(
        sub,
        "solve",
        cmd_solve,
        "solve a problem file exactly and with every heuristic, with certified gaps",
    )
    solve.description = SOLVE_DESCRIPTION
    solve.epilog = (
        "A method that fails does not stop the others: its row has status 'error' and a\n"
        "numbered note under the table says why. Exit codes: 0 every method ran, 1 some method failed,\n"
        "2 bad input, 130 interrupted (Ctrl-C)."
    )
    solve.add_argument("file", help="a JSON problem file, or example:NAME (a packaged example)")
    _common(solve, "methods", "seed", "time-limit", "plot")
    solve.add_argument(
        "--gantt",
        default=None,
        metavar="PNG",
        help="delivery files: truck and drone timelines (default: none)",
    )
    solve.add_argument(
        "--trace",
        default=None,
        metavar="GIF",
        help="an animation of the exact method's rounds, one frame per round: the DFJ cut loop "
        "(routing) or the ideal DP's layers (delivery) (default: none)",
    )
    solve.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="write each solution as DIR/<method>.json, for taopt verify (default: none)",
    )
    deprecated(solve, "--save", "out", "--out DIR", metavar="DIR")

    export = add_subcommand(
        sub, "export", cmd_export, "write a problem's MILP as an LP or MPS file (thesis names)"
    )
    export.add_argument("file", help="a JSON problem file, or example:NAME (a packaged example)")
    from taopt.orchestration.export import MODELS  # light: no numpy, cvxpy or highspy

    export.add_argument(
        "--model",
        required=True,
        help="the model, per problem type: "
        + "; ".join(f"{kind} {'|'.join(names)}" for kind, names in MODELS.items()),
    )
    export.add_argument(
        "--format", choices=("lp", "mps"), default=None, help="default: the extension of --out"
    )
    export.add_argument("--out", required=True, metavar="PATH", help="the file to write")

    verify = add_subcommand(
        sub,
        "verify",
        cmd_verify,
        "re-score a saved solution from the problem file alone and check every constraint",
    )
    verify.epilog = (
        "Always checked: the payload fits the problem, every constraint holds, the status\n"
        "agrees with it, the objective re-scores to the saved value, a saved bound is not\n"
        "above it. Claims about the optimum (an 'optimal' status, a saved bound, an\n"
        "'infeasible' status) need --exact, which re-solves with the family's fastest exact\n"
        "method (the DP over order ideals for delivery instances) within --time-limit; those it\n"
        "cannot check are printed '[not checked] ...'. The last line is VALID, 'VALID (k\n"
        "claims not checked)' or NOT VALID. Exit codes: 0 valid and every claim checked,\n"
        "1 a check failed, 2 bad input (a malformed file), 3 valid but some claims not\n"
        "checked, 130 interrupted (Ctrl-C)."
    )
    verify.add_argument(
        "solution", help="a solution JSON (taopt solve --out, Solution.save), or example:solution"
    )
    verify.add_argument("problem", help="the problem file it solves, or example:NAME")
    verify.add_argument(
        "--exact",
        action="store_true",
        help="also re-solve exactly here and compare (small problems)",
    )
    _common(verify, "time-limit")

    kinds = add_subcommand(
        sub, "kinds", cmd_kinds, "list the problem families: file kind, schema, bounds, methods"
    )
    kinds.set_defaults(quiet=False, verbose=False)

    claims = add_subcommand(
        sub, "claims", cmd_claims, "check chapter 2's lemmas and theorems on random instances"
    )
    claims.add_argument("--samples", type=int, default=200, help="instances per class")
    claims.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="folder for the smallest counterexamples, as JSON (default: none: not saved)",
    )
    claims.add_argument(
        "--classes",
        default="euclidean,uniform-drift,drift,metric",
        help="comma list of instance classes",
    )
    _common(claims, "seed")

    simulate = add_subcommand(
        sub,
        "simulate",
        cmd_simulate,
        "chapter 4: simulate CAA, DAA or HDA on a comm_problem file (limited range)",
    )
    simulate.add_argument("file", help="a comm_problem JSON file, or example:comm_problem")
    simulate.add_argument(
        "--methods",
        default="DAA",
        metavar="LIST",
        help="comma-separated algorithms: DAA, CAA, HDA (case-insensitive)",
    )
    deprecated(simulate, "--algorithm", "methods", "--methods NAME", metavar="NAME")
    simulate.add_argument(
        "--range",
        type=float,
        default=None,
        metavar="METRES",
        help="communication range r (default: none: the file's r)",
    )
    simulate.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="write each solution as DIR/<method>.json, for taopt verify (default: none)",
    )
    deprecated(simulate, "--save", "save_file", "--out DIR (writes DIR/<method>.json)")
    simulate.set_defaults(save_file=None)
    simulate.add_argument(
        "--animate", default=None, metavar="GIF", help="write an animation (default: none)"
    )
    simulate.add_argument("--frames", type=int, default=120, help="frames of the animation")
    _common(simulate, "seed", "plot")

    study = sub.add_parser(
        "study", help="run a thesis study (resumable, parallel)", formatter_class=_Formatter
    )
    studies = study.add_subparsers(dest="study", metavar="STUDY")
    studies.required = True
    if with_studies:
        add_studies(studies)

    return parser


def add_studies(studies: Any) -> None:
    """One ``taopt study NAME`` per study a family's spec declares
    (:class:`taopt.registry.Study`): its module's ``HELP``, ``add_arguments`` and ``run``, and
    the flags every study takes."""
    import importlib

    from taopt.registry import families

    for spec in sorted((s for f in families() for s in f.studies), key=lambda s: s.name):
        module = importlib.import_module(spec.module)
        parser = add_subcommand(studies, spec.name, module.run, module.HELP)
        module.add_arguments(parser)
        _study_flags(parser, module.CSV)


def _study_flags(parser: argparse.ArgumentParser, csv: str) -> None:
    """What every study takes: --out, --seed, --time-limit, --jobs, --dask, --plot."""
    parser.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help=f"output folder ({csv}; resumable)",
    )
    _common(parser, "seed", "time-limit", "jobs", "plot")


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse an image or animation file of the wrong kind, or in a folder that cannot be
    written, before any work starts (nothing is written by the check)."""
    for option, suffix in (
        ("plot", ".png"),
        ("gantt", ".png"),
        ("animate", ".gif"),
        ("trace", ".gif"),
    ):
        if getattr(args, option, None) is not None:
            from taopt.io import check_writable_file
            from taopt.plot import check_output

            check_output(getattr(args, option), suffix, f"--{option}")
            check_writable_file(getattr(args, option), f"--{option}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``taopt`` script. Returns the exit code (2 on bad input).

    Ctrl-C at any point (while modules load, in a solver, in a study) prints one line,
    ``taopt COMMAND: interrupted`` (a study adds where its rows are), and returns 130. As
    the script (``argv`` None) a command other than a study then ends the process at once
    (see :func:`_end_after_interrupt`); so does any command whose HiGHS run was stopped.
    """
    # Worker processes killed on Ctrl-C leave their queue's semaphore to the OS; the
    # multiprocessing resource tracker (started with these warning options) would print a
    # warning about it after our one-line message.
    sys.warnoptions.append("ignore:resource_tracker:UserWarning")
    words = list(sys.argv[1:] if argv is None else argv)
    try:
        return _main(argv)
    except KeyboardInterrupt as exc:  # StudyInterrupted is one, and says where its rows are
        command = next((w for w in words if not w.startswith("-")), "")
        message = str(exc) if isinstance(exc, TaoptError) and str(exc) else "interrupted"
        print(f"taopt{' ' + command if command else ''}: {message}", file=sys.stderr)
        _end_after_interrupt(script=argv is None, study=isinstance(exc, TaoptError))
        return 130


def _end_after_interrupt(script: bool, study: bool) -> None:
    """After Ctrl-C, end the process now with 130 when that is safe and useful.

    When Ctrl-C stopped a HiGHS run, the interpreter's teardown would destroy HiGHS's
    static objects while its threads may still be winding down (an abort or a segmentation
    fault at exit, now and then). As the script, the teardown is also seconds of work on a
    loaded machine for nothing: taopt has nothing left to write (files are written
    atomically; the message is printed and the streams are flushed first). A study keeps
    the ordinary exit, whose hooks close its executor.
    """
    from taopt.runtime.interrupt import exit_now, solver_interrupted

    if solver_interrupted() or (script and not study):
        exit_now(130)


def _main(argv: Sequence[str] | None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(with_studies="study" in words)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse already printed usage and the error
        return int(exc.code or 0)
    setup_logging(quiet=getattr(args, "quiet", False), verbose=getattr(args, "verbose", False))
    try:
        _check_outputs(args)
        return int(args.handler(args) or 0)
    except KeyboardInterrupt:  # StudyInterrupted is a TaoptError too: main() reports it
        raise
    except (TaoptError, ValueError, OSError) as exc:
        message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        if isinstance(exc, OSError) and exc.filename and exc.strerror:  # name the file
            message = f"{exc.filename}: {exc.strerror}"
        print(f"taopt {args.command}: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
