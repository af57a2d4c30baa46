"""The command line: navigate, demo, field specs, clean errors with exit code 2."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from taopt.cli import build_parser, main, parse_field
from taopt.errors import InstanceError
from taopt.fields import LinearField, UniformField, thesis_field
from taopt.instance import Instance


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

    from taopt.demo import load_demo_instance, run_demo
    from taopt.navigation import min_time_path

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
    from taopt.solving import solve_file

    # chapter 2, from a cost matrix
    rng = np.random.default_rng(5)
    problem = taopt.AssignmentProblem(rng.uniform(1, 50, size=(9, 9)), n_targets=6)
    problem.save(tmp_path / "p.json")
    result = solve_file(tmp_path / "p.json", out=io.StringIO(), progress=False)
    table = result["table"]
    assert table.loc[table.method == "exact", "status"].item() == "optimal"
    assert (table["gap_to_optimum"] >= -1e-9).all()
    # chapter 5, with the exact subset DP and the MILP
    inst = DeliveryInstance.grid(
        rng.uniform(0, 600, size=(5, 2)), 3, 600.0, 1.0, 1.0, 700.0, precedences=[(0, 1), (2, 3)]
    )
    inst.save(tmp_path / "d.json")
    png, gantt = tmp_path / "plan.png", tmp_path / "gantt.png"
    argv = ["solve", str(tmp_path / "d.json"), "--methods", "NIA,MMA,SMMA,DP,exact"]
    assert main(argv + ["--plot", str(png), "--gantt", str(gantt), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "DP" in out and "exact" in out and png.exists() and gantt.exists()
    result = solve_file(tmp_path / "d.json", methods=("MMA", "DP", "exact"), out=io.StringIO())
    table = result["table"].set_index("method")
    assert table.loc["DP", "objective"] == pytest.approx(table.loc["exact", "objective"], rel=1e-6)
    assert table.loc["MMA", "objective"] >= table.loc["DP", "objective"] * (1 - 1e-9)


def test_solve_command_rejects_unknown_kind(tmp_path, capsys):
    """An unknown file kind is a one-line error naming it, exit code 2."""
    bad = tmp_path / "x.json"
    bad.write_text('{"schema_version": 1, "kind": "pizza"}')
    assert main(["solve", str(bad)]) == 2
    assert "kind 'pizza'" in capsys.readouterr().err
