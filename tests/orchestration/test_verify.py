"""`taopt solve --out` writes certificates that `taopt verify` re-checks from the problem alone."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from conftest import ROOT

from taopt.orchestration.cli import main

EXAMPLES = ROOT / "taopt" / "data" / "examples"


@pytest.mark.parametrize(
    "kind",
    [
        "assignment_problem",
        "delivery_instance",
        "sop_problem",
        "comm_problem",
        "capability_problem",
        "budgeted_problem",
    ],
)
def test_saved_solutions_verify(tmp_path, kind, capsys):
    """Every solution `taopt solve --out` writes passes `taopt verify --exact`."""
    problem = EXAMPLES / f"{kind}.json"
    assert main(["solve", str(problem), "--out", str(tmp_path), "--quiet"]) == 0
    saved = sorted(tmp_path.glob("*.json"))
    assert saved
    for path in saved:
        assert main(["verify", str(path), str(problem), "--exact"]) == 0, path.name
    assert "NOT VALID" not in capsys.readouterr().out


def test_swapped_arguments_say_the_order(capsys, assignment_example_file, solution_example_file):
    """`taopt verify PROBLEM SOLUTION` (swapped) is exit 2 with the right order named."""
    problem, solution = assignment_example_file, solution_example_file
    assert main(["verify", str(problem), str(solution)]) == 2
    assert "takes the solution first, then the problem" in capsys.readouterr().err


def test_tampered_solutions_fail(tmp_path, capsys, assignment_example_file, solution_example_file):
    """A changed objective, a false 'optimal' claim or infeasible routes are each caught."""
    problem = assignment_example_file
    good = json.loads(solution_example_file.read_text())
    cases = {
        "objective": {**good, "objective": good["objective"] - 1},
        "claim": {**good, "status": "optimal", "bound": good["objective"] / 2},
        "routes": {**good, "payload": {"routes": [[0], [0, 1, 2]]}},
        "family": {**good, "payload_kind": "order", "payload": {"order": [0, 1, 2]}},
    }
    for name, data in cases.items():
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(data))
        assert main(["verify", str(path), str(problem)]) == 1, name
    out = capsys.readouterr().out
    assert "visited twice" in out and "payload is 'order'" in out


# --------------------------------------------------------------- what verify checks (issue 15)
def _write(tmp_path: Path, name: str, data: dict) -> Path:
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(data))
    return path


def _last_line(text: str) -> str:
    return text.strip().splitlines()[-1]


def _worse_routes() -> dict:
    """The shipped optimal certificate with other feasible routes, objective re-scored."""
    import taopt
    from taopt.orchestration.solving import load_problem_file

    good = json.loads((EXAMPLES / "solution.json").read_text())
    problem, _ = load_problem_file(EXAMPLES / "assignment_problem.json")
    routes = [[], [1, 2, 0]]
    value = taopt.evaluate(problem, taopt.Routes(routes))
    assert value > good["objective"]  # not optimal
    return {**good, "method": "MC", "objective": value, "payload": {"routes": routes}}


def ten_customer_delivery():
    """A 10-customer layered-DAG delivery instance where SMMA is not optimal (seed 0)."""
    from reference import layered_grid_delivery

    return layered_grid_delivery(10).replace(name="ten")


def test_unchecked_optimality_is_said(tmp_path, capsys, assignment_example_file):
    """A solution relabelled "optimal" (bound = objective) is not called plainly VALID without --exact."""
    worse = _worse_routes()
    relabelled = {**worse, "status": "optimal", "bound": worse["objective"]}
    problem = assignment_example_file
    solution = _write(tmp_path, "relabelled", relabelled)
    assert main(["verify", str(solution), str(problem)]) == 3
    out = capsys.readouterr().out
    assert "[not checked] optimality: needs --exact" in out
    assert _last_line(out) == "VALID (2 claims not checked)"
    assert main(["verify", str(solution), str(problem), "--exact"]) == 1
    out = capsys.readouterr().out
    assert "[FAIL] optimality: the re-solve found 10.5" in out
    assert _last_line(out) == "NOT VALID"


def test_fully_checked_certificate_is_plainly_valid(
    tmp_path, capsys, assignment_example_file, solution_example_file
):
    """The shipped optimal solution: every claim checked with --exact, exit 0, last line VALID."""
    solution, problem = solution_example_file, assignment_example_file
    assert main(["verify", str(solution), str(problem), "--exact"]) == 0
    out = capsys.readouterr().out
    assert "[not checked]" not in out and _last_line(out) == "VALID"


@pytest.mark.parametrize("status", ["infeasible", "error", "relaxation"])
def test_status_contradicting_a_feasible_payload(
    tmp_path, capsys, status, assignment_example_file, solution_example_file
):
    """A feasible payload saved with a status that says it is no solution is rejected."""
    good = json.loads(solution_example_file.read_text())
    solution = _write(tmp_path, status, {**good, "status": status, "bound": None})
    assert main(["verify", str(solution), str(assignment_example_file)]) == 1
    assert f"status '{status}' contradicts a feasible payload" in capsys.readouterr().out


def test_false_bound_caught_with_exact(tmp_path, capsys, assignment_example_file):
    """A bound above the optimum (but below the objective) is unchecked alone, refuted with --exact."""
    worse = _worse_routes()
    tampered = {**worse, "status": "feasible", "bound": worse["objective"] - 0.1}
    solution = _write(tmp_path, "bound", tampered)
    problem = assignment_example_file
    assert main(["verify", str(solution), str(problem)]) == 3
    assert main(["verify", str(solution), str(problem), "--exact"]) == 1
    assert "is above a solution the re-solve found" in capsys.readouterr().out


def test_delivery_exact_uses_dp_and_rejects_relabelled_smma(tmp_path, capsys):
    """--exact on 10 customers re-solves with the ideal DP and rejects a relabelled SMMA plan."""
    import taopt
    from taopt.orchestration.pipeline import certifying_method

    instance = ten_customer_delivery()
    assert certifying_method(instance) == "exact"
    problem = tmp_path / "ten.json"
    instance.save(problem)
    smma = taopt.solve(instance, "SMMA")
    smma.replace(status="optimal", bound=smma.objective).save(tmp_path / "smma.json")
    code = main(["verify", str(tmp_path / "smma.json"), str(problem), "--exact"])
    out = capsys.readouterr().out
    assert code == 1 and "re-solved with 'exact'" in out
    assert "[FAIL] optimality: the re-solve found" in out
    # a limit too short for the DP leaves the claims unchecked, said plainly
    code = main(["verify", str(tmp_path / "smma.json"), str(problem), "--exact",
                 "--time-limit", "0.001"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 3 and "[not checked] optimality: the re-solve stopped" in out


@pytest.mark.timing
def test_delivery_exact_re_solve_is_quick(tmp_path, capsys):
    """--exact on 10 customers (the ideal DP) returns within 30 s of wall-clock time."""
    import time

    import taopt

    instance = ten_customer_delivery()
    problem = tmp_path / "ten.json"
    instance.save(problem)
    smma = taopt.solve(instance, "SMMA")
    smma.replace(status="optimal", bound=smma.objective).save(tmp_path / "smma.json")
    began = time.perf_counter()
    assert main(["verify", str(tmp_path / "smma.json"), str(problem), "--exact"]) == 1
    assert time.perf_counter() - began < 30


MALFORMED = {
    "plan payload on routes": {"payload_kind": "plan"},
    "order payload on routes": {"payload_kind": "order"},
    "routes not a list": {"payload": {"routes": "abc"}},
    "route of strings": {"payload": {"routes": [["a"]]}},
    "payload missing": {"payload": None},
    "unknown payload kind": {"payload_kind": "nothing"},
    "objective a string": {"objective": "ten"},
    "status unknown": {"status": "certain"},
    "index out of range": {"payload": {"routes": [[], [0, 1, 7]]}},
    "negative index": {"payload": {"routes": [[], [0, 1, -2]]}},
    "huge index": {"payload": {"routes": [[], [0, 1, 10**30]]}},
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_certificates_clear_error(
    tmp_path, capsys, name, assignment_example_file, solution_example_file
):
    """Every malformed certificate ends in a FAIL line or a one-line error naming the file."""
    good = json.loads(solution_example_file.read_text())
    solution = _write(tmp_path, "bad", {**good, **MALFORMED[name]})
    code = main(["verify", str(solution), str(assignment_example_file)])
    captured = capsys.readouterr()
    assert code in (1, 2)
    if code == 2:
        assert captured.err.count("\n") == 1 and str(solution) in captured.err
    else:
        assert _last_line(captured.out) == "NOT VALID"
