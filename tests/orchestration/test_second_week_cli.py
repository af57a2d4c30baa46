"""Issue 30 (a user's second week): every bad input a one-line answer naming the file, one grammar.

Defects 5 and 6 (deep JSON, unknown kinds, numpy reprs, full disks, endless files) and the
frictions 8-12 (study defaults, packaged examples, method sets, flag names, readable output).
"""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

from taopt import examples
from taopt.errors import InstanceError, OutputError
from taopt.io import load_json, save_json
from taopt.orchestration.cli import main


def _error_line(capsys) -> str:
    """The one line ``main`` printed on stderr (asserting there is exactly one)."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


# -- defect 5: one reader for every JSON file, with a depth guard -----------------------------


@pytest.mark.parametrize("command", ["navigate", "solve"])
def test_deeply_nested_file_is_one_line_naming_it(command, tmp_path, capsys):
    """100,000 nested '[' is refused in one line naming the file, by navigate as by solve."""
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000)
    argv = (
        ["navigate", "--field", str(deep), "--from", "0,0", "--to", "1,1"]
        if command == "navigate"
        else ["solve", str(deep)]
    )
    assert main(argv) == 2
    line = _error_line(capsys)
    assert str(deep) in line and "nested" in line


def test_moderately_deep_file_is_refused_by_the_depth_guard(tmp_path):
    """A nesting the parser survives (500 levels) is still refused, naming the file."""
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 500 + "]" * 500)
    with pytest.raises(InstanceError, match=r"deep\.json: .*nested more than 64"):
        load_json(deep)


# -- defect 6: messages name the file -------------------------------------------------------------


def test_field_file_given_to_solve_points_at_navigate(capsys):
    """A drift field file given to solve names the file and says to use navigate --field."""
    field = ROOT / "taopt/data/examples/field.json"
    assert main(["solve", str(field)]) == 2
    line = _error_line(capsys)
    assert str(field) in line and "taopt navigate --field" in line and "unknown" not in line


def test_unknown_kind_names_the_file(tmp_path, capsys):
    """An unknown kind names the file and lists the kinds, 'instance' among them."""
    odd = tmp_path / "odd.json"
    odd.write_text('{"kind": "zebra"}')
    assert main(["solve", str(odd)]) == 2
    line = _error_line(capsys)
    assert line.startswith(f"taopt solve: error: {odd}: unknown file kind")
    assert "instance" in line and "delivery_instance" in line


def test_navigate_field_error_names_the_file(tmp_path, capsys):
    """A malformed field file given to navigate is named in the error."""
    bad = tmp_path / "bad_field.json"
    bad.write_text('{"kind": "uniform", "vx": "fast", "vy": 0}')
    assert main(["navigate", "--field", str(bad), "--from", "0,0", "--to", "1,1"]) == 2
    line = _error_line(capsys)
    assert str(bad) in line and "vx" in line


def test_target_inside_obstacle_names_file_with_plain_floats(tmp_path, capsys):
    """A target inside an obstacle: the file is named, the point in plain floats (no np.float64)."""
    data = json.loads((ROOT / "taopt/data/examples/instance.json").read_text())
    data["targets"][2]["position"] = [50.0, 45.0]  # inside the triangle 'rock'
    path = tmp_path / "inst.json"
    path.write_text(json.dumps(data))
    assert main(["solve", str(path), "--quiet"]) == 2
    line = _error_line(capsys)
    assert str(path) in line and "(50.0, 45.0)" in line and "np." not in line


def test_endless_device_is_refused_after_the_size_guard(capsys, monkeypatch):
    """/dev/zero is refused once the size guard is read, not read until killed."""
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero here")
    monkeypatch.setenv("TAOPT_MAX_FILE_MB", "1")
    assert main(["solve", "/dev/zero"]) == 2
    line = _error_line(capsys)
    assert "/dev/zero" in line and "size guard" in line


def test_fifo_is_read_with_a_cap(tmp_path, monkeypatch):
    """A FIFO fed without end is refused after the cap (the read is chunked, never unbounded)."""
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    import threading

    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    stop = threading.Event()

    def feed() -> None:
        try:
            with open(fifo, "wb") as out:
                while not stop.is_set():
                    out.write(b" " * 65536)
        except (BrokenPipeError, OSError):
            pass

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    monkeypatch.setenv("TAOPT_MAX_FILE_MB", "0.5")
    try:
        with pytest.raises(InstanceError, match="pipe.json: longer than 0.5 MB"):
            load_json(fifo)
    finally:
        stop.set()
    writer.join(timeout=5)


def _full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_full_disk_names_the_file_and_leaves_no_temp(tmp_path, monkeypatch):
    """ENOSPC while saving JSON: an OutputError naming the path, no temp or partial file left."""
    monkeypatch.setattr("taopt.io.os.replace", _full_disk)
    target = tmp_path / "sol.json"
    with pytest.raises(OutputError, match=r"sol\.json: cannot be written \(No space left"):
        save_json({"a": 1}, target)
    assert list(tmp_path.iterdir()) == []


def test_unwritable_out_folder_refused_before_solving(tmp_path, capsys, monkeypatch):
    """solve --out into an unwritable folder fails before any method runs, naming the folder."""
    import taopt.orchestration.solving as solving

    ran = []
    monkeypatch.setattr(solving, "method_table", lambda *a, **k: ran.append(1))
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker / "sub"  # a folder under a file: cannot be made
    code = main(["solve", "example:assignment_problem", "--out", str(out), "--quiet"])
    assert code == 2 and not ran
    line = _error_line(capsys)
    assert str(out) in line and "--out folder" in line


def test_study_cache_leaves_no_orphan_npy(tmp_path, monkeypatch):
    """A failure writing a cached matrix's description removes its .npy; the error names it."""
    import taopt.routing.scenarios as scenarios

    def failing_save(data, path):
        raise OutputError(f"{path}: cannot be written (No space left on device)")

    monkeypatch.setattr(scenarios, "save_json", failing_save)
    with pytest.raises(OutputError, match="No space left"):
        scenarios.drift_scenario(3, 1, 0, field="thesis", cache_dir=tmp_path, method="pmp")
    assert [p.name for p in tmp_path.iterdir()] == []


