"""The command line: navigate, demo, field specs, clean errors with exit code 2."""

from __future__ import annotations

import importlib
import io
import json

import numpy as np
import pytest
from conftest import ROOT

from taopt.errors import InstanceError
from taopt.fields import LinearField, UniformField, thesis_field
from taopt.instance import Instance
from taopt.orchestration.cli import build_parser, main, parse_field


def test_navigate_prints_both_directions(capsys, tmp_path):
    png = tmp_path / "nav.png"
    code = main(
        ["navigate", "--field", "fig21", "--from", "10,80", "--to", "90,15", "--plot", str(png)]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "t(i, j) = 90.3" in out and "t(j, i) = 125.9" in out
    assert png.exists() and png.stat().st_size > 1000


def test_navigate_uniform_closed_form(capsys):
    code = main(
        [
            "navigate",
            "--field",
            "uniform:0.5,0",
            "--from",
            "0,0",
            "--to",
            "3,0",
            "--method",
            "closed_form",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0 and "t(i, j) = 2.000000" in out and "t(j, i) = 6.000000" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["navigate", "--from", "a,b", "--to", "1,2"], "--from"),
        (["navigate", "--field", "linear:1,0", "--from", "0,0", "--to", "1,2"], "linear field"),
        (["navigate", "--field", "swirl", "--from", "0,0", "--to", "1,2"], "unknown field 'swirl'"),
        (
            ["navigate", "--field", "fig21", "--from", "0,0", "--to", "90,90", "--speed", "0.1"],
            "Assumption 2.1",
        ),
        (["navigate", "--field", "missing.json", "--from", "0,0", "--to", "1,2"], "does not exist"),
        (
            ["navigate", "--field", "fig21", "--from", "0,0", "--to", "1,2", "--speed", "-1"],
            "speed",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["demo", "--seed", "-3"], "--seed: expected an integer in [0, 2**32), got '-3'"),
        (["claims", "--seed", "x"], "--seed: expected an integer, got 'x'"),
    ],
)
def test_a_bad_seed_is_refused_before_any_work(capsys, argv, message):
    """A seed numpy would refuse inside each method (rows of "error") is an argument error."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_argparse_errors_exit_2(capsys):
    assert main(["bogus"]) == 2
    assert main(["navigate", "--to", "1,2"]) == 2


def test_parse_field_specs(tmp_path):
    assert parse_field("thesis") == thesis_field(1e-3)
    assert parse_field("fig21") == thesis_field(1e-2)
    assert parse_field("still") is None
    assert parse_field("uniform:0.1,-0.2") == UniformField(0.1, -0.2)
    assert parse_field("linear:1,2,3,4") == LinearField([[1, 2], [3, 4]])
    field_file = tmp_path / "f.json"
    field_file.write_text(json.dumps(UniformField(0.3, 0.0).to_dict()))
    assert parse_field(str(field_file)) == UniformField(0.3, 0.0)
    inst_file = tmp_path / "inst.json"
    Instance.random(3, 1, side=100.0, field=thesis_field(1e-2), seed=0).save(inst_file)
    assert parse_field(str(inst_file)) == thesis_field(1e-2)
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(InstanceError, match="not valid JSON"):
        parse_field(str(bad))


def test_demo_runs_and_reports(capsys, tmp_path):
    """`taopt demo` reports the matrix checks, the certified optimum and the gap table."""
    png = tmp_path / "demo.png"
    assert main(["demo", "--quiet", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "10 targets, 3 vehicles" in out
    assert "Lemma 2.3 triangle inequality within 1e-6: True" in out
    assert "exact: optimal" in out and "gap_to_optimum" in out
    assert png.exists()


def test_run_demo_matrix_matches_navigation():
    """The demo's matrix equals shooting on an entry; no heuristic beats its optimum."""
    import io

    from taopt.navigation import min_time_path
    from taopt.orchestration.demo import load_demo_instance, run_demo

    result = run_demo(out=io.StringIO(), progress=False)
    inst = load_demo_instance()
    T = result["matrix"]
    assert T.shape == (13, 13) and np.all(np.diag(T) == 0)
    i, j = 11, 4  # a vehicle start to a target
    ref = min_time_path(inst.field, inst.points[i], inst.points[j], method="shooting").time
    assert T[i, j] == pytest.approx(ref, rel=1e-6)
    # The demo's gap table: a certified optimum that no heuristic beats, every objective
    # re-scored by the one scorer.
    import taopt

    solutions = result["solutions"]
    exact = solutions["exact"]
    assert exact.status == "optimal"
    assert exact.objective == pytest.approx(
        taopt.evaluate(result["problem"], exact.routes), rel=1e-6
    )
    for name, sol in solutions.items():
        assert sol.objective == pytest.approx(
            taopt.evaluate(result["problem"], sol.routes), rel=1e-9
        )
        assert sol.objective >= exact.objective * (1 - 1e-6), name
    assert set(result["table"]["method"]) == {"exact", "VN", "VM", "EVN", "EVM", "MC", "GA"}
    assert (result["table"]["gap_to_optimum"] >= -1e-6).all()