def test_study_cache_npy_write_failure_names_the_file(tmp_path, monkeypatch):
    """ENOSPC while writing the cached matrix: OutputError naming the .npy, nothing left."""
    import taopt.routing.scenarios as scenarios

    monkeypatch.setattr(scenarios.np, "save", _full_disk)
    with pytest.raises(OutputError, match=r"\.npy: cannot be written"):
        scenarios.drift_scenario(3, 1, 0, field="thesis", cache_dir=tmp_path, method="pmp")
    assert [p.name for p in tmp_path.iterdir()] == []


# -- friction 9: packaged examples ------------------------------------------------------------------


def test_examples_path_finds_every_kind():
    """taopt.examples.path gives an existing file for every listed example."""
    names = examples.names()
    assert {"budgeted_problem", "field", "demo", "delivery_example_20"} <= set(names)
    for name in names:
        assert examples.path(name).is_file()
    with pytest.raises(InstanceError, match="no example 'nope'; examples: assignment_problem"):
        examples.path("nope")


def test_example_prefix_in_solve_from_another_folder(tmp_path, capsys, monkeypatch):
    """taopt solve example:budgeted_problem works from a folder other than the clone's root."""
    monkeypatch.chdir(tmp_path)
    assert main(["solve", "example:budgeted_problem", "--methods", "MC", "--quiet"]) == 0
    assert "budgeted_problem.json" in capsys.readouterr().out


def test_example_prefix_in_verify_and_navigate(capsys):
    """verify and navigate read example:NAME too (the solution example checks against its problem)."""
    code = main(["verify", "example:solution", "example:assignment_problem"])
    assert code in (0, 3)
    assert "VALID" in capsys.readouterr().out
    code = main(["navigate", "--field", "example:field", "--from", "10,10", "--to", "20,20"])
    assert code == 0 and "t(i, j)" in capsys.readouterr().out


# -- friction 8: a study's defaults are the methods installed here ----------------------------------


def test_budgeted_defaults_leave_out_missing_peers(monkeypatch, tmp_path):
    """Without pyvrp/ortools the budgeted study's defaults omit them; naming one writes nothing."""
    import taopt.registry as registry
    from taopt.orchestration.studies import budgeted

    monkeypatch.setattr(registry, "_installed", lambda package: package not in ("pyvrp", "ortools"))
    assert budgeted.default_methods() == ["MC", "EVM", "GA", "exact"]
    out = tmp_path / "study"
    with pytest.raises(InstanceError, match="'pyvrp' needs pyvrp, not installed"):
        budgeted.budgeted_study("n6m2", "none", 1, methods="MC,pyvrp", out_dir=out)
    assert not out.exists()