def test_parser_has_subcommands_for_extension():
    """Every subcommand has a handler."""
    parser = build_parser()
    args = parser.parse_args(["demo"])
    assert args.command == "demo" and callable(args.handler)


def test_solve_command_on_each_file_kind(tmp_path, capsys):
    """`taopt solve` reads the JSON kinds; no method beats the certified optimum."""
    import taopt
    from taopt.delivery.instance import DeliveryInstance
    from taopt.orchestration.solving import solve_file

    # chapter 2, from a cost matrix
    rng = np.random.default_rng(5)
    problem = taopt.AssignmentProblem(rng.uniform(1, 50, size=(9, 9)), n_targets=6)
    problem.save(tmp_path / "p.json")
    result = solve_file(tmp_path / "p.json", out=io.StringIO(), progress=False)
    table = result["table"]
    assert table.loc[table.method == "exact", "status"].item() == "optimal"
    assert (table["gap_to_optimum"] >= -1e-9).all()
    # chapter 5, with the exact ideal DP, the subset DP and the MILP
    inst = DeliveryInstance.grid(
        rng.uniform(0, 600, size=(5, 2)), 3, 600.0, 1.0, 1.0, 700.0, precedences=[(0, 1), (2, 3)]
    )
    inst.save(tmp_path / "d.json")
    png, gantt = tmp_path / "plan.png", tmp_path / "gantt.png"
    argv = ["solve", str(tmp_path / "d.json"), "--methods", "NIA,MMA,SMMA,subset-dp,exact"]
    assert main(argv + ["--plot", str(png), "--gantt", str(gantt), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "subset-dp" in out and "exact" in out and png.exists() and gantt.exists()
    methods = ("MMA", "subset-dp", "exact", "milp")
    result = solve_file(tmp_path / "d.json", methods=methods, out=io.StringIO())
    table = result["table"].set_index("method")
    exact = table.loc["exact", "objective"]
    assert table.loc["subset-dp", "objective"] == pytest.approx(exact, rel=1e-9)
    assert table.loc["milp", "objective"] == pytest.approx(exact, rel=1e-6)
    assert table.loc["MMA", "objective"] >= exact * (1 - 1e-9)


def test_a_heuristic_without_an_answer_is_not_a_failure(tmp_path, capsys, budgeted_example_file):
    """The budgeted example: EVM finds no feasible answer (status no_solution, the reason in
    the message column), the exact optimum stands, the exit code is 0; saved and verified,
    the no-answer file claims nothing and passes."""
    example = str(budgeted_example_file)
    argv = ["solve", example, "--methods", "exact,EVM", "--quiet", "--save", str(tmp_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "no_solution" in out and "no feasible answer: EVM" in out and "failed" not in out
    assert main(["verify", str(tmp_path / "EVM.json"), example]) == 0
    assert "carries no payload" not in capsys.readouterr().out


def test_solve_command_rejects_unknown_kind(tmp_path, capsys):
    """An unknown file kind is a one-line error naming it, exit code 2."""
    bad = tmp_path / "x.json"
    bad.write_text('{"schema_version": 1, "kind": "pizza"}')
    assert main(["solve", str(bad)]) == 2
    assert "kind 'pizza'" in capsys.readouterr().err


# -- one grammar ------------------------------------------------------------------------------


def _commands(parser=None, prefix=()):
    """(command words, parser) of every leaf subcommand of the taopt parser."""
    import argparse

    parser = parser or build_parser()
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                found += _commands(child, (*prefix, name))
    return found or [(prefix, parser)]


def _options(parser):
    """The visible options of ``parser`` (not -h, --version or hidden deprecated spellings)."""
    import argparse

    return [
        a
        for a in parser._actions
        if a.option_strings
        and a.help is not argparse.SUPPRESS
        and not isinstance(a, (argparse._HelpAction, argparse._VersionAction))
    ]


def test_every_command_is_listed():
    """The walk finds every command: the fixed ones and one study per study a family's spec
    declares (a guard for the grammar tests below)."""
    from taopt.registry import families

    names = {" ".join(words) for words, _ in _commands()}
    studies = {f"study {s.name}" for f in families() for s in f.studies}
    assert {"study drift", "study delivery", "study capability", "study comm"} <= studies
    assert names == {
        "navigate", "demo", "solve", "export", "verify", "kinds", "claims", "simulate", *studies,
    }  # fmt: skip


def test_every_option_help_shows_a_default():
    """Every option of every subcommand states its default in --help, never "None"."""
    for words, parser in _commands():
        text = parser.format_help()
        assert "default: None" not in text, words
        formatter = parser._get_formatter()
        for action in _options(parser):
            shown = formatter._expand_help(action)
            assert "default" in shown, (words, action.option_strings)
            assert action.option_strings[-1] in text


def test_seed_and_time_limit_defaults_are_the_same_everywhere():
    """--seed defaults to 0 and --time-limit to one value in every command that has them."""
    seeds, limits = {}, {}
    for words, parser in _commands():
        for action in _options(parser):
            if "--seed" in action.option_strings:
                seeds[" ".join(words)] = action.default
            if "--time-limit" in action.option_strings:
                limits[" ".join(words)] = action.default
    assert set(seeds) >= {"demo", "solve", "claims", "simulate", "study drift", "study comm"}
    assert set(seeds.values()) == {0}
    assert set(limits) >= {"solve", "verify", "study drift", "study delivery", "study comm"}
    assert len(set(limits.values())) == 1 and None not in limits.values()


def test_every_command_takes_quiet_and_verbose():
    """--quiet and -v parse on every subcommand (the log level of the taopt logger)."""
    for _, parser in _commands():
        flags = {flag for a in _options(parser) for flag in a.option_strings}
        assert {"--quiet", "-v"} <= flags


def test_shared_flags_have_one_name_and_meaning():
    """--out, --methods, --jobs are spelled one way; --instances is a count wherever it is."""
    for words, parser in _commands():
        options = {flag: a for a in _options(parser) for flag in a.option_strings}
        assert not {"--save", "--exact-methods", "--n-jobs", "--workers"} & set(options), words
        if "--instances" in options:
            assert options["--instances"].type is int, words
        if "--jobs" in options:
            assert "--dask" in options and options["--jobs"].default == 1


def test_old_spelling_still_works_and_warns(tmp_path, capsys):
    """`solve --save DIR` (now --out) still writes the solutions and warns on stderr."""
    problem = "taopt/data/examples/assignment_problem.json"

    problem = str(ROOT / problem)
    assert main(["solve", problem, "--methods", "MC", "--save", str(tmp_path), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "DeprecationWarning" in err and "--save" in err and "--out" in err
    assert (tmp_path / "MC.json").exists()
    parser = build_parser()
    args = parser.parse_args(["study", "capability", "--instances", "n5m2", "--out", "x"])
    assert args.sizes == "n5m2"
    args = parser.parse_args(["study", "comm", "--exact", "--out", "x"])
    assert args.exact_alias is True
    assert capsys.readouterr().err.count("DeprecationWarning") == 2


def test_time_limit_none_means_no_limit(capsys):
    """--time-limit none is no limit; a negative limit is an argparse error (exit 2)."""
    parser = build_parser()
    assert parser.parse_args(["verify", "a", "b", "--time-limit", "none"]).time_limit is None
    assert parser.parse_args(["verify", "a", "b", "--time-limit", "2.5"]).time_limit == 2.5
    assert main(["verify", "a", "b", "--time-limit", "-1"]) == 2
    assert "--time-limit" in capsys.readouterr().err


# -- a light entry point ------------------------------------------------------------------------


def test_version_loads_no_heavy_module():
    """`python -m taopt --version` answers without importing numpy, pandas, cvxpy, matplotlib."""
    import subprocess
    import sys

    code = (
        "import runpy, sys\n"
        "sys.argv = ['taopt', '--version']\n"
        "try:\n"
        "    runpy.run_module('taopt', run_name='__main__', alter_sys=True)\n"
        "except SystemExit as exc:\n"
        "    assert not exc.code, exc.code\n"
        "heavy = ('numpy', 'pandas', 'cvxpy', 'matplotlib', 'scipy')\n"
        "print('loaded:', sorted(m for m in heavy if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("taopt ") and lines[-1] == "loaded: []"


def test_python_dash_m_taopt_runs_the_cli():
    """`python -m taopt navigate ...` is the taopt command."""
    import subprocess
    import sys

    argv = ["navigate", "--field", "still", "--from", "0,0", "--to", "3,4"]
    done = subprocess.run(
        [sys.executable, "-m", "taopt", *argv, "--method", "closed_form", "--quiet"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "t(i, j) = 5.000000" in done.stdout


def test_top_level_api_is_complete_and_lazy():
    """taopt.__all__ names every problem type and resolves; `import taopt` loads no numpy."""
    import subprocess
    import sys

    import taopt

    for name in taopt.__all__:
        assert getattr(taopt, name) is not None, name
    families = {f.problem_type for f in taopt.registry.families()}
    assert families <= {getattr(taopt, name) for name in taopt.__all__}
    assert {"CapabilityProblem", "CommProblem", "available_methods", "bounds"} <= set(taopt.__all__)
    code = "import sys, taopt; print('numpy' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout.strip() == "False", done.stderr


def test_the_core_imports_no_method_or_orchestration_module():
    """Importing taopt and every family (problem data, scorers, bounds, plots' modules) loads no
    module of taopt.models, taopt.heuristics or taopt.orchestration (architecture.md, "Layers")."""
    import subprocess
    import sys

    code = (
        "import sys, taopt\n"
        "from taopt.registry import families\n"
        "[f.kind for f in families()]\n"
        "bad = ('taopt.models', 'taopt.heuristics', 'taopt.orchestration')\n"
        "print(sorted(m for m in sys.modules if m.startswith(bad)))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]", done.stdout


# -- methods: discovered, only what is usable here -----------------------------------------------


def test_available_methods_lists_installed_peers_only(monkeypatch, ref_routing_quick_tour):
    """A peer is listed only when its package is installed (found, never imported)."""
    import importlib.util

    import taopt
    from taopt import registry

    problem = ref_routing_quick_tour.problem
    listed = taopt.available_methods(problem)
    assert listed[0] == "exact" and {"VN", "VM", "EVN", "EVM", "MC", "GA"} <= set(listed)
    for peer in ("pyvrp", "ortools"):
        assert (peer in listed) == (importlib.util.find_spec(peer) is not None)
    monkeypatch.setattr(registry, "_installed", lambda package: package != "pyvrp")
    assert "pyvrp" not in taopt.available_methods(problem)
    assert "pyvrp" in registry.method_names(problem)  # registered, but not usable here


def test_every_exact_method_is_registered_by_taopt_models():
    """Importing taopt.models registers the exact methods of every family, the delivery DPs too."""
    import taopt
    import taopt.models  # noqa: F401
    from taopt.registry import families, method_names

    for family in families():
        assert method_names(family.problem_type, "exact"), family.kind
    assert {"exact", "subset-dp", "milp"} <= set(method_names(taopt.DeliveryInstance, "exact"))


def test_every_family_package_is_discovered():
    """Each taopt subpackage with a family.py is found, and each declares a registered spec."""
    from pathlib import Path

    import taopt
    from taopt import families, registry

    root = Path(taopt.__file__).parent
    on_disk = {p.parent.name for p in root.glob("*/family.py")}
    assert {m.split(".")[1] for m in families.family_modules()} == on_disk
    kinds = {f.kind for f in registry.families()}
    assert len(kinds) >= len(on_disk)
    for module in families.family_modules():
        spec = importlib.import_module(module).FAMILY
        assert spec.kind in kinds and registry.family_of(spec.problem_type) is spec


def test_a_family_that_fails_to_import_fails_loudly(monkeypatch):
    """ensure_families raises the ImportError of a broken family instead of skipping it."""
    from taopt import families, registry

    broken = (*families.family_modules(), "taopt._no_such_family.family")
    monkeypatch.setattr(families, "family_modules", lambda: broken)
    with pytest.raises(ImportError, match="_no_such_family"):
        registry.file_kinds()


def test_solve_delivery_example_shows_the_certified_optimum(capsys):
    """`taopt solve delivery_instance.json` prints an optimal row with its bound by default."""

    path = ROOT / "taopt/data/examples/delivery_instance.json"
    assert main(["solve", str(path), "--quiet"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    optimal = [row for row in rows if len(row) > 3 and row[1] == "optimal"]
    assert optimal, rows
    objective, bound = float(optimal[0][2]), float(optimal[0][3])
    assert bound == pytest.approx(objective) and objective > 0
    heuristics = [float(row[2]) for row in rows if len(row) > 3 and row[1] == "feasible"]
    assert heuristics and min(heuristics) >= objective * (1 - 1e-9)


def test_solve_says_why_no_optimum_is_computed():
    """Past 2,000,000 order ideals the exact DP is left out by default; the reason names n."""
    from taopt.delivery.instance import DeliveryInstance
    from taopt.orchestration.pipeline import default_methods, no_optimum_note

    rng = np.random.default_rng(0)

    def grid(n):
        return DeliveryInstance.grid(rng.uniform(0, 600, size=(n, 2)), 3, 600.0, 1.0, 1.0, 700.0)

    small, large = grid(5), grid(22)  # 2^22 ideals without precedences
    assert "exact" in default_methods(small) and no_optimum_note(small) == ""
    assert not {"exact", "subset-dp", "milp"} & set(default_methods(large))
    note = no_optimum_note(large)
    assert "n = 22" in note and "--methods exact" in note and "\n" not in note


# -- logging ------------------------------------------------------------------------------------


@pytest.mark.parametrize(("flags", "shown"), [((), True), (("--quiet",), False), (("-v",), True)])
def test_cli_sends_library_logs_to_stderr(capsys, flags, shown):
    """Library messages go to the taopt logger; the CLI shows INFO on stderr unless --quiet."""
    import logging

    from taopt.models.routing import describe
    from taopt.orchestration.cli import setup_logging

    parser = build_parser()
    args = parser.parse_args(["demo", *flags])
    setup_logging(args.quiet, args.verbose)
    problem = __import__("taopt").AssignmentProblem(np.ones((3, 3)) - np.eye(3), n_targets=2)
    describe(problem, "mtz")
    captured = capsys.readouterr()
    assert captured.out == ""  # never on stdout
    assert ("(2.2)-(2.5) with sec='mtz'" in captured.err) == shown
    expected = logging.DEBUG if "-v" in flags else logging.WARNING if flags else logging.INFO
    assert logging.getLogger("taopt").level == expected
    setup_logging(quiet=True)  # leave the logger quiet for the other tests


def test_study_comm_takes_exact_as_a_method(tmp_path, capsys):
    """`study comm --methods DAA,exact` certifies f_o once per scenario (was --exact)."""
    import pandas as pd

    argv = ["study", "comm", "--preset", "homogeneous15", "--scenarios", "1", "--quiet"]
    assert main([*argv, "--methods", "DAA,exact", "--out", str(tmp_path)]) == 0
    rows = pd.read_csv(tmp_path / "comm.csv")
    assert (rows.method == "exact").sum() == 1 and (rows.method == "DAA").sum() > 1
    assert "mean true gap" in capsys.readouterr().out
    assert main([*argv, "--methods", "exact", "--out", str(tmp_path / "x")]) == 2
    assert "beside 'exact'" in capsys.readouterr().err


def test_solve_shows_which_method_runs_and_its_limit(capsys, budgeted_example_file):
    """`taopt solve` shows a bar on stderr naming each method as it runs, with the time limit
    an exact method may take; `--quiet` shows none; stdout has the table either way."""

    path = budgeted_example_file
    assert main(["solve", str(path), "--methods", "exact,MC", "--time-limit", "7"]) == 0
    captured = capsys.readouterr()
    assert "exact (up to 7 s)" in captured.err
    assert "MC" in captured.err and "MC (up to" not in captured.err  # a heuristic: no limit
    assert "optimal" in captured.out
    assert main(["solve", str(path), "--methods", "MC", "--quiet"]) == 0
    captured = capsys.readouterr()
    assert "MC" not in captured.err and "feasible" in captured.out