@pytest.mark.slow
def test_budgeted_study_runs_without_peers(tmp_path):
    """`taopt study budgeted --sizes n6m2 --levels none,Q1 --scenarios 1` runs with pyvrp and
    ortools unimportable (a sitecustomize shim), from a folder other than the clone."""
    shim = tmp_path / "shim"
    shim.mkdir()
    (shim / "sitecustomize.py").write_text(
        "import sys\nfor name in ('pyvrp', 'ortools'):\n    sys.modules[name] = None\n"
    )
    out = tmp_path / "budgeted"
    argv = ["--sizes", "n6m2", "--levels", "none,Q1", "--scenarios", "1", "--out", str(out)]
    done = subprocess.run(
        [sys.executable, "-m", "taopt", "study", "budgeted", *argv, "--quiet"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        env=dict(os.environ, PYTHONPATH=f"{shim}{os.pathsep}{ROOT}", MPLBACKEND="Agg"),
    )
    assert done.returncode == 0, done.stderr
    assert " MC " in done.stdout and " exact " in done.stdout and "pyvrp" not in done.stdout


# -- friction 10: which methods run ---------------------------------------------------------------


def test_method_names_are_case_insensitive(capsys):
    """--methods mc,evm runs MC and EVM; taopt.solve takes 'mc' and reports 'MC'."""
    import taopt
    from taopt.routing.problem import AssignmentProblem

    assert main(["solve", "example:assignment_problem", "--methods", "mc,evm", "--quiet"]) == 0
    rows = [line.split()[0] for line in capsys.readouterr().out.splitlines()[2:4]]
    assert rows == ["MC", "EVM"]
    problem = AssignmentProblem.load(examples.path("assignment_problem"))
    assert taopt.solve(problem, "mc").method == "MC"


def test_methods_all_is_every_available_method():
    """--methods all is taopt.available_methods (what taopt kinds lists), in its order."""
    import taopt
    from taopt.orchestration.solving import load_problem_file, resolve_methods

    problem, _ = load_problem_file("example:delivery_instance", progress=False)
    assert resolve_methods(problem, ("all",)) == taopt.available_methods(problem)
    assert {"subset-dp", "milp", "ILS"} <= set(resolve_methods(problem, "ALL"))


def test_default_set_is_named_under_the_table(capsys, monkeypatch):
    """With no --methods the notes name the default set, what is left out and why."""
    monkeypatch.setenv("COLUMNS", "100")
    assert main(["solve", "example:delivery_instance", "--quiet"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "default methods: exact, NIA, MMA, SMMA, GA" in out
    assert "subset-dp, milp (other exact models" in out and "--methods all" in out


# -- friction 11: one grammar -----------------------------------------------------------------------


def test_python_defaults_equal_the_cli_defaults():
    """taopt.solve, solve_file and the solve command share seed and time limit (taopt.defaults)."""
    import inspect

    import taopt
    from taopt import defaults
    from taopt.orchestration.cli import build_parser
    from taopt.orchestration.solving import solve_file

    args = build_parser(with_studies=False).parse_args(["solve", "x.json"])
    for function in (taopt.solve, solve_file):
        parameters = inspect.signature(function).parameters
        assert parameters["seed"].default == args.seed == defaults.SEED
        assert parameters["time_limit"].default == args.time_limit == defaults.TIME_LIMIT


def test_simulate_takes_methods_and_warns_on_algorithm(capsys):
    """simulate --methods hda runs HDA; the old --algorithm still works with a deprecation line."""
    assert main(["simulate", "example:comm_problem", "--methods", "hda"]) == 0
    assert capsys.readouterr().out.startswith("HDA")
    assert main(["simulate", "example:comm_problem", "--algorithm", "CAA"]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("CAA")
    assert "--algorithm is deprecated" in captured.err and "--methods" in captured.err


def test_study_counts_and_sizes_have_one_name(capsys):
    """study drift takes --sizes (old --n/--m warn); study delivery's count is --scenarios."""
    from taopt.orchestration.cli import build_parser
    from taopt.orchestration.studies.drift import _cli_sizes

    parser = build_parser()
    args = parser.parse_args(["study", "drift", "--sizes", "n5m2,n6m2", "--out", "x"])
    assert _cli_sizes(args) == ["n5m2", "n6m2"]
    assert capsys.readouterr().err == ""
    args = parser.parse_args(["study", "drift", "--n", "5", "--m", "2", "--out", "x"])
    assert _cli_sizes(args) == ["n5m2"]
    assert "--n is deprecated" in capsys.readouterr().err
    args = parser.parse_args(["study", "delivery", "--scenarios", "3", "--out", "x"])
    assert args.scenarios == 3
    args = parser.parse_args(["study", "delivery", "--instances", "4", "--out", "x"])
    assert args.scenarios == 4 and "--instances is deprecated" in capsys.readouterr().err
    for study in ("drift", "delivery", "capability", "comm", "budgeted"):
        assert parser.parse_args(["study", study, "--out", "x"]).scenarios >= 1


# -- friction 12: readable output -------------------------------------------------------------------


def test_table_fits_the_terminal_and_messages_become_notes():
    """Every printed line of a table is within the terminal width; messages move to notes."""
    import pandas as pd

    from taopt.orchestration.solving import format_table, wrap_notes

    table = pd.DataFrame(
        {
            "method": ["exact", "GA"],
            "status": ["optimal", "error"],
            "objective": [1.0, np.nan],
            "gap_to_optimum": [0.0, np.nan],
            "q_valid": [1.0, np.nan],
            "q_thesis": [0.9, np.nan],
            "seconds": [0.1, 0.2],
            "message": ["", "SolverError: " + "a long reason " * 12],
        }
    )
    text, notes = format_table(table, width=50)
    assert max(len(line) for line in text.splitlines()) <= 50
    assert "[1]" in text and "long reason" not in text
    assert notes[0].startswith("[1] GA: SolverError: a long reason")
    assert all(len(line) <= 50 for line in wrap_notes(notes, width=50))


def test_ratio_columns_explained_in_help_and_footer(capsys):
    """q_valid and q_thesis are explained in solve --help and under the table."""
    assert main(["solve", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.split())
    assert "q_valid = objective / the family's fast valid lower bound" in help_text
    assert "q_thesis = objective / the thesis's Algorithm 1 value" in help_text
    assert "example:NAME" in help_text and "budgeted_problem" in help_text
    assert main(["solve", "example:assignment_problem", "--methods", "MC", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "q_valid = objective /" in out and "q_thesis = objective / thesis_mcga" in out


def test_verify_exact_prints_the_gap_to_the_optimum(tmp_path, capsys):
    """verify --exact prints the checked solution's gap to the optimum it re-solved."""
    out = tmp_path / "sols"
    assert main(["solve", "example:delivery_instance", "--methods", "NIA", "--out", str(out)]) == 0
    capsys.readouterr()
    code = main(["verify", str(out / "NIA.json"), "example:delivery_instance", "--exact"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "gap of the checked solution to the re-solved optimum 178.54" in text
    assert "0.04514 %" in text


def test_claims_shows_a_progress_bar_unless_quiet(capsys):
    """taopt claims draws a progress bar on stderr; --quiet hides it."""
    argv = ["claims", "--samples", "3", "--classes", "metric"]
    assert main(argv) == 0
    assert "instance" in capsys.readouterr().err
    assert main([*argv, "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_full_disk_while_appending_rows_names_the_csv(tmp_path, monkeypatch):
    """ENOSPC while a study appends rows: an OutputError naming the CSV; earlier rows kept."""
    import builtins

    from taopt.orchestration.studyio import ResultsStore

    store = ResultsStore(tmp_path, "rows.csv", ["k", "v"], ["k"], {"seed": 0})
    store.append([{"k": 0, "v": 1.0}])
    real_open = builtins.open

    def full(path, mode="r", *args, **kwargs):
        if "a" in mode:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_open(path, mode, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", full)
    with pytest.raises(OutputError, match=r"rows\.csv: cannot be written \(No space left"):
        store.append([{"k": 1, "v": 2.0}])
    monkeypatch.setattr(builtins, "open", real_open)
    again = ResultsStore(tmp_path, "rows.csv", ["k", "v"], ["k"], {"seed": 0})
    assert len(again.read()) == 1


def test_file_of_another_kind_is_named_by_its_kind(capsys):
    """A field file given where a solution or comm problem is expected says which kind it is."""
    field = str(examples.path("field"))
    assert main(["verify", field, "example:assignment_problem"]) == 2
    assert _error_line(capsys).endswith(
        f"{field}: expected a 'solution' file, got kind \"gridded\""
    )
    assert main(["simulate", field]) == 2
    assert "expected a 'comm_problem' file, got kind \"gridded\"" in _error_line(capsys)


def test_readme_snippets_with_files_run_from_another_folder(tmp_path, monkeypatch, capsys):
    """The README's snippets that read a file run outside the clone (packaged examples)."""
    import re
    import shlex

    text = (ROOT / "README.md").read_text()
    monkeypatch.chdir(tmp_path)
    blocks = [b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "examples.path" in b]
    assert blocks, "the README lost its packaged-example snippet"
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})
    commands = [
        shlex.split(line, comments=True)[1:]
        for block in re.findall(r"```bash\n(.*?)```", text, re.S)
        for line in block.splitlines()
        if line.startswith("taopt ") and "example:" in line
    ]
    assert not [c for c in commands for w in c if w.startswith("taopt/data")]
    quick = [c for c in commands if c[:2] in (["solve", "example:sop_problem"],)]
    for argv in quick:
        assert main([*argv, "--quiet"]) == 0
    assert "infeasible" in capsys.readouterr().out
